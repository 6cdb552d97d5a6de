"""A session from a directory of per-trial C3D files and a mapping TOML (``anklelab import c3d``).

The mapping (``format = "anklelab-c3d-map/1"``; documented, with an example, in the guide
"Lab data formats") says which force platform to use and how to store it, which analog channels
hold the motor angle and the goniometer (and a bench test's displacement and force), and where
the trial list comes from: a CSV naming each file's role, or the files' events. Every C3D file
must have the same analog rate (it becomes ``sample_rate_hz``) and, for the ``kistler8`` and
``six_axis`` plate types, the same plate geometry.

Plate storage (``[plate] type``):

- ``kistler8`` (C3D type 3 only): the 8 channels as recorded; ``a_m``, ``b_m``, ``az0_m`` from
  ``ORIGIN``.
- ``six_axis`` (types 2, 3, 4; the default for 2 and 4): Fx..Mz after ``CAL_MATRIX``, in N and
  N·m, moments about the point ``az0_m`` below the centre of the surface.
- ``grf_cop`` (any supported type): the GRF and COP of :func:`~anklelab.data.c3d.plate_load`
  turned into the walking frame (x along ``walking_axis``, z up); the COP is empty where the
  vertical force's magnitude is at most ``min_force_n`` (default 0: kept wherever Fz is not 0,
  so that the calibration trials teach the platform filters the plate's own moment).

For the first two, ``anterior_axis`` is the plate axis that ``CORNERS`` align with the lab's
``walking_axis`` (within 10°).
"""

from __future__ import annotations

import csv
import fnmatch
import io
import math
import re
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from anklelab._params import Parameters
from anklelab.data._checks import check_walking_row
from anklelab.data._files import MAX_MANIFEST_BYTES, read_bytes
from anklelab.data._mapping import (
    ColumnMap,
    SessionTable,
    column_quantity,
    import_provenance,
    naming_the_mapping,
    read_map,
    session_info,
)
from anklelab.data._text import excerpt
from anklelab.data._units import read_unit, si_unit
from anklelab.data.c3d import C3DFile, C3DPlate, plate_load, plate_wrench, read_c3d_files
from anklelab.data.directory import _flag, _float  # the manifest cells' rules
from anklelab.data.session import BenchTest, Recording, Session, WalkingTrial, label_text
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import CHANNELS, GRF_COP_CHANNELS, SIX_AXIS_CHANNELS

__all__ = ["C3D_MAP_FORMAT", "C3DMapping", "c3d_import_inputs", "import_c3d"]

C3D_MAP_FORMAT = "anklelab-c3d-map/1"
ALIGNMENT_DEG = 10.0
"""Largest angle between a plate axis and the lab's walking axis for them to count as aligned."""
WalkingAxis = Literal["+x", "-x", "+y", "-y", "+z", "-z"]
_ROLES = ("calibration", "walking", "bench")


class AnalogMap(ColumnMap):
    """An analog channel by its ``ANALOG:LABELS`` entry, and its conversion."""

    label: str = Field(min_length=1)


class ChannelsTable(Parameters):
    """``[channels.*]``: the analog channels of the non-plate columns."""

    motor_angle: AnalogMap
    ankle_angle: AnalogMap | None = None
    displacement_m: AnalogMap | None = None
    force_n: AnalogMap | None = None


class PlateTable(Parameters):
    """``[plate]``: which force platform, how the session stores it, the walking direction, how
    much later its channels are recorded than the angles (``delay_ms``, the amplifier's
    anti-alias filter; ``[force_plate] delay_ms`` of ``session.toml``), and, for ``grf_cop``,
    the force (N) at or below which the COP is left empty (``min_force_n``)."""

    number: int = Field(1, ge=1)
    type: Literal["kistler8", "six_axis", "grf_cop"] | None = None
    walking_axis: WalkingAxis
    min_force_n: float = Field(0.0, ge=0, allow_inf_nan=False)
    delay_ms: float = Field(0.0, ge=0, le=50)


class TrialsFromCsv(Parameters):
    """``[trials] source = "csv"``: a CSV in the C3D directory, one row per file used."""

    source: Literal["csv"]
    file: str = Field(min_length=1)


