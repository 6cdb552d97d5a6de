"""The native HDF5 session store (format ``anklelab-h5/2``): reader and atomic writer.

The file is laid out for reading a whole session at once::

    /                           attributes format = "anklelab-h5/2", content_sha256 and
                                sha256_<part> for each part below
    /session                    the session.toml document (keys as attributes, tables as
                                groups)
    /calibration, /walking, /bench
        manifest/               one 1-D dataset per column, one row per recording, in order:
                                  file      recording name (UTF-8 text)
                                  trial     walking: trial label (text); perturbed (int8 0/1),
                                            direction (text), delay_ms (float64, NaN if none)
                                  test      bench: test label (text); distance_m (float64)
                                  extra     walking, bench: further manifest columns, one JSON
                                            object of text values per row
                                  layout    which layout_<k> holds the recording's samples
                                  start, length   its samples: data[:, start:start + length]
        layout_<k>/             the recordings that share one list of column names:
                                  columns   the column names (text)
                                  data      float64, (columns, samples of all its recordings)
                                            end to end, chunked along samples, fletcher32
    /truth                      optional ground-truth tree (groups, datasets, attributes)
    /provenance                 provenance tree

Integrity: every dataset with data carries HDF5's fletcher32 checksum, and the root attribute
``sha256_<part>`` is the SHA-256 of that part's content (:mod:`anklelab.data._digest`: values, not
file bytes); the root's ``content_sha256`` hashes the parts' hashes. The reader verifies all of
them and reports a mismatch as corruption, naming the file and the part. ``content_sha256``
therefore pins everything a session holds; :func:`h5_content_hash` returns it.

Trial and test labels are text (an integer label in older files reads as its decimal text);
the plate type travels in ``/session`` with the rest of ``session.toml``. No timestamps are
stored and trees are written in sorted order, so saving the same session twice gives
byte-identical files. The file is built in memory, then written to a temporary file beside the
target and renamed into place when complete (HDF5 itself cannot fail cleanly on a full disk: it
reports the error when the file is closed and may crash the interpreter; a plain write raises
``OSError``). Files of the first layout (``anklelab-h5/1``, :mod:`anklelab.data._hdf5_v1`) are
still read.
"""

from __future__ import annotations

import hashlib
import io
import json
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from anklelab._atomic import atomic_file
from anklelab.data._checks import excerpt, info_to_mapping, validate_session
from anklelab.data._digest import sha256_tree, update, update_array_header
from anklelab.data._h5safe import H5_ERRORS, check_h5_file, damaged, open_h5
from anklelab.data._hdf5_v1 import read_v1
from anklelab.data._hdf5_v2 import (
    H5_FORMAT,
    INDEX,
    MANIFEST,
    SECTIONS,
    content_hash,
    read_v2,
)
from anklelab.data._progress import Progress
from anklelab.data._tree import create_group, write_h5_tree
from anklelab.data.session import Recording, Session
from anklelab.errors import SessionFormatError

__all__ = [
    "H5_FORMAT",
    "H5_FORMATS",
    "h5_content_hash",
    "is_hdf5",
    "read_hdf5",
    "write_hdf5",
]

H5_FORMATS = ("anklelab-h5/1", H5_FORMAT)
_CHUNK_SAMPLES = 1 << 16  # 512 KiB of float64 per chunk


def is_hdf5(path: str | Path) -> bool:
    """Whether ``path`` is an HDF5 file (by its signature, wherever the user block ends)."""
    return Path(path).is_file() and h5py.is_hdf5(str(path))


# --- writing ------------------------------------------------------------------------------------


def _write_column(group: h5py.Group, name: str, values: Sequence[str] | np.ndarray) -> None:
    """One manifest or name column: text as fixed-length UTF-8, numbers as they are."""
    if isinstance(values, np.ndarray):
        data = values
    else:
        encoded = [v.encode("utf-8") for v in values]
        data = np.array(encoded, dtype=h5py.string_dtype("utf-8", max([1, *map(len, encoded)])))
    checked = {"chunks": data.shape, "fletcher32": True} if data.size else {}
    group.create_dataset(name, data=data, track_times=False, **checked)


