"""C3D files through ezc3d: analog channels, force platforms (types 2, 3, 4), events.

:func:`read_c3d` returns a :class:`C3DFile`: the analog channels (ezc3d applies each channel's
``ANALOG:SCALE``, ``OFFSET`` and ``GEN_SCALE`` as ``(stored - |OFFSET|) * SCALE * GEN_SCALE``:
the magnitude of a negative ``OFFSET``, which the C3D specification would add), their labels
and units, the force platforms
described by the ``FORCE_PLATFORM`` group and the events. :func:`plate_load` computes a
platform's ground reaction force, centre of pressure and free moment in the file's global
(lab) frame:

- **channels** (``FORCE_PLATFORM:CHANNEL``): type 2 and 4 give Fx, Fy, Fz, Mx, My, Mz about the
  plate's origin (type 4 through ``CAL_MATRIX``, a 6x6 matrix per plate, ``CAL_MATRIX(i, j)``
  multiplying channel ``j``), type 3 the 8 Kistler channels ``fx12 fx34 fy14 fy23 fz1 fz2 fz3
  fz4`` with ``ORIGIN = (a, b, az0)``, read as ``(|a|, |b|, -|az0|)`` whichever signs the file
  gives (ezc3d takes a positive ``az0`` as given, and its COP is then wrong). Plate frame and
  sign as the manufacturers give them: load on the plate, plate z down;
- **origin** (``ORIGIN``, types 2 and 4): the vector between the plate's origin and the centre
  of its surface, in plate coordinates; its z is made negative (surface above the origin)
  whichever sign the file uses, as ezc3d and the C3D manual's note on AMTI plates do;
- **corners** (``CORNERS``): the surface's corners 1-4 in the global frame; plate x points
  from corner 2 to corner 1, plate y from corner 4 to corner 1, z = x × y (down);
- **units**: positions (``CORNERS``, ``ORIGIN``, COP) are converted from ``POINT:UNITS`` to
  metres; force channels must be in N; moment channels in N·m or N·mm by their
  ``ANALOG:UNITS`` (empty: N·``POINT:UNITS``), type 4 calibrated moments in N·``POINT:UNITS``;
- **results**: GRF is the force of the plate on the body (the opposite of the plate's
  channels); the COP lies on the plate surface and is NaN where the vertical force's
  magnitude is below ``min_force_n`` (a pulling force keeps its COP, where its moment
  vanishes); type 3's ``FPCOPPOLY`` COP correction is applied when present; the free
  moment is the plate's moment on the body about the upward vertical through the COP;
- **errors**: a NaN or infinite value in a channel that is used, a non-finite ``ORIGIN`` or
  ``CORNERS`` that do not span a plane are errors naming the file and the channel or parameter.

ezc3d's C++ reader can crash or hang on a corrupt file, so files are read in worker processes
(:mod:`anklelab.data._isolated`) after a check of the file's block structure; either failure is
a :class:`~anklelab.errors.SessionFormatError` naming the file.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from anklelab.data._isolated import IsolatedFailure, map_isolated
from anklelab.data._units import UNITS, read_unit
from anklelab.errors import SessionFormatError
from anklelab.forceplate import cop_from_moment, kistler_matrix

__all__ = [
    "SUPPORTED_PLATE_TYPES",
    "C3DEvent",
    "C3DFile",
    "C3DPlate",
    "GlobalLoad",
    "plate_load",
    "plate_wrench",
    "read_c3d",
    "read_c3d_files",
]

SUPPORTED_PLATE_TYPES = (2, 3, 4)
_WORKER = Path(__file__).with_name("_c3d_worker.py")
T = TypeVar("T")


@dataclass(frozen=True)
class C3DEvent:
    """An event: its label, context (``"Left"``, ``"General"``...) and time, s."""

    label: str
    context: str
    time_s: float


@dataclass(frozen=True)
class C3DPlate:
    """One force platform of a C3D file, as its ``FORCE_PLATFORM`` parameters describe it.

    Attributes
    ----------
    number : int
        1-based index in the ``FORCE_PLATFORM`` group.
    type : int
        The C3D plate type (2, 3 and 4 are supported).
    channels : tuple of int
        0-based indices of its analog channels.
    origin_m : ndarray, shape (3,)
        ``ORIGIN`` in metres, as in the file.
    corners_m : ndarray, shape (4, 3)
        Surface corners 1-4 in the global frame, m.
    cal_matrix : ndarray, shape (6, 6), or None
        ``CAL_MATRIX`` (type 4).
    cop_poly : ndarray, shape (12,), or None
        ``FPCOPPOLY`` (type 3 COP correction), if the file has it.
    """

    number: int
    type: int
    channels: tuple[int, ...]
    origin_m: NDArray[np.float64]
    corners_m: NDArray[np.float64]
    cal_matrix: NDArray[np.float64] | None = None
    cop_poly: NDArray[np.float64] | None = None

    @property
    def name(self) -> str:
        """``"plate 2 (type 4)"``, for messages."""
        return f"plate {self.number} (type {self.type})"

    def axes(self) -> NDArray[np.float64]:
        """Rotation from plate to global coordinates: columns are the plate's x, y, z axes."""
        c = self.corners_m
        x = c[0] - c[1]
        z = np.cross(x, c[0] - c[3])
        y = np.cross(z, x)
        return np.stack([v / np.linalg.norm(v) for v in (x, y, z)], axis=1)

    @property
    def centre_m(self) -> NDArray[np.float64]:
        """Centre of the plate surface in the global frame, m."""
        return self.corners_m.mean(axis=0)


