"""Validation shared by every reader and writer: session metadata, recordings, manifests.

Every check raises :class:`~anklelab.errors.SessionFormatError` with one message that names the
file (or HDF5 / MATLAB location), the column or key, the row, and what was expected. Row labels
are supplied by the caller (``"line 17"`` for CSV files, ``"sample 16"`` elsewhere), so the same
checks serve the CSV directory, the HDF5 store, MATLAB files and sessions built in memory.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeGuard

import numpy as np
from numpy.typing import NDArray

from anklelab._params import found_instead, parameters_from_mapping
from anklelab.data._text import excerpt, plain_text, storable
from anklelab.data._tree import canonical
from anklelab.data.session import (
    BENCH_COLUMNS,
    BENCH_MANIFEST_COLUMNS,
    DIRECTIONS,
    SESSION_FORMAT,
    WALKING_MANIFEST_COLUMNS,
    BenchTest,
    Direction,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
    label_text,
)
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import PLATE_TYPES, plate_class

__all__ = [
    "MAX_STEP_JITTER",
    "PLAUSIBLE_M",
    "RATE_TOLERANCE",
    "SESSION_PLATFORMS",
    "RowLabel",
    "check_bench_tests",
    "check_columns",
    "check_distance",
    "check_file_name",
    "check_file_names",
    "check_recording",
    "check_recordings",
    "check_unique",
    "check_walking_row",
    "check_walking_trials",
    "info_from_mapping",
    "info_to_mapping",
    "recordings_pass",
    "sample_label",
    "section_columns",
    "validate_session",
]

RowLabel = Callable[[int], str]
RATE_TOLERANCE = 0.02
"""Largest relative difference between the median time step and ``1 / sample_rate_hz``."""
MAX_STEP_JITTER = 0.5
"""Largest deviation of any single time step from ``1 / sample_rate_hz``, as a fraction of it."""

_GEOMETRY_KEYS = ("ankle_height_m", "heel_to_ankle_m")
MAX_FORCE_DELAY_MS = 50.0
"""Largest ``[force_plate] delay_ms`` accepted: an anti-alias filter delays by a few ms at most."""
SESSION_PLATFORMS = ("perturberator",)
"""Platforms whose sessions hold walking trials (the capstan platform's identification data
is a directory of its own)."""
PLAUSIBLE_M = {
    "geometry.ankle_height_m": (0.02, 0.25),
    "geometry.heel_to_ankle_m": (0.0, 0.25),
    "force_plate.a_m": (0.01, 1.0),
    "force_plate.b_m": (0.01, 1.0),
    "force_plate.az0_m": (-0.2, 0.0),
}
"""Physically plausible range (m) of each length in ``session.toml``; outside it, the value is
refused with a hint when it fits in centimetres or millimetres."""


def sample_label(index: int) -> str:
    """Row label for array data: ``"sample 1"`` is the first sample (1-based)."""
    return f"sample {index + 1}"


# --- session.toml -------------------------------------------------------------------------------


def _number(data: Mapping[str, Any], key: str, where: str, *, positive: bool) -> float:
    value = data.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SessionFormatError(f"{where}{key}: expected a finite number, got {excerpt(value)}")
    if positive and value <= 0:
        raise SessionFormatError(f"{where}{key}: expected a number > 0, got {excerpt(value)}")
    return float(value)


def _plausible(value: float, key: str, where: str) -> None:
    """Refuse a length outside :data:`PLAUSIBLE_M`, hinting at the unit it fits in."""
    low, high = PLAUSIBLE_M[key]
    if low <= value <= high:
        return
    hint = next(
        (
            f": did you give {unit}? "
            for factor, unit in ((100, "centimetres"), (1000, "millimetres"))
            if low <= value / factor <= high
        ),
        "; ",
    )
    raise SessionFormatError(
        f"{where}{key} = {value:g} m{hint}expected {low:g}–{high:g} m (lengths are in metres)"
    )


def _table(data: Mapping[str, Any], key: str, origin: str, prefix: str) -> dict[str, Any]:
    table = data.get(key)
    if table is None:
        raise SessionFormatError(
            f"{origin}: {prefix}{key}: required table is missing{found_instead(key, data)}"
        )
    if not isinstance(table, Mapping):
        raise SessionFormatError(f"{origin}: {prefix}{key}: expected a table, got {excerpt(table)}")
    return dict(table)


def info_from_mapping(data: Mapping[str, Any], origin: str, prefix: str = "") -> SessionInfo:
    """Validate the contents of ``session.toml`` (or its HDF5 / MATLAB twin) into SessionInfo.

    Parameters
    ----------
    data : mapping
        The parsed document.
    origin : str
        File name used in messages.
    prefix : str
        Written before each key in messages (``"session."`` for a MATLAB struct).

    Unknown top-level keys and tables, and unknown keys inside ``[force_plate]`` and
    ``[geometry]``, are kept in :attr:`SessionInfo.extra`. ``[force_plate] type`` selects the
    plate type (default ``kistler8``) and with it the keys the table needs.
    """
    from anklelab.platforms import PLATFORM_NAMES  # the names only: the models cost 70 ms

    try:
        data = canonical(data)
    except ValueError as exc:
        raise SessionFormatError(f"{origin}: {prefix}{exc}") from None
    where = f"{origin}: {prefix}"
    fmt = data.get("format")
    if not isinstance(fmt, str) or fmt != SESSION_FORMAT:
        raise SessionFormatError(f"{where}format: expected {SESSION_FORMAT!r}, got {excerpt(fmt)}")
    platform = data.get("platform")
    if not isinstance(platform, str) or platform not in PLATFORM_NAMES:
        raise SessionFormatError(
            f"{where}platform: unknown platform {excerpt(platform)}; expected one of "
            f"{sorted(PLATFORM_NAMES)}"
        )
    if platform not in SESSION_PLATFORMS:
        raise SessionFormatError(
            f"{where}platform: {platform!r} does not record walking sessions; expected one of "
            f"{', '.join(map(repr, SESSION_PLATFORMS))} (a {platform} identification directory "
            "is read by `anklelab identify friction`)"
        )
    fs = _number(data, "sample_rate_hz", where, positive=True)
    subject = data.get("subject")
    if not isinstance(subject, str):
        raise SessionFormatError(f"{where}subject: expected a string, got {excerpt(subject)}")
    plate = _table(data, "force_plate", origin, prefix)
    plate_type = plate.pop("type", "kistler8")
    delay_ms = 0.0
    if "delay_ms" in plate:
        delay_ms = _number(plate, "delay_ms", f"{where}force_plate.", positive=False)
        if not 0 <= delay_ms <= MAX_FORCE_DELAY_MS:
            raise SessionFormatError(
                f"{where}force_plate.delay_ms: expected 0 to {MAX_FORCE_DELAY_MS:g} ms, got "
                f"{delay_ms:g}"
            )
        del plate["delay_ms"]
    if not isinstance(plate_type, str) or plate_type not in PLATE_TYPES:
        raise SessionFormatError(
            f"{where}force_plate.type: expected one of {', '.join(PLATE_TYPES)}, got "
            f"{excerpt(plate_type)}"
        )
    plate_model = plate_class(plate_type)
    known = plate_model.model_fields
    try:
        geometry_plate = parameters_from_mapping(
            plate_model,
            {k: v for k, v in plate.items() if k in known},
            origin=f"{origin}: {prefix}force_plate",
        )
    except ParameterError as exc:  # one line per key after a heading; name each key in full
        details = "; ".join(
            f"{prefix}force_plate.{line.strip()}" for line in str(exc).split("\n")[1:]
        )
        raise SessionFormatError(f"{origin}: {details}") from None
    geometry = _table(data, "geometry", origin, prefix)
    for key in _GEOMETRY_KEYS:
        if key not in geometry:
            raise SessionFormatError(
                f"{where}geometry.{key}: required key is missing{found_instead(key, geometry)}"
            )
    ankle_height = _number(geometry, "ankle_height_m", f"{where}geometry.", positive=True)
    heel_to_ankle = _number(geometry, "heel_to_ankle_m", f"{where}geometry.", positive=False)
    lengths = {
        "geometry.ankle_height_m": ankle_height,
        "geometry.heel_to_ankle_m": heel_to_ankle,
    } | {f"force_plate.{k}": getattr(geometry_plate, k, None) for k in ("a_m", "b_m", "az0_m")}
    for key, value in lengths.items():
        if value is not None:  # a plate type without this length
            _plausible(value, key, where)
    extra = {
        k: v
        for k, v in data.items()
        if k not in ("format", "platform", "sample_rate_hz", "subject", "force_plate", "geometry")
    }
    for key, table, names in (
        ("force_plate", plate, known),
        ("geometry", geometry, _GEOMETRY_KEYS),
    ):
        unknown = {k: v for k, v in table.items() if k not in names}
        if unknown:
            extra[key] = unknown
    return SessionInfo(
        platform=platform,
        sample_rate_hz=fs,
        subject=subject,
        force_plate=geometry_plate,
        ankle_height_m=ankle_height,
        heel_to_ankle_m=heel_to_ankle,
        extra=extra,
        force_delay_ms=delay_ms,
    )


def info_to_mapping(info: SessionInfo) -> dict[str, Any]:
    """The ``session.toml`` document for ``info`` (inverse of :func:`info_from_mapping`)."""
    extra = canonical(info.extra)
    out: dict[str, Any] = {
        "format": SESSION_FORMAT,
        "platform": info.platform,
        "sample_rate_hz": float(info.sample_rate_hz),
        "subject": info.subject,
    }
    out |= {k: v for k, v in extra.items() if k not in ("force_plate", "geometry")}
    plate = info.force_plate
    out["force_plate"] = {"type": plate.type} | plate.model_dump() | extra.get("force_plate", {})
    if info.force_delay_ms:  # written only when there is one: older readers keep it as extra
        out["force_plate"]["delay_ms"] = float(info.force_delay_ms)
    out["geometry"] = {
        "ankle_height_m": float(info.ankle_height_m),
        "heel_to_ankle_m": float(info.heel_to_ankle_m),
    } | extra.get("geometry", {})
    return out


# --- recordings ---------------------------------------------------------------------------------


def check_columns(file: str, names: Iterable[str], required: tuple[str, ...], where: str) -> None:
    """Reject duplicate column names and missing required columns.

    ``where`` says where the names were found (``"header (line 1)"``, ``"datasets"``, ...).
    """
    names = list(names)
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise SessionFormatError(f"{file}: column {name!r} appears twice in the {where}")
        seen.add(name)
    missing = [name for name in required if name not in seen]
    if missing:
        hints = "".join(found_instead(m, names) for m in missing)
        raise SessionFormatError(
            f"{file}: missing required column(s) {', '.join(map(repr, missing))} in the {where}"
            f"{hints}; expected columns {', '.join(required)} (found {', '.join(names) or 'none'})"
        )


def section_columns(info: SessionInfo, section: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The required and the nullable columns of a section's recordings (``"calibration"``,
    ``"walking"`` or ``"bench"``) with ``info``'s plate type."""
    if section == "bench":
        return BENCH_COLUMNS, ()
    columns = info.calibration_columns if section == "calibration" else info.walking_columns
    return columns, info.force_plate.nullable


