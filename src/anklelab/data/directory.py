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
      provenance.json       optional: how the session was made

The plate channels are those of the session's plate type (``[force_plate] type``: ``fx12 ...
fz4`` for ``kistler8``, see :mod:`anklelab.forceplate`); trial and test labels are text. Each
folder is optional; a folder that exists must be complete. Unknown columns are kept
(recordings: as float columns; manifests: as strings in ``extra``), unknown files are ignored.
Error messages name the file, the column and the CSV **line** (line 1 is the header).

Numbers are parsed by :func:`numpy.loadtxt` (C parser, one call per file); only when that fails
is the file scanned row by row to say which cell is wrong. The writer prints every float with
its shortest exact representation, so reading a written directory gives bit-identical arrays.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import tomllib
from collections.abc import Callable, Iterable, Iterator, Mapping
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from anklelab._atomic import atomic_directory
from anklelab.data import _toml
from anklelab.data._checks import (
    check_columns,
    check_distance,
    check_recording,
    check_unique,
    check_walking_row,
    info_from_mapping,
    info_to_mapping,
    validate_session,
)
from anklelab.data._progress import Progress, ticker
from anklelab.data._tree import from_json, to_json
from anklelab.data.session import (
    BENCH_COLUMNS,
    BENCH_MANIFEST_COLUMNS,
    WALKING_MANIFEST_COLUMNS,
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
)
from anklelab.errors import SessionFormatError

__all__ = [
    "read_csv_recording",
    "read_directory",
    "write_csv_recording",
    "write_directory",
]


# --- reading ------------------------------------------------------------------------------------


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise SessionFormatError(f"{path}: file not found") from None
    except UnicodeDecodeError as exc:
        raise SessionFormatError(
            f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); expected a CSV file"
        ) from None


def _header(path: Path, text: str, required: tuple[str, ...]) -> list[str]:
    first = text.split("\n", 1)[0]
    if not first.strip():
        raise SessionFormatError(
            f"{path}: empty file or blank line 1; expected a header line naming the columns "
            f"{', '.join(required)}"
        )
    names = [name.strip() for name in next(csv.reader([first]))]
    if len(names) == 1 and any(sep in first for sep in ";\t"):
        raise SessionFormatError(
            f"{path}: header (line 1) {first.strip()!r} is not comma-separated; expected the "
            f"columns {', '.join(required)} separated by commas"
        )
    if "" in names:
        raise SessionFormatError(
            f"{path}: column {names.index('') + 1} of the header (line 1) has no name; expected "
            "a name for every column"
        )
    check_columns(str(path), names, required, "header (line 1)")
    return names


def _data_line(text: str, index: int) -> str:
    """CSV line number of data row ``index`` (0-based; blank lines are skipped by the parser)."""
    lines = [k + 1 for k, line in enumerate(text.split("\n")) if k > 0 and line.strip()]
    return f"line {lines[index]}"


def _empty_as_nan(cell: str) -> float:
    return float(cell) if cell.strip() else math.nan


def _bad_cell(
    path: Path, text: str, names: list[str], nullable: tuple[str, ...] = ()
) -> SessionFormatError | None:
    """Locate the first malformed row or cell (slow path, only after the fast parser failed)."""
    reader = csv.reader(io.StringIO(text))
    next(reader)
    for fields in reader:
        line = reader.line_num
        if not any(field.strip() for field in fields):
            continue
        if len(fields) != len(names):
            return SessionFormatError(
                f"{path}: line {line} has {len(fields)} fields; expected {len(names)} like the "
                "header (line 1)"
            )
        for name, field in zip(names, fields, strict=True):
            if name in nullable and not field.strip():
                continue
            try:
                float(field)
            except ValueError:
                got = "an empty cell" if not field.strip() else repr(field)
                return SessionFormatError(
                    f"{path}: column {name!r}, line {line}: {got}; expected a number"
                )
    return None