@dataclass(frozen=True)
class C3DFile:
    """What anklelab reads from a C3D file.

    Attributes
    ----------
    path : Path
    analog_rate_hz, point_rate_hz : float
    start_s : float
        Time of the first analog sample, s (from the header's first frame).
    labels, units : tuple of str
        ``ANALOG:LABELS`` and ``ANALOG:UNITS`` (stripped; units may be empty).
    analogs : ndarray, shape (n_channels, n_samples)
        Analog values after ``SCALE``, ``OFFSET`` and ``GEN_SCALE``.
    length_scale : float
        ``POINT:UNITS`` in metres (1e-3 for mm; 1 when the file gives no unit, as ezc3d).
    plates : tuple of C3DPlate
    events : tuple of C3DEvent
    parameters : mapping
        Every parameter, ``{group: {name: value}}`` (text as lists of str, numbers as arrays).
    problems : tuple of str
        What a lenient read (:func:`read_c3d_files`) could not interpret and left out (then
        ``length_scale`` may be NaN: ``POINT:UNITS`` unknown).
    """

    path: Path
    analog_rate_hz: float
    point_rate_hz: float
    start_s: float
    labels: tuple[str, ...]
    units: tuple[str, ...]
    analogs: NDArray[np.float64]
    length_scale: float
    plates: tuple[C3DPlate, ...] = ()
    events: tuple[C3DEvent, ...] = ()
    parameters: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    problems: tuple[str, ...] = ()

    @property
    def n_samples(self) -> int:
        """Analog samples per channel."""
        return self.analogs.shape[1]

    @property
    def time_s(self) -> NDArray[np.float64]:
        """Time of each analog sample, s."""
        return self.start_s + np.arange(self.n_samples) / self.analog_rate_hz

    def analog(self, label: str) -> NDArray[np.float64]:
        """The channel called ``label``.

        Raises
        ------
        SessionFormatError
            Naming the file and the labels it has, when no channel or several are called
            ``label``.
        """
        if label not in self.labels:
            from anklelab._params import did_you_mean

            raise SessionFormatError(
                f"{self.path}: no analog channel {label!r}{did_you_mean(label, self.labels)} "
                f"(ANALOG:LABELS: {', '.join(self.labels) or 'none'})"
            )
        found = [str(k + 1) for k, name in enumerate(self.labels) if name == label]
        if len(found) > 1:
            at = f"{', '.join(found[:-1])} and {found[-1]}"
            raise SessionFormatError(f"{self.path}: ANALOG:LABELS has {label!r} at channels {at}")
        return self.channel(self.labels.index(label))

    def channel(self, index: int) -> NDArray[np.float64]:
        """The analog channel ``index`` (0-based), every value finite.

        Raises
        ------
        SessionFormatError
            Naming the file, the channel's number and label, and the first sample (1-based)
            that is NaN or infinite.
        """
        values = self.analogs[index]
        finite = np.isfinite(values)
        if not finite.all():
            i = int(np.argmin(finite))
            raise SessionFormatError(
                f"{self.path}: analog channel {index + 1} {self.labels[index]!r}, sample "
                f"{i + 1}: value {values[i]}; expected a finite number"
            )
        return values

    def plate(self, number: int) -> C3DPlate:
        """Force platform ``number`` (1-based)."""
        if not 1 <= number <= len(self.plates):
            raise SessionFormatError(
                f"{self.path}: no force platform {number}; FORCE_PLATFORM:USED = {len(self.plates)}"
            )
        return self.plates[number - 1]


