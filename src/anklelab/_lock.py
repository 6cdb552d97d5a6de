"""An advisory lock on an output, so that two anklelab processes never write it at once.

The lock is ``fcntl.flock`` on a hidden file beside the output (``.NAME.anklelab.lock``) holding
the owner's process id. The kernel releases it when the process ends, however it ends, so a
killed writer never leaves the output locked; the file itself is removed by its owner on release
(and, after a ``kill -9``, by the next writer beside it: :func:`reap_locks`).
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from anklelab.errors import OutputError

__all__ = ["lock_path", "output_lock", "reap_locks"]

_SUFFIX = ".anklelab.lock"


def lock_path(target: str | os.PathLike[str]) -> Path:
    """The lock file of ``target``.

    >>> lock_path("runs/out")
    PosixPath('runs/.out.anklelab.lock')
    """
    target = Path(target)
    return target.parent / f".{target.name[:200]}{_SUFFIX}"


def _holder(fd: int) -> str:
    text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    return f"pid {text}" if text.isdigit() else "another process"


@contextmanager
def output_lock(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Hold the exclusive lock of ``target`` (see the module docstring); yield the lock file.

    Raises
    ------
    OutputError
        Another process holds the lock: the message names the output, the lock file and the
        holder's process id. Fails at once; it never waits. Also when the lock file cannot be
        created (a read-only or full file system, no permission).
    """
    target = Path(target)
    lock = lock_path(target)
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as exc:
            raise OutputError(f"{target}: cannot be written: {exc.strerror}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise OutputError(
                f"{target}: another anklelab process ({holder}) is writing it (lock {lock}); "
                "wait for it to finish, or choose another output"
            ) from None
        # the previous owner may have removed the file between our open and our lock
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(lock))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield lock
    finally:
        with suppress(OSError):
            os.unlink(lock)
        os.close(fd)


def reap_locks(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the lock files in ``directory`` that no process holds (left by a killed writer).

    Each is removed while locked, so a writer that opened it meanwhile notices (its file is no
    longer the one at the path) and starts over. Returns the paths removed.
    """
    removed = []
    for lock in Path(directory).glob(f".*{_SUFFIX}"):
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CLOEXEC)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if os.path.samestat(os.fstat(fd), os.stat(lock)):
                os.unlink(lock)
                removed.append(lock)
        except OSError:  # held by a live writer, or gone already
            pass
        finally:
            os.close(fd)
    return removed
