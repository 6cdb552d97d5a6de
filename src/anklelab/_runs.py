"""The run manifest: ``run.json``, the record of one command's output directory.

Every output directory of a command (``analyze``, ``identify friction``, ``simulate``, ``demo``)
belongs to one run. The command builds it whole under a temporary name and writes ``run.json``
last, before renaming it into place::

    {"format": "anklelab-run/1", "run_id": "<32 hex>", "command": "analyze",
     "anklelab_version": "...", "settings": {...},
     "inputs": [{"path": "/abs/session.h5", "sha256": "..."}],
     "files": {"results.json": {"size": 1234, "sha256": "..."}, ...}}

``files`` lists every file the run wrote (POSIX paths relative to the directory). Readers of
an output (``anklelab report``) use only those files, as regular files inside the directory
whose size and SHA-256 match (:meth:`RunManifest.read`): nothing from another run, edited by
hand, or reached through a symbolic link.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
import uuid
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any

from anklelab._version import __version__
from anklelab.errors import ResultsFormatError

__all__ = [
    "RUN_FILE",
    "RUN_FORMAT",
    "NotEmbeddable",
    "RunManifest",
    "read_inside",
    "sha256_bytes",
    "sha256_file",
    "write_run_manifest",
]

RUN_FILE = "run.json"
RUN_FORMAT = "anklelab-run/1"
_MAX_MANIFEST_BYTES = 16 << 20
_SHA256 = re.compile(r"[0-9a-f]{64}")
_CHUNK = 1 << 20


class NotEmbeddable(Exception):  # a reason, not an error: callers decide
    """A file that a reader must not use; ``str()`` says why, naming the file."""


def sha256_bytes(data: bytes) -> str:
    """SHA-256 of ``data`` (hex)."""
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes (hex), read in chunks."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def _written_files(directory: Path) -> dict[str, dict[str, Any]]:
    files = {}
    for path in sorted(directory.rglob("*")):
        name = path.relative_to(directory).as_posix()
        if name == RUN_FILE or path.is_dir():
            continue
        if path.is_symlink() or not path.is_file():
            raise ResultsFormatError(f"{path}: a run output holds only regular files")
        files[name] = {"size": path.stat().st_size, "sha256": sha256_file(path)}
    return files


def read_inside(directory: str | os.PathLike[str], name: str, *, limit: int) -> bytes:
    """The bytes of ``DIRECTORY/NAME``, if it is a regular file inside ``DIRECTORY``.

    The file is opened without following a final symbolic link and without blocking on a FIFO,
    and must resolve to a path inside ``directory``.

    Raises
    ------
    NotEmbeddable
        The file is missing, a symbolic link, not a regular file, outside the directory, or
        larger than ``limit`` bytes.
    """
    directory = Path(directory)
    relative = PurePosixPath(name)
    path = directory / relative
    if relative.is_absolute() or ".." in relative.parts:
        raise NotEmbeddable(f"{path}: not a plain name inside {directory}")
    if not os.path.lexists(path):
        raise NotEmbeddable(f"{path}: not found")
    if Path(os.path.realpath(directory)) not in Path(os.path.realpath(path)).parents:
        raise NotEmbeddable(f"{path}: leads outside {directory}")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as exc:
        kind = "a symbolic link" if os.path.islink(path) else exc.strerror
        raise NotEmbeddable(f"{path}: {kind}; expected a regular file") from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode) or info.st_size > limit:
        os.close(fd)
        if not stat.S_ISREG(info.st_mode):
            raise NotEmbeddable(f"{path}: not a regular file")
        raise NotEmbeddable(f"{path}: {info.st_size} bytes; more than the {limit} expected")
    with os.fdopen(fd, "rb") as f:
        data = f.read(info.st_size + 1)  # a buffer of the file's size, not of ``limit``
    if len(data) != info.st_size:
        raise NotEmbeddable(f"{path}: changed size while being read")
    return data


@dataclass(frozen=True)
class RunManifest:
    """A parsed ``run.json`` (see the module docstring).

    Attributes
    ----------
    directory : Path
        The output directory it describes.
    run_id, command, anklelab_version : str
    settings : dict
    inputs : list of dict
        ``{"path": ..., "sha256": ...}`` of each input read.
    files : dict
        ``{relative POSIX path: {"size": bytes, "sha256": hex}}`` of each file written.
    """

    directory: Path
    run_id: str
    command: str
    anklelab_version: str
    settings: dict[str, Any] = field(default_factory=dict)
    inputs: list[dict[str, Any]] = field(default_factory=list)
    files: dict[str, dict[str, Any]] = field(default_factory=dict)

    @classmethod
    def load(cls, directory: str | os.PathLike[str]) -> RunManifest | None:
        """The manifest of ``directory``; ``None`` if it has no ``run.json``.

        Raises
        ------
        ResultsFormatError
            ``run.json`` is not a regular file, not valid JSON or not a run manifest.
        """
        directory = Path(directory)
        path = directory / RUN_FILE
        if not os.path.lexists(path):
            return None
        try:
            text = read_inside(directory, RUN_FILE, limit=_MAX_MANIFEST_BYTES)
            document = json.loads(text.decode("utf-8"))
        except NotEmbeddable as exc:
            raise ResultsFormatError(str(exc)) from None
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            raise ResultsFormatError(f"{path}: not a valid run manifest: {exc}") from None
        return cls._from_document(directory, path, document)

    @classmethod
    def _from_document(cls, directory: Path, path: Path, document: Any) -> RunManifest:
        def fail(what: str) -> ResultsFormatError:
            return ResultsFormatError(f"{path}: {what}; is this a run manifest of anklelab?")

        if not isinstance(document, dict) or document.get("format") != RUN_FORMAT:
            raise fail(f"expected an object with format {RUN_FORMAT!r}")
        for key in ("run_id", "command", "anklelab_version"):
            if not isinstance(document.get(key), str):
                raise fail(f"{key}: expected text")
        files = document.get("files")
        if not isinstance(files, dict):
            raise fail("files: expected an object")
        for name, entry in files.items():
            if not (
                isinstance(entry, dict)
                and isinstance(entry.get("size"), int)
                and isinstance(entry.get("sha256"), str)
                and _SHA256.fullmatch(entry["sha256"])
            ):
                raise fail(f"files.{name}: expected {{size, sha256}}")
        settings, inputs = document.get("settings", {}), document.get("inputs", [])
        if not isinstance(settings, dict) or not isinstance(inputs, list):
            raise fail("settings/inputs: expected an object and a list")
        return cls(
            directory,
            document["run_id"],
            document["command"],
            document["anklelab_version"],
            settings,
            inputs,
            files,
        )

    def read(self, name: str, *, limit: int) -> bytes:
        """The bytes of a file this run wrote, checked against the manifest.

        Raises
        ------
        NotEmbeddable
            ``name`` is not listed, is not a regular file inside the directory, or its size or
            SHA-256 differs from what the run wrote.
        """
        path = self.directory / name
        entry = self.files.get(name)
        if entry is None:
            raise NotEmbeddable(f"{path}: not written by the run (not listed in {RUN_FILE})")
        data = read_inside(self.directory, name, limit=limit)
        if len(data) != entry["size"] or sha256_bytes(data) != entry["sha256"]:
            raise NotEmbeddable(
                f"{path}: changed since the run wrote it (SHA-256 differs from {RUN_FILE})"
            )
        return data


def write_run_manifest(
    directory: str | os.PathLike[str],
    *,
    command: str,
    settings: Mapping[str, Any],
    inputs: Iterable[tuple[str | os.PathLike[str], str]],
) -> RunManifest:
    """Write ``DIRECTORY/run.json`` listing every file below ``directory``; return it.

    Call it last, on the run's temporary directory, before renaming that into place.

    Parameters
    ----------
    directory : path
        The run's output, complete.
    command : str
        The command, e.g. ``"analyze"``.
    settings : mapping
        The settings the run used (JSON-serialisable; other values are written as text).
    inputs : iterable of (path, sha256)
        Each input read and its SHA-256.
    """
    directory = Path(directory)
    manifest = RunManifest(
        directory,
        uuid.uuid4().hex,
        command,
        __version__,
        dict(settings),
        [{"path": os.path.abspath(path), "sha256": sha} for path, sha in inputs],
        _written_files(directory),
    )
    document = {"format": RUN_FORMAT} | {
        key: getattr(manifest, key)
        for key in ("run_id", "command", "anklelab_version", "settings", "inputs", "files")
    }
    text = json.dumps(document, indent=2, default=str) + "\n"
    (directory / RUN_FILE).write_text(text, encoding="utf-8")
    return manifest