@dataclass(frozen=True)
class GlobalLoad:
    """A plate's load in the file's global frame: GRF (plate on body), N, shape (3, n); COP on
    the plate surface, m, shape (3, n), NaN where unloaded; free moment about the upward
    vertical (plate on body), N·m, shape (n,)."""

    grf: NDArray[np.float64]
    cop: NDArray[np.float64]
    free_moment: NDArray[np.float64]


# --- reading --------------------------------------------------------------------------------------


def _timeout(path: Path) -> float:
    try:
        size = path.stat().st_size
    except OSError:
        size = 0
    return 30.0 + size / 1e6  # ezc3d reads ~50 MB/s; a hang is far beyond this


def read_c3d_files(
    paths: Sequence[str | Path], *, workers: int = 2, lenient: bool = False
) -> list[C3DFile]:
    """Read C3D files (in worker processes; see the module docstring).

    Parameters
    ----------
    paths : sequence of str or Path
        The files.
    workers : int
        Worker processes reading them.
    lenient : bool
        Note what keeps a file's parameters from being read (the analog rate, ``POINT:UNITS``,
        the force platforms, the events) in :attr:`C3DFile.problems` instead of raising, and
        leave out what it concerns (``anklelab inspect`` shows such files).

    Raises
    ------
    SessionFormatError
        Naming the file and the parameter for the first file that is missing, malformed or
        (unless ``lenient``) describes its force platforms inconsistently.
    """
    files = [Path(p) for p in paths]
    for path in files:
        if not path.is_file():
            raise SessionFormatError(f"{path}: no such file")
    try:
        loaded = map_isolated(_WORKER, "load", files, workers=workers, timeout_s=_timeout)
    except IsolatedFailure as exc:
        raise SessionFormatError(
            f"{exc.item}: cannot read as C3D: {exc.reason} (the file is corrupt)"
        ) from None
    except ValueError as exc:  # the worker's report of a malformed file
        raise SessionFormatError(str(exc)) from None
    return [
        _build(path, data, [] if lenient else None)
        for path, data in zip(files, loaded, strict=True)
    ]


def read_c3d(path: str | Path, *, lenient: bool = False) -> C3DFile:
    """Read one C3D file (see :func:`read_c3d_files`)."""
    return read_c3d_files([path], workers=1, lenient=lenient)[0]


# --- interpreting the parameters ------------------------------------------------------------------


def _param(path: Path, params: Mapping[str, Any], group: str, name: str) -> Any:
    try:
        return params[group][name]
    except KeyError:
        raise SessionFormatError(f"{path}: parameter {group}:{name} is missing") from None


def _text_list(path: Path, params: Mapping[str, Any], group: str, name: str) -> list[str]:
    """A text parameter with its continuations (``LABELS``, ``LABELS2``...)."""
    values: list[str] = []
    for key in [name, *(f"{name}{i}" for i in range(2, 100))]:
        value = params.get(group, {}).get(key)
        if value is None:
            break
        values += [str(v) for v in value] if isinstance(value, list) else []
    return values


