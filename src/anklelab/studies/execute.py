"""Run many independent tasks on Dask, keeping each result on disk as it arrives.

Three ways to run, one code path for what happens to the results:

- by default, Dask's local scheduler over a pool of worker processes on this machine (one per
  CPU unless told otherwise);
- ``local-cluster``: a ``distributed.LocalCluster`` of worker processes talking TCP on the
  loopback interface (what a real cluster does, on one machine);
- an address (``tcp://host:8786``): the scheduler of a running Dask cluster, whose workers must
  have anklelab installed (and, for ``batch``, see the session files at the same paths).

Every task is a pure function of its arguments. :func:`attempt` runs it, retries it when it
raises, and returns either its value or the error as text: a failed task is recorded, never
dropped. Each finished task is written to a :class:`ResultStore` at once (atomically), so a
killed run loses only the tasks in flight: :func:`run_tasks` skips every task whose file
exists. A command keeps its store beside its output (:func:`checkpoint_for`), because the
output directory itself is built under a temporary name and only appears when the run
completes. Worker processes run with one BLAS/OpenMP thread (as Dask's own nannies set them), so
numbers do not depend on how many tasks share a machine.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from anklelab._atomic import write_text_atomic
from anklelab._version import __version__, code_fingerprint
from anklelab.errors import AnklelabWarning, ParameterError

__all__ = [
    "LOCAL_CLUSTER",
    "ResultStore",
    "Task",
    "attempt",
    "check_scheduler",
    "checkpoint_for",
    "default_workers",
    "failed_tasks",
    "run_tasks",
]

LOCAL_CLUSTER = "local-cluster"
_ONE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")}


@dataclass(frozen=True)
class Task:
    """``func(*args)`` under a stable ``key`` (the name of its result file)."""

    key: str
    func: Callable[..., dict[str, Any]]
    args: tuple[Any, ...]


class ResultStore:
    """One JSON file per finished task under ``directory``.

    Parameters
    ----------
    directory : Path
        Where the results are kept.
    fields : tuple of str
        What a task's value holds (``("rows",)`` for a study's sessions): a kept result that
        lacks one of them, as one that is no :func:`attempt` record at all, is computed again.
    """

    def __init__(self, directory: Path, *, fields: tuple[str, ...] = ()) -> None:
        self.directory = Path(directory)
        self.fields = fields

    def path(self, key: str) -> Path:
        return self.directory / f"{key}.json"

    def has(self, key: str) -> bool:
        """Whether ``key``'s result is stored and readable; an unreadable one (a file cut short,
        or edited by hand into something else) is named in a warning and computed again."""
        path = self.path(key)
        if not path.is_file():
            return False
        try:
            problem = self._problem(json.loads(path.read_text(encoding="utf-8")))
        except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError is a ValueError
            problem = f"{type(exc).__name__}: {exc}"
        if problem:
            warnings.warn(
                f"{path}: an earlier run's result is unreadable ({problem}); computing it again",
                AnklelabWarning,
                stacklevel=2,
            )
        return not problem

    def _problem(self, record: Any) -> str:
        """What keeps ``record`` from being a finished task's (empty when nothing does)."""
        if not isinstance(record, dict):
            return "not a JSON object"
        if not isinstance(record.get("ok"), bool):
            return "no 'ok' flag, true or false"
        needed = self.fields if record["ok"] else ("error",)
        return ", ".join(f"no {name!r}" for name in needed if name not in record)

    def read(self, key: str) -> dict[str, Any]:
        result: dict[str, Any] = json.loads(self.path(key).read_text(encoding="utf-8"))
        return result

    def write(self, key: str, record: dict[str, Any]) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        write_text_atomic(self.path(key), json.dumps(record, allow_nan=True))

    def copy_into(self, keys: Sequence[str], directory: Path) -> None:
        """Copy the results of ``keys`` to ``directory`` (nothing when it is this store)."""
        directory = Path(directory)
        if directory.resolve() == self.directory.resolve():
            return
        directory.mkdir(parents=True, exist_ok=True)
        for key in keys:
            shutil.copyfile(self.path(key), directory / self.path(key).name)