def read_csv_recording(
    path: Path, required: tuple[str, ...], fs: float, *, nullable: tuple[str, ...] = ()
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
    """
    text = _read_text(path)
    names = _header(path, text, required)
    body = text.split("\n", 1)[1] if "\n" in text else ""
    if not body.strip():
        raise SessionFormatError(f"{path}: no data rows after the header; expected samples")
    try:
        data = np.loadtxt(
            io.StringIO(body),
            delimiter=",",
            dtype=np.float64,
            ndmin=2,
            comments=None,
            quotechar='"',
            converters=_empty_as_nan if nullable else None,
        )
    except ValueError as exc:
        raise _bad_cell(path, text, names, nullable) or SessionFormatError(
            f"{path}: {exc}"
        ) from None
    if data.shape[1] != len(names):
        raise _bad_cell(path, text, names, nullable) or SessionFormatError(
            f"{path}: {data.shape[1]} fields per row; expected {len(names)} like the header"
        )
    columns = dict(zip(names, np.ascontiguousarray(data.T), strict=True))
    row = partial(_data_line, text)
    check_recording(str(path), columns, required, fs, row, nullable=nullable)
    return Recording(path.name, columns)


def _read_manifest(path: Path, required: tuple[str, ...]) -> list[tuple[str, dict[str, str]]]:
    """Rows of a manifest as (``"line N"``, {column: stripped text})."""
    text = _read_text(path)
    names = _header(path, text, required)
    reader = csv.reader(io.StringIO(text))
    next(reader)
    rows = []
    for fields in reader:
        if not any(field.strip() for field in fields):
            continue
        if len(fields) != len(names):
            raise SessionFormatError(
                f"{path}: line {reader.line_num} has {len(fields)} fields; expected "
                f"{len(names)} like the header (line 1)"
            )
        rows.append(
            (f"line {reader.line_num}", {n: f.strip() for n, f in zip(names, fields, strict=True)})
        )
    if not rows:
        raise SessionFormatError(f"{path}: no rows after the header; expected one row per file")
    return rows


def _label(text: str, where: str, column: str) -> str:
    if not text:
        raise SessionFormatError(
            f"{where}, column {column!r}: empty cell; expected a label (any non-empty text)"
        )
    return text


def _float(text: str, where: str, column: str, *, empty_ok: bool = False) -> float:
    if empty_ok and text.lower() in ("", "nan"):
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise SessionFormatError(
            f"{where}, column {column!r}: got {text!r}; expected a number"
            + (" or an empty cell" if empty_ok else "")
        ) from None


def _flag(text: str, where: str, column: str) -> bool:
    flags = {"0": False, "1": True, "false": False, "true": True}
    if text.lower() not in flags:
        raise SessionFormatError(f"{where}, column {column!r}: got {text!r}; expected 0 or 1")
    return flags[text.lower()]


def _data_file(folder: Path, name: str, where: str) -> Path:
    if not name or name in (".", "..") or "/" in name or "\\" in name:
        raise SessionFormatError(
            f"{where}, column 'file': got {name!r}; expected a file name inside {folder}"
        )
    path = folder / name
    if not path.is_file():
        raise SessionFormatError(f"{where}, column 'file': {path} does not exist")
    return path


# Each manifest row, checked, with the data file to read and how to build the trial from it.
Row = tuple[Path, Callable[..., Any]]


def _manifest_rows(
    folder: Path, name: str, columns: tuple[str, ...]
) -> Iterator[tuple[str, str, dict[str, str], Path, dict[str, str]]]:
    """(line, location, fields, data file, extra fields) of each manifest row."""
    manifest = folder / name
    if not manifest.is_file():
        raise SessionFormatError(f"{manifest}: missing; a {folder.name}/ folder needs its manifest")
    rows = _read_manifest(manifest, columns)
    check_unique(((row["file"], line) for line, row in rows), "file", str(manifest))
    for line, row in rows:
        where = f"{manifest}: {line}"
        extra = {k: v for k, v in row.items() if k not in columns}
        yield line, where, row, _data_file(folder, row["file"], where), extra


def _walking_rows(folder: Path) -> list[Row]:
    rows: list[Row] = []
    ids: list[tuple[str, str]] = []
    for line, where, row, path, extra in _manifest_rows(
        folder, "trials.csv", WALKING_MANIFEST_COLUMNS
    ):
        trial = _label(row["trial"], where, "trial")
        perturbed = _flag(row["perturbed"], where, "perturbed")
        direction = row["direction"].lower()
        delay = _float(row["delay_ms"], where, "delay_ms", empty_ok=True)
        check_walking_row(where, perturbed, direction, delay)
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


def _bench_rows(folder: Path) -> list[Row]:
    rows: list[Row] = []
    ids: list[tuple[str, str]] = []
    for line, where, row, path, extra in _manifest_rows(
        folder, "tests.csv", BENCH_MANIFEST_COLUMNS
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


def _json_tree(path: Path) -> dict[str, Any] | None:
    if not path.is_file():
        return None
    try:
        return from_json(_read_text(path))
    except json.JSONDecodeError as exc:
        raise SessionFormatError(
            f"{path}: line {exc.lineno}, column {exc.colno}: {exc.msg}; expected JSON"
        ) from None
    except ValueError as exc:
        raise SessionFormatError(f"{path}: {exc}") from None


def read_directory(path: str | Path, *, progress: Progress | None = None) -> Session:
    """Read and validate a CSV session directory.

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
    root = Path(path)
    toml_path = root / "session.toml"
    if not root.is_dir():
        raise SessionFormatError(f"{root}: not a directory; expected a session directory")
    try:
        document = tomllib.loads(_read_text(toml_path))
    except tomllib.TOMLDecodeError as exc:
        raise SessionFormatError(f"{toml_path}: not valid TOML: {exc}") from None
    info = info_from_mapping(document, str(toml_path))
    fs = info.sample_rate_hz
    calibration_files = sorted((root / "calibration").glob("*.csv"), key=_natural)
    walking_rows = _walking_rows(root / "walking") if (root / "walking").is_dir() else []
    bench_rows = _bench_rows(root / "bench") if (root / "bench").is_dir() else []
    tick = ticker(progress, len(calibration_files) + len(walking_rows) + len(bench_rows))

    def read(path: Path, required: tuple[str, ...], nullable: tuple[str, ...] = ()) -> Recording:
        recording = read_csv_recording(path, required, fs, nullable=nullable)
        tick()
        return recording

    nullable = info.force_plate.nullable
    calibration = tuple(read(p, info.calibration_columns, nullable) for p in calibration_files)
    walking = tuple(
        make(recording=read(p, info.walking_columns, nullable)) for p, make in walking_rows
    )
    bench = tuple(make(recording=read(p, BENCH_COLUMNS)) for p, make in bench_rows)
    return Session(
        info=info,
        calibration=calibration,
        walking=walking,
        bench=bench,
        truth=_json_tree(root / "truth.json"),
        provenance=_json_tree(root / "provenance.json") or {},
    )


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


def _plain_name(name: str, where: str, suffix: str = "") -> None:
    if not name or name.startswith(".") or "/" in name or "\\" in name or not name.endswith(suffix):
        raise SessionFormatError(
            f"{where}: recording name {name!r} is not a plain file name"
            + (f" ending in {suffix!r}" if suffix else "")
        )


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
    validate_session(session)
    names = [r.name for r in session.calibration]
    for i, name in enumerate(names):
        _plain_name(name, f"session.calibration[{i}]", ".csv")
    check_unique(((n, f"calibration[{i}]") for i, n in enumerate(names)), "file", "session")
    for i, trial in enumerate(session.walking):
        _plain_name(trial.recording.name, f"session.walking[{i}]")
    for i, test in enumerate(session.bench):
        _plain_name(test.recording.name, f"session.bench[{i}]")
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
            (tmp / "truth.json").write_text(to_json(session.truth), encoding="utf-8")
        if session.provenance:
            (tmp / "provenance.json").write_text(to_json(session.provenance), encoding="utf-8")
    return target