class TrialsFromEvents(Parameters):
    """``[trials] source = "events"``: roles and conditions from each file's events.

    Every ``.c3d`` file of the directory (any case) is a trial: a calibration trial if its name
    matches a ``calibration`` pattern, none if it matches an ``ignore`` pattern (a static or a
    bench trial), else a walking trial; patterns are matched without regard to case.
    ``heel_strike_context`` (``"Right"``...) selects the heel strikes of the foot on the plate
    by their ``EVENT:CONTEXTS``; it is needed when the files mark both feet's strikes.
    """

    source: Literal["events"]
    calibration: tuple[str, ...] = ()
    ignore: tuple[str, ...] = ()
    heel_strike: str = Field(min_length=1)
    heel_strike_context: str | None = Field(None, min_length=1)
    dorsi: str = Field(min_length=1)
    plantar: str = Field(min_length=1)
    timing_points_ms: tuple[float, ...] = Field(min_length=1)


class C3DMapping(Parameters):
    """A C3D mapping file (``format = "anklelab-c3d-map/1"``)."""

    format: Literal["anklelab-c3d-map/1"]
    session: SessionTable
    plate: PlateTable
    channels: ChannelsTable
    trials: TrialsFromCsv | TrialsFromEvents = Field(discriminator="source")


# --- the trial list -------------------------------------------------------------------------------

Entry = tuple[str, Path, dict[str, str]]  # role, file, manifest fields


def _natural(path: Path) -> list[object]:
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", path.name)]


def _entries_from_csv(root: Path, table: TrialsFromCsv) -> list[Entry]:
    name = table.file
    if "/" in name or "\\" in name or name in (".", ".."):
        raise ParameterError(f"trials.file: expected a file name inside {root}, got {name!r}")
    path = root / name
    try:
        text = read_bytes(path, root, MAX_MANIFEST_BYTES, "a CSV trial list").decode("utf-8-sig")
    except UnicodeDecodeError:
        raise SessionFormatError(f"{path}: not UTF-8 text; expected a CSV trial list") from None
    rows = list(csv.reader(io.StringIO(text)))
    header = [h.strip() for h in rows[0]] if rows else []
    for column in ("file", "role"):
        if column in header:
            continue
        first = text.splitlines()[0] if text else ""
        if ";" in first and "," not in first:
            raise SessionFormatError(
                f"{path}: line 1 is separated by semicolons ({excerpt(first, 80)}); expected a "
                "comma-separated CSV"
            )
        raise SessionFormatError(
            f"{path}: header (line 1) lacks the column {column!r}; expected file, role and "
            "(walking) perturbed, direction, delay_ms, (bench) distance_m, optionally label"
        )
    entries = []
    seen: dict[str, int] = {}
    labels: dict[tuple[str, str], int] = {}  # (role, label): line
    for line, fields in enumerate(rows[1:], start=2):
        if not any(f.strip() for f in fields):
            continue
        if len(fields) != len(header):
            raise SessionFormatError(
                f"{path}: line {line} has {len(fields)} fields; expected {len(header)}"
            )
        row = {h: f.strip() for h, f in zip(header, fields, strict=True)}
        where = f"{path}: line {line}"
        if row["role"] not in _ROLES:
            raise SessionFormatError(
                f"{where}, column 'role': got {row['role']!r}; expected one of {', '.join(_ROLES)}"
            )
        file = row["file"]
        if not file or "/" in file or "\\" in file or not (root / file).is_file():
            raise SessionFormatError(f"{where}, column 'file': {file!r} is not a file in {root}")
        if file in seen:
            raise SessionFormatError(f"{where}: file {file!r} already listed at line {seen[file]}")
        seen[file] = line
        if row["role"] != "calibration":  # walking trials and bench tests are labelled
            label = row.get("label") or Path(file).stem
            if (row["role"], label) in labels:
                default = "" if row.get("label") else " (the file name, as the label is empty)"
                raise SessionFormatError(
                    f"{where}, column 'label': {excerpt(label)}{default} is already the label of "
                    f"line {labels[row['role'], label]}"
                )
            labels[row["role"], label] = line
        entries.append((row["role"], root / file, row | {"_where": where}))
    if not entries:
        raise SessionFormatError(f"{path}: no rows after the header; expected one row per file")
    return entries


