"""Force-plate conventions: 8-channel Kistler signals, resultants, COP, GRF and ankle torque.

Raw channels follow the manufacturer's convention (Kistler 9260-type): forces applied **by the
load to the plate**, plate frame x anterior, y to the right, z down; sensor 1 at (+a, +b),
2 at (-a, +b), 3 at (-a, -b), 4 at (+a, -b). Resultants are linear in the channels,
``r = A @ c`` with ``r = (Fx, Fy, Fz, Mx, My, Mz)`` about the centre of the sensor plane, so the
forward map and its inverse (the minimum-norm channels that produce a given load, used by the
digital twin) are both a single matrix product, vectorised over samples and trials.

The lab frame for analysis has x anterior (walking direction) and z up, and the ground reaction
force is the force of the plate on the foot; ``anterior_axis`` says which plate axis points in
the walking direction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from anklelab._params import Parameters
from anklelab.errors import EventNotFoundError, ParameterError

__all__ = [
    "CHANNELS",
    "PlateGeometry",
    "Resultants",
    "SagittalLoad",
    "ankle_torque",
    "channels_from_load",
    "cop_from_moment",
    "resultants",
    "sagittal_load",
    "sagittal_matrix",
]

CHANNELS = ("fx12", "fx34", "fy14", "fy23", "fz1", "fz2", "fz3", "fz4")
AnteriorAxis = Literal["+x", "-x", "+y", "-y"]


class PlateGeometry(Parameters):
    """Where the plate's sensors sit and how the plate is mounted.

    Attributes
    ----------
    a_m, b_m : float
        Sensor offsets from the plate centre along x and y, m (> 0).
    az0_m : float
        Offset of the plate surface from the sensor plane along z, m (< 0: surface above it).
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Plate axis that points in the walking direction.
    """

    a_m: float = Field(gt=0)
    b_m: float = Field(gt=0)
    az0_m: float = Field(lt=0)
    anterior_axis: AnteriorAxis = "+x"

    def matrix(self) -> NDArray[np.float64]:
        """The 6x8 map from channels (:data:`CHANNELS` order) to (Fx, Fy, Fz, Mx, My, Mz)."""
        a, b = self.a_m, self.b_m
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


def resultants(
    channels: ArrayLike, geometry: PlateGeometry, *, min_fz_n: float = 1.0, axis: int = -2
) -> Resultants:
    """Forces, moments and centre of pressure from the 8 channels.

    Parameters
    ----------
    channels : array_like, shape (..., 8, ...)
        Channel values in :data:`CHANNELS` order along ``axis``, N.
    geometry : PlateGeometry
        Sensor offsets of the plate.
    min_fz_n : float
        Below this vertical force the COP is undefined and returned as NaN, N.
    axis : int
        Axis of ``channels`` that holds the 8 channels (default -2, as in
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
    if c.shape[-1] != len(CHANNELS):
        raise ParameterError(
            f"channels: expected {len(CHANNELS)} channels on axis {axis}, got {c.shape[-1]}"
        )
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
    geometry: PlateGeometry,
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
    geometry : PlateGeometry
        Sensor offsets of the plate.
    free_moment_nm : array_like
        Free moment about the vertical axis, N·m, broadcast against the samples.
    axis : int
        Axis of ``force``/``cop`` holding the components; the channels come back on that axis.

    Returns
    -------
    ndarray
        Channels in :data:`CHANNELS` order on ``axis``, N. :func:`resultants` recovers the load.

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


def sagittal_matrix(geometry: PlateGeometry) -> NDArray[np.float64]:
    """The (3, 8) map from channels to ``(grf_x, grf_z, grf_z * cop_x)`` in the walking frame.

    All three are linear in the channels (the COP times the vertical force is a moment), so a
    trial's sagittal load can be filtered and corrected as three signals and the COP taken once,
    with :func:`cop_from_moment`, where it is needed. The rows follow :func:`resultants` and
    :func:`sagittal_load` for the plate's ``anterior_axis``.

    Examples
    --------
    >>> g = PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045, anterior_axis="-y")
    >>> c = channels_from_load([0.0, -20.0, 700.0], [0.01, -0.06], g, axis=0)
    >>> grf_x, grf_z, moment = sagittal_matrix(g) @ c
    >>> [round(float(v), 9) for v in (grf_x, grf_z, moment / grf_z)]
    [-20.0, 700.0, 0.06]
    """
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
