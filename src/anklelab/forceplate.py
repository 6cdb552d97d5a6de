"""Force-plate conventions: plate types, resultants, COP, GRF and ankle torque.

A session's force plate is one of three **types** (``[force_plate] type`` in ``session.toml``):

- ``kistler8`` (:class:`PlateGeometry`, the default): the 8 Kistler channels :data:`CHANNELS`.
  Raw channels follow the manufacturer's convention (Kistler 9260-type): forces applied **by
  the load to the plate**, plate frame x anterior, y to the right, z down; sensor 1 at
  (+a, +b), 2 at (-a, +b), 3 at (-a, -b), 4 at (+a, -b).
- ``six_axis`` (:class:`SixAxisPlate`): the six components :data:`SIX_AXIS_CHANNELS`
  (Fx, Fy, Fz, Mx, My, Mz; AMTI, Bertec) in the same convention (load on plate, z down), the
  moments taken about a declared origin below the surface.
- ``grf_cop`` (:class:`GrfCopPlate`): ground reaction force and centre of pressure already
  reduced to a lab frame with z up (:data:`GRF_COP_CHANNELS`; GRF = plate on body, COP empty
  where the plate carries too little to define it).

For the linear types the resultants are linear in the channels, ``r = A @ c`` with
``r = (Fx, Fy, Fz, Mx, My, Mz)``, so the forward map and its inverse (the minimum-norm channels
that produce a given load, used by the digital twin) are both one matrix product, vectorised
over samples and trials.

The walking analysis uses three **sagittal signals** in the walking frame (x anterior, z up;
GRF = plate on foot): ``(grf_x, grf_z, grf_z * cop_x)``. Every plate type maps its recording to
them in two steps, so the analysis never needs to know the type: :meth:`load_signals` gives
the signals that are linear in the load (the channels themselves for the linear types; the
sagittal signals, computed per sample, for ``grf_cop``), and :meth:`sagittal_matrix` the
``(3, n_signals)`` matrix from those to the sagittal signals. The platform filters model the
load signals; ``anterior_axis`` says which plate (or lab) axis points in the walking direction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, field_validator

from anklelab._params import Parameters
from anklelab.errors import EventNotFoundError, ParameterError

__all__ = [
    "CHANNELS",
    "GRF_COP_CHANNELS",
    "PLATE_TYPES",
    "SAGITTAL_SIGNALS",
    "SIX_AXIS_CHANNELS",
    "ForcePlate",
    "GrfCopPlate",
    "LabLoad",
    "PlateGeometry",
    "Resultants",
    "SagittalLoad",
    "SixAxisPlate",
    "ankle_torque",
    "channels_from_load",
    "cop_from_moment",
    "kistler_matrix",
    "plate_class",
    "resultants",
    "sagittal_load",
    "sagittal_matrix",
]

CHANNELS = ("fx12", "fx34", "fy14", "fy23", "fz1", "fz2", "fz3", "fz4")
"""The ``kistler8`` channels, N."""
SIX_AXIS_CHANNELS = ("fx", "fy", "fz", "mx", "my", "mz")
"""The ``six_axis`` channels: forces (N) and moments about the plate's origin (N·m)."""
GRF_COP_CHANNELS = ("grf_x_n", "grf_y_n", "grf_z_n", "cop_x_m", "cop_y_m")
"""The ``grf_cop`` channels: lab-frame GRF (N) and COP (m); the COP may be NaN (empty)."""
SAGITTAL_SIGNALS = ("grf_x", "grf_z", "grf_z_cop_x")
"""The walking analysis's signals: anterior and vertical GRF (N) and ``grf_z * cop_x`` (N·m)."""
AnteriorAxis = Literal["+x", "-x", "+y", "-y"]
DEFAULT_MIN_FZ_N = 1.0
"""Below this vertical force the COP is undefined (returned as NaN), N."""