def checkpoint_for(out: Path) -> Path:
    """Where a command writing ``out`` keeps finished tasks until its run completes.

    A hidden directory beside the output, ``.NAME.anklelab-cells``: it outlives a run that is
    stopped (even by ``kill -9``), so the next run into ``out`` resumes from it; the command
    removes it once the output is in place.

    >>> checkpoint_for(Path("/runs/misalignment")).as_posix()
    '/runs/.misalignment.anklelab-cells'
    """
    out = Path(os.path.abspath(out))
    return out.parent / f".{out.name}{_CHECKPOINT}"


_CHECKPOINT = ".anklelab-cells"
"""The suffix of :func:`checkpoint_for`'s directories."""


def failed_tasks(out: Path, command: str, keys: Sequence[str]) -> list[str]:
    """The tasks to compute again when ``command`` runs into ``out`` once more.

    When ``out`` is a completed output of ``command`` whose ``cells/`` hold the results of
    exactly ``keys`` (the same tasks: same settings, same anklelab code), the keys whose result
    is a failure (or unreadable); else, or when none failed, an empty list.
    """
    from anklelab._runs import RunManifest
    from anklelab.errors import ResultsFormatError

    kept = ResultStore(out / "cells")
    try:
        manifest = RunManifest.load(out)
    except ResultsFormatError:
        return []
    stored = {path.stem for path in kept.directory.glob("*.json")}
    if manifest is None or manifest.command != command or stored != set(keys):
        return []
    return [key for key in keys if not (kept.has(key) and kept.read(key)["ok"])]


def attempt(func: Callable[..., dict[str, Any]], args: Sequence[Any], retries: int) -> dict:
    """``func(*args)`` tried up to ``1 + retries`` times.

    Returns ``{"ok": True, "attempts": n, **value}`` or, when every try raised,
    ``{"ok": False, "attempts": n, "error": "ExceptionType: message"}``.
    """
    error = ""
    for n in range(1, retries + 2):
        try:
            return {"ok": True, "attempts": n} | func(*args)
        except Exception as exc:  # recorded with the task, never dropped
            error = " ".join(f"{type(exc).__name__}: {exc}".split())
    return {"ok": False, "attempts": retries + 1, "error": error}


def check_scheduler(scheduler: str | None, workers: int | None) -> None:
    """Check :func:`run_tasks`'s ``scheduler`` and ``workers`` together, before any work:
    ``workers`` is for this machine's pools only; a running cluster has the workers it has.
    (Whether a scheduler answers at the address is known only once it is asked.)"""
    if workers is not None and workers < 1:
        raise ParameterError(f"--workers: expected >= 1, got {workers}")
    if workers is not None and scheduler not in (None, LOCAL_CLUSTER):
        raise ParameterError(
            f"--workers: a running Dask cluster (--scheduler {scheduler}) has its own workers; "
            f"give --workers only with the default scheduler or --scheduler {LOCAL_CLUSTER}"
        )


