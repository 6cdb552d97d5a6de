"""Haptic rendering on the platform: a virtual spring-damper about a (terrain-given) angle.

The virtual environment pulls the foot toward an equilibrium angle ``theta_eq(t)`` with a
stiffness ``K`` and damping ``B``. ``theta_eq`` is constant for a plain spring-damper or follows
the slope under the foot as a user walks over a virtual terrain (uphill dorsiflexes).

Two renderings are offered:

- **impedance** (:func:`impedance_torque`): the motor applies ``-K (theta - theta_eq) - B w`` on
  top of gravity (and friction) compensation: no force sensing needed, but the device's own
  inertia and uncompensated friction are felt;
- **admittance** (:func:`admittance_update`): the human torque ``T_hat`` estimated by the
  disturbance observer drives a virtual deflection ``d`` from the equilibrium,
  ``J_v d'' = T_hat - B d' - K d``, and ``theta_eq + d`` becomes the position controller's
  reference: the user feels ``J_v`` instead of the device, and friction is hidden behind the
  position loop. The observer's estimate is its Q-filter's output, ``T_hat = Q(s) T``; with
  ``Q = w0^2 / (s^2 + 2 zeta w0 s + w0^2)`` the reference is ``theta_eq + d + (2 zeta / w0) d'
  + d'' / w0^2``, i.e. ``d`` passed through ``1/Q``, so that the rendered deflection answers the
  true torque and not its delayed estimate (the lag compensation; ``lag = (0, 0)`` turns it off).
  An infinite stiffness renders rigid ground: no deflection.
"""

from __future__ import annotations

import math
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
    "new_admittance_state",
]


class VirtualEnvironment(Parameters):
    """The rendered environment.

    Attributes
    ----------
    stiffness_nm_per_rad : float
        Virtual stiffness about the equilibrium angle (``inf``: rigid, admittance only).
    damping_nms_per_rad : float
        Virtual damping.
    inertia_kgm2 : float
        Virtual inertia (admittance rendering only).
    angle_limit_rad : float
        The rendered angle is held within ``±angle_limit_rad`` (the workspace).
    """

    stiffness_nm_per_rad: float = Field(ge=0)
    damping_nms_per_rad: float = Field(ge=0, allow_inf_nan=False)
    inertia_kgm2: float = Field(default=0.2, gt=0, allow_inf_nan=False)
    angle_limit_rad: float = Field(default=0.6, gt=0, lt=math.pi / 2)

    def constants(
        self,
        *,
        lag: tuple[float, float] = (0.0, 0.0),
        passivity_control: bool = False,
        max_passivity_damping_nms_per_rad: float = 50.0,
    ) -> EnvironmentConstants:
        """The compiled form.

        Parameters
        ----------
        lag : (float, float)
            ``(2 zeta / w0, 1 / w0^2)`` of the observer's Q-filter (s, s^2), for the admittance's
            lag compensation; zeros turn it off.
        passivity_control : bool
            Impedance rendering: dissipate whatever energy the passivity observer finds the
            rendering has produced (:mod:`anklelab.control.passivity`).
        max_passivity_damping_nms_per_rad : float
            Largest damping the passivity controller may add.
        """
        return EnvironmentConstants(
            self.inertia_kgm2,
            self.angle_limit_rad,
            lag[0],
            lag[1],
            1.0 if passivity_control else 0.0,
            max_passivity_damping_nms_per_rad,
        )


class EnvironmentConstants(NamedTuple):
    """Compiled rendering constants (stiffness and damping come per tick)."""

    inertia: float
    angle_limit: float
    lag1: float
    lag2: float
    passivity_control: float
    max_passivity_damping: float


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
        return np.arctan(np.interp(np.asarray(distance_m), self.distance_m, gradient))

    def equilibrium(self, duration_s: float, fs: float, speed_m_s: float) -> NDArray[np.float64]:
        """Platform equilibrium angle (rad) for a walk at ``speed_m_s``, sampled at ``fs`` Hz."""
        return self.slope_angle(speed_m_s * np.arange(round(duration_s * fs)) / fs)


@njit(cache=True, inline="always")
def impedance_torque(
    stiffness: float, damping: float, angle: float, speed: float, equilibrium: float
) -> float:
    """Virtual spring-damper torque on the foot, N·m."""
    return -stiffness * (angle - equilibrium) - damping * speed


@njit(cache=True)
def new_admittance_state() -> NDArray[np.float64]:
    """Fresh admittance state ``[deflection, its speed, its last acceleration]``."""
    return np.zeros(3)


@njit(cache=True, inline="always")
def admittance_update(
    env: EnvironmentConstants,
    state: NDArray[np.float64],
    human_torque: float,
    stiffness: float,
    damping: float,
    equilibrium: float,
    dt: float,
) -> tuple[float, float, float]:
    """Advance the virtual deflection ``state`` by ``dt`` s; return the reference offset.

    Parameters
    ----------
    env : EnvironmentConstants
        Virtual inertia, angle limit, lag compensation.
    state : ndarray, shape (3,)
        :func:`new_admittance_state`, updated in place (semi-implicit Euler).
    human_torque : float
        The observer's estimate of the human torque, N·m.
    stiffness, damping : float
        This tick's virtual stiffness (``inf``: rigid ground) and damping.
    equilibrium : float
        This tick's equilibrium angle, rad (the deflection is held so that ``equilibrium +
        deflection`` stays within ``±env.angle_limit``).
    dt : float
        Control period, s.

    Returns
    -------
    offset, offset_speed : float
        What to add to the equilibrium's angle and speed for the position controller's
        reference: the deflection through the lag compensation.
    acceleration : float
        The deflection's acceleration, for the inverse-dynamics feed-forward (without the lag
        compensation's higher derivatives, which would differentiate the estimate's noise).
    """
    if not math.isfinite(stiffness):
        state[0] = state[1] = state[2] = 0.0
        return 0.0, 0.0, 0.0
    acceleration = (human_torque - damping * state[1] - stiffness * state[0]) / env.inertia
    jerk = (acceleration - state[2]) / dt
    state[2] = acceleration
    offset = state[0] + env.lag1 * state[1] + env.lag2 * acceleration
    offset_speed = state[1] + env.lag1 * acceleration + env.lag2 * jerk
    state[1] += dt * acceleration
    state[0] += dt * state[1]
    low, high = -env.angle_limit - equilibrium, env.angle_limit - equilibrium
    if state[0] < low or state[0] > high:
        state[0] = min(max(state[0], low), high)
        state[1] = 0.0
    return offset, offset_speed, acceleration
