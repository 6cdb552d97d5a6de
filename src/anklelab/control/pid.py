"""Platform-angle PID with gravity feed-forward and optional friction compensation (paper 001).

The control law at the platform axis (eqs. 3, 4 and 6 of paper 001) is

``T = Kp e + Kd (w_ref - w_hat) + Ki I + m g l sin(theta + alpha) + T_friction``,
``i = T / (K_i r_g r_c)``,

with ``e = theta_ref - theta``. The integral accumulates a *saturated* error,
``I' = clip(e, -e_max, e_max)``: as in the paper, a large error (a step just commanded) cannot
wind the integral up faster than a small one, while near the set-point the integral removes the
offset static friction leaves. ``w_hat`` is the encoder angle differentiated and low-pass
filtered. ``T_friction`` (off by default) is the identified pinion friction, Coulomb and viscous,
referred to the platform and evaluated at the reference speed while tracking (or the measured
speed otherwise), its sign ramped linearly over a small speed range.

:func:`position_control_update` is the compiled kernel the twin's loops call;
:class:`PositionController` runs the same arithmetic tick by tick for Python or hardware loops.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray
from pydantic import Field

from anklelab._params import Parameters
from anklelab.control._platform_model import friction_feedforward, model_fields
from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters
from anklelab.sim.capstan import linear_platform
from anklelab.sim.capstan._jit import FAST

__all__ = [
    "ControlConstants",
    "PIDGains",
    "PositionController",
    "control_constants",
    "design_critically_damped",
    "new_control_state",
    "position_control_update",
]


class PIDGains(Parameters):
    """Gains of the platform-angle PID (platform axis, SI).

    Attributes
    ----------
    kp_nm_per_rad, ki_nm_per_rad_s, kd_nms_per_rad : float
        Proportional, integral and derivative gains.
    integral_error_limit_rad : float
        Saturation of the error fed to the integral (the error-accumulation rate limit).
    velocity_filter_hz : float
        Cut-off of the first-order filter on the differentiated encoder angle.
    """

    kp_nm_per_rad: float = Field(ge=0)
    ki_nm_per_rad_s: float = Field(ge=0)
    kd_nms_per_rad: float = Field(ge=0)
    integral_error_limit_rad: float = Field(gt=0)
    velocity_filter_hz: float = Field(gt=0)


def design_critically_damped(
    params: CapstanParameters,
    *,
    settling_time_s: float = 0.2,
    integral_fraction: float = 0.2,
    integral_error_limit_rad: float = math.radians(1.0),
    velocity_filter_hz: float = 100.0,
    with_user: bool = False,
) -> PIDGains:
    """Gains for a critically damped platform (paper 001, section 3.2).

    The PD part places both closed-loop poles at ``-w0`` for the lumped platform
    ``J s^2 + b s`` (gravity assumed compensated): ``Kp = J w0^2``, ``Kd = 2 J w0 - b``, with
    ``w0 = 5.83 / settling_time_s`` (2 % settling of a critically damped pair). The integral
    gain ``Ki = integral_fraction * J w0^3`` then moves the poles to ``w0`` times the roots of
    ``x^3 + 2 x^2 + x + integral_fraction`` (for 0.2: -1.38 and -0.31 ± 0.22j); because the
    integrated error is saturated (``integral_error_limit_rad``), the integral acts near the
    set-point only and removes the offset left by friction and the user's ankle.

    Parameters
    ----------
    params : CapstanParameters
        Platform parameters.
    settling_time_s : float
        Target 2 % settling time of the PD loop, s.
    integral_fraction : float
        Integral gain as a fraction of ``J w0^3`` (0 for PD).
    integral_error_limit_rad : float
        Saturation of the integrated error, rad.
    velocity_filter_hz : float
        Velocity-estimate filter cut-off, Hz.
    with_user : bool
        Include the user's foot inertia, ankle damping and stiffness in the plant.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> g = design_critically_damped(load_platform("capstan"), settling_time_s=0.2)
    >>> round(g.kp_nm_per_rad), round(g.kd_nms_per_rad, 1)
    (317, 21.5)
    """
    if not settling_time_s > 0:
        raise ParameterError(f"settling_time_s must be > 0; got {settling_time_s}")
    lin = linear_platform(params, params.user if with_user else None)
    w0 = 5.83 / settling_time_s
    kp = lin.inertia_kgm2 * w0**2 - lin.stiffness_nm_per_rad
    kd = 2.0 * lin.inertia_kgm2 * w0 - lin.damping_nms_per_rad
    if kp < 0 or kd < 0:
        raise ParameterError(
            f"settling_time_s={settling_time_s} is too slow for this plant: the passive "
            "stiffness or damping alone already exceeds the critically damped gains"
        )
    return PIDGains(
        kp_nm_per_rad=kp,
        ki_nm_per_rad_s=integral_fraction * lin.inertia_kgm2 * w0**3,
        kd_nms_per_rad=kd,
        integral_error_limit_rad=integral_error_limit_rad,
        velocity_filter_hz=velocity_filter_hz,
    )


class ControlConstants(NamedTuple):
    """What the compiled controller needs (built by :func:`control_constants`)."""

    kp: float
    ki: float
    kd: float
    error_limit: float
    dt: float
    velocity_alpha: float
    gravity_torque: float
    com_angle: float
    friction_gain: float
    coulomb_cw: float
    coulomb_ccw: float
    viscous_cw: float
    viscous_ccw: float
    smoothing_speed: float
    capstan_ratio: float
    torque_per_amp: float


def control_constants(
    params: CapstanParameters,
    gains: PIDGains,
    fs: float,
    *,
    gravity_compensation: bool = True,
    friction_compensation: float = 0.0,
    friction: FrictionParameters | None = None,
    smoothing_speed_rad_s: float = 0.5,
) -> ControlConstants:
    """Controller constants from the platform model, the gains and the compensation options.

    Parameters
    ----------
    params : CapstanParameters
        Platform model (gravity, ratios, torque constant).
    gains : PIDGains
        PID gains.
    fs : float
        Control rate, Hz.
    gravity_compensation : bool
        Add the feed-forward ``m g l sin(theta + alpha)``.
    friction_compensation : float
        Fraction (0 to 1) of the modelled friction to add; 0 turns it off.
    friction : FrictionParameters, optional
        The friction model to compensate (e.g. the identified one); ``params.friction`` by default.
    smoothing_speed_rad_s : float
        Pinion speed over which the Coulomb term's sign ramps linearly from -1 to 1, rad/s.
    """
    if not fs > 0:
        raise ParameterError(f"fs must be > 0 Hz; got {fs}")
    if not 0.0 <= friction_compensation <= 1.0:
        raise ParameterError(
            f"friction_compensation must be in [0, 1]; got {friction_compensation}"
        )
    return ControlConstants(
        kp=gains.kp_nm_per_rad,
        ki=gains.ki_nm_per_rad_s,
        kd=gains.kd_nms_per_rad,
        error_limit=gains.integral_error_limit_rad,
        dt=1.0 / fs,
        velocity_alpha=-math.expm1(-2.0 * math.pi * gains.velocity_filter_hz / fs),
        friction_gain=friction_compensation,
        **model_fields(params, friction, smoothing_speed_rad_s, gravity=gravity_compensation),
    )


@njit(cache=True)
def new_control_state(angle: float = 0.0) -> NDArray[np.float64]:
    """Fresh controller state ``[integral, previous angle, speed estimate, ticks]``."""
    return np.array([0.0, angle, 0.0, 0.0])


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def position_control_update(
    c: ControlConstants,
    state: NDArray[np.float64],
    reference: float,
    reference_speed: float,
    angle: float,
) -> tuple[float, float]:
    """One controller tick (compiled).

    Parameters
    ----------
    c : ControlConstants
        From :func:`control_constants`.
    state : ndarray, shape (4,)
        :func:`new_control_state`, updated in place.
    reference, reference_speed : float
        Desired platform angle (rad) and speed (rad/s).
    angle : float
        Measured platform angle (encoder), rad.

    Returns
    -------
    current : float
        Motor current to command, A.
    speed : float
        The speed estimate, rad/s.
    """
    if state[3] > 0:
        state[2] += c.velocity_alpha * ((angle - state[1]) / c.dt - state[2])
    state[1] = angle
    state[3] += 1.0
    speed = state[2]
    error = reference - angle
    state[0] += min(max(error, -c.error_limit), c.error_limit) * c.dt
    torque = c.kp * error + c.kd * (reference_speed - speed) + c.ki * state[0]
    torque += c.gravity_torque * np.sin(angle + c.com_angle)
    if c.friction_gain > 0.0:
        moving = reference_speed if reference_speed != 0.0 else speed
        torque += c.friction_gain * friction_feedforward(c, moving)
    return torque / c.torque_per_amp, speed


class PositionController:
    """PID + gravity (+ friction) controller of the platform angle, one tick at a time.

    Parameters
    ----------
    params : CapstanParameters
        Platform model.
    gains : PIDGains
        PID gains (e.g. :func:`design_critically_damped`).
    fs : float
        Control rate, Hz.
    **options
        ``gravity_compensation``, ``friction_compensation``, ``friction``: see
        :func:`control_constants`.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("capstan")
    >>> ctrl = PositionController(p, design_critically_damped(p), fs=1000.0)
    >>> round(ctrl.step(0.0, 0.0, 0.0), 3)     # at rest, level: gravity current only
    0.225
    """

    def __init__(
        self, params: CapstanParameters, gains: PIDGains, fs: float, **options: object
    ) -> None:
        self.constants = control_constants(params, gains, fs, **options)  # type: ignore[arg-type]
        self.state = new_control_state()

    def reset(self, angle: float = 0.0) -> None:
        """Forget the integral and the speed estimate."""
        self.state = new_control_state(angle)

    def step(self, reference: float, reference_speed: float, angle: float) -> float:
        """Current (A) to command for this tick's reference and measured angle (rad)."""
        current, _ = position_control_update(
            self.constants, self.state, reference, reference_speed, angle
        )
        return float(current)