def _write_layout(group: h5py.Group, columns: tuple[str, ...], recordings: list[Recording]) -> str:
    """The recordings' columns end to end as one 2-D dataset; returns its SHA-256 (hex)."""
    total = sum(r.n_samples for r in recordings)
    _write_column(group, "columns", columns)
    dataset = group.create_dataset(
        "data",
        shape=(len(columns), total),
        dtype="<f8",
        chunks=(1, min(total, _CHUNK_SAMPLES)),
        fletcher32=True,
        track_times=False,
    )
    digest = hashlib.sha256()
    update(digest, columns)
    update_array_header(digest, dataset.dtype, dataset.shape)
    # hashlib lets go of the interpreter while it hashes: one row is hashed while the next is
    # gathered and written (the one worker keeps the rows in order)
    with ThreadPoolExecutor(1) as hashing:
        for j, name in enumerate(columns):
            row = np.concatenate([np.asarray(r.columns[name], dtype="<f8") for r in recordings])
            dataset[j] = row
            hashing.submit(digest.update, row.data)
    return digest.hexdigest()


def _write_section(
    f: h5py.File, name: str, recordings: list[Recording], manifest: dict[str, Any]
) -> str:
    """One section (layouts, then the manifest); returns its SHA-256 (hex)."""
    group = create_group(f, name)
    layouts: dict[tuple[str, ...], list[int]] = {}
    for i, recording in enumerate(recordings):
        layouts.setdefault(tuple(recording.columns), []).append(i)
    index = {key: np.zeros(len(recordings), dtype=np.int64) for key in INDEX}
    digests = []
    for k, (columns, members) in enumerate(layouts.items()):
        lengths = np.array([recordings[i].n_samples for i in members], dtype=np.int64)
        index["layout"][members] = k
        index["start"][members] = np.cumsum(lengths) - lengths
        index["length"][members] = lengths
        layout = group.create_group(f"layout_{k}")
        digests.append(_write_layout(layout, columns, [recordings[i] for i in members]))
    manifest = {"file": tuple(r.name for r in recordings)} | manifest | index
    columns = group.create_group("manifest", track_order=True)
    for key in MANIFEST[name]:
        _write_column(columns, key, manifest[key])
    return sha256_tree({"manifest": manifest, "layouts": tuple(digests)})


def _write_tree(f: h5py.File, name: str, tree: Any) -> str:
    return sha256_tree(write_h5_tree(create_group(f, name), tree))


def _extra_json(extra: Any) -> str:
    return json.dumps(dict(extra), sort_keys=True, ensure_ascii=False)


