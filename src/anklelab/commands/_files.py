"""The paths a command reads and writes, checked before any work is done.

Inputs must exist and be regular files or directories (a FIFO or a device would block or never
end). Outputs are planned before the work starts: a file where a directory is expected (or the
reverse), a path inside an input (or an input inside it, symbolic links and ``..`` resolved), a
read-only or full file system, or another process writing it, all end the command at once.
Then:

- :func:`output_file` holds the output's lock while the command runs; the command writes the
  file itself through the atomic writers (temporary file, then rename).
- :func:`output_directory` also builds the directory whole under a temporary name, writes the
  run manifest (``run.json``) last and renames it into place, so a directory always holds one
  complete run. An existing directory is replaced only with ``--force``, and only if it is an
  output of the same command (its ``run.json`` says so) or empty; never a session of the user.
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from anklelab._atomic import atomic_directory, reap_temporaries
from anklelab._lock import output_lock, reap_locks
from anklelab._runs import RUN_FILE, RunManifest, sha256_file, write_run_manifest
from anklelab.errors import AnklelabError, OutputError, ParameterError, ResultsFormatError

__all__ = [
    "Run",
    "array_bytes",
    "check_input",
    "check_output",
    "check_space",
    "output_directory",
    "output_file",
]

MIN_FREE_BYTES = 64 << 10
"""Below this many free bytes a file system counts as full before anything is written."""


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISDIR, "a directory"),
    ):
        if test(mode):
            return name
    return "a file"


def check_input(
    path: Path,
    *,
    what: str,
    kinds: Sequence[Literal["file", "directory"]] = ("file", "directory"),
    error: type[AnklelabError] = ParameterError,
) -> Path:
    """``path`` if it exists and is a regular file or a directory, as ``kinds`` allow.

    Parameters
    ----------
    path : Path
        The input named on the command line.
    what : str
        What it should be, for the message (``"session"``).
    kinds : sequence of {"file", "directory"}
        What it may be.
    error : type
        The exception raised, naming the path and what was expected.
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise error(f"{path}: no such file or directory; expected {what}") from None
    except OSError as exc:
        raise error(f"{path}: {exc.strerror}; expected {what}") from None
    if (stat.S_ISREG(mode) and "file" in kinds) or (stat.S_ISDIR(mode) and "directory" in kinds):
        return path
    raise error(f"{path}: {_kind(mode)}; expected {what}")


def _existing_ancestor(path: Path) -> Path:
    for parent in path.absolute().parents:
        if os.path.lexists(parent):
            return parent
    return Path("/")


def _check_overlap(path: Path, inputs: Sequence[Path], option: str) -> None:
    out = path.resolve()
    for given in inputs:
        source = Path(given).resolve()
        if out == source or source in out.parents:
            raise OutputError(f"{option} {path}: lies inside the input {given}; write elsewhere")
        if out in source.parents:
            raise OutputError(f"{option} {path}: holds the input {given}; write elsewhere")


def _check_writable(path: Path) -> None:
    """A read-only or full file system, or no permission, before any work."""
    ancestor = _existing_ancestor(path)
    if not ancestor.is_dir():
        raise OutputError(f"{path}: cannot be created: {ancestor} is not a directory")
    fs = os.statvfs(ancestor)
    if fs.f_flag & os.ST_RDONLY:
        raise OutputError(f"{path}: cannot be written: read-only file system")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise OutputError(f"{path}: cannot be written: permission denied in {ancestor}")
    if fs.f_bavail * fs.f_frsize < MIN_FREE_BYTES:
        free = fs.f_bavail * fs.f_frsize
        raise OutputError(f"{path}: cannot be written: no space left on device ({free} bytes free)")


def array_bytes(*trees: Any) -> int:
    """Bytes of every NumPy array in nested mappings, sequences and objects with ``columns``.

    A lower bound of what a session takes on disk, to check for space before writing it.
    """
    import numpy as np

    total, stack = 0, list(trees)
    while stack:
        node = stack.pop()
        if isinstance(node, np.ndarray):
            total += node.nbytes
        elif isinstance(node, Mapping):
            stack += node.values()
        elif isinstance(node, list | tuple):
            stack += node
        elif hasattr(node, "recording"):
            stack.append(node.recording)
        elif hasattr(node, "columns"):
            stack.append(node.columns)
    return total


def check_space(path: Path, needed: int) -> None:
    """Refuse before writing when the file system of ``path`` has less than ``needed`` bytes.

    Some writers (HDF5) cannot fail cleanly when the disk fills up under them.
    """
    fs = os.statvfs(_existing_ancestor(path))
    free = fs.f_bavail * fs.f_frsize
    if free < needed:
        raise OutputError(
            f"{path}: no space left on device: it needs about {needed / 1e6:.3g} MB, "
            f"{free / 1e6:.3g} MB are free; nothing was written"
        )


_WRITE_ERRORS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG)


@contextmanager
def _name_write_errors(path: Path) -> Iterator[None]:
    """A write error that names no file (a failed flush) is attributed to the output."""
    try:
        yield
    except OSError as exc:
        if exc.filename or exc.errno not in _WRITE_ERRORS or isinstance(exc, AnklelabError):
            raise
        reason = os.strerror(exc.errno or 0)
        raise OSError(exc.errno, reason, str(path)) from None