def _matches(name: str, patterns: tuple[str, ...]) -> bool:
    return any(fnmatch.fnmatchcase(name.casefold(), g.casefold()) for g in patterns)


def _entries_from_events(root: Path, table: TrialsFromEvents) -> list[Entry]:
    files = sorted((p for p in root.iterdir() if p.suffix.casefold() == ".c3d"), key=_natural)
    stems: dict[str, Path] = {}
    for path in files:
        if (other := stems.setdefault(path.stem.casefold(), path)) is not path:
            raise SessionFormatError(
                f"{path}: the same trial name as {other.name} but for case; rename one (trial "
                "labels are the file names)"
            )
    files = [p for p in files if not _matches(p.name, table.ignore)]
    if not files:
        raise SessionFormatError(f"{root}: no .c3d files besides those [trials] ignore matches")
    return [
        ("calibration" if _matches(p.name, table.calibration) else "walking", p, {"_where": str(p)})
        for p in files
    ]


def _check_role(c3d: C3DFile, spec: C3DMapping, role: str) -> None:
    """A file the events took for a calibration or walking trial must have the channels and the
    plate of one; else it is named with what it looks like (a bench, static... trial)."""
    channels = spec.channels
    wanted = [channels.motor_angle] + ([channels.ankle_angle] if role == "walking" else [])
    missing = [m.label for m in wanted if m is not None and m.label not in c3d.labels]
    lacks = [f"analog channel {', '.join(map(repr, missing))}"] if missing else []
    if len(c3d.plates) < spec.plate.number:
        lacks.append(f"force platform {spec.plate.number}")
    if not lacks:
        return
    bench = [m.label for m in (channels.displacement_m, channels.force_n) if m is not None]
    if bench and all(label in c3d.labels for label in bench):
        looks = f"a bench test (it has {', '.join(map(repr, bench))})"
    else:
        looks = "a static or bench trial"
    why = "a" if role == "calibration" else "no calibration or ignore"
    raise SessionFormatError(
        f'{c3d.path}: taken for a {role} trial ([trials] source = "events": it matches {why} '
        f"pattern), but it has no {' and no '.join(lacks)}: it looks like {looks}; list it in "
        '[trials] ignore, or list the trials in a CSV (source = "csv")'
    )


def _heel_strikes(c3d: C3DFile, table: TrialsFromEvents) -> list[float]:
    """Times of the heel strikes of the foot on the plate, s (``heel_strike_context``)."""
    strikes = [e for e in c3d.events if e.label == table.heel_strike]
    if table.heel_strike_context is not None:
        return [e.time_s for e in strikes if e.context == table.heel_strike_context]
    contexts = sorted({e.context for e in strikes})
    if len(contexts) > 1:
        named = ", ".join(map(repr, contexts[:-1])) + f" and {contexts[-1]!r}"
        choices = " or ".join(f'"{context}"' for context in contexts)
        raise SessionFormatError(
            f"{c3d.path}: {table.heel_strike!r} events of the contexts {named} "
            "(EVENT:CONTEXTS); say which foot's strikes time the perturbation (the foot on the "
            f"plate): [trials] heel_strike_context = {choices}"
        )
    return [e.time_s for e in strikes]


def _event_row(c3d: C3DFile, table: TrialsFromEvents) -> dict[str, str]:
    """perturbed, direction and delay_ms of a walking file from its events."""
    strikes = _heel_strikes(c3d, table)
    onsets = [e for e in c3d.events if e.label in (table.dorsi, table.plantar)]
    if not onsets:
        return {"perturbed": "0", "direction": "none", "delay_ms": ""}
    onset = min(onsets, key=lambda e: e.time_s)
    before = [t for t in strikes if t <= onset.time_s]
    if not before:
        context = table.heel_strike_context
        of = f" of context {context!r}" if context is not None else ""
        raise SessionFormatError(
            f"{c3d.path}: a {onset.label!r} event at {onset.time_s:g} s but no "
            f"{table.heel_strike!r} event{of} before it; expected the heel strike the "
            "perturbation is timed from"
        )
    delay = (onset.time_s - max(before)) * 1000.0
    points = np.array(table.timing_points_ms)
    nearest = float(points[np.argmin(np.abs(points - delay))])
    direction = "dorsi" if onset.label == table.dorsi else "plantar"
    return {"perturbed": "1", "direction": direction, "delay_ms": f"{nearest:g}"}