def check_recording(
    file: str,
    columns: Mapping[str, NDArray[np.float64]],
    required: tuple[str, ...],
    fs: float,
    row: RowLabel = sample_label,
    *,
    nullable: tuple[str, ...] = (),
) -> None:
    """Check one recording: required columns finite, time strictly increasing at ``fs``.

    The median time step must be within :data:`RATE_TOLERANCE` of ``1 / fs`` (else the message
    names the first row whose step is not), and every step within :data:`MAX_STEP_JITTER`.

    Parameters
    ----------
    file : str
        File (or location) named in messages.
    columns : mapping of str to ndarray
        The recording's columns, equal lengths.
    required : tuple of str
        Columns that must be present and finite (unknown columns are not checked).
    fs : float
        Sample rate from ``session.toml``, Hz.
    row : callable
        Maps a 0-based sample index to the label used in messages.
    nullable : tuple of str
        Required columns that may also hold NaN (empty cells), e.g. a ``grf_cop`` plate's COP;
        they must not hold infinities.
    """
    check_columns(file, columns, required, "columns")
    lengths = {name: np.shape(values) for name, values in columns.items()}
    n = lengths["time_s"][0] if len(lengths["time_s"]) == 1 else -1
    for name, shape in lengths.items():
        if shape != (n,):
            raise SessionFormatError(
                f"{file}: column {name!r} has shape {shape}; expected ({n},) like 'time_s'"
            )
    if n < 2:
        raise SessionFormatError(f"{file}: {n} data row(s); expected at least 2 samples")
    for name in required:
        finite = np.isfinite(columns[name])
        if name in nullable:
            finite |= np.isnan(columns[name])
        if not finite.all():
            i = int(np.argmin(finite))
            raise SessionFormatError(
                f"{file}: column {name!r}, {row(i)}: value {float(columns[name][i])!r}; "
                "expected a finite number" + (" or an empty cell" if name in nullable else "")
            )
    t = columns["time_s"]
    step = np.diff(t)
    if not (step > 0).all():
        i = int(np.argmin(step > 0)) + 1
        raise SessionFormatError(
            f"{file}: column 'time_s', {row(i)}: time {float(t[i])!r} s does not increase "
            f"(previous {float(t[i - 1])!r} s); expected strictly increasing time"
        )
    period = 1.0 / fs
    median = float(np.median(step))
    if abs(median - period) > RATE_TOLERANCE * period:
        unit_hint = (
            " (is time in ms? time_s must be in seconds)"
            if (abs(median / 1000 - period) <= RATE_TOLERANCE * period)
            else ""
        )
        i = int(np.argmax(np.abs(step - period) > RATE_TOLERANCE * period)) + 1
        raise SessionFormatError(
            f"{file}: column 'time_s', {row(i)}: time step {step[i - 1]:.6g} s from the "
            f"previous row; expected {period:.6g} s ± {RATE_TOLERANCE:.0%} (session.toml "
            f"sample_rate_hz = {fs:g}); the median time step {median:.6g} s "
            f"({1 / median:.6g} Hz) does not match it either{unit_hint}"
        )
    jitter = np.abs(step - period)
    if (jitter > MAX_STEP_JITTER * period).any():
        i = int(np.argmax(jitter > MAX_STEP_JITTER * period)) + 1
        raise SessionFormatError(
            f"{file}: column 'time_s', {row(i)}: time step {step[i - 1]:.6g} s; expected "
            f"{period:.6g} s ± {MAX_STEP_JITTER:.0%} at {fs:g} Hz (dropped or repeated samples?)"
        )


