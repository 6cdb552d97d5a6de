"""Run a reader of native code in worker processes, so that a crash or a hang is an error.

Some readers wrap C++ libraries that can crash the interpreter or loop forever on a corrupt file
(ezc3d does both on truncated or bit-flipped C3D files, found by fuzzing). :func:`map_isolated`
calls such a reader in worker processes: a Python exception comes back as itself, a worker that
dies or exceeds its time limit becomes :class:`IsolatedFailure` naming the item, and the other
items are unaffected.

Workers are fresh interpreters running a standalone script (``python _isolated.py SCRIPT
FUNCTION``) that talk pickle over their standard input and output, not :mod:`multiprocessing`
processes: those re-run the caller's main script, which a user's script without a ``__main__``
guard does not survive. The script is loaded by its path, without importing anklelab (which
keeps a worker's start-up to the libraries it needs); it reports bad input by raising
``ValueError``. Anything the native code prints goes to the worker's standard error, which is
discarded.
"""

from __future__ import annotations

import importlib.util
import os
import pickle
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from multiprocessing.connection import wait
from pathlib import Path
from typing import IO, Any, TypeVar

__all__ = ["IsolatedFailure", "map_isolated"]

T = TypeVar("T")


class IsolatedFailure(RuntimeError):
    """A worker died or exceeded its time limit on ``item``; ``reason`` says which."""

    def __init__(self, item: Any, reason: str) -> None:
        super().__init__(f"{item}: {reason}")
        self.item, self.reason = item, reason


def _start(script: Path, function: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        # -P: the script's directory (this package's, which has an inspect.py) must not
        # shadow the standard library
        [sys.executable, "-P", __file__, str(script), function],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )


def _channel(process: subprocess.Popen[bytes]) -> IO[bytes]:
    """The pipe a worker's replies come on (:func:`_start` always opens it)."""
    assert process.stdout is not None
    return process.stdout


def map_isolated(
    script: Path,
    function: str,
    items: Sequence[T],
    *,
    workers: int = 2,
    timeout_s: Callable[[T], float] | float = 60.0,
) -> list[Any]:
    """``[function(item) for item in items]``, each call in a worker process.

    Parameters
    ----------
    script : Path
        A standalone Python file (it must not need anklelab).
    function : str
        The name of a function in ``script``; items and results must pickle.
    items : sequence
        Arguments, one call each.
    workers : int
        Worker processes (at most one per item).
    timeout_s : float or callable
        Time limit of one call, s, or a function of the item giving it.

    Returns
    -------
    list
        The results in the order of ``items``.

    Raises
    ------
    Exception
        The first exception ``function`` raised (in the order of ``items``).
    IsolatedFailure
        A worker died (a crash in native code) or exceeded the time limit.
    """
    if not items:
        return []
    limit = timeout_s if callable(timeout_s) else (lambda _: float(timeout_s))
    pool = [_start(script, function) for _ in range(max(1, min(workers, len(items))))]
    results: dict[int, tuple[bool, Any]] = {}
    pending = list(enumerate(items))[::-1]
    busy: dict[int, tuple[int, float]] = {}  # worker -> (item index, deadline)
    try:
        while pending or busy:
            for w, process in enumerate(pool):
                if w not in busy and pending:
                    index, item = pending.pop()
                    assert process.stdin is not None
                    try:
                        pickle.dump(item, process.stdin)
                        process.stdin.flush()
                    except BrokenPipeError:
                        raise IsolatedFailure(item, "the reader could not be started") from None
                    busy[w] = (index, time.monotonic() + limit(item))
            deadline = min(due for _, due in busy.values())
            ready = wait(
                [_channel(pool[w]).fileno() for w in busy],
                timeout=max(0.0, deadline - time.monotonic()),
            )
            for w, (index, due) in list(busy.items()):
                process = pool[w]
                if _channel(process).fileno() in ready:
                    try:
                        results[index] = pickle.load(_channel(process))
                    except (EOFError, pickle.UnpicklingError):
                        code = process.wait()
                        raise IsolatedFailure(
                            items[index], f"the reader crashed (exit code {code})"
                        ) from None
                    del busy[w]
                elif time.monotonic() >= due:
                    raise IsolatedFailure(
                        items[index], f"the reader did not finish in {limit(items[index]):g} s"
                    )
    finally:
        for process in pool:
            if process.poll() is None:
                process.kill()
            process.wait()
            for stream in (process.stdin, process.stdout):
                if stream is not None:
                    stream.close()
    out = []
    for index in range(len(items)):
        ok, value = results[index]
        if not ok:
            raise value
        out.append(value)
    return out


def _serve(script: str, function: str) -> None:
    """Worker loop: unpickle an item from stdin, call the function, pickle (ok, result) back."""
    spec = importlib.util.spec_from_file_location("_isolated_script", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    func = getattr(module, function)
    channel = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # whatever the native code prints must not corrupt the channel
    source = sys.stdin.buffer
    while True:
        try:
            item = pickle.load(source)
        except EOFError:
            return
        try:
            reply = (True, func(item))
        except Exception as exc:  # returned to the caller, which raises it
            reply = (False, exc)
        pickle.dump(reply, channel)
        channel.flush()


if __name__ == "__main__":
    _serve(sys.argv[1], sys.argv[2])
