"""Friction at the capstan pinion: Stribeck curve, direction-dependent Coulomb and viscous terms,
and a time step that sticks for real.

The kinetic law (paper 001, section 3.3, with its misprinted Stribeck term written out) is

``F(w) = sign(w) [Tc(w) + (Ts - Tc(w)) exp(-(|w| / ws)^sigma)] + b(w) w``

with ``Tc``, ``b`` taking their ``cw`` values for ``w > 0`` and ``ccw`` values for ``w < 0``. At
rest friction is set-valued: it takes whatever value in ``[-Ts, Ts]`` keeps the shaft still.
:func:`friction_step` integrates ``J w' = T - F(w)`` over one step implicitly in the friction, so
a shaft that reaches zero speed under a torque below ``Ts`` stops exactly and stays stopped.

The law is passed to compiled code as the array :func:`friction_array` builds:
``[Tc_cw, Tc_ccw, b_cw, b_ccw, Ts, ws, sigma]``.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from anklelab.platforms.capstan import FrictionParameters

__all__ = ["friction_array", "friction_step", "friction_torque", "kinetic_friction"]


def friction_array(friction: FrictionParameters) -> NDArray[np.float64]:
    """Pack friction parameters as ``[Tc_cw, Tc_ccw, b_cw, b_ccw, Ts, ws, sigma]`` (SI)."""
    return np.array(
        [
            friction.coulomb_cw_nm,
            friction.coulomb_ccw_nm,
            friction.viscous_cw_nms_per_rad,
            friction.viscous_ccw_nms_per_rad,
            friction.static_friction_nm,
            friction.stribeck_velocity_rad_s,
            friction.stribeck_exponent,
        ]
    )


@njit(cache=True)
def kinetic_friction(w: float, law: NDArray[np.float64]) -> float:
    """Kinetic friction torque at speed ``w`` (N·m, opposing motion; 0 at ``w == 0``)."""
    if w > 0.0:
        tc, b, s = law[0], law[2], 1.0
    elif w < 0.0:
        tc, b, s = law[1], law[3], -1.0
    else:
        return 0.0
    stribeck = (law[4] - tc) * np.exp(-((abs(w) / law[5]) ** law[6]))
    return s * (tc + stribeck) + b * w


@njit(cache=True)
def friction_step(
    w: float, torque: float, inertia: float, h: float, law: NDArray[np.float64]
) -> tuple[float, float]:
    """Advance ``J w' = torque - F(w)`` by one implicit step of ``h`` seconds.

    Parameters
    ----------
    w : float
        Speed at the start of the step, rad/s.
    torque : float
        Every torque on the shaft except friction, N·m (held over the step).
    inertia : float
        Shaft inertia, kg·m².
    h : float
        Step, s.
    law : ndarray
        :func:`friction_array`.

    Returns
    -------
    w_new : float
        Speed at the end of the step, rad/s (exactly 0 while stuck).
    friction : float
        Friction torque applied over the step, N·m.
    """
    w_free = w + h * torque / inertia
    if inertia * abs(w_free) <= h * law[4]:  # static friction can stop the shaft this step
        return 0.0, torque + inertia * w / h
    s = 1.0 if w_free > 0.0 else -1.0
    tc, b = (law[0], law[2]) if s > 0.0 else (law[1], law[3])
    target = inertia * abs(w_free)
    # g(v) = J v + h F(s v) s - J |w_free| is increasing in v > 0 with g(0+) < 0 <= g(hi)
    lo, hi = 0.0, (target - h * min(tc, law[4])) / (inertia + h * b)
    v = hi
    for _ in range(40):
        e = np.exp(-((v / law[5]) ** law[6]))
        g = inertia * v + h * (tc + (law[4] - tc) * e + b * v) - target
        if g > 0.0:
            hi = v
        else:
            lo = v
        if abs(g) <= 1e-13 * target:
            break
        slope = inertia + h * (b - (law[4] - tc) * e * law[6] * (v / law[5]) ** law[6] / v)
        v_next = v - g / slope
        v = v_next if lo < v_next < hi else 0.5 * (lo + hi)
    w_new = s * v
    return w_new, torque - inertia * (w_new - w) / h


def friction_torque(w: ArrayLike, friction: FrictionParameters) -> NDArray[np.float64]:
    """Kinetic friction torque for an array of speeds (N·m), for plots and model checks.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> f = load_platform("capstan").friction
    >>> friction_torque([-50.0, 1e-9, 50.0], f).round(4)
    array([-0.0681,  0.045 ,  0.0666])
    """
    w = np.asarray(w, dtype=float)
    tc = np.where(w > 0, friction.coulomb_cw_nm, friction.coulomb_ccw_nm)
    b = np.where(w > 0, friction.viscous_cw_nms_per_rad, friction.viscous_ccw_nms_per_rad)
    ratio = np.abs(w) / friction.stribeck_velocity_rad_s
    stribeck = (friction.static_friction_nm - tc) * np.exp(-(ratio**friction.stribeck_exponent))
    return np.sign(w) * (tc + stribeck) + b * w