def _not_finite(values: NDArray[np.float64]) -> NDArray[np.bool_]:
    return ~np.isfinite(values)


def recordings_pass(
    names: Sequence[str],
    data: NDArray[np.float64],
    starts: NDArray[np.int64],
    lengths: NDArray[np.int64],
    required: tuple[str, ...],
    fs: float,
    *,
    nullable: tuple[str, ...] = (),
) -> bool:
    """Whether the quick test, one array pass per check, shows that every recording stored end
    to end in ``data`` passes :func:`check_recording`: every required value finite (not
    infinite in a ``nullable`` column) and every time step within :data:`RATE_TOLERANCE` of
    ``1 / fs``.

    Parameters
    ----------
    names : sequence of str
        The rows of ``data`` (the ``required`` columns among them).
    data : ndarray, shape (n_columns, n_samples)
        The recordings end to end.
    starts, lengths : ndarray of int
        Where each recording starts in ``data`` and its samples.
    required : tuple of str
        The columns checked.
    fs : float
        Sample rate, Hz.
    nullable : tuple of str
        Required columns that may hold NaN (empty cells).

    Returns
    -------
    bool
        ``True``: each recording would pass. ``False`` decides nothing (a step 10 % off passes
        :func:`check_recording` if the median step is right): run it, which names any problem.
    """
    period = 1.0 / fs
    valid = {name: np.isinf if name in nullable else _not_finite for name in required}
    if lengths.min() < 2 or any(bad(data[names.index(name)]).any() for name, bad in valid.items()):
        return False
    step = np.diff(data[names.index("time_s")])
    step[starts[1:] - 1] = period  # across two recordings
    return bool((np.abs(step - period) <= RATE_TOLERANCE * period).all())


