"""Atomic writes: build the output beside the target under a temporary name, then rename.

A crash or an exception while writing leaves the target untouched (absent, or the previous
version) and removes the temporary output, so readers see either the old target or the whole
new one. A temporary is a hidden sibling whose name records the writing process
(``.NAME.anklelab-HOST-PID-RANDOM.tmp``); one left behind by a process that was killed
(``kill -9`` gives no chance to clean up) is removed by the next write into the same directory
(:func:`reap_temporaries`), and only once that process is gone.

A directory that already exists is swapped with the new one in a single step where the file
system allows it (Linux ``renameat2(RENAME_EXCHANGE)``), so the target never goes missing.

An interruption (SIGINT, SIGTERM) noted with :func:`note_interrupt` stops every later commit:
the command line's signal handler raises :class:`Interrupted` to unwind the command, but a
handler that fires inside a finaliser (``__del__``, a weak-reference callback) has its exception
swallowed by Python, and the command would then run on and commit its outputs as if nothing had
happened.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import secrets
import shutil
import socket
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

__all__ = [
    "Interrupted",
    "atomic_directory",
    "atomic_file",
    "forget_interrupts",
    "is_temporary",
    "note_interrupt",
    "reap_temporaries",
    "untemporary",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_text_atomic",
]

_HOST = hashlib.sha256(socket.gethostname().encode()).hexdigest()[:6]
_TEMPORARY = re.compile(
    r"\.(?P<name>.+)\.anklelab-(?P<host>[0-9a-f]{6})-(?P<pid>\d{1,10})-[0-9a-f]{8}\.tmp"
    r"(?:\.[A-Za-z0-9]{1,10})?"
)
_NAME_ROOM = 180  # characters of the target's name kept in a temporary's name (NAME_MAX 255)


def _temporary(target: Path, suffix: str = "") -> Path:
    name = target.name[:_NAME_ROOM]
    token = secrets.token_hex(4)
    return target.parent / f".{name}.anklelab-{_HOST}-{os.getpid()}-{token}.tmp{suffix}"


def is_temporary(name: str) -> bool:
    """Whether a file name is one of this module's temporaries.

    >>> is_temporary(_temporary(Path("out")).name), is_temporary("out")
    (True, False)
    """
    return _TEMPORARY.fullmatch(name) is not None


_IN_TEXT = re.compile(
    r"(?<![^/\s'\"])\.(?P<name>[^/\s]+?)\.anklelab-[0-9a-f]{6}-\d{1,10}-[0-9a-f]{8}\.tmp"
    r"(?:\.[A-Za-z0-9]{1,10}(?![\w-]))?"
)


def untemporary(text: str) -> str:
    """``text`` with every temporary's name replaced by the target it stands for.

    Messages name the output the user asked for, not the hidden name it is built under.

    >>> untemporary(f"{_temporary(Path('runs/out')) / 'results.json'}: disk full")
    'runs/out/results.json: disk full'
    """
    while True:
        replaced = _IN_TEXT.sub(lambda match: match["name"], text)
        if replaced == text:
            return text
        text = replaced


def _process_gone(pid: int) -> bool:
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):  # no such process (or not a pid at all)
        return True
    except PermissionError:  # alive, run by another user
        return False
    return False


def reap_temporaries(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporaries in ``directory`` whose writing process is gone.

    Only names this module makes are considered, and only those written on this host (a
    process elsewhere cannot be checked). Returns the paths removed; errors are ignored (a
    temporary that cannot be removed now is tried again next time).
    """
    removed: list[Path] = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = _TEMPORARY.fullmatch(entry.name)
        if not match or match["host"] != _HOST or not _process_gone(int(match["pid"])):
            continue
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            with suppress(OSError):
                os.unlink(entry.path)
        removed.append(Path(entry.path))
    return removed


