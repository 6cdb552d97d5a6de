"""Figures rendered to PNG in worker processes that start before the results they draw exist.

A command that ends in figures spends most of its time in matplotlib: importing it (about 0.7 s)
and laying out and drawing every panel (0.5-1 s per walking figure). The analysis before it is
single-threaded. :class:`FigureRenderer` therefore starts its workers first: while the caller
computes, they import matplotlib and the figure modules on the cores the analysis leaves idle.
Given the results, they render one figure per task, in parallel, and return PNG bytes.

Workers are forks of a fork server (:mod:`multiprocessing`'s ``forkserver``: a fresh,
single-threaded interpreter that imports matplotlib and the figure modules once, so that two
workers cost one import, 1.3 s of CPU less on a paper-size ``analyze``), or spawned where there is
no fork server (Windows); never forks of the command's own process, whose threads may hold
locks. Starting a worker waits for the server's imports, so a thread starts them and the caller
goes on. Workers ignore Ctrl-C from their first instant (the command handles it and, leaving the
``with`` block, shuts them down) and exit when the process that started them dies, however it
dies. With one usable core everything is drawn in the calling process, and so it is when
worker processes cannot be started (no shared-memory semaphores, say), die, or cannot be sent
the data: the figures are then slower, never missing.

As with every spawned process, the starting script must guard its top level with
``if __name__ == "__main__":`` (the ``anklelab`` command does): the server imports the main
module.
"""

from __future__ import annotations

import atexit
import importlib
import multiprocessing
import os
import pickle
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import CancelledError, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from multiprocessing import forkserver, get_context
from multiprocessing.connection import wait
from types import TracebackType
from typing import Any, TypeVar

from anklelab.report.html import figure_png

__all__ = ["FigureRenderer", "PendingFigures"]

T = TypeVar("T")

_MATPLOTLIB = ("matplotlib.figure", "matplotlib.backends.backend_agg")
_STARTUP_S = 10.0
"""The longest wait for a figure worker to start or end when a command is abandoned, s."""
_MAX_PROCESSES = 4
"""More workers than this would only add start-up work: a command draws at most a few figures."""


def _exit_with(parent: Any) -> None:
    wait([parent.sentinel])
    os._exit(1)


