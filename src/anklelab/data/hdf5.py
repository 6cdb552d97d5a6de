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

Labels are stored as text: an integer label is written in decimal and read back as an integer
(:func:`label_from_text`). No timestamps are stored and trees are written in sorted order, so
saving the same session twice gives byte-identical files. Writing goes to a temporary file
beside the target, renamed into place when complete. Files of the first layout
(``anklelab-h5/1``, :mod:`anklelab.data._hdf5_v1`) are still read.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from anklelab._atomic import atomic_file
from anklelab.data._checks import (
    check_bench_tests,
    check_recordings,
    check_walking_row,
    check_walking_trials,
    excerpt,
    info_from_mapping,
    info_to_mapping,
    validate_session,
)
from anklelab.data._digest import sha256_tree, update, update_array_header
from anklelab.data._h5safe import H5_ERRORS, check_h5_file, damaged, open_h5
from anklelab.data._hdf5_v1 import read_v1
from anklelab.data._progress import Progress, ticker
from anklelab.data._tree import canonical, create_group, read_h5_tree, write_h5_tree
from anklelab.data.session import (
    BENCH_COLUMNS,
    CALIBRATION_COLUMNS,
    WALKING_COLUMNS,
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
)
from anklelab.errors import SessionFormatError

__all__ = [
    "H5_FORMAT",
    "H5_FORMATS",
    "h5_content_hash",
    "is_hdf5",
    "label_from_text",
    "read_hdf5",
    "write_hdf5",
]

H5_FORMAT = "anklelab-h5/2"
"""The layout written; :data:`H5_FORMATS` lists every layout read."""
H5_FORMATS = ("anklelab-h5/1", H5_FORMAT)
_SECTIONS = ("calibration", "walking", "bench")
_CHUNK_SAMPLES = 1 << 16  # 512 KiB of float64 per chunk
_INDEX = ("layout", "start", "length")
_MANIFEST = {
    "calibration": ("file", *_INDEX),
    "walking": ("file", "trial", "perturbed", "direction", "delay_ms", "extra", *_INDEX),
    "bench": ("file", "test", "distance_m", "extra", *_INDEX),
}
_REQUIRED = {
    "calibration": CALIBRATION_COLUMNS,
    "walking": WALKING_COLUMNS,
    "bench": BENCH_COLUMNS,
}


def is_hdf5(path: str | Path) -> bool:
    """Whether ``path`` is an HDF5 file (by its signature, wherever the user block ends)."""
    return Path(path).is_file() and h5py.is_hdf5(str(path))


def label_from_text(text: str) -> int | str:
    """A stored label as the session holds it: an integer if ``text`` is one in canonical
    decimal form, else the text.

    >>> label_from_text("12"), label_from_text("012"), label_from_text("d060_1")
    (12, '012', 'd060_1')
    """
    try:
        number = int(text)
    except ValueError:
        return text
    return number if str(number) == text else text


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
    for j, name in enumerate(columns):
        row = np.concatenate([np.asarray(r.columns[name], dtype="<f8") for r in recordings])
        dataset[j] = row
        digest.update(row)
    return digest.hexdigest()


def _write_section(
    f: h5py.File, name: str, recordings: list[Recording], manifest: dict[str, Any]
) -> str:
    """One section (layouts, then the manifest); returns its SHA-256 (hex)."""
    group = create_group(f, name)
    layouts: dict[tuple[str, ...], list[int]] = {}
    for i, recording in enumerate(recordings):
        layouts.setdefault(tuple(recording.columns), []).append(i)
    index = {key: np.zeros(len(recordings), dtype=np.int64) for key in _INDEX}
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
    for key in _MANIFEST[name]:
        _write_column(columns, key, manifest[key])
    return sha256_tree({"manifest": manifest, "layouts": tuple(digests)})


def _write_tree(f: h5py.File, name: str, tree: Any) -> str:
    write_h5_tree(create_group(f, name), tree)
    return sha256_tree(canonical(tree))


def _extra_json(extra: Any) -> str:
    return json.dumps(dict(extra), sort_keys=True, ensure_ascii=False)