def write_hdf5(
    session: Session,
    path: str | Path,
    *,
    overwrite: bool = True,
    progress: Progress | None = None,
) -> Path:
    """Write ``session`` to a native HDF5 file, atomically and deterministically.

    Parameters
    ----------
    session : Session
        Validated first with the readers' checks.
    path : str or Path
        Target file (``.h5``).
    overwrite : bool
        Replace an existing file; otherwise raise ``FileExistsError``.
    progress : callable, optional
        Called as ``progress(done, total)`` after each section is written, counting recordings.

    Returns
    -------
    Path
        ``path``.
    """
    validate_session(session)
    n = {"calibration": len(session.calibration), "walking": len(session.walking)}
    total = n["calibration"] + n["walking"] + len(session.bench)
    target = Path(path)
    walking, bench = session.walking, session.bench
    manifests = {
        "calibration": {},
        "walking": {
            "trial": tuple(str(t.trial) for t in walking),
            "perturbed": np.array([t.perturbed for t in walking], dtype=np.int8),
            "direction": tuple(t.direction for t in walking),
            "delay_ms": np.array([t.delay_ms for t in walking], dtype=np.float64),
            "extra": tuple(_extra_json(t.extra) for t in walking),
        },
        "bench": {
            "test": tuple(str(b.test) for b in bench),
            "distance_m": np.array([b.distance_m for b in bench], dtype=np.float64),
            "extra": tuple(_extra_json(b.extra) for b in bench),
        },
    }
    recordings = {
        "calibration": list(session.calibration),
        "walking": [t.recording for t in walking],
        "bench": [b.recording for b in bench],
    }
    image = io.BytesIO()  # HDF5 cannot fail cleanly on a full disk: it writes to memory
    with h5py.File(image, "w", track_order=True) as f:
        f.attrs["format"] = H5_FORMAT
        parts: dict[str, str | None] = {
            "session": _write_tree(f, "session", info_to_mapping(session.info))
        }
        done = 0
        for name in SECTIONS:
            parts[name] = _write_section(f, name, recordings[name], manifests[name])
            done += len(recordings[name])
            if progress is not None:
                progress(done, total)
        parts["truth"] = None if session.truth is None else _write_tree(f, "truth", session.truth)
        parts["provenance"] = _write_tree(f, "provenance", session.provenance)
        for name, digest in parts.items():
            if digest is not None:
                f.attrs[f"sha256_{name}"] = digest
        f.attrs["content_sha256"] = content_hash(parts)
    with atomic_file(target, overwrite=overwrite) as tmp:
        tmp.write_bytes(image.getbuffer())
    return target


# --- reading ------------------------------------------------------------------------------------


def _format(f: h5py.File, path: Path) -> str:
    fmt = f.attrs.get("format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode("utf-8", "replace")
    if fmt not in H5_FORMATS:
        known = isinstance(fmt, str) and fmt.startswith("anklelab-h5/")
        raise SessionFormatError(
            f"{path}: attribute 'format' = {excerpt(fmt)}; expected {H5_FORMAT!r} (or the older "
            f"{H5_FORMATS[0]!r})"
            + (
                " (written by a different anklelab version)"
                if known
                else " (not an anklelab session file)"
            )
        )
    return fmt


def read_hdf5(path: str | Path, *, progress: Progress | None = None) -> Session:
    """Read, verify and validate a native HDF5 session file (``anklelab-h5/2`` or ``/1``).

    ``progress``, if given, is called as ``progress(done, total)`` after each recording.

    Raises
    ------
    SessionFormatError
        Not an anklelab HDF5 file, an unsupported format version, a link or an oversized
        dataset (see :func:`~anklelab.data._h5safe.check_h5_file`), corruption (a checksum or
        content hash that does not match, naming the part), or any problem the directory
        reader would reject (naming the HDF5 path, column and 1-based sample).
    """
    path = Path(path)
    try:
        with open_h5(path, "an anklelab HDF5 session") as f:
            fmt = _format(f, path)
            check_h5_file(f, path)
            reader: Callable[[h5py.File, Path, Progress | None], Session] = (
                read_v2 if fmt == H5_FORMAT else read_v1
            )
            return reader(f, path, progress)
    except SessionFormatError:
        raise
    except H5_ERRORS as exc:  # HDF5 reports damage as any of these
        raise damaged(path, exc) from None


def h5_content_hash(path: str | Path) -> str | None:
    """The ``content_sha256`` an ``anklelab-h5/2`` file stores (verified whenever the session is
    read), or ``None`` for any other HDF5 file (the older layout, or not a session)."""
    path = Path(path)
    try:
        with open_h5(path, "an anklelab HDF5 session") as f:
            if f.attrs.get("format") != H5_FORMAT:
                return None
            value = f.attrs.get("content_sha256")
    except H5_ERRORS as exc:
        raise damaged(path, exc) from None
    if not (isinstance(value, str) and len(value) == 64):
        raise SessionFormatError(f"{path}: attribute 'content_sha256' is missing or malformed")
    return value