def check_recordings(
    files: Sequence[str],
    names: tuple[str, ...],
    data: NDArray[np.float64],
    starts: NDArray[np.int64],
    lengths: NDArray[np.int64],
    required: tuple[str, ...],
    fs: float,
    *,
    nullable: tuple[str, ...] = (),
) -> None:
    """:func:`check_recording` for many recordings stored end to end, in a few array passes.

    Recording ``i`` is ``data[:, starts[i]:starts[i] + lengths[i]]``, its columns named by
    ``names`` and located by ``files[i]`` in messages; ``nullable`` columns may hold NaN. When
    the whole block passes the checks at once (every required value finite, or not infinite in
    a nullable column; every time step within :data:`RATE_TOLERANCE` of ``1 / fs``), each
    recording would pass on its own; otherwise each is checked on its own, in order, and the
    first problem is reported with the same message.
    """
    if not len(files):
        return
    check_columns(files[0], names, required, "columns")
    if not recordings_pass(names, data, starts, lengths, required, fs, nullable=nullable):
        for file, start, n in zip(files, starts, lengths, strict=True):
            columns = {name: data[j, start : start + n] for j, name in enumerate(names)}
            check_recording(file, columns, required, fs, nullable=nullable)


# --- manifests ----------------------------------------------------------------------------------