def _prepare_worker(modules: Sequence[str]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # already so if started by the constructor
    parent = multiprocessing.parent_process()
    if parent is not None:  # a worker whose parent was killed would wait for tasks forever
        threading.Thread(target=_exit_with, args=(parent,), daemon=True).start()
    for module in (*_MATPLOTLIB, *modules):  # already imported by a fork server's workers
        importlib.import_module(module)
    atexit.register(_exit_at_once)  # run first (last registered): the rest is never needed


def _exit_at_once() -> None:
    """End a worker without tearing its interpreter down: with matplotlib loaded that took
    0.3 s, which the command waited for when it shut the pool down. A worker holds no file
    and has sent every result by then (the result queue is written synchronously).

    Its exit code is then 0 even when it dies of an error outside a task (its traceback is
    still printed). Nothing reads it: the pool sees a dead worker by its process sentinel and
    breaks, and the figures are drawn in the calling process.
    """
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    os._exit(0)


def _ready() -> None:
    """A task that only makes the pool start a worker now."""


def _png(draw: Callable[[T, str], Any], payload: bytes, name: str) -> bytes:
    png = figure_png(draw(pickle.loads(payload), name))
    # still the first exit handler to run, whatever the drawing registered (a spawned worker
    # ends by sys.exit; a forked one by os._exit, which runs none)
    atexit.unregister(_exit_at_once)
    atexit.register(_exit_at_once)
    return png


def _start_method() -> str:
    """``forkserver`` where the platform has it (module docstring), else ``spawn``."""
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


def _usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextmanager
def _ctrl_c_held() -> Iterator[None]:
    """Ctrl-C held back while workers start: they inherit that from their first instant (the
    initializer would come too late to spare the terminal their tracebacks).

    Where the platform can block the signal, this thread blocks it, so that the workers it
    starts are born with it blocked. One that arrives meanwhile is kept and delivered to the
    command when the workers have started, not lost (an ignored one was, and the command ran to
    its end). It is kept by a handler of its own, not by the block alone: another thread of the
    process (the figure starter, a thread pool of the analysis) may take a signal sent to the
    process, and its handler then runs here at once (a test saw exactly that).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda number, frame: arrived.append(number))
    blocks = hasattr(signal, "pthread_sigmask")
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT}) if blocks else None
    try:
        yield
    finally:
        if mask is not None:  # a signal pending on this thread is taken by the handler above
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        signal.signal(signal.SIGINT, previous)
        if arrived:
            signal.raise_signal(signal.SIGINT)


class FigureRenderer:
    """Render named figures to PNG bytes, in parallel worker processes started ahead of need.

    Parameters
    ----------
    modules : sequence of str
        Modules each worker imports on start (those defining the figure functions, and the
        classes of the data they draw), besides matplotlib.
    processes : int, optional
        Worker processes; by default one per usable core, at most 4. With 1 (or a single-core
        machine, or inside a worker process) figures are drawn in the calling process and
        nothing is started.

    Examples
    --------
    >>> from anklelab.report.figures_walking import walking_figure
    >>> with FigureRenderer(["anklelab.report.figures_walking"]) as renderer:  # doctest: +SKIP
    ...     results = analyze_walking(session)  # the workers import matplotlib meanwhile
    ...     pngs = renderer.render(walking_figure, results, ["filters", "model_fit"])
    """

    def __init__(self, modules: Sequence[str] = (), processes: int | None = None) -> None:
        if processes is None:
            processes = min(_usable_cores(), _MAX_PROCESSES)
        if multiprocessing.parent_process() is not None:
            processes = 1  # never workers of workers
        self.processes = processes
        self._pool: ProcessPoolExecutor | None = None
        self._starter: threading.Thread | None = None
        if processes > 1:
            try:
                method = _start_method()
                context = get_context(method)
                forked = method == "forkserver"
                if forked:
                    context.set_forkserver_preload(["__main__", *_MATPLOTLIB, *modules])
                    with _ctrl_c_held():  # its workers inherit that
                        forkserver.ensure_running()
                self._pool = ProcessPoolExecutor(
                    processes,
                    mp_context=context,
                    initializer=_prepare_worker,
                    initargs=(tuple(modules),),
                )
                if forked:  # starting a worker waits for the server's imports: not the caller
                    self._starter = threading.Thread(
                        target=self._start, args=(self._pool,), daemon=True
                    )
                    self._starter.start()
                else:
                    with _ctrl_c_held():
                        self._start(self._pool)
            except (OSError, NotImplementedError, BrokenProcessPool):
                self.close()
            except BaseException:
                # interrupted (SIGTERM) while they start: end them before this process ends, or a
                # worker still starting would find its semaphores gone and print a traceback
                self.close(abandon=True)
                raise

    def _start(self, pool: ProcessPoolExecutor) -> None:
        """Start every worker now (the pool starts one per pending task)."""
        try:
            for _ in range(self.processes):
                pool.submit(_ready)
        except (RuntimeError, OSError, BrokenProcessPool):  # closed meanwhile, or cannot start
            return

    def render(
        self, draw: Callable[[T, str], Any], data: T, names: Sequence[str]
    ) -> dict[str, bytes]:
        """PNG bytes of ``draw(data, name)`` for every name, in the order given.

        ``draw`` should be a module-level function and ``data`` picklable: each worker is sent
        them (``data`` pickled once for all). An exception raised while drawing is raised here,
        with its traceback.
        """
        return self.submit(draw, data, names).result()

    def submit(
        self, draw: Callable[[T, str], Any], data: T, names: Sequence[str]
    ) -> PendingFigures:
        """As :meth:`render`, but return at once: the workers draw while the caller goes on,
        and :meth:`PendingFigures.result` waits for the PNG bytes."""
        if self._pool is not None:
            try:
                payload = pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL)
                pickle.dumps(draw)
            except (pickle.PicklingError, TypeError, AttributeError):
                self.close()  # a lambda, a local class: drawn here
            else:
                try:
                    tasks = {name: self._pool.submit(_png, draw, payload, name) for name in names}
                except BrokenProcessPool:
                    self.close()
                else:
                    return PendingFigures(self, draw, data, tasks)
        return PendingFigures(self, draw, data, dict.fromkeys(names))

    def close(self, *, abandon: bool = False) -> None:
        """Stop the workers, waiting for any task they are running, or with ``abandon`` (the
        command failed) ending them at once: a worker may still be importing matplotlib, a
        second or more that an error message should not wait for. Idempotent."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if abandon:
            # waits only for the workers being started (their server's imports: a second at
            # most), then ends them all and waits for them: one still starting when this
            # process ended would find its setup's semaphore gone and print a traceback after
            # the command's last line
            pool.shutdown(wait=False, cancel_futures=True)
            if self._starter is not None and self._starter.ident is not None:  # started
                self._starter.join(timeout=_STARTUP_S)
            # no public way before Python 3.14's terminate_workers()
            processes = list((getattr(pool, "_processes", None) or {}).values())
            for process in processes:
                process.terminate()
            for process in processes:
                process.join(timeout=_STARTUP_S)
            return
        pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> FigureRenderer:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close(abandon=error is not None)


class PendingFigures:
    """Figures submitted to a :class:`FigureRenderer`; :meth:`result` returns their PNG bytes.

    A figure whose worker died (killed, out of memory), or that no worker was sent, is drawn in
    the calling process when the result is asked for: slower, never missing.
    """

    def __init__(
        self,
        renderer: FigureRenderer,
        draw: Callable[[Any, str], Any],
        data: Any,
        tasks: Mapping[str, Future[bytes] | None],
    ) -> None:
        self._renderer, self._draw, self._data, self._tasks = renderer, draw, data, tasks

    @property
    def names(self) -> tuple[str, ...]:
        """The figures' names, in the order submitted."""
        return tuple(self._tasks)

    def result(self) -> dict[str, bytes]:
        """PNG bytes by name, in the order submitted (waiting for the workers)."""
        pngs = {}
        for name, task in self._tasks.items():
            try:
                pngs[name] = task.result() if task is not None else None
            except (BrokenProcessPool, CancelledError):  # a worker died; the rest were cancelled
                self._renderer.close()
                pngs[name] = None
        return {
            name: png if png is not None else figure_png(self._draw(self._data, name))
            for name, png in pngs.items()
        }