def default_workers() -> int:
    """Worker processes by default: the CPUs this process may use."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def run_tasks(
    tasks: Sequence[Task],
    store: ResultStore,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, float]:
    """Run every task whose result is not in ``store`` yet; write each result as it finishes.

    Parameters
    ----------
    tasks : sequence of Task
    store : ResultStore
    scheduler : str, optional
        None: Dask's local scheduler over worker processes; ``"local-cluster"``: a
        ``LocalCluster`` over TCP on the loopback interface; else the address of a running
        Dask scheduler.
    workers : int, optional
        Worker processes for the local scheduler and the local cluster (default: the CPUs).
    retries : int
        Extra tries of a task that raises (and, on a cluster, of one whose worker died).
    progress : callable, optional
        ``progress(done, total)`` as tasks finish (resumed ones count as done).

    Returns
    -------
    dict
        ``{"resumed": tasks found done, "ran": tasks run, "wall_s": seconds}``.
    """
    if retries < 0:
        raise ParameterError(f"retries: expected >= 0, got {retries}")
    check_scheduler(scheduler, workers)
    todo = [task for task in tasks if not store.has(task.key)]
    done = len(tasks) - len(todo)
    keys = {task.key for task in tasks}
    others = [path for path in store.directory.glob("*.json") if path.stem not in keys]
    if not done and (stored := len(others)):
        removed = store.directory.name.endswith(_CHECKPOINT)  # a command's: see checkpoint_for
        warnings.warn(
            f"{store.directory}: none of its {stored} stored results is for these sessions "
            f"(they have other settings, or were computed by another anklelab version or "
            f"code): all {len(tasks)} run"
            + ("; the kept sessions will be removed when this run completes" if removed else ""),
            AnklelabWarning,
            stacklevel=2,
        )
    report = progress or (lambda _done, _total: None)
    report(done, len(tasks))
    start = time.perf_counter()
    if todo:
        counter = [done]

        def finished(key: str, record: dict[str, Any]) -> None:
            store.write(key, record)
            counter[0] += 1
            report(counter[0], len(tasks))

        n_workers = default_workers() if workers is None else workers
        if scheduler is None:
            _run_local(todo, n_workers, retries, finished)
        else:
            _run_distributed(todo, scheduler, n_workers, retries, finished)
    return {"resumed": done, "ran": len(todo), "wall_s": time.perf_counter() - start}


def _run_local(
    tasks: list[Task], workers: int, retries: int, finished: Callable[[str, dict], None]
) -> None:
    """Dask's local scheduler on a pool of spawned worker processes.

    A worker process that dies (out of memory, killed, a crash in compiled code) breaks the
    pool, and every task running at that moment is a suspect. The suspects run again one at a
    time, each on a fresh pool of one process, so that a death is charged to the task that
    caused it: a task whose process died on each of its ``1 + retries`` tries is recorded as
    failed (as on a cluster), and the others go on.
    """
    pending = {task.key: task for task in tasks}
    deaths: dict[str, int] = {}
    suspects: list[str] = []

    def done(key: str, record: dict[str, Any]) -> None:
        del pending[key]
        finished(key, record)

    while pending:
        batch = [pending[key] for key in suspects or pending]
        running = _run_pool(batch, 1 if suspects else workers, retries, done)
        if len(running) > 1:
            suspects = sorted(running)
            continue
        for key in running:
            deaths[key] = deaths.get(key, 0) + 1
            if deaths[key] > retries:
                done(key, {"ok": False, "attempts": deaths[key], "error": _DIED})
        suspects = [key for key in suspects if key in pending]


_DIED = "the worker process running it died (out of memory, or killed?)"


def _run_pool(
    tasks: list[Task], workers: int, retries: int, finished: Callable[[str, dict], None]
) -> set[str]:
    """Run ``tasks`` on a fresh pool of ``workers`` spawned processes; the keys of the tasks that
    were running when a worker process died (empty when every task finished)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    import dask.multiprocessing

    graph = {task.key: (attempt, task.func, task.args, retries) for task in tasks}
    running: set[str] = set()

    def started(key: str, dsk: Any, state: Any) -> None:
        running.add(key)

    def written(key: str, result: dict, dsk: Any, state: Any, worker: Any) -> None:
        running.discard(key)
        finished(key, result)

    # dask's local callbacks: (start, start_state, pretask, posttask, finish)
    callbacks = [(None, None, started, written, None)]
    try:
        with (
            _environment(_ONE_THREAD),
            ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool,
        ):
            # chunksize 1: each result comes back (and is written) as soon as it is done
            dask.multiprocessing.get(
                graph, list(graph), pool=pool, callbacks=callbacks, chunksize=1
            )
    except BrokenProcessPool:
        return running
    return set()


