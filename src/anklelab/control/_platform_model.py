"""The capstan platform's model terms that the PID and the disturbance observer both use.

Both compiled constants tuples (:class:`~anklelab.control.pid.ControlConstants`,
:class:`~anklelab.control.observer.ObserverConstants`) carry the fields of
:func:`model_fields`, so :func:`friction_feedforward` serves either.
"""

from __future__ import annotations

from typing import Any

from numba import njit

from anklelab.platforms.capstan import CapstanParameters, FrictionParameters
from anklelab.sim.capstan._jit import FAST
from anklelab.sim.capstan.plant import GRAVITY_M_S2


def model_fields(
    params: CapstanParameters,
    friction: FrictionParameters | None,
    smoothing_speed_rad_s: float,
    *,
    gravity: bool = True,
) -> dict[str, float]:
    """Gravity, friction (``params.friction`` unless given), ratios and torque constant, SI."""
    f = params.friction if friction is None else friction
    plat = params.platform
    return {
        "gravity_torque": plat.mass_kg * GRAVITY_M_S2 * plat.com_distance_m if gravity else 0.0,
        "com_angle": plat.com_angle_rad,
        "coulomb_cw": f.coulomb_cw_nm,
        "coulomb_ccw": f.coulomb_ccw_nm,
        "viscous_cw": f.viscous_cw_nms_per_rad,
        "viscous_ccw": f.viscous_ccw_nms_per_rad,
        "smoothing_speed": smoothing_speed_rad_s,
        "capstan_ratio": params.capstan.ratio,
        "torque_per_amp": params.motor.torque_constant_nm_per_a * params.total_ratio,
    }


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def friction_feedforward(c: Any, speed: float) -> float:
    """Modelled friction torque referred to the platform at platform speed ``speed``, N·m.

    Coulomb and viscous friction at the pinion (speed ``r_c * speed``), the Coulomb sign ramped
    linearly over ``±c.smoothing_speed``; ``c`` holds the fields of :func:`model_fields`.
    """
    wp = c.capstan_ratio * speed
    s = min(max(wp / c.smoothing_speed, -1.0), 1.0)
    tc = c.coulomb_cw if wp > 0 else c.coulomb_ccw
    b = c.viscous_cw if wp > 0 else c.viscous_ccw
    return c.capstan_ratio * (tc * s + b * wp)