def _content_hash(parts: dict[str, str | None]) -> str:
    return sha256_tree({"format": H5_FORMAT, "parts": parts})


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
    with (
        atomic_file(target, overwrite=overwrite) as tmp,
        h5py.File(tmp, "w", track_order=True) as f,
    ):
        f.attrs["format"] = H5_FORMAT
        parts: dict[str, str | None] = {
            "session": _write_tree(f, "session", info_to_mapping(session.info))
        }
        done = 0
        for name in _SECTIONS:
            parts[name] = _write_section(f, name, recordings[name], manifests[name])
            done += len(recordings[name])
            if progress is not None:
                progress(done, total)
        parts["truth"] = None if session.truth is None else _write_tree(f, "truth", session.truth)
        parts["provenance"] = _write_tree(f, "provenance", session.provenance)
        for name, digest in parts.items():
            if digest is not None:
                f.attrs[f"sha256_{name}"] = digest
        f.attrs["content_sha256"] = _content_hash(parts)
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


def _group(f: h5py.File | h5py.Group, name: str, where: str) -> h5py.Group:
    item = f.get(name)
    if not isinstance(item, h5py.Group):
        raise SessionFormatError(
            f"{where}/{name}: expected a group, found {'nothing' if item is None else 'a dataset'}"
        )
    return item


def _tree(f: h5py.File, name: str, path: Path) -> dict[str, Any]:
    try:
        return read_h5_tree(_group(f, name, f"{path}:"))
    except (ValueError, TypeError) as exc:
        raise SessionFormatError(f"{path}:/{name}: {exc}") from None
    except RecursionError:
        raise SessionFormatError(f"{path}:/{name}: groups nested too deeply") from None


def _read(dataset: h5py.Dataset, where: str) -> np.ndarray:
    try:
        return dataset[()]
    except OSError as exc:
        raise SessionFormatError(
            f"{where}: cannot be read, the stored data is corrupted (HDF5: {excerpt(str(exc), 80)})"
        ) from None


def _column(group: h5py.Group, key: str, n: int | None, where: str) -> tuple[str, ...] | np.ndarray:
    """A manifest or name column: a tuple of text, or a numeric array."""
    item = group.get(key)
    where = f"{where}/{key}"
    if not isinstance(item, h5py.Dataset) or item.ndim != 1 or (n is not None and len(item) != n):
        expected = "a 1-D dataset" + ("" if n is None else f" of {n} rows like 'file'")
        raise SessionFormatError(f"{where}: expected {expected}, found {excerpt(item)}")
    if h5py.check_string_dtype(item.dtype) is not None:
        try:
            return tuple(item.asstr()[()])
        except (OSError, UnicodeDecodeError) as exc:
            raise SessionFormatError(f"{where}: cannot be read as UTF-8 text ({exc})") from None
    values = _read(item, where)
    if values.dtype.kind not in "biuf":
        raise SessionFormatError(f"{where}: expected numbers or text, found {values.dtype}")
    return values


def _layout_digest(names: tuple[str, ...], values: np.ndarray) -> str:
    digest = hashlib.sha256()
    update(digest, names)
    update_array_header(digest, values.dtype, values.shape)
    digest.update(values)
    return digest.hexdigest()


Layouts = list[tuple[tuple[str, ...], np.ndarray]]


def _stored_section(
    group: h5py.Group, where: str, pool: ThreadPoolExecutor
) -> tuple[dict[str, Any], Layouts, Callable[[], str]]:
    """A section as stored: (manifest columns, [(column names, data)], its SHA-256 when
    called). Each layout's data is hashed in ``pool`` while the next one is read."""
    name = group.name.lstrip("/")
    columns = _group(group, "manifest", where)
    files = _column(columns, "file", None, f"{where}/manifest")
    if not isinstance(files, tuple):
        raise SessionFormatError(f"{where}/manifest/file: expected text (recording names)")
    manifest = {"file": files}
    for key in _MANIFEST[name][1:]:
        manifest[key] = _column(columns, key, len(files), f"{where}/manifest")
    layouts = []
    digests = []
    k = 0
    while f"layout_{k}" in group:
        layout_where = f"{where}/layout_{k}"
        layout = _group(group, f"layout_{k}", where)
        names = _column(layout, "columns", None, layout_where)
        data = layout.get("data")
        if (
            not isinstance(names, tuple)
            or not isinstance(data, h5py.Dataset)
            or data.ndim != 2
            or data.shape[0] != len(names)
            or data.dtype.kind != "f"
        ):
            raise SessionFormatError(
                f"{layout_where}: expected 'columns' (text) and 'data', a 2-D float dataset "
                f"with one row per column"
            )
        values = np.empty(data.shape, dtype=np.float64)
        try:
            data.read_direct(values)
        except OSError as exc:
            raise SessionFormatError(
                f"{layout_where}/data: cannot be read, the stored data is corrupted "
                f"(HDF5: {excerpt(str(exc), 80)})"
            ) from None
        digests.append(pool.submit(_layout_digest, names, values))
        layouts.append((names, values))
        k += 1

    def computed() -> str:
        return sha256_tree({"manifest": manifest, "layouts": tuple(d.result() for d in digests)})

    return manifest, layouts, computed