def _run_distributed(
    tasks: list[Task],
    scheduler: str,
    workers: int,
    retries: int,
    finished: Callable[[str, dict], None],
) -> None:
    """A ``distributed`` cluster: a local one over TCP, or the one at ``scheduler``."""
    import logging

    from distributed import Client, LocalCluster, as_completed

    logging.getLogger("distributed").setLevel(logging.ERROR)
    with _client(scheduler, workers, Client, LocalCluster) as client:
        identity = _identity()
        _check_workers(client, scheduler, identity)
        futures = client.map(
            _attempt_as,
            [identity] * len(tasks),
            [task.func for task in tasks],
            [task.args for task in tasks],
            [retries] * len(tasks),
            key=[task.key for task in tasks],
            retries=retries,
            pure=False,
        )
        for future in as_completed(futures):
            if future.status == "finished":
                record = future.result()
            else:  # the worker died (every retry): the task's error, not the study's
                exc = future.exception()
                error = "the worker running it died (out of memory?): " + " ".join(
                    f"{type(exc).__name__}: {exc}".split()
                )
                record = {"ok": False, "attempts": retries + 1, "error": error}
            finished(future.key, record)
            future.release()


def _identity() -> tuple[str, str]:
    """This process's anklelab: its version and code fingerprint, which the tasks' keys hash."""
    return __version__, code_fingerprint()


def _describe(identity: tuple[str, str]) -> str:
    return f"anklelab {identity[0]} (code {identity[1]})"


def _check_workers(client: Any, scheduler: str, identity: tuple[str, str]) -> None:
    """Refuse a cluster whose workers run other anklelab code than this process: their results
    would be kept under this code's keys."""
    for address, found in sorted(client.run(_identity, on_error="return").items()):
        if isinstance(found, BaseException):
            runs = f"cannot run anklelab ({type(found).__name__}: {found})"
        elif tuple(found) != identity:
            runs = f"runs {_describe(tuple(found))}"
        else:
            continue
        raise ParameterError(
            f"--scheduler {scheduler}: worker {address} {runs}; this command runs "
            f"{_describe(identity)}. Give every worker the same anklelab (the same version "
            "installed, or PYTHONPATH pointing at the same source tree)"
        )


def _attempt_as(
    identity: tuple[str, str],
    func: Callable[..., dict[str, Any]],
    args: Sequence[Any],
    retries: int,
) -> dict[str, Any]:
    """:func:`attempt`, on a worker running the anklelab ``identity`` names (a worker that joined
    the cluster after :func:`_check_workers` may run other code: its tasks fail)."""
    if _identity() != tuple(identity):
        return {
            "ok": False,
            "attempts": 1,
            "error": f"this worker runs {_describe(_identity())}, not {_describe(identity)}",
        }
    return attempt(func, args, retries)


@contextmanager
def _client(scheduler: str, workers: int, client_type: Any, cluster_type: Any) -> Iterator[Any]:
    """A client of the cluster at ``scheduler``, or of a local cluster whose workers keep their
    scratch space in a temporary directory of their own, removed with the cluster (Dask's
    default, ``TMPDIR/dask-scratch-space``, stays behind)."""
    if scheduler == LOCAL_CLUSTER:
        import dask

        with (
            tempfile.TemporaryDirectory(prefix="anklelab-dask-", ignore_cleanup_errors=True)
            as scratch,
            dask.config.set({"temporary-directory": scratch}),
            cluster_type(
                n_workers=workers, threads_per_worker=1, processes=True, protocol="tcp",
                host="127.0.0.1", dashboard_address=None, local_directory=scratch,
                preload=["anklelab.studies._worker_setup"],
            ) as cluster,
            client_type(cluster) as client,
        ):  # fmt: skip
            yield client
        return
    try:
        client = client_type(scheduler, timeout="10s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(
            f"--scheduler {scheduler}: no Dask scheduler answers there ({exc}); give "
            f"'{LOCAL_CLUSTER}', or the address of a running scheduler (tcp://HOST:8786)"
        ) from None
    with client:
        yield client


@contextmanager
def _environment(values: dict[str, str]) -> Iterator[None]:
    """Set environment variables for the block (spawned workers inherit them)."""
    saved = {name: os.environ.get(name) for name in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