def _is_direction(text: str) -> TypeGuard[Direction]:
    return text in DIRECTIONS


def check_walking_row(where: str, perturbed: bool, direction: str, delay_ms: float) -> Direction:
    """Consistency of one manifest row; ``where`` names the file and row. Returns
    ``direction``, checked to be one of :data:`~anklelab.data.session.DIRECTIONS`."""
    if not _is_direction(direction):
        raise SessionFormatError(
            f"{where}, column 'direction': got {excerpt(direction)}; expected one of "
            f"{', '.join(DIRECTIONS)}"
        )
    if perturbed:
        if direction == "none":
            raise SessionFormatError(
                f"{where}, column 'direction': a perturbed trial needs 'dorsi' or 'plantar', "
                "got 'none'"
            )
        if not (math.isfinite(delay_ms) and delay_ms >= 0):
            raise SessionFormatError(
                f"{where}, column 'delay_ms': a perturbed trial needs a delay >= 0 ms after heel "
                f"contact, got {delay_ms!r}"
            )
    else:
        if direction != "none":
            raise SessionFormatError(
                f"{where}, column 'direction': an unperturbed trial (perturbed = 0) needs "
                f"'none', got {excerpt(direction)}"
            )
        if not math.isnan(delay_ms):
            raise SessionFormatError(
                f"{where}, column 'delay_ms': an unperturbed trial (perturbed = 0) needs an "
                f"empty delay, got {delay_ms!r}"
            )
    return direction


def check_unique(items: Iterable[tuple[Any, str]], what: str, file: str) -> None:
    """Reject repeated values; ``items`` yields (value, where-it-is) pairs."""
    seen: dict[Any, str] = {}
    for value, where in items:
        if value in seen:
            raise SessionFormatError(
                f"{file}: {where}: duplicate {what} {excerpt(value)} (already at {seen[value]}); "
                f"expected each {what} once"
            )
        seen[value] = where


def check_file_name(name: str, where: str, suffix: str = "") -> None:
    """A recording's file name must be a plain name inside its section's folder: no folder
    separator, not hidden (so never ``..``), ending in ``suffix``. Whatever a session file
    says, nothing derived from its names may land outside the folder it is written to."""
    if not name or name.startswith(".") or "/" in name or "\\" in name or not name.endswith(suffix):
        raise SessionFormatError(
            f"{where}: recording name {excerpt(name)} is not a plain file name"
            + (f" ending in {suffix!r}" if suffix else "")
            + " (no folder separator, not starting with '.')"
        )


def check_file_names(session: Session, origin: str) -> None:
    """Every recording's file name plain (:func:`check_file_name`) and unique in its section."""
    sections = {
        "calibration": session.calibration,
        "walking": [t.recording for t in session.walking],
        "bench": [t.recording for t in session.bench],
    }
    for section, recordings in sections.items():
        for i, recording in enumerate(recordings):
            check_file_name(recording.name, f"{origin}: {section}[{i}]")
        labelled = ((r.name, f"{section}[{i}]") for i, r in enumerate(recordings))
        check_unique(labelled, "file", origin)


