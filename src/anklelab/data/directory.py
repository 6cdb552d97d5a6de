"""The CSV session directory (DESIGN.md section 4): reader and atomic writer.

::

    session_dir/
      session.toml          format, platform, sample_rate_hz, subject, [force_plate], [geometry]
      calibration/*.csv     time_s, motor_angle, plate channels    (read in natural name order)
      walking/trials.csv    trial, file, perturbed (0/1), direction (dorsi|plantar|none), delay_ms
      walking/<file>.csv    time_s, motor_angle, ankle_angle, plate channels
      bench/tests.csv       test, file, distance_m
      bench/<file>.csv      time_s, displacement_m, force_n
      truth.json            optional: the twin's ground truth (arrays as lists)
      truth/**/<key>.npy    its arrays of 4096 values or more, by key path (see below)
      provenance.json       optional: how the session was made (large arrays in provenance/)

The plate channels are those of the session's plate type (``[force_plate] type``: ``fx12 ...
fz4`` for ``kistler8``, see :mod:`anklelab.forceplate`); trial and test labels are text. Each
folder is optional; a folder that exists must be complete. Unknown columns are kept
(recordings: as float columns; manifests: as strings in ``extra``), unknown files are ignored.
Error messages name the file, the column and the CSV **line** (line 1 is the header).

Only regular files inside the directory are read (a symbolic link may point elsewhere inside it,
never outside), each up to a size limit checked before reading (:mod:`anklelab.data._files`).
Numbers are parsed by pyarrow's CSV reader, files in parallel threads; only when it refuses a
file is the file scanned row by row to say which cell is wrong (:mod:`anklelab.data._csv`).
Messages show at most a short escaped excerpt of a file's content. The writer prints every float
with its shortest exact representation, so reading a written directory gives bit-identical
arrays.

A tree's large arrays (the twin's time courses: 3.5 million values in a paper-size session) are
NumPy ``.npy`` files in a folder named after the tree, one per array, at the path of its keys
(each key percent-encoded): ``truth/time_courses/ankle_angle_rad.npy`` is
``truth["time_courses"]["ankle_angle_rad"]``. As JSON lists they took 1.6 s of the 3.5 s that
reading such a session took. Every ``.npy`` file in the folder is read (pickled objects never);
a linked folder inside it is followed, and a file it leads to outside the session is refused.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
import re
import tomllib
import urllib.parse
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from anklelab._atomic import atomic_directory
from anklelab.data import _toml
from anklelab.data._checks import (
    check_distance,
    check_file_name,
    check_recording,
    check_unique,
    check_walking_row,
    excerpt,
    info_from_mapping,
    info_to_mapping,
    recordings_pass,
    validate_session,
)
from anklelab.data._csv import NUMBER, decode, header, parse_numeric
from anklelab.data._files import (
    MAX_CSV_BYTES,
    MAX_JSON_BYTES,
    MAX_MANIFEST_BYTES,
    MAX_TOML_BYTES,
    file_problem,
    read_bytes,
)
from anklelab.data._progress import Progress, ticker
from anklelab.data._tree import from_json, insert_array, split_arrays, to_json
from anklelab.data.session import (
    BENCH_COLUMNS,
    BENCH_MANIFEST_COLUMNS,
    WALKING_MANIFEST_COLUMNS,
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
    label_text,
)
from anklelab.errors import SessionFormatError

__all__ = [
    "SessionReader",
    "directory_hash",
    "files_hash",
    "read_csv_recording",
    "read_directory",
    "read_session_toml",
    "write_csv_recording",
    "write_directory",
]


_NPY_MIN_VALUES = 4096
"""Arrays of a truth or provenance tree with this many values or more are ``.npy`` files."""
_WORKERS = min(4, os.cpu_count() or 1)
"""Threads parsing recording files at once (pyarrow parses without holding the GIL)."""

# --- reading ------------------------------------------------------------------------------------


class SessionReader:
    """Reads the files of one session directory, only from inside it, and remembers the SHA-256
    of each file read (see :func:`~anklelab.data._files.read_bytes` for what is refused).

    Parameters
    ----------
    root : Path
        The session directory; messages name files below it as the user gave it.
    """

    def __init__(self, root: Path) -> None:
        self.root = root
        self.digests: dict[Path, bytes] = {}

    def bytes(self, path: Path, limit: int, expected: str = "a CSV file") -> bytes:
        """The bytes of ``path`` (inside the session, at most ``limit`` bytes)."""
        data = read_bytes(path, self.root, limit, expected)
        self.digests[path] = hashlib.sha256(data).digest()
        return data

    def text(self, path: Path, limit: int, expected: str = "a CSV file") -> str:
        """The text of ``path`` (UTF-8, optional byte-order mark)."""
        return decode(path, self.bytes(path, limit, expected), expected)

    def data_file(self, folder: Path, name: str, where: str) -> Path:
        """The recording file a manifest row names: a plain name of a regular file in
        ``folder``."""
        if not name or name in (".", "..") or "/" in name or "\\" in name:
            raise SessionFormatError(
                f"{where}, column 'file': got {excerpt(name)}; expected a file name inside {folder}"
            )
        path = folder / name
        problem = file_problem(path, self.root)
        if problem:
            raise SessionFormatError(f"{where}, column 'file': {path} {problem}")
        return path

    def sha256(self, files: Iterable[Path]) -> str:
        """SHA-256 (hex) over ``files`` in order: each one's path relative to the session and
        the SHA-256 of its bytes (read now unless already read)."""
        digest = hashlib.sha256()
        for path in files:
            if path not in self.digests:
                self.bytes(path, max(MAX_CSV_BYTES, MAX_JSON_BYTES), "a session file")
            digest.update(path.relative_to(self.root).as_posix().encode() + b"\0")
            digest.update(self.digests[path])
        return digest.hexdigest()


def _recording(
    path: Path, data: bytes, required: tuple[str, ...], fs: float, nullable: tuple[str, ...]
) -> Recording:
    names = header(path, data, required)
    values, line = parse_numeric(path, data, names, nullable)
    columns = dict(zip(names, values, strict=True))
    start, length = np.array([0]), np.array([values.shape[1]])  # one recording, whole
    if not recordings_pass(names, values, start, length, required, fs, nullable=nullable):
        check_recording(str(path), columns, required, fs, line, nullable=nullable)
    return Recording(path.name, columns)


def read_csv_recording(
    path: Path,
    required: tuple[str, ...],
    fs: float,
    *,
    nullable: tuple[str, ...] = (),
    reader: SessionReader | None = None,
) -> Recording:
    """Read and check one recording file.

    Parameters
    ----------
    path : Path
        The CSV file (header line, then one row per sample).
    required : tuple of str
        Columns that must be present (others are kept).
    fs : float
        Sample rate from ``session.toml``, Hz; the ``time_s`` column must agree with it.
    nullable : tuple of str
        Required columns whose cells may be empty (read as NaN).
    reader : SessionReader, optional
        The session's reader (the file must lie inside its directory); by default the file's
        own folder.
    """
    reader = reader or SessionReader(path.parent)
    return _recording(path, reader.bytes(path, MAX_CSV_BYTES), required, fs, nullable)


def _read_manifest(
    reader: SessionReader, path: Path, required: tuple[str, ...]
) -> list[tuple[str, dict[str, str]]]:
    """Rows of a manifest as (``"line N"``, {column: stripped text})."""
    data = reader.bytes(path, MAX_MANIFEST_BYTES, "a manifest (CSV file)")
    names = header(path, data, required)
    rows = []
    table = csv.reader(io.StringIO(decode(path, data)))
    try:
        next(table)
        for fields in table:
            if not any(field.strip() for field in fields):
                continue
            if len(fields) != len(names):
                raise SessionFormatError(
                    f"{path}: line {table.line_num} has {len(fields)} fields; expected "
                    f"{len(names)} like the header (line 1)"
                )
            row = {n: f.strip() for n, f in zip(names, fields, strict=True)}
            rows.append((f"line {table.line_num}", row))
    except csv.Error as exc:
        raise SessionFormatError(f"{path}: line {max(table.line_num, 1)}: {exc}") from None
    if not rows:
        raise SessionFormatError(f"{path}: no rows after the header; expected one row per file")
    return rows


def _label(text: str, where: str, column: str) -> str:
    if not text:
        raise SessionFormatError(
            f"{where}, column {column!r}: empty cell; expected a label (any non-empty text)"
        )
    return label_text(text, f"{where}, column {column!r}")


def _float(text: str, where: str, column: str, *, empty_ok: bool = False) -> float:
    if empty_ok and text.lower() in ("", "nan"):
        return math.nan
    if not NUMBER.fullmatch(text):
        raise SessionFormatError(
            f"{where}, column {column!r}: got {excerpt(text)}; expected a number"
            + (" or an empty cell" if empty_ok else "")
        )
    return float(text)


def _flag(text: str, where: str, column: str) -> bool:
    flags = {"0": False, "1": True, "false": False, "true": True}
    if text.lower() not in flags:
        raise SessionFormatError(
            f"{where}, column {column!r}: got {excerpt(text)}; expected 0 or 1"
        )
    return flags[text.lower()]


# Each manifest row, checked, with the data file to read and how to build the trial from it.
Row = tuple[Path, Callable[..., Any]]


def _manifest_rows(
    reader: SessionReader, folder: Path, name: str, columns: tuple[str, ...]
) -> Iterator[tuple[str, str, dict[str, str], Path, dict[str, str]]]:
    """(line, location, fields, data file, extra fields) of each manifest row."""
    manifest = folder / name
    if file_problem(manifest, reader.root) == "does not exist":
        raise SessionFormatError(f"{manifest}: missing; a {folder.name}/ folder needs its manifest")
    rows = _read_manifest(reader, manifest, columns)
    check_unique(((row["file"], line) for line, row in rows), "file", str(manifest))
    for line, row in rows:
        where = f"{manifest}: {line}"
        extra = {k: v for k, v in row.items() if k not in columns}
        yield line, where, row, reader.data_file(folder, row["file"], where), extra


def _walking_rows(reader: SessionReader, folder: Path) -> list[Row]:
    rows: list[Row] = []
    ids: list[tuple[str, str]] = []
    for line, where, row, path, extra in _manifest_rows(
        reader, folder, "trials.csv", WALKING_MANIFEST_COLUMNS
    ):
        trial = _label(row["trial"], where, "trial")
        perturbed = _flag(row["perturbed"], where, "perturbed")
        delay = _float(row["delay_ms"], where, "delay_ms", empty_ok=True)
        direction = check_walking_row(where, perturbed, row["direction"].lower(), delay)
        ids.append((trial, line))
        make = partial(
            WalkingTrial,
            trial=trial,
            perturbed=perturbed,
            direction=direction,
            delay_ms=delay,
            extra=extra,
        )
        rows.append((path, make))
    check_unique(ids, "trial", str(folder / "trials.csv"))
    return rows


def _bench_rows(reader: SessionReader, folder: Path) -> list[Row]:
    rows: list[Row] = []
    ids: list[tuple[str, str]] = []
    for line, where, row, path, extra in _manifest_rows(
        reader, folder, "tests.csv", BENCH_MANIFEST_COLUMNS
    ):
        test = _label(row["test"], where, "test")
        distance = _float(row["distance_m"], where, "distance_m")
        check_distance(where, distance)
        ids.append((test, line))
        rows.append((path, partial(BenchTest, test=test, distance_m=distance, extra=extra)))
    check_unique(ids, "test", str(folder / "tests.csv"))
    return rows


def _natural(path: Path) -> list[Any]:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def _json_tree(reader: SessionReader, path: Path, arrays: Iterable[Path] = ()) -> dict[str, Any]:
    """The tree of a JSON file, with the ``arrays`` (``.npy`` files in the folder named after
    it) put at the key paths of their names."""
    text = reader.text(path, MAX_JSON_BYTES, "a JSON file")
    try:
        tree = from_json(text)
    except json.JSONDecodeError as exc:
        raise SessionFormatError(
            f"{path}: line {exc.lineno}, column {exc.colno}: {exc.msg}; expected JSON"
        ) from None
    except RecursionError:
        raise SessionFormatError(f"{path}: nested too deeply; expected a JSON tree") from None
    except ValueError as exc:
        raise SessionFormatError(f"{path}: {excerpt(str(exc), 200, quote=False)}") from None
    folder = path.with_suffix("")
    for file in arrays:
        data = reader.bytes(file, MAX_JSON_BYTES, "a NumPy .npy file")
        keys = [urllib.parse.unquote(part) for part in file.relative_to(folder).parts]
        keys[-1] = keys[-1].removesuffix(".npy")
        try:
            insert_array(tree, keys, _npy_array(data))
        except ValueError as exc:  # not an array of numbers; a key given twice
            raise SessionFormatError(
                f"{file}: {excerpt(str(exc), 200, quote=False)}; expected a NumPy .npy array of "
                f"numbers for a key that {path.name} does not hold"
            ) from None
    return tree


def _npy_array(data: bytes) -> np.ndarray:
    """The array of ``.npy`` bytes, its header checked against the data's size before any
    memory is set aside for it."""
    from numpy.lib import format as npy

    stream = io.BytesIO(data)
    try:
        version = npy.read_magic(stream)
        read_header = {(1, 0): npy.read_array_header_1_0, (2, 0): npy.read_array_header_2_0}
        if version not in read_header:
            raise ValueError(f"format version {version[0]}.{version[1]}; expected 1.0 or 2.0")
        shape, _, dtype = read_header[version](stream)
    except (ValueError, EOFError) as exc:
        raise ValueError(f"not a NumPy .npy file ({exc})") from None
    if dtype.kind not in "biuf" or dtype.hasobject:
        raise ValueError(f"holds {dtype} values")
    size, held = math.prod(shape) * dtype.itemsize, len(data) - stream.tell()
    if size != held:
        raise ValueError(f"its header gives {size} bytes of data, the file holds {held}")
    return np.load(io.BytesIO(data), allow_pickle=False)


def _write_tree(root: Path, name: str, tree: Mapping[str, Any]) -> None:
    """``root/name.json``, and each of the tree's large arrays as ``root/name/<keys>.npy``."""
    small, arrays = split_arrays(tree, _NPY_MIN_VALUES)
    (root / f"{name}.json").write_text(to_json(small), encoding="utf-8")
    for keys, array in arrays.items():
        parts = [_file_part(key) for key in keys]
        file = root.joinpath(name, *parts[:-1], parts[-1] + ".npy")
        file.parent.mkdir(parents=True, exist_ok=True)
        np.save(file, array, allow_pickle=False)