def kistler_matrix(a_m: float, b_m: float) -> NDArray[np.float64]:
    """The 6x8 map from the 8 Kistler channels (:data:`CHANNELS` order) to (Fx, Fy, Fz, Mx, My,
    Mz) about the centre of the sensor plane, for sensor offsets ``a_m``, ``b_m`` (m)."""
    a, b = a_m, b_m
    return np.array(
        [
            [1, 1, 0, 0, 0, 0, 0, 0],
            [0, 0, 1, 1, 0, 0, 0, 0],
            [0, 0, 0, 0, 1, 1, 1, 1],
            [0, 0, 0, 0, b, b, -b, -b],
            [0, 0, 0, 0, -a, a, a, -a],
            [-b, b, a, -a, 0, 0, 0, 0],
        ],
        dtype=float,
    )


class _LinearPlate(Parameters):
    """A plate whose resultants are a linear map of its channels (``kistler8``, ``six_axis``)."""

    type: ClassVar[str]
    channels: ClassVar[tuple[str, ...]]
    nullable: ClassVar[tuple[str, ...]] = ()
    if TYPE_CHECKING:  # fields of the subclasses, declared there (in their own order)
        anterior_axis: AnteriorAxis
        az0_m: float

    def matrix(self) -> NDArray[np.float64]:
        """The ``(6, n_channels)`` map from the channels to (Fx, Fy, Fz, Mx, My, Mz)."""
        raise NotImplementedError

    @property
    def signals(self) -> tuple[str, ...]:
        """Names of :meth:`load_signals`: the plate's own channels."""
        return self.channels

    def load_signals(self, data: ArrayLike, *, axis: int = -2) -> NDArray[np.float64]:
        """The signals that are linear in the load: the channels themselves."""
        data = np.asarray(data, dtype=float)
        _check_count(data.shape[axis], self, axis)
        return data

    def sagittal_matrix(self) -> NDArray[np.float64]:
        """The ``(3, n_channels)`` map to :data:`SAGITTAL_SIGNALS` (:func:`sagittal_matrix`)."""
        return sagittal_matrix(self)

    def lab_load(
        self, data: ArrayLike, *, min_fz_n: float = DEFAULT_MIN_FZ_N, axis: int = -2
    ) -> LabLoad:
        """GRF, COP and free moment in the walking frame (origin at the plate surface's
        centre for ``kistler8``, above the moment origin for ``six_axis``)."""
        res = resultants(data, self, min_fz_n=min_fz_n, axis=axis)
        rotation = _walking_rotation(self.anterior_axis, z_down=True)
        force = np.stack([res.fx, res.fy, res.fz], axis=-1)
        cop = np.stack([res.ax, res.ay, np.zeros_like(res.ax)], axis=-1)
        grf = -force @ rotation.T
        position = cop @ rotation.T
        free = res.mz - res.ax * res.fy + res.ay * res.fx
        grf_x, grf_y, grf_z = np.moveaxis(grf, -1, 0)
        cop_x, cop_y = np.moveaxis(position, -1, 0)[:2]
        return LabLoad(grf_x, grf_y, grf_z, cop_x, cop_y, free)


class PlateGeometry(_LinearPlate):
    """The ``kistler8`` plate: where its sensors sit and how it is mounted.

    Attributes
    ----------
    a_m, b_m : float
        Sensor offsets from the plate centre along x and y, m (> 0).
    az0_m : float
        Offset of the plate surface from the sensor plane along z, m (< 0: surface above it).
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Plate axis that points in the walking direction.
    """

    type: ClassVar[str] = "kistler8"
    channels: ClassVar[tuple[str, ...]] = CHANNELS
    a_m: float = Field(gt=0)
    b_m: float = Field(gt=0)
    az0_m: float = Field(lt=0)
    anterior_axis: AnteriorAxis = "+x"

    def matrix(self) -> NDArray[np.float64]:
        """The 6x8 map from channels (:data:`CHANNELS` order) to (Fx, Fy, Fz, Mx, My, Mz)."""
        return kistler_matrix(self.a_m, self.b_m)


class SixAxisPlate(_LinearPlate):
    """The ``six_axis`` plate: Fx..Mz (load on plate, z down) about a declared origin.

    Attributes
    ----------
    az0_m : float
        z of the plate surface relative to the point the moments are taken about, m (<= 0:
        plate z points down, so a surface above the origin is negative; 0 when the moments are
        already about the surface).
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Plate axis that points in the walking direction.
    """

    type: ClassVar[str] = "six_axis"
    channels: ClassVar[tuple[str, ...]] = SIX_AXIS_CHANNELS
    az0_m: float = Field(le=0)
    anterior_axis: AnteriorAxis = "+x"

    def matrix(self) -> NDArray[np.float64]:
        """The identity: the channels are the resultants."""
        return np.eye(6)