def _verify(f: h5py.File, part: str, computed: str, path: Path) -> str:
    stored = f.attrs.get(f"sha256_{part}")
    where = f"{path}:/{part}"
    if stored != computed:
        raise SessionFormatError(
            f"{where}: corrupted: its content does not match the SHA-256 stored when it was "
            f"written (stored {str(stored)[:16]}…, computed {computed[:16]}…); the file was "
            "damaged or changed after anklelab wrote it"
        )
    return computed


def _recordings(
    where: str,
    manifest: dict[str, Any],
    layouts: Layouts,
    required: tuple[str, ...],
    fs: float,
) -> list[Recording]:
    """Every recording of a section, checked, as views into its layout's data."""
    files = manifest["file"]
    layout, start, length = (np.asarray(manifest[k]) for k in _INDEX)
    if any(a.dtype.kind not in "iu" for a in (layout, start, length)):
        raise SessionFormatError(f"{where}/manifest: layout, start and length must be integers")
    out: list[Recording | None] = [None] * len(files)
    for k, (names, data) in enumerate(layouts):
        members = np.flatnonzero(layout == k)
        lengths = length[members]
        expected = np.cumsum(lengths) - lengths
        if (
            (lengths < 0).any()
            or (start[members] != expected).any()
            or lengths.sum() != data.shape[1]
        ):
            raise SessionFormatError(
                f"{where}/manifest: 'start' and 'length' of the recordings in layout_{k} do not "
                f"cover its {data.shape[1]} samples end to end; the index is damaged"
            )

        located = [f"{where}/{files[i]}" for i in members]
        check_recordings(located, names, data, expected, lengths, required, fs)
        for i, (s, n) in zip(members, zip(expected, lengths, strict=True), strict=True):
            out[i] = Recording(files[i], {c: data[j, s : s + n] for j, c in enumerate(names)})
    missing = [files[i] for i, r in enumerate(out) if r is None]
    if missing:
        raise SessionFormatError(
            f"{where}/{excerpt(missing[0], 60, quote=False)}: manifest 'layout' names no stored "
            "layout; the index is damaged"
        )
    return out  # type: ignore[return-value]


def _extra(text: str, where: str) -> dict[str, str]:
    try:
        extra = json.loads(text)
    except (json.JSONDecodeError, TypeError):
        extra = None
    if not isinstance(extra, dict) or not all(isinstance(v, str) for v in extra.values()):
        raise SessionFormatError(
            f"{where}: manifest 'extra' = {excerpt(text)}; expected a JSON object of text values"
        )
    return extra


def _labels(values: Any, where: str, column: str) -> list[int | str]:
    if not isinstance(values, tuple):
        raise SessionFormatError(f"{where}/manifest/{column}: expected text labels")
    return [label_from_text(v) for v in values]


def _walking(
    where: str, manifest: dict[str, Any], recordings: list[Recording]
) -> tuple[WalkingTrial, ...]:
    """The walking trials of a section's manifest rows, checked."""
    walking = []
    for i, (recording, label, perturbed, direction, delay, extra) in enumerate(
        zip(
            recordings,
            _labels(manifest["trial"], where, "trial"),
            np.asarray(manifest["perturbed"]),
            manifest["direction"],
            np.asarray(manifest["delay_ms"], dtype=np.float64),
            manifest["extra"],
            strict=True,
        )
    ):
        row = f"{where}/{recording.name}"
        if perturbed not in (0, 1) or not isinstance(direction, str):
            raise SessionFormatError(
                f"{row}: manifest 'perturbed' must be 0 or 1 and 'direction' text"
            )
        trial = WalkingTrial(
            label, recording, bool(perturbed), direction, float(delay), _extra(extra, row)
        )  # type: ignore[arg-type]
        check_walking_row(row, trial.perturbed, trial.direction, trial.delay_ms)
        walking.append((trial, f"row {i + 1}"))
    check_walking_trials(f"{where}/manifest", walking)
    return tuple(t for t, _ in walking)


