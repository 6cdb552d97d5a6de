"""The person guard: what the capstan platform may impose on the person standing on it, and the
fall-safe stop.

Every tick, before the generic safety monitor (:mod:`anklelab.control.safety`), the guard takes
the controller's current request and

1. limits the motor torque beyond gravity compensation, ``K_i r_g r_c i - m g l sin(theta +
   alpha)``, to ``±torque_limit_nm``: the most the platform may push on the person;
2. limits that torque's rate of change to ``jerk_limit_rad_s3`` times the platform's (and
   foot's) inertia: the angular jerk the motor may ask for;
3. latches a fall when the magnitude of the disturbance observer's estimate of the human
   torque, averaged over the last ``fall_window_s``, has dropped by more than
   ``fall_torque_change_nm`` below its average over the ``fall_baseline_s`` before (a standing
   person's load vanishing; a terrain that tilts the foot loads the ankle more, not less), or
   when a stop is requested (a harness or VR fall detector, an operator); it then
   brakes the platform like a damper (``brake_damping_nms_per_rad``, within the torque limit)
   for ``stop_time_s`` and cuts the current: the fall-safe stop (``Fault.FALL_STOP``).

A non-finite request passes unchanged, so that the safety monitor latches ``COMMAND_NAN``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.platforms.capstan import CapstanParameters
from anklelab.sim.capstan import linear_platform
from anklelab.sim.capstan.plant import GRAVITY_M_S2

__all__ = ["GuardConstants", "guard_constants", "guard_update", "new_guard_state"]


class GuardConstants(NamedTuple):
    """What the compiled guard needs (built by :func:`guard_constants`)."""

    torque_limit: float
    torque_step: float  # largest change of the torque per tick
    fall_change: float
    window_ticks: int
    baseline_ticks: int
    still: float
    brake_damping: float
    stop_ticks: int
    gravity_torque: float
    com_angle: float
    torque_per_amp: float
    enabled: float
    detect_falls: float


def guard_constants(
    params: CapstanParameters,
    fs: float,
    *,
    foot_inertia_kgm2: float,
    enabled: bool = True,
    detect_falls: bool = True,
) -> GuardConstants:
    """The guard's constants at the control rate ``fs`` (Hz) from ``params.person_safety``.

    ``foot_inertia_kgm2`` is the person's foot, added to the platform's inertia for the jerk
    limit; ``enabled=False`` makes the guard pass every request unchanged (no person);
    ``detect_falls=False`` leaves only the requested stop (a seated user cannot fall, and the
    torque a rendered terrain puts on a relaxed ankle changes as fast as a fall's).
    """
    s, plat = params.person_safety, params.platform
    inertia = linear_platform(params).inertia_kgm2 + foot_inertia_kgm2
    return GuardConstants(
        torque_limit=s.torque_limit_nm,
        torque_step=s.jerk_limit_rad_s3 * inertia / fs,
        fall_change=s.fall_torque_change_nm,
        window_ticks=max(1, round(s.fall_window_s * fs)),
        baseline_ticks=max(1, round(s.fall_baseline_s * fs)),
        still=s.fall_still_rad,
        brake_damping=s.brake_damping_nms_per_rad,
        stop_ticks=max(1, round(s.stop_time_s * fs)),
        gravity_torque=plat.mass_kg * GRAVITY_M_S2 * plat.com_distance_m,
        com_angle=plat.com_angle_rad,
        torque_per_amp=params.motor.torque_constant_nm_per_a * params.total_ratio,
        enabled=1.0 if enabled else 0.0,
        detect_falls=1.0 if detect_falls else 0.0,
    )


@njit(cache=True)
def new_guard_state(c: GuardConstants) -> NDArray[np.float64]:
    """Fresh state ``[latched, ticks since the stop, last torque, ring index, samples seen,
    window sum, baseline sum, torque ring..., angle ring...]``; the rings hold the last
    ``window_ticks + baseline_ticks`` torque estimates and angles."""
    return np.zeros(7 + 2 * (c.window_ticks + c.baseline_ticks))


@njit(cache=True, inline="always")
def guard_update(
    c: GuardConstants,
    state: NDArray[np.float64],
    request: float,
    angle: float,
    speed: float,
    human_torque: float,
    stop: float,
) -> tuple[float, float]:
    """One guard tick (compiled).

    Parameters
    ----------
    c : GuardConstants
        From :func:`guard_constants`.
    state : ndarray
        :func:`new_guard_state`, updated in place.
    request : float
        The controller's current request, A.
    angle, speed : float
        Measured platform angle (rad) and speed estimate (rad/s).
    human_torque : float
        The disturbance observer's estimate of the human torque, N·m.
    stop : float
        Nonzero requests the fall-safe stop.

    Returns
    -------
    current : float
        The current to pass on to the safety monitor, A.
    clamped : float
        1.0 if the torque or jerk limit changed the request this tick, else 0.0.
    """
    if c.enabled == 0.0:
        return request, 0.0
    size = c.window_ticks + c.baseline_ticks
    ring = state[7 : 7 + size]
    angles = state[7 + size :]
    index = int(state[3])
    angle_then = angles[index]  # the angle size ticks ago
    angles[index] = angle
    leaving_baseline = ring[index]  # the oldest estimate leaves the baseline ...
    joining_baseline = ring[(index + c.baseline_ticks) % size]  # ... one leaves the window
    ring[index] = human_torque
    state[3] = (index + 1) % size
    state[5] += human_torque - (joining_baseline if state[4] >= c.window_ticks else 0.0)
    state[6] += (joining_baseline if state[4] >= c.window_ticks else 0.0) - (
        leaving_baseline if state[4] >= size else 0.0
    )
    if state[4] < size:  # the window and its baseline are not full yet
        state[4] += 1.0
    elif state[0] == 0.0 and c.detect_falls != 0.0:
        drop = abs(state[6] / c.baseline_ticks) - abs(state[5] / c.window_ticks)
        still = abs(angle - angle_then) < c.still
        if drop > c.fall_change and still:  # the person's load is gone, not moved away
            state[0] = 1.0
    if stop != 0.0:
        state[0] = 1.0
    if not math.isfinite(request):
        return request, 0.0
    gravity = c.gravity_torque * np.sin(angle + c.com_angle)
    if state[0] != 0.0:
        state[1] += 1.0
        if state[1] > c.stop_ticks:
            state[2] = 0.0
            return 0.0, 0.0
        wanted = -c.brake_damping * speed
    else:
        wanted = request * c.torque_per_amp - gravity
    torque, clamped = wanted, 0.0
    if abs(torque) > c.torque_limit:
        torque, clamped = math.copysign(c.torque_limit, torque), 1.0
    if abs(torque - state[2]) > c.torque_step:
        torque, clamped = state[2] + math.copysign(c.torque_step, torque - state[2]), 1.0
    state[2] = torque
    if state[0] != 0.0:
        clamped = 0.0  # braking: the limits shape the stop, they do not clamp a request
    return (torque + gravity) / c.torque_per_amp, clamped