def _length_scale(path: Path, params: Mapping[str, Any]) -> float:
    units = _text_list(path, params, "POINT", "UNITS")
    if not units or not units[0]:
        return 1.0
    found = read_unit(units[0])
    if found is None or found[0] != "length":
        raise SessionFormatError(
            f"{path}: POINT:UNITS = {units[0]!r}; expected one of {', '.join(UNITS['length'])}"
        )
    return UNITS["length"][found[1]]


def _numbers(path: Path, params: Mapping[str, Any], name: str, shape: tuple[int, ...]) -> NDArray:
    """``FORCE_PLATFORM:name`` as floats, checked to hold at least ``shape`` (last: plates)."""
    value = np.asarray(_param(path, params, "FORCE_PLATFORM", name))
    if (
        value.dtype.kind not in "biuf"
        or value.ndim != len(shape)
        or any(have < need for have, need in zip(value.shape, shape, strict=True))
    ):
        raise SessionFormatError(
            f"{path}: FORCE_PLATFORM:{name} has shape {value.shape}; expected numbers of shape "
            f"{shape} (at least) for {shape[-1]} plate(s)"
        )
    return value.astype(np.float64)


def _plates(path: Path, params: Mapping[str, Any], n_analog: int, scale: float) -> list[C3DPlate]:
    if "FORCE_PLATFORM" not in params:
        return []
    used = np.asarray(params["FORCE_PLATFORM"].get("USED", [0])).ravel()
    n = int(used[0]) if used.size and used.dtype.kind in "biuf" else 0
    if n <= 0:
        return []
    types = _numbers(path, params, "TYPE", (n,)).astype(int)
    channel = _numbers(path, params, "CHANNEL", (6, n)).astype(int)
    origin = _numbers(path, params, "ORIGIN", (3, n))
    corners = _numbers(path, params, "CORNERS", (3, 4, n))
    has_cal = np.asarray(params["FORCE_PLATFORM"].get("CAL_MATRIX", [])).size > 0
    poly = params["FORCE_PLATFORM"].get("FPCOPPOLY")
    plates = []
    for i in range(n):
        kind = int(types[i])
        width = 8 if kind == 3 else 6
        if kind in SUPPORTED_PLATE_TYPES and channel.shape[0] < width:
            raise SessionFormatError(
                f"{path}: plate {i + 1} (type {kind}): FORCE_PLATFORM:CHANNEL has "
                f"{channel.shape[0]} rows; a type-{kind} plate needs {width}"
            )
        indices = tuple(int(c) - 1 for c in channel[:width, i])
        if kind in SUPPORTED_PLATE_TYPES and not all(0 <= c < n_analog for c in indices):
            raise SessionFormatError(
                f"{path}: plate {i + 1} (type {kind}): FORCE_PLATFORM:CHANNEL "
                f"{[c + 1 for c in indices]} names channels outside 1..{n_analog} (ANALOG:USED)"
            )
        cal = None
        if kind == 4:
            if not has_cal:
                raise SessionFormatError(
                    f"{path}: plate {i + 1} (type 4): FORCE_PLATFORM:CAL_MATRIX is missing or "
                    "empty; a type-4 plate needs its 6x6 calibration matrix"
                )
            cal = _numbers(path, params, "CAL_MATRIX", (6, 6, n))[:6, :6, i]
        cop_poly = None
        if kind == 3 and poly is not None and np.asarray(poly).size >= 12 * (i + 1):
            cop_poly = np.asarray(poly, dtype=float).ravel(order="F")[12 * i : 12 * (i + 1)]
        plate = C3DPlate(
            number=i + 1,
            type=kind,
            channels=indices,
            origin_m=origin[:, i] * scale,
            corners_m=corners[:, :4, i].T * scale,
            cal_matrix=cal,
            cop_poly=cop_poly,
        )
        if kind in SUPPORTED_PLATE_TYPES:
            _check_geometry(path, plate, origin[:, i], corners[:, :4, i].T)
        plates.append(plate)
    return plates