class GrfCopPlate(Parameters):
    """The ``grf_cop`` plate: GRF and COP already in a lab frame with z up.

    Columns :data:`GRF_COP_CHANNELS`: ``grf_*_n`` is the force of the plate on the body, N;
    ``cop_*_m`` the centre of pressure, m, NaN (an empty cell) where the plate carries too
    little to define it.

    Attributes
    ----------
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Lab axis that points in the walking direction.
    plate_centre_m : (float, float)
        Lab x and y of the centre of the plate surface, m: the walking-frame COP is taken
        relative to it. The analysis does not need it when the calibration trials record the
        COP, but where they leave it empty the platform filters cannot learn the plate's moment,
        which is then taken as zero about this point (see :meth:`load_signals`).
    """

    type: ClassVar[str] = "grf_cop"
    channels: ClassVar[tuple[str, ...]] = GRF_COP_CHANNELS
    nullable: ClassVar[tuple[str, ...]] = ("cop_x_m", "cop_y_m")
    signals: ClassVar[tuple[str, ...]] = SAGITTAL_SIGNALS
    anterior_axis: AnteriorAxis = "+x"
    plate_centre_m: tuple[float, float] = (0.0, 0.0)

    @field_validator("plate_centre_m", mode="before")
    @classmethod
    def _pair(cls, value: object) -> object:
        """Accept any sequence of two numbers (TOML array, HDF5 or MATLAB vector)."""
        if isinstance(value, list | np.ndarray):
            return tuple(float(v) if isinstance(v, np.floating) else v for v in list(value))
        return value

    def load_signals(self, data: ArrayLike, *, axis: int = -2) -> NDArray[np.float64]:
        """The sagittal signals, per sample: ``grf_z * cop_x`` is 0 where the COP is empty.

        ``cop_x`` is relative to ``plate_centre_m``. The moment is linear in the load wherever
        the COP is recorded, so the platform filters model and remove it there; where the COP is
        empty (an unloaded plate in processed exports) the moment is taken as zero about the
        plate's centre, which is where the plate's own moment is smallest.

        Returns an array with :data:`SAGITTAL_SIGNALS` on ``axis``.
        """
        c = np.moveaxis(np.asarray(data, dtype=float), axis, 0)
        _check_count(c.shape[0], self, axis)
        load = self.lab_load(c, axis=0)
        moment = np.where(np.isfinite(load.cop_x), load.grf_z * load.cop_x, 0.0)
        return np.moveaxis(np.stack([load.grf_x, load.grf_z, moment]), 0, axis)

    def sagittal_matrix(self) -> NDArray[np.float64]:
        """The identity: :meth:`load_signals` are already the sagittal signals."""
        return sagittal_matrix(self)

    def lab_load(
        self, data: ArrayLike, *, min_fz_n: float = DEFAULT_MIN_FZ_N, axis: int = -2
    ) -> LabLoad:
        """GRF and COP (relative to ``plate_centre_m``) turned into the walking frame; the free
        moment is unknown (NaN).

        ``min_fz_n`` is accepted for symmetry with the linear plates and ignored: the COP is
        as recorded.
        """
        c = np.moveaxis(np.asarray(data, dtype=float), axis, -1)
        _check_count(c.shape[-1], self, axis)
        rotation = _walking_rotation(self.anterior_axis, z_down=False)
        grf = c[..., :3] @ rotation.T
        cop = c[..., 3:5] - np.asarray(self.plate_centre_m)
        cop = np.concatenate([cop, np.zeros_like(c[..., :1])], axis=-1) @ rotation.T
        grf_x, grf_y, grf_z = np.moveaxis(grf, -1, 0)
        cop_x, cop_y = np.moveaxis(cop, -1, 0)[:2]
        return LabLoad(grf_x, grf_y, grf_z, cop_x, cop_y, np.full(c.shape[:-1], np.nan))


