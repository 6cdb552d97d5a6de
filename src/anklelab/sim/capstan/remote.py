"""The far side of teleoperation: the network that delays packets, and the remote robot's ankle
joint standing on its ground.

- :func:`arrivals` turns a delay (constant, plus a random jitter per packet) into, for each
  tick, the newest packet that has arrived by then (packets overtaken by newer ones are simply
  never used). Vectorised.
- :func:`remote_step` advances the remote robot's foot-pitch joint by one tick (compiled): its
  local controller follows a desired velocity (and the position that integrates it) while the
  foot rests on a ground whose slope changes as the robot walks; it returns the force the
  controller exerts (what the channel feeds back) and the ground's torque on the foot.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.errors import ParameterError
from anklelab.platforms.capstan import TeleopParameters

__all__ = ["RemoteConstants", "arrivals", "new_remote_state", "remote_constants", "remote_step"]


def arrivals(
    n: int, fs: float, delay_s: float, jitter_s: float, *, seed: int | np.random.Generator = 0
) -> NDArray[np.int64]:
    """For each of ``n`` ticks, the index of the newest packet received by then (-1: none yet).

    One packet is sent per tick; packet ``k`` arrives ``delay_s`` plus a uniform random
    ``[0, jitter_s]`` after it was sent, rounded up to the receiver's next tick, and one tick
    after it was sent at the earliest (it is sent at the end of the tick that computed it).

    Examples
    --------
    >>> arrivals(6, 1000.0, 0.002, 0.0)
    array([-1, -1,  0,  1,  2,  3])
    >>> arrivals(4, 1000.0, 0.0, 0.0)
    array([-1,  0,  1,  2])
    """
    if not (delay_s >= 0 and jitter_s >= 0 and math.isfinite(delay_s + jitter_s)):
        raise ParameterError(
            f"delay and jitter must be finite and >= 0 s; got {delay_s}, {jitter_s}"
        )
    rng = np.random.default_rng(seed)
    sent = np.arange(n)
    lag = delay_s + (rng.uniform(0.0, jitter_s, n) if jitter_s > 0 else 0.0)
    arrive = sent + np.maximum(np.ceil(np.round(lag * fs, 9)), 1).astype(np.int64)
    newest = np.full(n, -1, dtype=np.int64)
    inside = arrive < n
    np.maximum.at(newest, arrive[inside], sent[inside])
    return np.maximum.accumulate(newest)


class RemoteConstants(NamedTuple):
    """The remote joint, its controller and ground (built by :func:`remote_constants`)."""

    inertia: float
    damping: float
    kp: float
    kd: float
    ground_stiffness: float
    ground_damping: float
    wave_impedance: float


def remote_constants(p: TeleopParameters) -> RemoteConstants:
    """The compiled form of ``params.teleop``."""
    return RemoteConstants(
        p.remote_inertia_kgm2,
        p.remote_damping_nms_per_rad,
        p.remote_kp_nm_per_rad,
        p.remote_kd_nms_per_rad,
        p.ground_stiffness_nm_per_rad,
        p.ground_damping_nms_per_rad,
        p.wave_impedance_nms_per_rad,
    )


@njit(cache=True)
def new_remote_state() -> NDArray[np.float64]:
    """Fresh state ``[angle, speed, desired angle]`` of the remote joint (rad, rad/s)."""
    return np.zeros(3)


@njit(cache=True, inline="always")
def remote_step(
    c: RemoteConstants,
    state: NDArray[np.float64],
    desired_speed: float,
    ground: float,
    dt: float,
) -> tuple[float, float]:
    """Advance the remote joint by ``dt`` following ``desired_speed`` (rad/s) on a ground tilted
    by ``ground`` (rad); returns the controller's torque and the ground's torque on the foot."""
    state[2] += dt * desired_speed
    actuator = c.kd * (desired_speed - state[1]) + c.kp * (state[2] - state[0])
    contact = -c.ground_stiffness * (state[0] - ground) - c.ground_damping * state[1]
    state[1] += dt * (actuator + contact - c.damping * state[1]) / c.inertia
    state[0] += dt * state[1]
    return actuator, contact