def check_output(
    path: Path, kind: Literal["file", "directory"], inputs: Sequence[Path], option: str = "--out"
) -> Path:
    """``path`` if it can be written as a ``kind``: not a symbolic link, not the other kind, not
    inside an input nor holding one, on a writable file system with space (for commands that
    write their output with their own atomic writer)."""
    if os.path.islink(path):
        raise OutputError(
            f"{option} {path}: a symbolic link (to {os.readlink(path)}); name the real path"
        )
    if os.path.lexists(path):
        is_dir = path.is_dir()
        if kind == "file" and is_dir:
            raise OutputError(f"{option} {path}: a directory; expected a file to write")
        if kind == "directory" and not is_dir:
            what = _kind(os.stat(path).st_mode)
            raise OutputError(f"{option} {path}: {what}, not a directory; expected a directory")
    _check_overlap(path, inputs, option)
    _check_writable(path)
    return path


@contextmanager
def _parents(path: Path) -> Iterator[None]:
    """Create the missing parents of ``path``; remove them again (if empty) on failure."""
    created = [p for p in reversed(path.absolute().parents) if not os.path.lexists(p)]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{path}: cannot be created: {exc.strerror}") from None
    try:
        yield
    except BaseException:
        for directory in reversed(created):
            with suppress(OSError):
                directory.rmdir()
        raise


def _refuse_existing(path: Path, force: bool, option: str) -> None:
    if os.path.lexists(path) and not force:
        raise OutputError(f"{option} {path}: already exists; pass --force to replace it")


@contextmanager
def output_file(
    path: Path, *, force: bool, inputs: Sequence[Path] = (), option: str = "--out"
) -> Iterator[Path]:
    """Check a file output before any work and hold its lock while the command runs.

    The command writes ``path`` itself, with the atomic writers. Raises :class:`OutputError`
    naming the option and the path when it cannot be written as asked.
    """
    check_output(path, "file", inputs, option)
    with _parents(path), output_lock(path), _name_write_errors(path):
        _refuse_existing(path, force, option)
        reap_temporaries(path.parent)
        reap_locks(path.parent)
        yield path


@dataclass
class Run:
    """One run of a command into an output directory, recorded in its ``run.json``.

    Attributes
    ----------
    directory : Path
        Where the command writes its files: a temporary directory, renamed into place when the
        command ends without error.
    settings : dict
        The settings to record (the command fills it in).
    inputs : list of (Path, str)
        Each input read and its SHA-256 (see :meth:`add_input`).
    """

    directory: Path
    settings: dict[str, Any] = field(default_factory=dict)
    inputs: list[tuple[Path, str]] = field(default_factory=list)

    def add_input(self, path: Path | None, sha256: str | None = None) -> None:
        """Record an input (a file's SHA-256 is computed unless given); ``None`` is skipped."""
        if path is not None:
            self.inputs.append((path, sha256 or sha256_file(path)))


def _refuse_other_kind(path: Path, command: str, writes_session: bool) -> None:
    """An existing, non-empty directory may be replaced only by a run of the same command."""
    if not path.is_dir() or next(path.iterdir(), None) is None:
        return
    if (path / "session.toml").exists() and not writes_session:
        raise OutputError(
            f"{path}: holds a session (session.toml); an analysis never replaces a session. "
            "Choose another --out"
        )
    try:
        manifest = RunManifest.load(path)
    except ResultsFormatError as exc:
        raise OutputError(f"{path}: not replaced: {exc}") from None
    if manifest is None:
        raise OutputError(
            f"{path}: not replaced: it has no {RUN_FILE}, so it is not an output of "
            f"`anklelab {command}` (perhaps your own files, or an older anklelab's output); "
            "remove it yourself or choose another --out"
        )
    if manifest.command != command:
        raise OutputError(
            f"{path}: not replaced: it is an output of `anklelab {manifest.command}`, "
            f"not of `anklelab {command}`; choose another --out"
        )


@contextmanager
def output_directory(
    path: Path,
    *,
    command: str,
    force: bool,
    inputs: Sequence[Path] = (),
    writes_session: bool = False,
    option: str = "--out",
) -> Iterator[Run]:
    """Check a directory output before any work; build it whole; record and publish the run.

    Parameters
    ----------
    path : Path
        The output directory.
    command : str
        The command writing it (``"analyze"``), recorded in ``run.json``.
    force : bool
        Replace an existing output of the same command.
    inputs : sequence of Path
        The inputs named on the command line: the output may be neither inside them nor hold
        them.
    writes_session : bool
        The output is a session directory (it may hold a ``session.toml``).
    option : str
        The option naming ``path``, for messages.

    Yields
    ------
    Run
        Write into ``run.directory``; fill in ``run.settings`` and ``run.add_input``.
    """
    check_output(path, "directory", inputs, option)
    with _parents(path), output_lock(path), _name_write_errors(path):
        if not (path.is_dir() and next(path.iterdir(), None) is None):
            _refuse_existing(path, force, option)
        _refuse_other_kind(path, command, writes_session)
        reap_locks(path.parent)
        with atomic_directory(path, overwrite=True, marker=RUN_FILE) as staging:
            run = Run(staging)
            yield run
            write_run_manifest(staging, command=command, settings=run.settings, inputs=run.inputs)
