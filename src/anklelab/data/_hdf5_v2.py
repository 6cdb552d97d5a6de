"""Reading the store layout ``anklelab-h5/2`` (described in :mod:`anklelab.data.hdf5`, which
also writes it): every part's content hash is verified before the session is validated.

Recordings come back as views into their layout's data array (one row per column), so reading
costs one read per layout and no copy.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from anklelab.data._checks import (
    check_bench_tests,
    check_recordings,
    check_walking_row,
    check_walking_trials,
    excerpt,
    info_from_mapping,
    section_columns,
)
from anklelab.data._digest import sha256_tree, update, update_array_header
from anklelab.data._progress import Progress, ticker
from anklelab.data._tree import read_h5_tree
from anklelab.data.session import (
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
    label_text,
)
from anklelab.errors import SessionFormatError

__all__ = [
    "H5_FORMAT",
    "INDEX",
    "MANIFEST",
    "SECTIONS",
    "content_hash",
    "layout_digest",
    "read_v2",
]

H5_FORMAT = "anklelab-h5/2"
"""The layout written; :data:`H5_FORMATS` lists every layout read."""
SECTIONS = ("calibration", "walking", "bench")
INDEX = ("layout", "start", "length")
MANIFEST = {
    "calibration": ("file", *INDEX),
    "walking": ("file", "trial", "perturbed", "direction", "delay_ms", "extra", *INDEX),
    "bench": ("file", "test", "distance_m", "extra", *INDEX),
}


def content_hash(parts: dict[str, str | None]) -> str:
    """The root ``content_sha256``: the hash of the parts' hashes (``None`` for an absent part)."""
    return sha256_tree({"format": H5_FORMAT, "parts": parts})


def layout_digest(names: tuple[str, ...], values: np.ndarray) -> str:
    """SHA-256 (hex) of one layout: its column names and its data (see :mod:`._digest`)."""
    digest = hashlib.sha256()
    update(digest, names)
    update_array_header(digest, values.dtype, values.shape)
    digest.update(values.data)
    return digest.hexdigest()


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
    manifest: dict[str, tuple[str, ...] | np.ndarray] = {"file": files}
    for key in MANIFEST[name][1:]:
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
        digests.append(pool.submit(layout_digest, names, values))
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
    nullable: tuple[str, ...],
) -> list[Recording]:
    """Every recording of a section, checked, as views into its layout's data (``nullable``
    columns may hold NaN)."""
    files = manifest["file"]
    layout, start, length = (np.asarray(manifest[k]) for k in INDEX)
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
        check_recordings(located, names, data, expected, lengths, required, fs, nullable=nullable)
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


def _labels(values: Any, where: str, column: str) -> list[str]:
    if not isinstance(values, tuple):
        raise SessionFormatError(f"{where}/manifest/{column}: expected text labels")
    return [label_text(v, f"{where}/manifest/{column}, row {i + 1}") for i, v in enumerate(values)]


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
        extras = _extra(extra, row)
        checked = check_walking_row(row, bool(perturbed), direction, float(delay))
        trial = WalkingTrial(label, recording, bool(perturbed), checked, float(delay), extras)
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


def read_v2(f: h5py.File, path: Path, progress: Progress | None) -> Session:
    """Read an open ``anklelab-h5/2`` file (already checked by :func:`check_h5_file`): verify
    every part's SHA-256, then validate the session."""
    with ThreadPoolExecutor(max_workers=1) as pool:  # hashes while HDF5 reads
        session_tree = _tree(f, "session", path)
        stored, digests = {}, {}
        for name in SECTIONS:
            group = _group(f, name, f"{path}:")
            manifest, layouts, digests[name] = _stored_section(group, f"{path}:/{name}", pool)
            stored[name] = (manifest, layouts)
        truth = _tree(f, "truth", path) if "truth" in f else None
        provenance = _tree(f, "provenance", path)
        trees = {"session": session_tree, "truth": truth, "provenance": provenance}
        hashed = {k: pool.submit(sha256_tree, v) for k, v in trees.items() if v is not None}
        parts: dict[str, str | None] = {}
        for name in ("session", *SECTIONS, "truth", "provenance"):
            if name in digests:
                parts[name] = _verify(f, name, digests[name](), path)
            else:
                parts[name] = (
                    _verify(f, name, hashed[name].result(), path) if name in hashed else None
                )
    if f.attrs.get("content_sha256") != content_hash(parts):
        raise SessionFormatError(
            f"{path}: corrupted: attribute 'content_sha256' does not match the hashes of the "
            "session's parts; the file was damaged or changed after anklelab wrote it"
        )

    info = info_from_mapping(session_tree, str(path), "/session/")
    tick = ticker(progress, sum(len(m["file"]) for m, _ in stored.values()))
    sections: dict[str, list[Recording]] = {}
    for name in SECTIONS:
        manifest, layouts = stored[name]
        required, nullable = section_columns(info, name)
        sections[name] = _recordings(
            f"{path}:/{name}", manifest, layouts, required, info.sample_rate_hz, nullable
        )
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