def _file_part(key: str) -> str:
    """A tree key as one file or folder name: percent-encoded, never ``.`` or ``..``."""
    part = urllib.parse.quote(key, safe="")
    return "%2E" + part[1:] if part.startswith(".") else part


def read_session_toml(reader: SessionReader, path: Path) -> dict[str, Any]:
    """The parsed ``session.toml`` (size-limited, deep nesting refused)."""
    text = reader.text(path, MAX_TOML_BYTES, "a TOML file")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SessionFormatError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:
        raise SessionFormatError(f"{path}: tables or arrays nested too deeply") from None


@dataclass(frozen=True)
class _Plan:
    """What a session directory holds, in reading order (manifests already read)."""

    toml: Path
    calibration: list[Path]
    walking: list[Row]
    bench: list[Row]
    trees: dict[str, Path]
    arrays: dict[str, list[Path]]  # each tree's .npy files

    def files(self, root: Path) -> list[Path]:
        """Every file read, in order."""
        walking = [root / "walking" / "trials.csv"] if self.walking else []
        bench = [root / "bench" / "tests.csv"] if self.bench else []
        return [
            self.toml,
            *self.calibration,
            *walking,
            *(p for p, _ in self.walking),
            *bench,
            *(p for p, _ in self.bench),
            *(p for name, json_file in self.trees.items() for p in (json_file, *self.arrays[name])),
        ]


