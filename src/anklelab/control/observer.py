"""Disturbance observer: the human's ankle torque from motor current and encoder alone.

The platform obeys ``J theta'' + F(theta') + m g l sin(theta + alpha) = T_motor + T_human``
(paper 001, eq. 5, with the friction ``F`` identified at the pinion and referred to the
platform). Given a model of ``J``, ``F`` and gravity, the observer returns

``T_hat = Q(s) [J s^2 theta + F(s theta) + m g l sin(theta + alpha) - K_i r_g r_c i]``

where ``Q`` is a unit-gain, critically damped (or ``damping_ratio``-damped) second-order
low-pass of cut-off ``cutoff_hz``: it makes ``J s^2 Q`` proper, so no raw double derivative of
the encoder is ever taken, and trades noise against delay. ``Q``, ``Q s`` and ``Q s^2`` share one
state space, discretised with the bilinear (Tustin) transform so that the channels stay
aligned sample for sample. While the pinion sticks the friction
torque is unknowable (anything within ``±T_s``); the observer then attributes none of it, and
the estimate is off by at most ``r_c T_s``. The friction model is evaluated at the raw
(differenced) encoder speed, so that after ``Q`` it lines up in time with ``Q s^2 theta``.
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.control._platform_model import friction_feedforward, model_fields
from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters
from anklelab.sim.capstan._jit import FAST

__all__ = [
    "DisturbanceObserver",
    "ObserverConstants",
    "new_observer_state",
    "observer_constants",
    "observer_update",
]


class ObserverConstants(NamedTuple):
    """What the compiled observer needs (built by :func:`observer_constants`).

    ``ad, bd, cd, dd`` are the Tustin-discretised state space of ``Q``; the rows of ``cd`` and
    ``dd`` give ``Q``, ``Q s`` and ``Q s^2``; ``rest`` is the steady state per unit input.
    """

    ad: NDArray[np.float64]
    bd: NDArray[np.float64]
    cd: NDArray[np.float64]
    dd: NDArray[np.float64]
    rest: NDArray[np.float64]
    inertia: float
    gravity_torque: float
    com_angle: float
    coulomb_cw: float
    coulomb_ccw: float
    viscous_cw: float
    viscous_ccw: float
    smoothing_speed: float
    capstan_ratio: float
    torque_per_amp: float
    fs: float


def _tustin(
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    c: NDArray[np.float64],
    d: NDArray[np.float64],
    dt: float,
) -> tuple[NDArray[np.float64], ...]:
    """Bilinear (Tustin) discretisation of a 2-state system (scipy's ``cont2discrete`` form)."""
    m = np.eye(2) - 0.5 * dt * a
    inv = np.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]]) / (
        m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    )
    ad = inv @ (np.eye(2) + 0.5 * dt * a)
    bd = inv @ (dt * b)
    return ad, bd, c @ inv, d + 0.5 * c @ bd


def observer_constants(
    params: CapstanParameters,
    fs: float,
    *,
    cutoff_hz: float = 20.0,
    damping_ratio: float = 1.0,
    inertia_kgm2: float | None = None,
    friction: FrictionParameters | None = None,
    smoothing_speed_rad_s: float = 0.5,
) -> ObserverConstants:
    """Observer constants from the (identified) platform model and the Q-filter settings.

    Parameters
    ----------
    params : CapstanParameters
        Platform model: gravity, ratios, torque constant, platform inertia.
    fs : float
        Control rate, Hz.
    cutoff_hz : float
        Q-filter natural frequency, Hz.
    damping_ratio : float
        Q-filter damping ratio (1: critically damped).
    inertia_kgm2 : float, optional
        Platform-axis inertia; default: the pinion inertia of ``friction`` referred
        (``J r_c^2``) plus the platform's.
    friction : FrictionParameters, optional
        Friction model (e.g. identified); ``params.friction`` by default.
    smoothing_speed_rad_s : float
        Pinion speed over which the Coulomb sign ramps linearly from -1 to 1, rad/s.
    """
    if not 0 < cutoff_hz < fs / 2:
        raise ParameterError(f"cutoff_hz must be in (0, fs/2) = (0, {fs / 2}); got {cutoff_hz}")
    if not damping_ratio > 0:
        raise ParameterError(f"damping_ratio must be > 0; got {damping_ratio}")
    f = params.friction if friction is None else friction
    if inertia_kgm2 is None:
        inertia_kgm2 = f.inertia_kgm2 * params.capstan.ratio**2 + params.platform.inertia_kgm2
    w0 = 2.0 * math.pi * cutoff_hz
    a = np.array([[0.0, 1.0], [-(w0**2), -2.0 * damping_ratio * w0]])
    b = np.array([[0.0], [w0**2]])
    c = np.array([[1.0, 0.0], [0.0, 1.0], [-(w0**2), -2.0 * damping_ratio * w0]])
    d = np.array([[0.0], [0.0], [w0**2]])
    ad, bd, cd, dd = _tustin(a, b, c, d, 1.0 / fs)
    return ObserverConstants(
        ad=np.ascontiguousarray(ad),
        bd=np.ascontiguousarray(bd[:, 0]),
        cd=np.ascontiguousarray(cd),
        dd=np.ascontiguousarray(dd[:, 0]),
        # float64 in, float64 out (NumPy's stubs type solve's result as any floating type)
        rest=cast("NDArray[np.float64]", np.linalg.solve(np.eye(2) - ad, bd[:, 0])),
        inertia=inertia_kgm2,
        fs=fs,
        **model_fields(params, f, smoothing_speed_rad_s),
    )


