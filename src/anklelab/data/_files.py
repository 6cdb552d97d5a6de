"""Reading the files of a session directory, and only those.

:func:`read_bytes` opens a file only if it is a regular file inside the session directory (a
symbolic link may point elsewhere inside it, never outside), and only up to a size limit checked
before anything is read, so a FIFO, a device, a link to ``/etc/shadow`` or a sparse 2 GB file
ends in one clear message naming the file, never in a hang, a leak or a memory blow-up.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from anklelab.data._text import excerpt, format_bytes
from anklelab.errors import SessionFormatError

__all__ = [
    "MAX_CSV_BYTES",
    "MAX_JSON_BYTES",
    "MAX_MANIFEST_BYTES",
    "MAX_TOML_BYTES",
    "file_kind",
    "file_problem",
    "not_a_file",
    "read_bytes",
]

MAX_CSV_BYTES = 2**30
"""Largest recording file read (1 GiB of text is hours of data at 1 kHz)."""
MAX_MANIFEST_BYTES = 64 * 2**20
"""Largest manifest (``trials.csv``, ``tests.csv``, ``runs.csv``)."""
MAX_TOML_BYTES = 2**20
"""Largest ``session.toml``."""
MAX_JSON_BYTES = 2**30
"""Largest ``truth.json`` or ``provenance.json``."""

_KINDS = {
    stat.S_IFDIR: "a directory",
    stat.S_IFIFO: "a named pipe (FIFO)",
    stat.S_IFSOCK: "a socket",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFLNK: "a symbolic link",
}


def _kind(mode: int) -> str:
    return _KINDS.get(stat.S_IFMT(mode), "not a regular file")


def file_kind(path: Path) -> str:
    """What ``path`` is, for messages ("a named pipe (FIFO)", "a directory", ...)."""
    return _kind(os.stat(path).st_mode)


def _outside(path: Path, root: Path) -> str | None:
    """Why ``path`` (every link resolved) lies outside ``root``, or ``None``."""
    real = os.path.realpath(path)
    if Path(real).is_relative_to(os.path.realpath(root)):
        return None
    return (
        f"is a link to {excerpt(real, 200)}, outside the session directory {root}; links may "
        "only point to files inside the session"
    )


def file_problem(path: Path, root: Path) -> str | None:
    """What keeps ``path`` from being read as a regular file inside ``root`` ("does not exist",
    "is a named pipe (FIFO), not a regular file", ...), or ``None``."""
    return _outside(path, root) or not_a_file(path)


def not_a_file(path: Path) -> str | None:
    """What keeps ``path`` from being read as a regular file ("does not exist", "is a
    directory, not a regular file", ...), or ``None``."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "is a dangling symbolic link" if path.is_symlink() else "does not exist"
    if not stat.S_ISREG(mode):
        return f"is {_kind(mode)}, not a regular file"
    return None


def read_bytes(path: Path, root: Path, limit: int, expected: str = "a CSV file") -> bytes:
    """The bytes of ``path``, a regular file inside ``root`` of at most ``limit`` bytes.

    Raises
    ------
    SessionFormatError
        The file is missing, not a regular file, a link leaving ``root``, unreadable, or larger
        than ``limit`` (checked before reading).
    """
    if outside := _outside(path, root):
        raise SessionFormatError(f"{path}: {outside}")
    try:
        fd = os.open(os.path.realpath(path), os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        dangling = path.is_symlink()
        raise SessionFormatError(
            f"{path}: " + ("is a dangling symbolic link" if dangling else "file not found")
        ) from None
    except OSError as exc:
        raise SessionFormatError(f"{path}: cannot be opened ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise SessionFormatError(
                f"{path}: is {_kind(info.st_mode)}, not a regular file; expected {expected}"
            )
        if info.st_size > limit:
            raise SessionFormatError(
                f"{path}: is {format_bytes(info.st_size)}, more than the limit of "
                f"{format_bytes(limit)} for {expected}"
            )
        try:  # one byte more than its size shows a file that grew; never a ``limit``-sized buffer
            data = f.read(info.st_size + 1)
        except OSError as exc:
            raise SessionFormatError(f"{path}: cannot be read ({exc.strerror})") from None
    if len(data) != info.st_size:
        raise SessionFormatError(
            f"{path}: changed size while being read ({format_bytes(info.st_size)} when opened); "
            "a file still being written cannot be read"
        )
    return data