# --- the plate ------------------------------------------------------------------------------------


def _axis_vector(axis: str) -> NDArray[np.float64]:
    vector = np.zeros(3)
    vector["xyz".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
    return vector


def _anterior_axis(c3d: C3DFile, plate: C3DPlate, walking_axis: str) -> str:
    """The plate axis (``"+x"``...) that points along the lab's walking axis."""
    axes, walk = plate.axes(), _axis_vector(walking_axis)
    along = axes[:, :2].T @ walk
    k = int(np.argmax(np.abs(along)))
    angle = math.degrees(math.acos(min(1.0, abs(float(along[k])))))
    if angle > ALIGNMENT_DEG:
        raise SessionFormatError(
            f"{c3d.path}: {plate.name}: no plate axis is within {ALIGNMENT_DEG:g}° of the "
            f"walking axis {walking_axis} (closest: plate {'xy'[k]}, {angle:.0f}° away); check "
            "[plate] walking_axis"
        )
    return ("+" if along[k] > 0 else "-") + "xy"[k]


def _walking_frame(plate: C3DPlate, walking_axis: str) -> NDArray[np.float64]:
    """Rows: x along the walking axis, y left, z up (against the plate's z), in global terms."""
    up = -plate.axes()[:, 2]
    forward = _axis_vector(walking_axis)
    forward = forward - (forward @ up) * up
    if np.linalg.norm(forward) < 0.5:
        raise ParameterError(f"plate.walking_axis: {walking_axis} is vertical for this plate")
    forward /= np.linalg.norm(forward)
    return np.stack([forward, np.cross(up, forward), up])


def _plate_columns(
    c3d: C3DFile, table: PlateTable, kind: str
) -> tuple[dict[str, NDArray[np.float64]], dict[str, object]]:
    """The plate's session columns and its ``[force_plate]`` table, from one file."""
    plate = c3d.plate(table.number)
    if kind == "grf_cop":
        load = plate_load(c3d, plate, min_force_n=table.min_force_n)
        frame = _walking_frame(plate, table.walking_axis)
        grf, cop = frame @ load.grf, frame @ (load.cop - plate.centre_m[:, None])
        values = (*grf, *cop[:2])
        return dict(zip(GRF_COP_CHANNELS, values, strict=True)), {"type": "grf_cop"}
    anterior = _anterior_axis(c3d, plate, table.walking_axis)
    force, moment, to_surface = plate_wrench(c3d, plate)
    if kind == "kistler8":
        if plate.type != 3:
            raise ParameterError(
                f"plate.type: 'kistler8' needs a C3D type-3 plate; {c3d.path} has "
                f"{plate.name} (use 'six_axis' or 'grf_cop')"
            )
        a, b, az0 = (float(v) for v in plate.origin_m)
        geometry = {"a_m": abs(a), "b_m": abs(b), "az0_m": -abs(az0)}
        channels = c3d.analogs[list(plate.channels)]
        columns = dict(zip(CHANNELS, channels, strict=True))
        return columns, {"type": "kistler8", **geometry, "anterior_axis": anterior}
    # moments about the point az0 below the surface centre (the origin's horizontal offset
    # removed), so that the COP is relative to the centre of the plate
    offset = np.array([to_surface[0], to_surface[1], 0.0])
    moment = moment + np.cross(force, offset, axis=0)
    columns = dict(zip(SIX_AXIS_CHANNELS, (*force, *moment), strict=True))
    return columns, {"type": "six_axis", "az0_m": float(to_surface[2]), "anterior_axis": anterior}


# --- building the session -------------------------------------------------------------------------


def _analog(c3d: C3DFile, spec: AnalogMap | None, column: str, key: str) -> NDArray[np.float64]:
    if spec is None:
        raise ParameterError(f"channels.{column}: required for {key} trials but not mapped")
    try:
        values = spec.convert(c3d.analog(spec.label), column)
    except ParameterError as exc:
        raise ParameterError(f"channels.{exc}") from None
    _check_unit(c3d, spec, column)
    return values


def _check_unit(c3d: C3DFile, spec: AnalogMap, column: str) -> None:
    """The mapping's unit must be the one a non-empty ``ANALOG:UNITS`` gives the channel (when
    it is a unit of :data:`~anklelab.data._units.UNITS`; a ``V`` channel is converted by
    ``scale``). Only where ``scale`` is 1 or -1: ``units`` is the unit of ``stored * scale``,
    and a scale may convert units (0.001 from mm to m) or refer an angle through a gear."""
    stored = c3d.units[c3d.labels.index(spec.label)]
    found, quantity = read_unit(stored), column_quantity(column)
    mapped = spec.units or (si_unit(quantity) if quantity else None)
    if found is None or quantity is None or found == (quantity, mapped) or abs(spec.scale) != 1:
        return
    default = "" if spec.units else " (the default)"
    head = (
        f"channels.{column}.units: {mapped!r}{default}, but {c3d.path} gives {spec.label!r} in "
        f"{stored!r} (ANALOG:UNITS)"
    )
    if found[0] == quantity:
        raise ParameterError(
            f'{head}; give units = "{found[1]}" if the file is right (or the scale that '
            "converts it)"
        )
    raise ParameterError(f"{head}: a unit of {found[0]}, not of {quantity}; is the label right?")


def _label(row: dict[str, str], path: Path) -> str:
    return label_text(row.get("label") or path.stem, f"{row['_where']}, column 'label'")


def _walking(c3d: C3DFile, row: dict[str, str], recording: Recording) -> WalkingTrial:
    where = row["_where"]
    perturbed = _flag(row.get("perturbed", ""), where, "perturbed")
    delay = _float(row.get("delay_ms", ""), where, "delay_ms", empty_ok=True)
    direction = check_walking_row(where, perturbed, row.get("direction", "").lower(), delay)
    known = {"file", "role", "label", "perturbed", "direction", "delay_ms", "distance_m", "_where"}
    extra = {k: v for k, v in row.items() if k not in known}
    return WalkingTrial(_label(row, c3d.path), recording, perturbed, direction, delay, extra)


def import_c3d(directory: str | Path, mapping: str | Path, *, workers: int = 2) -> Session:
    """Read a directory of C3D trials into a session, as ``mapping`` describes.

    Parameters
    ----------
    directory : str or Path
        The C3D files (and the CSV trial list, if the mapping uses one).
    mapping : str or Path
        The mapping TOML.
    workers : int
        Worker processes reading the files.

    Returns
    -------
    Session
        ``provenance`` records the anklelab version, the importer, the directory's content hash
        and the mapping's SHA-256.

    Raises
    ------
    ParameterError
        A malformed mapping (naming the key).
    SessionFormatError
        A malformed file or trial list (naming the file and the row, label or parameter).
    """
    root, mapping = Path(directory), Path(mapping)
    spec, entries, read = _plan(root, mapping)
    with naming_the_mapping(mapping):
        return _import(root, mapping, spec, entries, read, workers)


def c3d_import_inputs(directory: str | Path, mapping: str | Path) -> list[Path]:
    """The files :func:`import_c3d` reads, for a command to check its output against before
    reading them.

    Parameters
    ----------
    directory : str or Path
        The C3D files (and the CSV trial list, if the mapping uses one).
    mapping : str or Path
        The mapping TOML.

    Returns
    -------
    list of Path
        The mapping, the CSV trial list (if the mapping names one) and the C3D files.

    Raises
    ------
    ParameterError, SessionFormatError
        As :func:`import_c3d`, for the mapping and the trial list.
    """
    mapping = Path(mapping)
    return [mapping, *_plan(Path(directory), mapping)[2]]


def _plan(root: Path, mapping: Path) -> tuple[C3DMapping, list[Entry], list[Path]]:
    """The mapping, the trial list's entries and the files to read (the trial list, if the
    mapping names one, then the C3D files)."""
    if not root.is_dir():
        raise SessionFormatError(f"{root}: not a directory; expected a directory of C3D files")
    spec = read_map(mapping, C3DMapping, C3D_MAP_FORMAT)
    with naming_the_mapping(mapping):
        if isinstance(spec.trials, TrialsFromCsv):
            entries = _entries_from_csv(root, spec.trials)
            listed = [root / spec.trials.file]
        else:
            entries = _entries_from_events(root, spec.trials)
            listed = []
    return spec, entries, [*listed, *(path for _, path, _ in entries)]


def _import(
    root: Path,
    mapping: Path,
    spec: C3DMapping,
    entries: list[Entry],
    read: list[Path],
    workers: int,
) -> Session:
    files = read_c3d_files([path for _, path, _ in entries], workers=workers)
    first = files[0]
    rate = first.analog_rate_hz
    kind = spec.plate.type or {3: "kistler8"}.get(first.plate(spec.plate.number).type, "six_axis")
    plate_table: dict[str, object] | None = None  # and the file it is from:
    plate_file = ""
    calibration: list[Recording] = []
    walking: list[WalkingTrial] = []
    bench: list[BenchTest] = []
    for (role, path, row), c3d in zip(entries, files, strict=True):
        if not math.isclose(c3d.analog_rate_hz, rate, rel_tol=1e-9):
            raise SessionFormatError(
                f"{path}: analog rate {c3d.analog_rate_hz:g} Hz; expected {rate:g} Hz like "
                f"{first.path.name} (one sample rate per session)"
            )
        if isinstance(spec.trials, TrialsFromEvents):
            _check_role(c3d, spec, role)
        columns = {"time_s": c3d.time_s}
        if role == "bench":
            columns["displacement_m"] = _analog(
                c3d, spec.channels.displacement_m, "displacement_m", role
            )
            columns["force_n"] = _analog(c3d, spec.channels.force_n, "force_n", role)
            distance = _float(row.get("distance_m", ""), row["_where"], "distance_m")
            bench.append(
                BenchTest(_label(row, path), Recording(f"{path.stem}.csv", columns), distance)
            )
            continue
        columns["motor_angle"] = _analog(c3d, spec.channels.motor_angle, "motor_angle", role)
        if role == "walking":
            columns["ankle_angle"] = _analog(c3d, spec.channels.ankle_angle, "ankle_angle", role)
        plate_columns, table = _plate_columns(c3d, spec.plate, kind)
        if plate_table is None:
            plate_table, plate_file = table, path.name
        elif kind != "grf_cop" and (differences := _plate_differences(table, plate_table)):
            shown = "; ".join(
                f"{key} = {ours} ({plate_file}: {theirs})" for key, ours, theirs in differences
            )
            raise SessionFormatError(
                f"{path}: plate {spec.plate.number} has {shown}; expected the same plate in "
                "every file"
            )
        recording = Recording(f"{path.stem}.csv", columns | plate_columns)
        if role == "calibration":
            calibration.append(recording)
        else:
            if isinstance(spec.trials, TrialsFromEvents):
                row = row | _event_row(c3d, spec.trials)
            walking.append(_walking(c3d, row, recording))
    if not walking:
        raise SessionFormatError(
            f"{root}: no walking trial among the {len(entries)} C3D file(s) the map lists "
            "(its [trials] table says which are calibration, walking or bench trials); a "
            "session needs walking trials"
        )
    assert plate_table is not None  # set by the first walking trial
    plate_table.setdefault("anterior_axis", "+x")
    if spec.plate.delay_ms:  # as session.toml's [force_plate] delay_ms
        plate_table["delay_ms"] = spec.plate.delay_ms
    info = session_info(spec.session, rate, plate_table)
    provenance = import_provenance(root, "c3d", mapping, read)
    return Session(info, tuple(calibration), tuple(walking), tuple(bench), None, provenance)


def _plate_differences(
    table: dict[str, object], first: dict[str, object]
) -> list[tuple[str, str, str]]:
    """(key, value, value in the first file) where two plate tables differ; floats (a plate's
    geometry, m) within 1e-6 of each other are the same."""
    return [
        (key, _shown(table.get(key)), _shown(first.get(key)))
        for key in sorted(table.keys() | first.keys())
        if not _same_value(table.get(key), first.get(key))
    ]


def _shown(value: object) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def _same_value(x: object, y: object) -> bool:
    if isinstance(x, float) and isinstance(y, float):
        return bool(np.isclose(x, y, atol=1e-6))
    return x == y