def _reader(path: str | Path) -> SessionReader:
    root = Path(path)
    if not root.is_dir():
        raise SessionFormatError(f"{root}: not a directory; expected a session directory")
    return SessionReader(root)


def _plan(reader: SessionReader) -> _Plan:
    root = reader.root
    toml = root / "session.toml"
    calibration = sorted((root / "calibration").glob("*.csv"), key=_natural)
    for path in calibration:
        if problem := file_problem(path, root):
            raise SessionFormatError(f"{path}: {problem}")
    walking = _walking_rows(reader, root / "walking") if (root / "walking").is_dir() else []
    bench = _bench_rows(reader, root / "bench") if (root / "bench").is_dir() else []
    trees = {
        name: root / f"{name}.json"
        for name in ("truth", "provenance")
        if os.path.lexists(root / f"{name}.json")
    }
    arrays = {name: _array_files(root, root / name) for name in trees}
    return _Plan(toml, calibration, walking, bench, trees, arrays)


def _array_files(root: Path, folder: Path) -> list[Path]:
    """The ``.npy`` files below ``folder`` in order of their paths (none if there is no folder);
    each must be a regular file inside the session. A linked folder is followed as the walking
    folder is: its files are then refused if they lie outside the session; a folder reached
    twice (a link loop) is refused."""
    if not folder.is_dir():
        return []
    files, seen = [], set()
    for top, _, names in os.walk(folder, followlinks=True):
        real = os.path.realpath(top)
        if real in seen:
            raise SessionFormatError(f"{top}: a link leads back to a folder already read")
        seen.add(real)
        files += [Path(top, name) for name in names if name.endswith(".npy")]
    files.sort()
    for path in files:
        if problem := file_problem(path, root):
            raise SessionFormatError(f"{path}: {problem}")
    return files


