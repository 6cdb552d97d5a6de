"""Load and save sessions in any supported form; content hashes; session comparison.

``load_session`` accepts a CSV session directory, a native HDF5 file or a MATLAB file and
detects which; ``save_session`` writes the native HDF5 store or the directory format. Sessions
read from a directory or MATLAB file are *imports*: their provenance gains ``source_sha256``
(:func:`session_hash` of the input) and an ``import`` record (anklelab version, importer, source
name). Native HDF5 files are returned exactly as stored.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path
from typing import Any, Literal

from anklelab._version import __version__
from anklelab.data._checks import check_file_names, info_to_mapping
from anklelab.data._files import file_kind
from anklelab.data._progress import Progress
from anklelab.data._tree import canonical, tree_differences
from anklelab.data.directory import _read_directory, directory_hash, write_directory
from anklelab.data.hdf5 import h5_content_hash, is_hdf5, read_hdf5, write_hdf5
from anklelab.data.matlab import read_matlab
from anklelab.data.session import Recording, Session
from anklelab.errors import ParameterError, SessionFormatError

__all__ = [
    "diff_sessions",
    "input_name",
    "load_session",
    "load_session_hashed",
    "save_session",
    "session_hash",
    "session_kind",
]

SessionKind = Literal["dir", "h5", "mat"]
_CHUNK = 1 << 20


def input_name(path: str | Path) -> str:
    """The name results give an input: its file or directory name (``.`` and ``..`` named by
    the directory they stand for, links not followed)."""
    return Path(os.path.abspath(path)).name


def session_kind(path: str | Path) -> SessionKind:
    """Which reader ``path`` needs: ``"dir"``, ``"h5"`` or ``"mat"``.

    Raises
    ------
    SessionFormatError
        ``path`` does not exist or is none of these.
    """
    path = Path(path)
    if path.is_dir():
        return "dir"
    if not path.exists():
        raise SessionFormatError(f"{path}: no such file or directory")
    if not path.is_file():
        raise SessionFormatError(
            f"{path}: is {file_kind(path)}, not a regular file; expected a session directory, "
            "an anklelab .h5 file or a MATLAB .mat file"
        )
    if path.suffix.lower() == ".mat":
        return "mat"
    if is_hdf5(path):
        return "h5"
    raise SessionFormatError(
        f"{path}: expected a session directory, an anklelab .h5 file or a MATLAB .mat file"
    )


def _file_digest(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        while chunk := f.read(_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def session_hash(path: str | Path) -> str:
    """SHA-256 (hex) of everything a session read takes in, for provenance.

    - A session directory: every file :func:`load_session` reads, in reading order, each as its
      relative path and the SHA-256 of its bytes (:func:`~anklelab.data.directory.directory_hash`);
      files the reader ignores do not count.
    - A native ``anklelab-h5/2`` file: its ``content_sha256``, the SHA-256 over every value it
      stores (metadata, manifests, channel data, truth, provenance), which :func:`load_session`
      verifies on every read.
    - Any other file (MATLAB, ``anklelab-h5/1``, a C3D file): the SHA-256 of its bytes.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.NamedTemporaryFile(suffix=".mat") as f:
    ...     session_hash(f.name)[:12]
    'e3b0c44298fc'
    """
    path = Path(path)
    if path.is_dir():
        return directory_hash(path)
    if not path.is_file():
        session_kind(path)  # names what the path is instead
    if is_hdf5(path) and (content := h5_content_hash(path)) is not None:
        return content
    return _file_digest(path)


def load_session(path: str | Path, *, progress: Progress | None = None) -> Session:
    """Read and validate a session: a CSV directory, a native ``.h5`` or a MATLAB ``.mat``.

    Parameters
    ----------
    path : str or Path
        The session. The kind is detected (see :func:`session_kind`).
    progress : callable, optional
        Called as ``progress(done, total)`` after each recording is read.

    Returns
    -------
    Session
        Imports (directory, MATLAB) carry ``provenance["source_sha256"]`` and
        ``provenance["import"]``; ``provenance["anklelab_version"]`` is set if absent.

    Raises
    ------
    SessionFormatError
        Naming the file, the column and the row of the first problem found.
    """
    return load_session_hashed(path, progress=progress)[0]


def load_session_hashed(
    path: str | Path, *, progress: Progress | None = None
) -> tuple[Session, str]:
    """:func:`load_session` and the :func:`session_hash` of what it read, for the provenance
    of results: a directory's files are hashed as they are read, not read a second time (0.2 s
    on a paper-size session).

    Parameters
    ----------
    path : str or Path
        The session (a CSV directory, a native ``.h5`` or a MATLAB ``.mat``).
    progress : callable, optional
        Called as ``progress(done, total)`` after each recording is read.

    Returns
    -------
    session : Session
        As :func:`load_session` gives it.
    sha256 : str
        Hex SHA-256, as :func:`session_hash` gives it for ``path``.
    """
    kind = session_kind(path)
    if kind == "h5":
        session = read_hdf5(path, progress=progress)
        check_file_names(session, str(path))
        return session, session_hash(path)
    if kind == "dir":
        session, digest = _read_directory(path, progress)
    else:
        session, digest = read_matlab(path, progress=progress), _file_digest(Path(path))
        check_file_names(session, str(path))
    provenance = dict(session.provenance)
    provenance.setdefault("anklelab_version", __version__)
    provenance["source_sha256"] = digest
    provenance["import"] = {
        "anklelab_version": __version__,
        "importer": {"dir": "csv-directory", "mat": "matlab"}[kind],
        "source_name": Path(path).name,
    }
    return dataclasses.replace(session, provenance=provenance), digest


def save_session(
    session: Session,
    path: str | Path,
    *,
    format: Literal["h5", "dir"] = "h5",
    overwrite: bool = True,
    progress: Progress | None = None,
) -> Path:
    """Write a session atomically (temporary file or directory beside ``path``, then rename).

    Parameters
    ----------
    session : Session
        Validated first with the readers' checks.
    path : str or Path
        Target ``.h5`` file or session directory.
    format : {"h5", "dir"}
        Native HDF5 store (deterministic bytes) or the CSV session directory.
    overwrite : bool
        Replace an existing target. A directory is only ever replaced if it holds a
        ``session.toml``.
    progress : callable, optional
        Called as ``progress(done, total)`` after each recording is written.

    Returns
    -------
    Path
        ``path``.
    """
    if format == "h5":
        return write_hdf5(session, path, overwrite=overwrite, progress=progress)
    if format == "dir":
        return write_directory(session, path, overwrite=overwrite, progress=progress)
    raise ParameterError(f"format: expected 'h5' or 'dir', got {format!r}")


def _recording_tree(recording: Recording, **fields: Any) -> dict[str, Any]:
    return {"name": recording.name, **fields, "columns": dict(recording.columns)}


def _session_tree(session: Session) -> dict[str, Any]:
    def indexed(items: list[dict[str, Any]]) -> dict[str, Any]:
        return {f"{i:06d}": item for i, item in enumerate(items)}

    return {
        "info": info_to_mapping(session.info),
        "calibration": indexed([_recording_tree(r) for r in session.calibration]),
        "walking": indexed(
            [
                _recording_tree(
                    t.recording,
                    trial=t.trial,
                    perturbed=bool(t.perturbed),
                    direction=t.direction,
                    delay_ms=float(t.delay_ms),
                    extra=dict(t.extra),
                )
                for t in session.walking
            ]
        ),
        "bench": indexed(
            [
                _recording_tree(
                    b.recording, test=b.test, distance_m=float(b.distance_m), extra=dict(b.extra)
                )
                for b in session.bench
            ]
        ),
        "truth": {} if session.truth is None else session.truth,
        "has_truth": session.truth is not None,
        "provenance": session.provenance,
    }


def diff_sessions(a: Session, b: Session, *, provenance: bool = True) -> list[str]:
    """Every difference between two sessions, as readable lines (empty when equal).

    Arrays must be exactly equal (NaN equal to NaN); recordings are compared in order.
    ``provenance=False`` ignores the provenance trees.
    """
    ta, tb = canonical(_session_tree(a)), canonical(_session_tree(b))
    if not provenance:
        ta.pop("provenance")
        tb.pop("provenance")
    return tree_differences(ta, tb)