class Interrupted(BaseException):
    """A signal arrived while outputs were being built: unwind, removing the temporaries.

    A ``BaseException``, like ``KeyboardInterrupt``, so that ``except Exception`` does not stop
    it.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


_pending: list[int] = []  # signals noted in this process and not yet cleared


def note_interrupt(signum: int) -> None:
    """Note that signal ``signum`` arrived: no output is committed after it."""
    _pending.append(signum)


def forget_interrupts() -> None:
    """Forget the signals noted so far (a new command starts)."""
    _pending.clear()


def _commit_allowed() -> None:
    """Raise :class:`Interrupted` if a signal was noted: its exception may have been lost."""
    if _pending:
        raise Interrupted(_pending[0])


def _refuse(target: Path, overwrite: bool) -> None:
    if os.path.lexists(target) and not overwrite:
        raise FileExistsError(f"{target}: already exists; refusing to overwrite it")


@contextmanager
def atomic_file(
    target: str | os.PathLike[str], *, overwrite: bool = True, keep_suffix: bool = False
) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target`` atomically.

    Missing parent directories are created; stale temporaries of dead processes beside
    ``target`` are removed first. With ``keep_suffix`` the temporary ends in ``target``'s
    suffix, for writers that choose the format by the file name (matplotlib's ``savefig``).

    Raises
    ------
    FileExistsError
        ``target`` exists and ``overwrite`` is false, or ``target`` is a directory.
    """
    target = Path(target)
    _refuse(target, overwrite)
    if target.is_dir():
        raise FileExistsError(f"{target}: is a directory; expected a file path")
    target.parent.mkdir(parents=True, exist_ok=True)
    reap_temporaries(target.parent)
    tmp = _temporary(target, target.suffix if keep_suffix else "")
    try:
        yield tmp
        _commit_allowed()
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths in one step (Linux ``renameat2``); False where unsupported."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError, TypeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def _is_empty_directory(path: Path) -> bool:
    return path.is_dir() and not path.is_symlink() and next(path.iterdir(), None) is None


@contextmanager
def atomic_directory(
    target: str | os.PathLike[str], *, overwrite: bool = True, marker: str = "session.toml"
) -> Iterator[Path]:
    """Yield a new temporary directory beside ``target``; on success it becomes ``target``.

    An existing ``target`` is replaced only when ``overwrite`` is true and it holds ``marker``
    (so that a mistyped path never deletes an unrelated directory); an empty directory is
    always replaced. The old directory is swapped out in one step where the file system
    allows it (else renamed away first) and deleted only after the new one is in place.
    """
    target = Path(target)
    empty = _is_empty_directory(target)
    if not empty:
        _refuse(target, overwrite)
        if os.path.lexists(target) and not (
            target.is_dir() and not target.is_symlink() and (target / marker).is_file()
        ):
            raise FileExistsError(f"{target}: exists and has no {marker}; refusing to replace it")
    target.parent.mkdir(parents=True, exist_ok=True)
    reap_temporaries(target.parent)
    tmp = _temporary(target)
    tmp.mkdir()
    try:
        yield tmp
        _commit_allowed()
        if not os.path.lexists(target) or (empty and _is_empty_directory(target)):
            os.replace(tmp, target)  # an empty directory is replaced by rename(2) itself
        elif _exchange(tmp, target):
            shutil.rmtree(tmp, ignore_errors=True)  # now the old directory
        else:
            old = _temporary(target)
            os.replace(target, old)
            try:
                os.replace(tmp, target)
            except BaseException:
                os.replace(old, target)
                raise
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_bytes_atomic(
    path: str | os.PathLike[str], data: bytes, *, overwrite: bool = True
) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_file`); return the path.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as root:
    ...     write_bytes_atomic(Path(root) / "a.bin", b"ok").read_bytes()
    b'ok'
    """
    with atomic_file(path, overwrite=overwrite) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | os.PathLike[str], text: str, *, overwrite: bool = True) -> Path:
    """:func:`write_bytes_atomic` for UTF-8 text."""
    return write_bytes_atomic(path, text.encode("utf-8"), overwrite=overwrite)


def write_json_atomic(
    path: str | os.PathLike[str], document: Any, *, overwrite: bool = True
) -> Path:
    """:func:`write_text_atomic` for ``document`` as indented JSON with a final newline;
    numpy scalars are written as numbers."""
    text = json.dumps(document, indent=2, default=float) + "\n"
    return write_text_atomic(path, text, overwrite=overwrite)