def check_walking_trials(file: str, trials: Iterable[tuple[WalkingTrial, str]]) -> None:
    """Unique trial ids and files across a walking manifest; pairs are (trial, row label)."""
    trials = list(trials)
    check_unique(((t.trial, w) for t, w in trials), "trial", file)
    check_unique(((t.recording.name, w) for t, w in trials), "file", file)


def check_distance(where: str, distance_m: float) -> None:
    """A bench test's actuator distance must be a finite number > 0 m."""
    if not (math.isfinite(distance_m) and distance_m > 0):
        raise SessionFormatError(
            f"{where}, column 'distance_m': got {distance_m!r}; expected a distance > 0 m"
        )


def check_bench_tests(file: str, tests: Iterable[tuple[BenchTest, str]]) -> None:
    """Unique test ids and files and positive distances across a bench manifest."""
    tests = list(tests)
    for test, where in tests:
        check_distance(f"{file}: {where}", test.distance_m)
    check_unique(((t.test, w) for t, w in tests), "test", file)
    check_unique(((t.recording.name, w) for t, w in tests), "file", file)


# --- whole sessions (before writing) ------------------------------------------------------------


def _check_names(where: str, recording: Recording) -> None:
    if not plain_text(recording.name):
        raise SessionFormatError(
            f"{where}: recording name {excerpt(recording.name)}; expected non-empty text "
            "without surrounding spaces, line breaks or NUL characters"
        )
    for name in recording.columns:
        if not plain_text(name):
            raise SessionFormatError(
                f"{where}: column name {excerpt(name)}; expected non-empty text without "
                "surrounding spaces, line breaks or NUL characters"
            )


def _check_extra(where: str, extra: Mapping[str, str], reserved: tuple[str, ...]) -> None:
    for key, value in extra.items():
        if (
            key in reserved
            or not plain_text(key)
            or not isinstance(value, str)
            or not storable(value)
        ):
            raise SessionFormatError(
                f"{where}: extra manifest field {excerpt(key)} = {excerpt(value)}; expected a "
                f"text value under a name other than {', '.join(reserved)}"
            )


def validate_session(session: Session, origin: str = "session") -> None:
    """Apply every reader check to an in-memory session, so writers never store what readers
    would reject. Messages name ``origin`` and the recording (``walking[3] 'trial_0004.csv'``)."""
    info_from_mapping(info_to_mapping(session.info), f"{origin}.info")
    for name in ("truth", "provenance"):
        tree = getattr(session, name)
        try:
            canonical(tree or {})
        except ValueError as exc:
            raise SessionFormatError(f"{origin}.{name}: {exc}") from None
    check_file_names(session, origin)
    info = session.info
    fs, nullable = info.sample_rate_hz, info.force_plate.nullable
    for i, rec in enumerate(session.calibration):
        where = f"{origin}.calibration[{i}] {excerpt(rec.name)}"
        _check_names(where, rec)
        check_recording(where, rec.columns, info.calibration_columns, fs, nullable=nullable)
    labelled = []
    for i, trial in enumerate(session.walking):
        where = f"{origin}.walking[{i}] {excerpt(trial.recording.name)}"
        label_text(trial.trial, f"{where}: trial")
        check_walking_row(where, trial.perturbed, trial.direction, trial.delay_ms)
        _check_names(where, trial.recording)
        _check_extra(where, trial.extra, WALKING_MANIFEST_COLUMNS)
        columns = trial.recording.columns
        check_recording(where, columns, info.walking_columns, fs, nullable=nullable)
        labelled.append((trial, f"walking[{i}]"))
    check_walking_trials(f"{origin}.walking", labelled)
    for i, test in enumerate(session.bench):
        where = f"{origin}.bench[{i}] {excerpt(test.recording.name)}"
        label_text(test.test, f"{where}: test")
        _check_names(where, test.recording)
        _check_extra(where, test.extra, BENCH_MANIFEST_COLUMNS)
        check_recording(where, test.recording.columns, BENCH_COLUMNS, fs)
    check_bench_tests(f"{origin}.bench", ((t, f"bench[{i}]") for i, t in enumerate(session.bench)))