def _bench(
    where: str, manifest: dict[str, Any], recordings: list[Recording]
) -> tuple[BenchTest, ...]:
    """The bench tests of a section's manifest rows, checked."""
    bench = [
        (
            BenchTest(
                label, recording, float(distance), _extra(extra, f"{where}/{recording.name}")
            ),  # type: ignore[arg-type]
            f"row {i + 1}",
        )
        for i, (recording, label, distance, extra) in enumerate(
            zip(
                recordings,
                _labels(manifest["test"], where, "test"),
                np.asarray(manifest["distance_m"], dtype=np.float64),
                manifest["extra"],
                strict=True,
            )
        )
    ]
    check_bench_tests(f"{where}/manifest", bench)
    return tuple(b for b, _ in bench)


def _read_v2(f: h5py.File, path: Path, progress: Progress | None) -> Session:
    with ThreadPoolExecutor(max_workers=1) as pool:  # hashes while HDF5 reads
        session_tree = _tree(f, "session", path)
        stored, digests = {}, {}
        for name in _SECTIONS:
            group = _group(f, name, f"{path}:")
            manifest, layouts, digests[name] = _stored_section(group, f"{path}:/{name}", pool)
            stored[name] = (manifest, layouts)
        truth = _tree(f, "truth", path) if "truth" in f else None
        provenance = _tree(f, "provenance", path)
        trees = {"session": session_tree, "truth": truth, "provenance": provenance}
        hashed = {k: pool.submit(sha256_tree, v) for k, v in trees.items() if v is not None}
        parts: dict[str, str | None] = {}
        for name in ("session", *_SECTIONS, "truth", "provenance"):
            if name in digests:
                parts[name] = _verify(f, name, digests[name](), path)
            else:
                parts[name] = (
                    _verify(f, name, hashed[name].result(), path) if name in hashed else None
                )
    if f.attrs.get("content_sha256") != _content_hash(parts):
        raise SessionFormatError(
            f"{path}: corrupted: attribute 'content_sha256' does not match the hashes of the "
            "session's parts; the file was damaged or changed after anklelab wrote it"
        )

    info = info_from_mapping(session_tree, str(path), "/session/")
    fs = info.sample_rate_hz
    tick = ticker(progress, sum(len(m["file"]) for m, _ in stored.values()))
    sections: dict[str, list[Recording]] = {}
    for name in _SECTIONS:
        manifest, layouts = stored[name]
        sections[name] = _recordings(f"{path}:/{name}", manifest, layouts, _REQUIRED[name], fs)
        for _ in sections[name]:
            tick()

    walking = _walking(f"{path}:/walking", stored["walking"][0], sections["walking"])
    bench = _bench(f"{path}:/bench", stored["bench"][0], sections["bench"])
    return Session(
        info=info,
        calibration=tuple(sections["calibration"]),
        walking=walking,
        bench=bench,
        truth=truth,
        provenance=provenance,
        source=str(path),
    )


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
                _read_v2 if fmt == H5_FORMAT else read_v1
            )
            return reader(f, path, progress)
    except SessionFormatError:
        raise
    except H5_ERRORS as exc:  # HDF5 reports damage as any of these
        raise damaged(path, exc) from None


def h5_content_hash(path: str | Path) -> str | None:
    """The ``content_sha256`` an ``anklelab-h5/2`` file stores (verified whenever the session is
    read), or ``None`` for files of the older layout."""
    path = Path(path)
    try:
        with open_h5(path, "an anklelab HDF5 session") as f:
            if _format(f, path) != H5_FORMAT:
                return None
            value = f.attrs.get("content_sha256")
    except H5_ERRORS as exc:
        raise damaged(path, exc) from None
    if not (isinstance(value, str) and len(value) == 64):
        raise SessionFormatError(f"{path}: attribute 'content_sha256' is missing or malformed")
    return value
