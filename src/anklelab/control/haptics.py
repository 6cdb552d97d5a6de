"""Haptic rendering on the platform: a virtual spring-damper about a (terrain-given) angle.

The virtual environment pulls the foot toward an equilibrium angle ``theta_eq(t)`` with a
stiffness ``K`` and damping ``B``. ``theta_eq`` is constant for a plain spring-damper or follows
the slope under the foot as a user walks over a virtual terrain (uphill dorsiflexes).

Two renderings are offered:

- **impedance** (:func:`impedance_torque`): the motor applies ``-K (theta - theta_eq) - B w`` on
  top of gravity (and friction) compensation: no force sensing needed, but the device's own
  inertia and uncompensated friction are felt;
- **admittance** (:func:`admittance_update`): the human torque estimated by the disturbance
  observer drives the virtual dynamics ``J_v w_v' = T_hat - B w_v - K (theta_v - theta_eq)``,
  whose state becomes the position controller's reference: the user feels ``J_v`` instead of
  the device and friction is hidden behind the position loop.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from anklelab._params import Parameters
from anklelab.errors import ParameterError

__all__ = [
    "EnvironmentConstants",
    "TerrainProfile",
    "VirtualEnvironment",
    "admittance_update",
    "impedance_torque",
]


class VirtualEnvironment(Parameters):
    """The rendered environment.

    Attributes
    ----------
    stiffness_nm_per_rad : float
        Virtual stiffness about the equilibrium angle.
    damping_nms_per_rad : float
        Virtual damping.
    inertia_kgm2 : float
        Virtual inertia (admittance rendering only).
    angle_limit_rad : float
        The virtual angle is held within ``±angle_limit_rad`` (the workspace).
    """

    stiffness_nm_per_rad: float = Field(ge=0)
    damping_nms_per_rad: float = Field(ge=0)
    inertia_kgm2: float = Field(default=0.2, gt=0)
    angle_limit_rad: float = Field(default=0.6, gt=0)

    def constants(self) -> EnvironmentConstants:
        """The compiled form."""
        return EnvironmentConstants(
            self.stiffness_nm_per_rad,
            self.damping_nms_per_rad,
            self.inertia_kgm2,
            self.angle_limit_rad,
        )


class EnvironmentConstants(NamedTuple):
    """Compiled form of :class:`VirtualEnvironment`."""

    stiffness: float
    damping: float
    inertia: float
    angle_limit: float


@dataclass(frozen=True)
class TerrainProfile:
    """Ground height along the virtual path.

    Attributes
    ----------
    distance_m, height_m : ndarray
        Samples of the profile (distance strictly increasing).

    Examples
    --------
    >>> ramp = TerrainProfile(np.arange(5.0), np.array([0.0, 0.0, 0.0, 0.1, 0.2]))
    >>> np.degrees(ramp.slope_angle([0.5, 3.5])).round(2)
    array([0.  , 5.71])
    """

    distance_m: NDArray[np.float64]
    height_m: NDArray[np.float64]

    def __post_init__(self) -> None:
        d, h = np.asarray(self.distance_m, float), np.asarray(self.height_m, float)
        if d.ndim != 1 or d.shape != h.shape or d.size < 2:
            raise ParameterError("distance_m and height_m must be 1-D arrays of equal length >= 2")
        if not np.all(np.diff(d) > 0) or not np.all(np.isfinite(h)):
            raise ParameterError("distance_m must be strictly increasing and height_m finite")

    @classmethod
    def hills(
        cls, length_m: float = 20.0, *, seed: int | np.random.Generator = 0
    ) -> TerrainProfile:
        """Gentle random hills: slopes mostly within ±15 degrees, smooth at 1 m scale."""
        rng = np.random.default_rng(seed)
        d = np.linspace(0.0, length_m, round(length_m * 20) + 1)
        waves = rng.uniform(2.0, 6.0, 4)
        phases = rng.uniform(0, 2 * np.pi, 4)
        h = (0.015 * waves * np.sin(2 * np.pi * d[:, None] / waves + phases)).sum(axis=1)
        return cls(d, h)

    def slope_angle(self, distance_m: ArrayLike) -> NDArray[np.float64]:
        """Ground slope (rad, uphill positive) at ``distance_m`` along the path.

        The profile's gradient (central differences) is interpolated linearly and held beyond
        the ends.
        """
        gradient = np.gradient(self.height_m, self.distance_m)
        return np.arctan(np.interp(distance_m, self.distance_m, gradient))

    def equilibrium(self, duration_s: float, fs: float, speed_m_s: float) -> NDArray[np.float64]:
        """Platform equilibrium angle (rad) for a walk at ``speed_m_s``, sampled at ``fs`` Hz."""
        return self.slope_angle(speed_m_s * np.arange(round(duration_s * fs)) / fs)


@njit(cache=True)
def impedance_torque(
    env: EnvironmentConstants, angle: float, speed: float, equilibrium: float
) -> float:
    """Virtual spring-damper torque on the foot, N·m."""
    return -env.stiffness * (angle - equilibrium) - env.damping * speed


@njit(cache=True)
def admittance_update(
    env: EnvironmentConstants,
    state: NDArray[np.float64],
    human_torque: float,
    equilibrium: float,
    dt: float,
) -> None:
    """Advance the virtual dynamics ``state = [theta_v, w_v]`` in place by ``dt`` seconds.

    Semi-implicit Euler; the angle is held within the environment's limit (the speed is
    zeroed there).
    """
    torque = human_torque + impedance_torque(env, state[0], state[1], equilibrium)
    state[1] += dt * torque / env.inertia
    state[0] += dt * state[1]
    if abs(state[0]) > env.angle_limit:
        state[0] = min(max(state[0], -env.angle_limit), env.angle_limit)
        state[1] = 0.0