ForcePlate = PlateGeometry | SixAxisPlate | GrfCopPlate
"""Any plate type."""
_PLATE_CLASSES: dict[str, type[ForcePlate]] = {
    cls.type: cls for cls in (PlateGeometry, SixAxisPlate, GrfCopPlate)
}
PLATE_TYPES = tuple(_PLATE_CLASSES)
"""The names of the plate types: ``kistler8`` (default), ``six_axis``, ``grf_cop``."""


def plate_class(type_name: str) -> type[ForcePlate]:
    """The class of a plate type (``"kistler8"`` -> :class:`PlateGeometry`).

    Raises
    ------
    ParameterError
        Naming the types when ``type_name`` is none of them.
    """
    try:
        return _PLATE_CLASSES[type_name]
    except (KeyError, TypeError):
        raise ParameterError(
            f"type: expected one of {', '.join(PLATE_TYPES)}, got {type_name!r}"
        ) from None


def _check_count(n: int, plate: _LinearPlate | GrfCopPlate, axis: int) -> None:
    if n != len(plate.channels):
        raise ParameterError(
            f"channels: expected {len(plate.channels)} channels on axis {axis} for a "
            f"{plate.type} plate ({', '.join(plate.channels)}), got {n}"
        )


_UNIT = {"x": np.array([1.0, 0.0, 0.0]), "y": np.array([0.0, 1.0, 0.0])}


def _walking_rotation(anterior_axis: AnteriorAxis, *, z_down: bool) -> NDArray[np.float64]:
    """Rows: the walking frame's axes (x anterior, y left, z up) in the source frame."""
    forward = _UNIT[anterior_axis[1]] * (1.0 if anterior_axis[0] == "+" else -1.0)
    up = np.array([0.0, 0.0, -1.0 if z_down else 1.0])
    return np.stack([forward, np.cross(up, forward), up])


@dataclass(frozen=True)
class Resultants:
    """Plate-frame resultants (load on plate, z down), N and N·m; COP ``ax, ay`` in m."""

    fx: NDArray[np.float64]
    fy: NDArray[np.float64]
    fz: NDArray[np.float64]
    mx: NDArray[np.float64]
    my: NDArray[np.float64]
    mz: NDArray[np.float64]
    ax: NDArray[np.float64]
    ay: NDArray[np.float64]


@dataclass(frozen=True)
class SagittalLoad:
    """Lab-frame sagittal GRF (plate on foot; x anterior, z up), N, and anterior COP, m."""

    grf_x: NDArray[np.float64]
    grf_z: NDArray[np.float64]
    cop_x: NDArray[np.float64]


@dataclass(frozen=True)
class LabLoad:
    """GRF (plate on body), N, COP, m, and free moment about the upward vertical through the
    COP (plate on body), N·m, in the walking frame: x anterior, y left, z up. The COP and the
    free moment are NaN where the COP is undefined."""

    grf_x: NDArray[np.float64]
    grf_y: NDArray[np.float64]
    grf_z: NDArray[np.float64]
    cop_x: NDArray[np.float64]
    cop_y: NDArray[np.float64]
    free_moment: NDArray[np.float64]


def resultants(
    channels: ArrayLike,
    geometry: _LinearPlate,
    *,
    min_fz_n: float = DEFAULT_MIN_FZ_N,
    axis: int = -2,
) -> Resultants:
    """Forces, moments and centre of pressure from a linear plate's channels.

    Parameters
    ----------
    channels : array_like, shape (..., n_channels, ...)
        Channel values in ``geometry.channels`` order along ``axis`` (8 for ``kistler8``,
        6 for ``six_axis``), N and N·m.
    geometry : PlateGeometry or SixAxisPlate
        The plate: sensor offsets, or the surface's offset from the moment origin.
    min_fz_n : float
        Below this vertical force the COP is undefined and returned as NaN, N.
    axis : int
        Axis of ``channels`` that holds the channels (default -2, as in
        ``(n_trials, n_channels, n_times)``).

    Returns
    -------
    Resultants
        Each field has the shape of ``channels`` without ``axis``.

    Examples
    --------
    A 400 N load straight over sensor 1 puts the COP at (+a, +b):

    >>> g = PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045)
    >>> r = resultants([0, 0, 0, 0, 400.0, 0, 0, 0], g, axis=0)
    >>> float(r.ax), float(r.ay)
    (0.12, 0.2)
    """
    c = np.moveaxis(np.asarray(channels, dtype=float), axis, -1)
    _check_count(c.shape[-1], geometry, axis)
    fx, fy, fz, mx, my, mz = np.moveaxis(c @ geometry.matrix().T, -1, 0)
    ax = cop_from_moment(fx * geometry.az0_m - my, fz, min_fz_n=min_fz_n)
    ay = cop_from_moment(fy * geometry.az0_m + mx, fz, min_fz_n=min_fz_n)
    return Resultants(fx, fy, fz, mx, my, mz, ax, ay)


