"""A session from a MATLAB file of any layout and a mapping TOML (``anklelab import matlab``).

The mapping (``format = "anklelab-matlab-map/1"``; documented, with an example, in the guide
"Lab data formats") names **struct paths** such as ``"{subject}.{direction}.t{delay_ms}"``: the
path's dot-separated parts are matched against field names, ``{subject}``, ``{direction}`` and
``{delay_ms}`` capturing part of a name (``t225`` gives 225) and ``*`` matching anything. Each
matched struct holds trials either as a struct array (``layout = "elements"``: one trial per
element, each field a vector, or a matrix of which ``column`` picks one) or as signal matrices
(``layout = "matrices"``: each field samples x trials, or samples x components x trials; the
trials are counted from the mapped fields, one trial may lack its trailing dimension of 1; NaN
padding at the end of shorter trials is removed). ``[columns.<name>]`` says which field holds
each session column and how to convert it (``units``, ``scale``, ``flip``), or gives a constant
``value``; a group may override them. ``time_s`` defaults to the sample index over the rate.

Trial labels are the matched path and the trial's index, ``S07.dorsiflexion.t225(3)``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, ValidationInfo, field_validator, model_validator

from anklelab._params import Parameters
from anklelab.data._checks import check_recording, check_walking_row
from anklelab.data._files import not_a_file
from anklelab.data._mapping import (
    ColumnMap,
    SessionTable,
    import_provenance,
    key_error,
    naming_the_mapping,
    read_map,
    session_info,
)
from anklelab.data.matlab import _load
from anklelab.data.session import Recording, Session, WalkingTrial
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import plate_class

__all__ = ["MATLAB_MAP_FORMAT", "MatlabMapping", "import_matlab"]

MATLAB_MAP_FORMAT = "anklelab-matlab-map/1"
WILDCARDS = {"subject": r".+?", "direction": r".+?", "delay_ms": r"\d+(?:\.\d+)?"}


class FieldMap(ColumnMap):
    """A session column: a field of each trial (with a ``column`` of a matrix field), or a
    constant ``value``."""

    field: str | None = None
    column: int | None = Field(None, ge=1)
    value: Annotated[float, Field(allow_inf_nan=False)] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> FieldMap:
        if (self.field is None) == (self.value is None):
            both = ", not both" if self.field is not None else ""
            raise key_error(f"give either field (where the values are) or value (a constant){both}")
        return self


class Group(Parameters):
    """A ``[[calibration]]`` or ``[[walking]]`` entry: where some trials are."""

    path: str = Field(min_length=1)
    layout: Literal["elements", "matrices"] = "elements"
    perturbed: bool = False
    direction: str | None = None
    delay_ms: float | None = None
    directions: dict[str, Literal["dorsi", "plantar"]] = Field(default_factory=dict)
    columns: dict[str, FieldMap] = Field(default_factory=dict)

    @field_validator("direction", "delay_ms")
    @classmethod
    def _not_also_a_wildcard(cls, value: object, info: ValidationInfo) -> object:
        wildcard, path = f"{{{info.field_name}}}", info.data.get("path", "")
        if wildcard in path:
            raise key_error(
                f"given both here and by the {wildcard} wildcard of path {path!r}; give one"
            )
        return value


class MatlabMapping(Parameters):
    """A MATLAB mapping file (``format = "anklelab-matlab-map/1"``)."""

    format: Literal["anklelab-matlab-map/1"]
    session: SessionTable
    plate: dict[str, Any]
    sample_rate_hz: float | None = Field(None, gt=0)
    sample_rate_path: str | None = None
    columns: dict[str, FieldMap]
    calibration: tuple[Group, ...] = ()
    walking: tuple[Group, ...] = Field(min_length=1)

    @model_validator(mode="after")
    def _rate(self) -> MatlabMapping:
        if (self.sample_rate_hz is None) == (self.sample_rate_path is None):
            raise ValueError("give either sample_rate_hz or sample_rate_path")
        return self


# --- struct paths ---------------------------------------------------------------------------------


def _pattern(part: str, where: str) -> re.Pattern[str]:
    out, position = [], 0
    for match in re.finditer(r"\{(\w+)\}|\*", part):
        out.append(re.escape(part[position : match.start()]))
        name = match.group(1)
        if name is None:
            out.append(".*")
        elif name in WILDCARDS:
            out.append(f"(?P<{name}>{WILDCARDS[name]})")
        else:
            raise ParameterError(
                f"{where}: unknown wildcard {{{name}}}; expected {{subject}}, {{direction}}, "
                "{delay_ms} or *"
            )
        position = match.end()
    out.append(re.escape(part[position:]))
    try:
        return re.compile("".join(out))
    except re.error as exc:  # a wildcard used twice in one part
        raise ParameterError(f"{where}: {exc}") from None


def _matches(
    tree: Mapping[str, Any], path: str, where: str
) -> Iterator[tuple[str, dict[str, str], Any]]:
    """(resolved path, captured wildcards, value) of every struct field ``path`` matches."""
    parts = path.split(".")
    patterns = [_pattern(p, where) for p in parts]

    def walk(node: Any, depth: int, trail: list[str], captured: dict[str, str]) -> Iterator:
        if depth == len(parts):
            yield ".".join(trail), captured, node
            return
        if not isinstance(node, Mapping):
            return
        for name in sorted(node, key=_natural):
            if name.startswith("__"):
                continue
            match = patterns[depth].fullmatch(name)
            if match is None:
                continue
            found = {k: v for k, v in match.groupdict().items() if v is not None}
            if any(captured.get(k, v) != v for k, v in found.items()):
                continue
            yield from walk(node[name], depth + 1, [*trail, name], captured | found)

    yield from walk(tree, 0, [], {})


def _natural(name: str) -> list[object]:
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name)]


# --- trials ---------------------------------------------------------------------------------------


def _trials(
    value: Any, group: Group, specs: Mapping[str, FieldMap], where: str
) -> list[tuple[str, dict[str, Any]]]:
    """(index label, fields) of each trial a matched value holds.

    In the ``matrices`` layout the trials are counted from the mapped fields only: the last
    axis of samples x trials (samples x components x trials for a field with a ``column``). A
    field with one dimension fewer holds one trial, as MATLAB drops a trailing dimension of 1.
    """
    if group.layout == "elements":
        if isinstance(value, Mapping):
            return [("(1)", dict(value))]
        items = list(value.ravel()) if isinstance(value, np.ndarray) else value
        if isinstance(items, list) and all(isinstance(v, Mapping) for v in items):
            return [(f"({k + 1})", dict(v)) for k, v in enumerate(items)]
        raise SessionFormatError(f'{where}: expected a struct array (layout = "elements")')
    if not isinstance(value, Mapping):
        raise SessionFormatError(f"{where}: expected a struct of signal matrices")
    ndims: dict[str, int] = {}  # dimensions of each mapped field, with its trial axis
    for spec in specs.values():
        if spec.field is not None and spec.field in value:
            ndims.setdefault(spec.field, 2 if spec.column is None else 3)
    counts: dict[str, int] = {}
    for name, ndim in ndims.items():
        shape = np.shape(value[name])
        if len(shape) not in (ndim, ndim - 1):
            expected = "samples x trials" if ndim == 2 else "samples x components x trials"
            raise SessionFormatError(
                f"{where}.{name}: an array of shape {shape}; expected {expected} "
                '(layout = "matrices")'
            )
        counts[name] = shape[-1] if len(shape) == ndim else 1
    if len(set(counts.values())) > 1:
        held = ", ".join(f"{name} {count}" for name, count in counts.items())
        raise SessionFormatError(
            f"{where}: the mapped fields hold different numbers of trials ({held}); expected "
            'the same trials in every field (layout = "matrices")'
        )
    count = next(iter(counts.values()), 1)  # no mapped field: the first missing one is named
    return [
        (
            f"({k + 1})",
            {
                name: np.asarray(v)[..., k] if np.ndim(v) == ndims.get(name) else v
                for name, v in value.items()
            },
        )
        for k in range(count)
    ]


def _column(fields: dict[str, Any], spec: FieldMap, name: str, where: str) -> NDArray | float:
    if spec.value is not None:
        try:
            return spec.convert(spec.value, name)
        except ParameterError as exc:
            raise ParameterError(f"columns.{exc}") from None
    assert spec.field is not None
    if spec.field not in fields:
        from anklelab._params import did_you_mean

        raise SessionFormatError(
            f"{where}.{spec.field}: field is missing{did_you_mean(spec.field, fields)} "
            f"(mapped to column {name!r})"
        )
    array = np.asarray(fields[spec.field])
    if array.dtype.kind not in "biuf":
        raise SessionFormatError(
            f"{where}.{spec.field}: expected numbers, got {type(fields[spec.field]).__name__}"
        )
    try:
        spec.factor(name)
    except ParameterError as exc:
        raise ParameterError(f"columns.{exc}") from None
    if spec.column is not None:
        if array.ndim != 2 or spec.column > array.shape[1]:
            raise SessionFormatError(
                f"{where}.{spec.field}: column {spec.column} requested of an array of shape "
                f"{array.shape}; expected a samples x components matrix"
            )
        array = array[:, spec.column - 1]
    elif array.ndim > 1 and min(array.shape) > 1:
        raise SessionFormatError(
            f"{where}.{spec.field}: a matrix of shape {array.shape}; give the column to use"
        )
    return spec.convert(array.ravel(), name)


def _recording(
    fields: dict[str, Any],
    specs: Mapping[str, FieldMap],
    required: tuple[str, ...],
    fs: float,
    where: str,
    name: str,
    nullable: tuple[str, ...],
) -> Recording:
    """One trial's recording, its NaN padding removed and checked: values finite (NaN allowed
    in the ``nullable`` columns: an empty COP), time increasing at ``fs``; errors name the
    struct path of the field."""
    for column in required:
        if column not in specs and column != "time_s":
            raise ParameterError(f"columns.{column}: required column is not mapped")
    values = {c: _column(fields, specs[c], c, where) for c in specs}
    arrays = [v for v in values.values() if isinstance(v, np.ndarray) and v.ndim == 1]
    if not arrays:
        raise SessionFormatError(f"{where}: no mapped field holds a signal")
    n = max(a.size for a in arrays)
    if any(a.size != n for a in arrays):
        sizes = {c: np.size(v) for c, v in values.items() if np.ndim(v) == 1}
        raise SessionFormatError(f"{where}: signals of different lengths {sizes}")
    stacked = np.stack(arrays)
    finite = np.flatnonzero(~np.isnan(stacked).all(axis=0))
    n = int(finite[-1]) + 1 if finite.size else 0  # drop NaN padding at the end
    columns = {
        c: (v[:n] if isinstance(v, np.ndarray) and v.ndim == 1 else np.full(n, float(v)))
        for c, v in values.items()
    }
    columns.setdefault("time_s", np.arange(n) / fs)
    for column, spec in specs.items():
        _check_finite(columns[column], spec, column, where, column in nullable)
    columns = {"time_s": columns.pop("time_s"), **columns}
    check_recording(where, columns, required, fs, nullable=nullable)
    return Recording(name, columns)


def _check_finite(
    values: NDArray[np.float64], spec: FieldMap, column: str, where: str, nullable: bool
) -> None:
    finite = np.isfinite(values) | (np.isnan(values) if nullable else False)
    if spec.field is None or finite.all():
        return
    i = int(np.argmin(finite))
    part = f"(:, {spec.column})" if spec.column is not None else ""
    raise SessionFormatError(
        f"{where}.{spec.field}{part}: sample {i + 1}: value {float(values[i])}; expected a "
        f"finite number{' or NaN' if nullable else ''} (mapped to column {column!r})"
    )


def _file_name(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]", "_", label).strip("._") + ".csv"


def _subject(found: set[str], subject: str | None, where: str) -> str | None:
    if subject is not None:
        if subject not in found and found:
            raise SessionFormatError(
                f"{where}: subject {subject!r} not found; the mapping matches "
                f"{', '.join(sorted(found))}"
            )
        return subject
    if len(found) > 1:
        raise SessionFormatError(
            f"{where}: the mapping matches the subjects {', '.join(sorted(found))}; choose one "
            "with --subject"
        )
    return next(iter(found), None)


def import_matlab(path: str | Path, mapping: str | Path, *, subject: str | None = None) -> Session:
    """Read a MATLAB file of any layout into a session, as ``mapping`` describes.

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file (v5/v7 or v7.3).
    mapping : str or Path
        The mapping TOML.
    subject : str, optional
        The subject to import when the ``{subject}`` wildcard matches several.

    Raises
    ------
    ParameterError
        A malformed mapping (naming the key).
    SessionFormatError
        A file that does not hold what the mapping says (naming the file and the MATLAB path).
    """
    path, mapping = Path(path), Path(mapping)
    if problem := not_a_file(path):
        raise SessionFormatError(f"{path}: {problem}; expected a MATLAB .mat file")
    spec = read_map(mapping, MatlabMapping, MATLAB_MAP_FORMAT)
    with naming_the_mapping(mapping):
        return _import(path, mapping, spec, subject)


def _import(path: Path, mapping: Path, spec: MatlabMapping, subject: str | None) -> Session:
    tree = _load(path)
    groups = [("calibration", g) for g in spec.calibration] + [("walking", g) for g in spec.walking]
    matched = []
    for section, group in groups:
        found = list(_matches(tree, group.path, f"{section}.path {group.path!r}"))
        if not found:
            raise SessionFormatError(f"{path}: nothing matches the struct path {group.path!r}")
        matched += [(section, group, hit) for hit in found]
    chosen = _subject(
        {c["subject"] for *_, (_, c, _) in matched if "subject" in c}, subject, str(path)
    )
    matched = [m for m in matched if m[2][1].get("subject", chosen) == chosen]
    rate = spec.sample_rate_hz
    if spec.sample_rate_path is not None:
        rate_path = spec.sample_rate_path.replace("{subject}", chosen or "")
        hits = list(_matches(tree, rate_path, "sample_rate_path"))
        values = [np.asarray(v) for *_, v in hits]
        if len(values) != 1 or values[0].size != 1 or values[0].dtype.kind not in "biuf":
            raise SessionFormatError(
                f"{path}: {rate_path}: expected one number (the sample rate, Hz)"
            )
        rate = float(values[0].item())
    assert rate is not None
    try:
        plate_model = plate_class(spec.plate.get("type", "kistler8"))
    except ParameterError as exc:
        raise ParameterError(f"plate.{exc}") from None
    info_plate = dict(spec.plate)
    calibration, walking = [], []
    labels: dict[str, str] = {}
    for section, group, (resolved, captured, value) in matched:
        where = f"{path}: {resolved}"
        specs = spec.columns | group.columns
        if section == "calibration":  # the goniometer is a walking column
            specs = {c: m for c, m in specs.items() if c != "ankle_angle"}
        required = ("time_s", "motor_angle", *(("ankle_angle",) if section == "walking" else ()))
        required += plate_model.channels
        for index, fields in _trials(value, group, specs, where):
            label = f"{resolved}{index}"
            trial_where = f"{where}{index}"
            rec = _recording(
                fields, specs, required, rate, trial_where, _file_name(label), plate_model.nullable
            )
            if rec.name in labels:
                raise SessionFormatError(
                    f"{where}{index}: file name {rec.name} clashes with {labels[rec.name]}"
                )
            labels[rec.name] = label
            if section == "calibration":
                calibration.append(rec)
                continue
            walking.append(_walking_trial(group, captured, label, rec, trial_where))
    info = session_info(_with_subject(spec.session, chosen), rate, info_plate)
    provenance = import_provenance(path, "matlab-map", mapping)
    return Session(info, tuple(calibration), tuple(walking), (), None, provenance)


def _with_subject(table: SessionTable, subject: str | None) -> SessionTable:
    if "{subject}" not in table.subject:
        return table
    if subject is None:
        raise ParameterError("session.subject: uses {subject}, but no struct path captures it")
    return table.model_copy(update={"subject": table.subject.replace("{subject}", subject)})


def _walking_trial(
    group: Group, captured: dict[str, str], label: str, rec: Recording, where: str
) -> WalkingTrial:
    if not group.perturbed:
        return WalkingTrial(label, rec, False, "none", math.nan)
    text = group.direction or captured.get("direction")
    if text is None:
        raise ParameterError(
            f"walking.path {group.path!r}: a perturbed group needs a direction (the "
            "{direction} wildcard or direction = ...)"
        )
    direction = group.directions.get(text, text.lower())
    delay = group.delay_ms if group.delay_ms is not None else captured.get("delay_ms")
    if delay is None:
        raise ParameterError(
            f"walking.path {group.path!r}: a perturbed group needs a delay (the {{delay_ms}} "
            "wildcard or delay_ms = ...)"
        )
    checked = check_walking_row(where, True, direction, float(delay))
    return WalkingTrial(label, rec, True, checked, float(delay))