def directory_hash(path: str | Path) -> str:
    """SHA-256 (hex) of every file :func:`read_directory` reads, in its order: ``session.toml``,
    the calibration files, the walking manifest and its files, the bench manifest and its files,
    ``truth.json`` and ``provenance.json``, each followed by its ``.npy`` arrays; each as its
    path relative to the session and the SHA-256 of its bytes. Files the reader ignores do not
    count."""
    reader = _reader(path)
    plan = _plan(reader)
    return reader.sha256(plan.files(reader.root))


def files_hash(root: str | Path, files: Iterable[Path]) -> str:
    """SHA-256 (hex) over ``files``, regular files inside the directory ``root``, in the order
    given: each as its path relative to ``root`` and the SHA-256 of its bytes (as
    :func:`directory_hash` pins a session directory), for importers that read other layouts."""
    return SessionReader(Path(root)).sha256(files)


def _not_c3d_trials(root: Path) -> None:
    """Refuse, saying what to run, a directory of C3D trials without a ``session.toml``."""
    if (root / "session.toml").exists():
        return
    with os.scandir(root) as entries:
        trials = sum(e.name.lower().endswith(".c3d") for e in entries)
    if trials:
        raise SessionFormatError(
            f"{root}: no session.toml, but {trials} C3D file(s): a directory of C3D trials is "
            "read with 'anklelab import c3d DIR --map MAP.toml' (see the guide 'Lab data "
            "formats'), then analysed"
        )


