"""Atomic writes: build the output beside the target under a temporary name, then rename.

A crash or an exception while writing leaves the target untouched (absent, or the previous
version) and removes the temporary output, so readers see either the old target or the whole
new one.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

__all__ = [
    "atomic_directory",
    "atomic_file",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_text_atomic",
]


def _temporary(target: Path) -> Path:
    return target.parent / f".{target.name}.{secrets.token_hex(4)}.tmp"


def _refuse(target: Path, overwrite: bool) -> None:
    if target.exists() and not overwrite:
        raise FileExistsError(f"{target}: already exists; refusing to overwrite it")


@contextmanager
def atomic_file(target: str | os.PathLike[str], *, overwrite: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target`` atomically.

    Missing parent directories are created.

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
    tmp = _temporary(target)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_directory(
    target: str | os.PathLike[str], *, overwrite: bool = True, marker: str = "session.toml"
) -> Iterator[Path]:
    """Yield a new temporary directory beside ``target``; on success it becomes ``target``.

    An existing ``target`` is replaced only when ``overwrite`` is true and it holds ``marker``
    (so that a mistyped path never deletes an unrelated directory). The old directory is
    renamed away first and deleted only after the new one is in place.
    """
    target = Path(target)
    _refuse(target, overwrite)
    if target.exists() and not (target.is_dir() and (target / marker).is_file()):
        raise FileExistsError(f"{target}: exists and has no {marker}; refusing to replace it")
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(target)
    tmp.mkdir()
    try:
        yield tmp
        if target.exists():
            old = _temporary(target)
            os.replace(target, old)
            try:
                os.replace(tmp, target)
            except BaseException:
                os.replace(old, target)
                raise
            shutil.rmtree(old)
        else:
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_file`); return the path.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as root:
    ...     write_bytes_atomic(Path(root) / "a.bin", b"ok").read_bytes()
    b'ok'
    """
    with atomic_file(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """:func:`write_bytes_atomic` for UTF-8 text."""
    return write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: str | os.PathLike[str], document: Any) -> Path:
    """Write ``document`` as indented JSON (with a final newline) atomically; numpy scalars
    are written as numbers."""
    return write_text_atomic(path, json.dumps(document, indent=2, default=float) + "\n")