def cop_from_moment(
    moment: ArrayLike, force_z: ArrayLike, *, min_fz_n: float = 1.0
) -> NDArray[np.float64]:
    """Centre of pressure ``moment / force_z``, NaN where ``|force_z| <= min_fz_n``.

    Every COP of the package is computed here: a moment (N·m) about an axis through the origin,
    divided by the vertical force (N), gives the COP coordinate (m) along the perpendicular
    horizontal axis.

    Examples
    --------
    >>> cop_from_moment([35.0, 0.5], [700.0, 0.5]).tolist()
    [0.05, nan]
    """
    moment = np.asarray(moment, dtype=float)
    force_z = np.asarray(force_z, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return np.where(np.abs(force_z) > min_fz_n, moment / force_z, np.nan)


def channels_from_load(
    force: ArrayLike,
    cop: ArrayLike,
    geometry: PlateGeometry | SixAxisPlate,
    *,
    free_moment_nm: ArrayLike = 0.0,
    axis: int = -2,
) -> NDArray[np.float64]:
    """Minimum-norm channel values produced by a load applied at a point of the plate surface.

    Parameters
    ----------
    force : array_like, shape (..., 3, ...)
        (Fx, Fy, Fz) applied by the load to the plate in the plate frame (z down), N.
    cop : array_like, shape (..., 2, ...)
        (ax, ay) point of application on the plate surface, m.
    geometry : PlateGeometry or SixAxisPlate
        The plate.
    free_moment_nm : array_like
        Free moment about the vertical axis, N·m, broadcast against the samples.
    axis : int
        Axis of ``force``/``cop`` holding the components; the channels come back on that axis.

    Returns
    -------
    ndarray
        Channels in ``geometry.channels`` order on ``axis``. :func:`resultants` recovers the
        load.

    Examples
    --------
    >>> g = PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045)
    >>> c = channels_from_load([10.0, 0.0, 700.0], [0.05, -0.02], g, axis=0)
    >>> r = resultants(c, g, axis=0)
    >>> [round(float(v), 9) for v in (r.fx, r.fz, r.ax, r.ay)]
    [10.0, 700.0, 0.05, -0.02]
    """
    f = np.moveaxis(np.asarray(force, dtype=float), axis, -1)
    p = np.moveaxis(np.asarray(cop, dtype=float), axis, -1)
    fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
    x, y, z = p[..., 0], p[..., 1], geometry.az0_m
    load = np.stack(
        np.broadcast_arrays(
            fx,
            fy,
            fz,
            y * fz - z * fy,
            z * fx - x * fz,
            x * fy - y * fx + np.asarray(free_moment_nm),
        ),
        axis=-1,
    )
    channels = load @ np.linalg.pinv(geometry.matrix()).T
    return np.moveaxis(channels, -1, axis)


_ANTERIOR = {
    "+x": ("fx", "ax", 1.0),
    "-x": ("fx", "ax", -1.0),
    "+y": ("fy", "ay", 1.0),
    "-y": ("fy", "ay", -1.0),
}


def sagittal_load(res: Resultants, anterior_axis: AnteriorAxis = "+x") -> SagittalLoad:
    """Lab-frame sagittal ground reaction force and anterior COP from plate resultants.

    Parameters
    ----------
    res : Resultants
        Output of :func:`resultants`.
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Plate axis pointing in the walking direction.

    Returns
    -------
    SagittalLoad
        ``grf_z = Fz`` (plate z is down, GRF is plate on foot), ``grf_x = -F_anterior``,
        ``cop_x`` = COP along the walking direction.
    """
    force_name, cop_name, sign = _ANTERIOR[anterior_axis]
    return SagittalLoad(
        grf_x=-sign * getattr(res, force_name),
        grf_z=res.fz,
        cop_x=sign * getattr(res, cop_name),
    )


def sagittal_matrix(geometry: _LinearPlate | GrfCopPlate) -> NDArray[np.float64]:
    """The ``(3, n_signals)`` map from a plate's load signals to :data:`SAGITTAL_SIGNALS`,
    ``(grf_x, grf_z, grf_z * cop_x)`` in the walking frame.

    For the linear plates the load signals are the channels (``(3, 8)`` for ``kistler8``,
    ``(3, 6)`` for ``six_axis``): all three are linear in the channels (the COP times the
    vertical force is a moment), so a trial's sagittal load can be filtered and corrected as
    three signals and the COP taken once, with :func:`cop_from_moment`, where it is needed. The
    rows follow :func:`resultants` and :func:`sagittal_load` for the plate's ``anterior_axis``.
    A ``grf_cop`` plate's load signals are already the sagittal signals (the identity).

    Examples
    --------
    >>> g = PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045, anterior_axis="-y")
    >>> c = channels_from_load([0.0, -20.0, 700.0], [0.01, -0.06], g, axis=0)
    >>> grf_x, grf_z, moment = sagittal_matrix(g) @ c
    >>> [round(float(v), 9) for v in (grf_x, grf_z, moment / grf_z)]
    [-20.0, 700.0, 0.06]
    """
    if isinstance(geometry, GrfCopPlate):
        return np.eye(3)
    force_name, _, sign = _ANTERIOR[geometry.anterior_axis]
    fx, fy, fz, mx, my, _ = geometry.matrix()
    if force_name == "fx":
        force, moment = fx, geometry.az0_m * fx - my
    else:
        force, moment = fy, geometry.az0_m * fy + mx
    return np.stack([-sign * force, fz, sign * moment])


def ankle_torque(
    load: SagittalLoad,
    heel_contact: int | ArrayLike,
    *,
    heel_to_ankle_m: float,
    ankle_height_m: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Dorsiflexing external ankle moment ``T_a = GRF_z*dx + GRF_x*dz`` (paper 000, eq. 1).

    Parameters
    ----------
    load : SagittalLoad
        GRF and COP, time on the last axis (one trial, or ``(n_trials, n_times)``).
    heel_contact : int or array_like of int
        Sample index of heel contact (one per trial); the COP is zeroed there.
    heel_to_ankle_m : float
        Anterior distance from the heel-contact COP to the ankle centre, m.
    ankle_height_m : float
        Height ``dz`` of the ankle centre above the plate surface, m (> 0).

    Returns
    -------
    torque : ndarray
        Ankle torque, N·m, dorsiflexion positive.
    dx : ndarray
        Lever arm ``(cop_x - cop_x[heel_contact]) - heel_to_ankle_m``, m.

    Examples
    --------
    >>> import numpy as np
    >>> load = SagittalLoad(np.zeros(3), np.full(3, 700.0), np.array([0.3, 0.35, 0.4]))
    >>> t, dx = ankle_torque(load, 0, heel_to_ankle_m=0.04, ankle_height_m=0.08)
    >>> np.round(t, 6).tolist()
    [-28.0, 7.0, 42.0]
    """
    if ankle_height_m <= 0:
        raise ParameterError(f"ankle_height_m: expected > 0, got {ankle_height_m}")
    cop = np.asarray(load.cop_x, dtype=float)
    index = np.asarray(heel_contact)
    if np.any((index < 0) | (index >= cop.shape[-1])):
        raise EventNotFoundError(
            f"heel_contact: index {index} outside the trial (0..{cop.shape[-1] - 1})"
        )
    cop0 = np.take_along_axis(cop, index.reshape((*index.shape, 1)), axis=-1)
    if np.any(np.isnan(cop0)):
        raise EventNotFoundError("heel_contact: COP undefined at heel contact (no vertical load)")
    dx = cop - cop0 - heel_to_ankle_m
    return load.grf_z * dx + load.grf_x * ankle_height_m, dx