def _read_directory(path: str | Path, progress: Progress | None) -> tuple[Session, str]:
    """The session and the SHA-256 of every file read (:func:`directory_hash`)."""
    reader = _reader(path)
    _not_c3d_trials(reader.root)
    info = info_from_mapping(
        read_session_toml(reader, reader.root / "session.toml"), str(reader.root / "session.toml")
    )
    plan = _plan(reader)
    fs = info.sample_rate_hz
    nullable = info.force_plate.nullable
    jobs = [
        *((p, info.calibration_columns, nullable) for p in plan.calibration),
        *((p, info.walking_columns, nullable) for p, _ in plan.walking),
        *((p, BENCH_COLUMNS, ()) for p, _ in plan.bench),
    ]
    tick = ticker(progress, len(jobs))

    def read(job: tuple[Path, tuple[str, ...], tuple[str, ...]]) -> Recording:
        path, required, nulls = job
        return read_csv_recording(path, required, fs, nullable=nulls, reader=reader)

    with ThreadPoolExecutor(max_workers=_WORKERS) as pool:  # pyarrow parses without the GIL
        try:
            trees = {
                name: pool.submit(_json_tree, reader, p, plan.arrays[name])
                for name, p in plan.trees.items()
            }
            recordings = []
            for recording in pool.map(read, jobs):
                recordings.append(recording)
                tick()
            truth = trees["truth"].result() if "truth" in trees else None
            provenance = trees["provenance"].result() if "provenance" in trees else {}
        except BaseException:  # the first problem is reported without reading the rest
            pool.shutdown(wait=False, cancel_futures=True)
            raise
    n_cal, n_walk = len(plan.calibration), len(plan.walking)
    session = Session(
        info=info,
        calibration=tuple(recordings[:n_cal]),
        walking=tuple(
            make(recording=r)
            for (_, make), r in zip(plan.walking, recordings[n_cal : n_cal + n_walk], strict=True)
        ),
        bench=tuple(
            make(recording=r)
            for (_, make), r in zip(plan.bench, recordings[n_cal + n_walk :], strict=True)
        ),
        truth=truth,
        provenance=provenance,
        source=str(reader.root),
    )
    return session, reader.sha256(plan.files(reader.root))