@njit(cache=True)
def new_observer_state() -> NDArray[np.float64]:
    """Fresh observer state: the angle filter's two states, the model-torque filter's two, a
    started flag (the first tick starts both filters at rest on its readings), the last angle."""
    return np.zeros(6)


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def observer_update(
    c: ObserverConstants, state: NDArray[np.float64], angle: float, current: float
) -> float:
    """One observer tick (compiled): returns the estimated human torque on the platform, N·m.

    Parameters
    ----------
    c : ObserverConstants
        From :func:`observer_constants`.
    state : ndarray, shape (6,)
        :func:`new_observer_state`, updated in place.
    angle : float
        Measured platform angle, rad.
    current : float
        Measured motor current, A.
    """
    if state[4] == 0.0:
        state[0], state[1], state[5] = c.rest[0] * angle, c.rest[1] * angle, angle
    p0, p1 = state[0], state[1]
    accel = c.cd[2, 0] * p0 + c.cd[2, 1] * p1 + c.dd[2] * angle  # Q s^2 theta
    # friction at the raw encoder speed: the model torque is Q-filtered below like s^2 theta
    friction = friction_feedforward(c, (angle - state[5]) * c.fs)
    state[5] = angle
    model = friction + c.gravity_torque * np.sin(angle + c.com_angle) - c.torque_per_amp * current
    if state[4] == 0.0:
        state[2], state[3], state[4] = c.rest[0] * model, c.rest[1] * model, 1.0
    q0, q1 = state[2], state[3]
    estimate = c.inertia * accel + c.cd[0, 0] * q0 + c.cd[0, 1] * q1 + c.dd[0] * model
    state[0] = c.ad[0, 0] * p0 + c.ad[0, 1] * p1 + c.bd[0] * angle
    state[1] = c.ad[1, 0] * p0 + c.ad[1, 1] * p1 + c.bd[1] * angle
    state[2] = c.ad[0, 0] * q0 + c.ad[0, 1] * q1 + c.bd[0] * model
    state[3] = c.ad[1, 0] * q0 + c.ad[1, 1] * q1 + c.bd[1] * model
    return estimate


class DisturbanceObserver:
    """Tick-by-tick wrapper of :func:`observer_update` (see the module docstring).

    Parameters
    ----------
    params : CapstanParameters
        Platform model.
    fs : float
        Control rate, Hz.
    **options
        ``cutoff_hz``, ``damping_ratio``, ``inertia_kgm2``, ``friction``: see
        :func:`observer_constants`.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("capstan")
    >>> dob = DisturbanceObserver(p, fs=1000.0, cutoff_hz=20.0)
    >>> c = dob.constants
    >>> gravity = c.gravity_torque * np.sin(c.com_angle)      # N·m needed to hold level
    >>> est = [dob.update(0.0, (gravity + 2.0) / c.torque_per_amp) for _ in range(500)]
    >>> round(est[-1], 3)          # platform still, motor pushes 2 N·m more: the human resists
    -2.0
    """

    def __init__(self, params: CapstanParameters, fs: float, **options: object) -> None:
        self.constants = observer_constants(params, fs, **options)  # type: ignore[arg-type]
        self.state = new_observer_state()

    def reset(self) -> None:
        """Restart the filters (at rest on the next tick's readings)."""
        self.state = new_observer_state()

    def update(self, angle: float, current: float) -> float:
        """Estimated human torque (N·m) from this tick's encoder angle (rad) and current (A)."""
        return float(observer_update(self.constants, self.state, angle, current))
