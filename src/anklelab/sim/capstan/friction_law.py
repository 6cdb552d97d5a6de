"""Friction at the capstan pinion: Stribeck curve, direction-dependent Coulomb and viscous terms,
and a time step that sticks for real.

The kinetic law (paper 001, section 3.3, with its misprinted Stribeck term written out) is

``F(w) = sign(w) [Tc(w) + (Ts - Tc(w)) exp(-(|w| / ws)^sigma)] + b(w) w``

with ``Tc``, ``b`` taking their ``cw`` values for ``w > 0`` and ``ccw`` values for ``w < 0``. At
rest friction is set-valued: it takes whatever value in ``[-Ts, Ts]`` keeps the shaft still.
:func:`friction_step` integrates ``J w' = T - F(w)`` over one step implicitly in the friction, so
a shaft that reaches zero speed under a torque below ``Ts`` stops exactly and stays stopped.

The law is passed to compiled code as the array :func:`friction_array` builds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from anklelab.platforms.capstan import FrictionParameters
from anklelab.sim.capstan._jit import FAST

__all__ = ["friction_array", "friction_step", "friction_torque", "kinetic_friction"]

NEGLIGIBLE_NM = 1e-14


def friction_array(friction: FrictionParameters) -> NDArray[np.float64]:
    """Pack friction parameters for compiled code (SI).

    Returns ``[Tc_cw, Tc_ccw, b_cw, b_ccw, Ts, ws, sigma, w_negligible]``, the last being the
    speed above which the Stribeck term is below 1e-14 N·m.
    """
    f = friction
    excess = max(
        abs(f.static_friction_nm - f.coulomb_cw_nm), abs(f.static_friction_nm - f.coulomb_ccw_nm)
    )
    negligible = (
        f.stribeck_velocity_rad_s * math.log(excess / NEGLIGIBLE_NM) ** (1.0 / f.stribeck_exponent)
        if excess > NEGLIGIBLE_NM
        else 0.0
    )
    return np.array(
        [
            f.coulomb_cw_nm,
            f.coulomb_ccw_nm,
            f.viscous_cw_nms_per_rad,
            f.viscous_ccw_nms_per_rad,
            f.static_friction_nm,
            f.stribeck_velocity_rad_s,
            f.stribeck_exponent,
            negligible,
        ]
    )


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def _decay(speed: float, law: NDArray[np.float64]) -> float:
    """Stribeck decay ``exp(-(speed / ws)^sigma)`` for ``speed >= 0`` (sigma = 2 fast path)."""
    ratio = speed / law[5]
    return np.exp(-(ratio * ratio if law[6] == 2.0 else ratio ** law[6]))


@njit(cache=True, fastmath=FAST, error_model="numpy")
def kinetic_friction(w: float, law: NDArray[np.float64]) -> float:
    """Kinetic friction torque at speed ``w`` (N·m, opposing motion; 0 at ``w == 0``)."""
    if w > 0.0:
        tc, b, s = law[0], law[2], 1.0
    elif w < 0.0:
        tc, b, s = law[1], law[3], -1.0
    else:
        return 0.0
    return s * (tc + (law[4] - tc) * _decay(abs(w), law)) + b * w


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
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
    stribeck = law[4] - tc
    denominator = inertia + h * b
    # g(v) = J v + h F(s v) s - J |w_free| is increasing in v > 0; its root lies in [lo, hi]
    lo = max(0.0, (target - h * max(tc, law[4])) / denominator)
    hi = (target - h * min(tc, law[4])) / denominator
    v = (target - h * tc) / denominator  # the root without the Stribeck term
    if v > law[7]:
        return s * v, torque - inertia * (s * v - w) / h  # Stribeck term negligible here
    # safeguarded Newton from there; h F' << J makes it converge in a step or two, and a step
    # is final when its quadratic error estimate |g''| step^2 / (2 |g'|) is below 1e-9 rad/s
    v = min(max(v, lo), hi)
    sigma, ws = law[6], law[5]
    for _ in range(60):
        e = _decay(v, law)
        g = denominator * v + h * (tc + stribeck * e) - target
        if g == 0.0:
            break
        if g > 0.0:
            hi = v
        else:
            lo = v
        r = v / ws
        rs = r if sigma == 2.0 else r ** (sigma - 1.0)  # r^(sigma-1)
        slope = denominator - h * stribeck * e * sigma * rs / ws
        step = g / slope
        v_next = v - step
        v = v_next if lo <= v_next <= hi else 0.5 * (lo + hi)
        if v == v_next:
            curvature = (
                h * stribeck * e * sigma * (sigma * rs * rs - (sigma - 1.0) * rs / r) / ws**2
            )
            if abs(curvature) * step * step <= 2e-9 * abs(slope) * (1.0 + v):
                break
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
