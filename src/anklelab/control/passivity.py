"""Passivity observer and controller for impedance rendering (Hannaford & Ryu, IEEE T-RA 18:1,
2002), on the energy the rendering exchanges with the foot.

The rendered torque ``tau_k`` is held over each control period (zero-order hold) while the
platform turns by ``delta_k`` relative to the equilibrium; the energy flowing *into* the virtual
environment over that period is ``-tau_k delta_k``, known one tick later from the encoder. The
observer sums it: ``E_k = sum -tau_j delta_j``. A passive environment (a spring stores,
a damper dissipates) keeps ``E_k >= 0``; sampling, the hold, the encoder's quantisation and the
velocity filter can make a stiff spring or a large damper generate energy, and then ``E_k``
turns negative. The controller adds, for the next period, the damping
``alpha = -E_k / (T w^2)`` (at most ``max_damping``) that dissipates the deficit if the platform
keeps the speed ``w = delta_k / T`` of the last period, so that the rendering as seen by the
foot never produces energy for long; what it really dissipates is counted when the next
increment arrives.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

__all__ = ["new_passivity_state", "passivity_update"]


@njit(cache=True)
def new_passivity_state() -> NDArray[np.float64]:
    """Fresh state ``[observed energy (J), last torque (N·m), last deflection (rad), started]``."""
    return np.zeros(4)


@njit(cache=True, inline="always")
def passivity_update(
    state: NDArray[np.float64],
    torque: float,
    deflection: float,
    dt: float,
    max_damping: float,
    enabled: float,
) -> tuple[float, float]:
    """One tick: observe the energy, and (``enabled``) add the damping that restores passivity.

    Parameters
    ----------
    state : ndarray, shape (4,)
        :func:`new_passivity_state`, updated in place.
    torque : float
        The virtual environment's torque for this tick, N·m.
    deflection : float
        Measured angle minus the equilibrium, rad.
    dt : float
        Control period, s.
    max_damping : float
        Largest damping the controller adds, N·m·s/rad.
    enabled : float
        Nonzero: add the controller's damping; zero: observe only.

    Returns
    -------
    torque : float
        The torque to render, N·m (``torque`` plus the controller's damping torque).
    energy : float
        The observed energy, J (after this tick's increment).
    """
    speed = 0.0
    if state[3] != 0.0:
        state[0] -= state[1] * (deflection - state[2])
        speed = (deflection - state[2]) / dt
    state[3] = 1.0
    extra = 0.0
    if enabled != 0.0 and state[0] < 0.0 and speed != 0.0:
        alpha = min(-state[0] / (dt * speed * speed), max_damping)
        extra = -alpha * speed
    out = torque + extra
    state[1] = out
    state[2] = deflection
    return out, state[0]