def read_directory(path: str | Path, *, progress: Progress | None = None) -> Session:
    """Read and validate a CSV session directory.

    Recording files are parsed in parallel threads; only regular files inside the directory
    are read (links may point inside it, never outside), each up to a size limit.

    Parameters
    ----------
    path : str or Path
        The session directory (holding ``session.toml``).
    progress : callable, optional
        Called as ``progress(done, total)`` after each recording is read.

    Returns
    -------
    Session
        With ``truth`` and ``provenance`` from ``truth.json`` / ``provenance.json`` when present.

    Raises
    ------
    SessionFormatError
        Naming the file, column and CSV line of the first problem found.
    """
    return _read_directory(path, progress)[0]


# --- writing ------------------------------------------------------------------------------------


def _csv_line(fields: Iterable[str]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(fields)
    return buffer.getvalue()


def write_csv_recording(path: Path, recording: Recording) -> None:
    """Write one recording: a header line, then each sample's values (shortest exact repr)."""
    names = list(recording.columns)
    data = np.column_stack([np.asarray(recording.columns[n], dtype=np.float64) for n in names])
    row = ",".join(["%r"] * len(names)) + "\n"
    body = (row * data.shape[0]) % tuple(data.ravel().tolist())
    path.write_text(_csv_line(names) + body, encoding="utf-8", newline="\n")


def _manifest(rows: list[dict[str, str]], columns: tuple[str, ...]) -> str:
    extra = list(dict.fromkeys(k for row in rows for k in row if k not in columns))
    header = [*columns, *extra]
    return _csv_line(header) + "".join(_csv_line(row.get(k, "") for k in header) for row in rows)


def _number_text(value: float) -> str:
    return "" if math.isnan(value) else repr(float(value))


def write_directory(
    session: Session,
    path: str | Path,
    *,
    overwrite: bool = True,
    progress: Progress | None = None,
) -> Path:
    """Write ``session`` as a CSV session directory, atomically.

    The session is validated first (the same checks as reading). The directory is built
    beside ``path`` under a temporary name and renamed into place; an existing ``path`` is
    replaced only if ``overwrite`` and it is a session directory (holds ``session.toml``).
    ``progress``, if given, is called as ``progress(done, total)`` after each recording.

    Returns
    -------
    Path
        ``path``.
    """
    validate_session(session)  # plain, unique file names among the rest
    for i, recording in enumerate(session.calibration):  # the folder is read as *.csv
        check_file_name(recording.name, f"session: calibration[{i}]", ".csv")
    target = Path(path)
    tick = ticker(progress, len(session.calibration) + len(session.walking) + len(session.bench))

    def write(path: Path, recording: Recording) -> None:
        write_csv_recording(path, recording)
        tick()

    def write_section(
        folder: Path,
        manifest: str,
        columns: tuple[str, ...],
        entries: list[tuple[Recording, Mapping[str, str], dict[str, str]]],
    ) -> None:
        """Each entry's recording, then the manifest of (extra columns | fields | file)."""
        if not entries:
            return
        folder.mkdir()
        rows = []
        for recording, extra, fields in entries:
            write(folder / recording.name, recording)
            rows.append(dict(extra) | fields | {"file": recording.name})
        text = _manifest(rows, columns)
        (folder / manifest).write_text(text, encoding="utf-8", newline="\n")

    with atomic_directory(target, overwrite=overwrite) as tmp:
        try:
            text = _toml.dumps(info_to_mapping(session.info))
        except ValueError as exc:
            raise SessionFormatError(f"session.info.extra: {exc}") from None
        (tmp / "session.toml").write_text(text, encoding="utf-8", newline="\n")
        if session.calibration:
            (tmp / "calibration").mkdir()
            for recording in session.calibration:
                write(tmp / "calibration" / recording.name, recording)
        write_section(
            tmp / "walking",
            "trials.csv",
            WALKING_MANIFEST_COLUMNS,
            [
                (
                    t.recording,
                    t.extra,
                    {
                        "trial": str(t.trial),
                        "perturbed": "1" if t.perturbed else "0",
                        "direction": t.direction,
                        "delay_ms": _number_text(t.delay_ms),
                    },
                )
                for t in session.walking
            ],
        )
        write_section(
            tmp / "bench",
            "tests.csv",
            BENCH_MANIFEST_COLUMNS,
            [
                (
                    b.recording,
                    b.extra,
                    {"test": str(b.test), "distance_m": _number_text(b.distance_m)},
                )
                for b in session.bench
            ],
        )
        if session.truth is not None:
            _write_tree(tmp, "truth", session.truth)
        if session.provenance:
            _write_tree(tmp, "provenance", session.provenance)
    return target