def _check_geometry(
    path: Path, plate: C3DPlate, origin: NDArray[np.float64], corners: NDArray[np.float64]
) -> None:
    """``ORIGIN`` finite and ``CORNERS`` spanning a plane (as the file gives them, for the
    message), checked before anything is divided by their lengths."""
    if not np.all(np.isfinite(origin)):
        raise SessionFormatError(
            f"{path}: {plate.name}: FORCE_PLATFORM:ORIGIN [{', '.join(f'{v:g}' for v in origin)}] "
            "is not finite; expected the vector from the plate's origin to its surface centre"
        )
    c = plate.corners_m
    x, y = c[0] - c[1], c[0] - c[3]
    with np.errstate(invalid="ignore", over="ignore"):
        area = float(np.linalg.norm(np.cross(x, y)))
        side = float(np.linalg.norm(x) * np.linalg.norm(y))
    if not (np.all(np.isfinite(c)) and side > 0 and area > 1e-9 * side):
        raise SessionFormatError(
            f"{path}: {plate.name}: FORCE_PLATFORM:CORNERS do not span a plane (corners "
            f"{corners.tolist()})"
        )


def _events(path: Path, params: Mapping[str, Any]) -> list[C3DEvent]:
    group = params.get("EVENT", {})
    labels = _text_list(path, params, "EVENT", "LABELS")
    if not labels:
        return []
    contexts = _text_list(path, params, "EVENT", "CONTEXTS") + [""] * len(labels)
    times = np.asarray(group.get("TIMES", np.empty((2, 0))), dtype=float)
    if times.ndim != 2 or times.shape[0] < 2 or times.shape[1] < len(labels):
        raise SessionFormatError(
            f"{path}: EVENT:TIMES has shape {times.shape}; expected (2, {len(labels)}) "
            "(minutes and seconds of each of EVENT:LABELS)"
        )
    return [
        C3DEvent(label, contexts[i], float(60.0 * times[0, i] + times[1, i]))
        for i, label in enumerate(labels)
    ]


def _check_rate(path: Path, rate: float, n_channels: int) -> None:
    if n_channels and not (math.isfinite(rate) and rate > 0):
        raise SessionFormatError(f"{path}: analog rate {rate!r} Hz; expected a rate > 0")


def _build(path: Path, data: Mapping[str, Any], problems: list[str] | None = None) -> C3DFile:
    """The file's contents interpreted; with ``problems``, a parameter that cannot be read is
    noted there (the file's name left out) and what it concerns left out, instead of raised."""

    def noted(read: Callable[[], T], fallback: T) -> T:
        if problems is None:
            return read()
        try:
            return read()
        except SessionFormatError as exc:
            problems.append(str(exc).removeprefix(f"{path}: "))
            return fallback

    params = data["parameters"]
    analogs = data["analogs"]
    rate = data["analog_rate_hz"]
    noted(lambda: _check_rate(path, rate, analogs.shape[0]), None)
    labels = _text_list(path, params, "ANALOG", "LABELS")[: analogs.shape[0]]
    labels += [f"channel_{i + 1}" for i in range(len(labels), analogs.shape[0])]
    units = _text_list(path, params, "ANALOG", "UNITS")[: analogs.shape[0]]
    units += [""] * (analogs.shape[0] - len(units))
    scale = noted(lambda: _length_scale(path, params), math.nan)
    plates: list[C3DPlate] = []
    if math.isfinite(scale):  # else the plates' lengths are in an unknown unit
        plates = noted(lambda: _plates(path, params, analogs.shape[0], scale), [])
    return C3DFile(
        path=path,
        analog_rate_hz=rate,
        point_rate_hz=data["point_rate_hz"],
        start_s=data["first_analog"] / rate if rate > 0 else 0.0,
        labels=tuple(labels),
        units=tuple(units),
        analogs=analogs,
        length_scale=scale,
        plates=tuple(plates),
        events=tuple(noted(lambda: _events(path, params), [])),
        parameters=params,
        problems=tuple(problems or ()),
    )


# --- force platforms ------------------------------------------------------------------------------


def _unit_factor(c3d: C3DFile, plate: C3DPlate, channel: int, moment: bool) -> float:
    unit = c3d.units[channel]
    label = c3d.labels[channel]
    if not unit.strip():
        return c3d.length_scale if moment else 1.0
    found = read_unit(unit)
    if not moment:
        if found == ("force", "N"):
            return 1.0
        raise SessionFormatError(
            f"{c3d.path}: {plate.name}: channel {label!r} has ANALOG:UNITS {unit!r}; expected N"
        )
    if found is None or found[0] != "moment":
        raise SessionFormatError(
            f"{c3d.path}: {plate.name}: channel {label!r} has ANALOG:UNITS {unit!r}; expected "
            "N·m or N·mm (Nm, Nmm)"
        )
    return UNITS["moment"][found[1]]


def plate_wrench(
    c3d: C3DFile, plate: C3DPlate
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """A plate's load on itself in plate coordinates (z down), SI units.

    Returns
    -------
    force : ndarray, shape (3, n)
        Force of the load on the plate, N.
    moment : ndarray, shape (3, n)
        Its moment about the plate's origin (type 2, 4) or sensor-plane centre (type 3), N·m.
    to_surface : ndarray, shape (3,)
        Vector from that point to the centre of the plate surface, plate coordinates, m (z <= 0).

    Raises
    ------
    SessionFormatError
        The plate's type is not 2, 3 or 4, or a channel's unit is not a force or moment unit.
    """
    if plate.type not in SUPPORTED_PLATE_TYPES:
        raise SessionFormatError(
            f"{c3d.path}: {plate.name}: unsupported force-platform type {plate.type}; "
            f"expected type {', '.join(map(str, SUPPORTED_PLATE_TYPES))}"
        )
    raw = np.stack([c3d.channel(k) for k in plate.channels])
    origin = plate.origin_m
    if plate.type == 3:
        a, b, az0 = abs(origin[0]), abs(origin[1]), -abs(origin[2])
        for k in plate.channels:
            _unit_factor(c3d, plate, k, moment=False)
        wrench = kistler_matrix(a, b) @ raw
        return wrench[:3], wrench[3:], np.array([0.0, 0.0, az0])
    if plate.type == 4:
        assert plate.cal_matrix is not None
        wrench = plate.cal_matrix @ raw
        wrench[3:] *= c3d.length_scale
    else:
        factors = [_unit_factor(c3d, plate, k, i >= 3) for i, k in enumerate(plate.channels)]
        wrench = raw * np.array(factors)[:, None]
    to_surface = origin if origin[2] <= 0 else -origin
    return wrench[:3], wrench[3:], to_surface


def plate_load(c3d: C3DFile, plate: C3DPlate, *, min_force_n: float = 10.0) -> GlobalLoad:
    """GRF, COP and free moment of ``plate`` in the global frame (see the module docstring).

    Parameters
    ----------
    c3d : C3DFile
    plate : C3DPlate
    min_force_n : float
        The COP (and the free moment) are NaN where the magnitude of the force normal to the
        plate is below this, N.
    """
    force, moment, to_surface = plate_wrench(c3d, plate)
    surface = moment + np.cross(force, to_surface, axis=0)  # moment about the surface centre
    x = cop_from_moment(-surface[1], force[2], min_fz_n=min_force_n)
    y = cop_from_moment(surface[0], force[2], min_fz_n=min_force_n)
    if plate.cop_poly is not None:
        # the manufacturer's correction acts on the COP in the file's units
        p = plate.cop_poly
        u, v = x / c3d.length_scale, y / c3d.length_scale
        dx = (p[0] * v**4 + p[1] * v**2 + p[2]) * u**3 + (p[3] * v**4 + p[4] * v**2 + p[5]) * u
        dy = (p[6] * u**4 + p[7] * u**2 + p[8]) * v**3 + (p[9] * u**4 + p[10] * u**2 + p[11]) * v
        x, y = x - dx * c3d.length_scale, y - dy * c3d.length_scale
    free = surface[2] + force[0] * y - force[1] * x
    axes = plate.axes()
    cop = axes[:, :2] @ np.stack([x, y]) + plate.centre_m[:, None]
    return GlobalLoad(grf=-(axes @ force), cop=cop, free_moment=free)
