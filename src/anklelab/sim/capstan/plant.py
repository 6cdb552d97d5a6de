"""Compiled plant of the capstan platform: drive, motor, pinion, cable, platform and foot.

The plant state is ``x = [current (A), pinion angle (rad), pinion speed (rad/s), platform angle
(rad), platform speed (rad/s)]``; the pinion turns ``capstan ratio`` times the platform angle
when the cable is unstretched. :func:`plant_advance` integrates one control period in ``n_sub``
sub-steps:

- the drive regulates the motor current to the (clamped) command through a first-order current
  loop, limited by the supply voltage; the winding's ``L di/dt = v - R i - K_b w_m`` is
  integrated exactly over each sub-step;
- the pinion shaft (motor, gearhead and pinion inertia ``J``) feels the motor torque, the cable
  and friction with real sticking (:func:`~anklelab.sim.capstan.friction_law.friction_step`);
- the two cable strands carry the preload plus ``k1 d`` and ``-k2 d`` (``d`` the stretch at the
  pulley rim, ``k2`` the strand with the tensioning spring in series) and go slack rather than
  push;
- the platform (plus the foot) feels the cable, gravity ``-m g l sin(q + alpha)``, the ankle's
  stiffness, damping and voluntary torque, and the end stops beyond the workspace.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, UserParameters
from anklelab.sim.capstan._jit import FAST
from anklelab.sim.capstan.friction_law import friction_step

__all__ = [
    "STATE_NAMES",
    "PlantConstants",
    "Stepping",
    "encoder_angle",
    "plant_advance",
    "plant_constants",
    "stepping",
]

STATE_NAMES = ("current_a", "pinion_angle_rad", "pinion_speed_rad_s", "angle_rad", "speed_rad_s")
GRAVITY_M_S2 = 9.81


class PlantConstants(NamedTuple):
    """Everything the compiled plant needs, in SI units (built by :func:`plant_constants`)."""

    resistance: float
    inductance: float
    torque_constant: float
    back_emf: float
    supply_voltage: float
    current_limit: float
    current_bandwidth: float
    gear_ratio: float
    pinion_inertia: float
    pinion_radius: float
    pulley_radius: float
    k_cable: float
    k_spring_strand: float
    preload: float
    cable_damping: float
    coupled: float
    platform_inertia: float
    foot_inertia: float
    gravity_torque: float
    com_angle: float
    angle_limit: float
    stop_stiffness: float
    stop_damping: float
    ankle_stiffness: float
    ankle_damping: float
    rest_angle: float


def plant_constants(
    params: CapstanParameters, user: UserParameters | None, *, coupled: bool = True
) -> PlantConstants:
    """Derive the compiled plant's constants from validated parameters.

    Parameters
    ----------
    params : CapstanParameters
        The platform.
    user : UserParameters or None
        The foot on the platform; None for an empty platform.
    coupled : bool
        False disconnects the cable: the motor, gearhead and pinion turn alone (the
        identification rig of paper 001, section 3.3).
    """
    cap, plat = params.capstan, params.platform
    foot = user.foot_inertia_kgm2 if user else 0.0
    platform_inertia = plat.inertia_kgm2 + foot
    pinion_side = params.friction.inertia_kgm2 * cap.ratio**2
    reduced = pinion_side * platform_inertia / (pinion_side + platform_inertia)
    torsional_damping = (
        2.0 * cap.damping_ratio * math.sqrt(cap.torsional_stiffness_nm_per_rad * reduced)
    )
    return PlantConstants(
        resistance=params.motor.resistance_ohm,
        inductance=params.motor.inductance_h,
        torque_constant=params.motor.torque_constant_nm_per_a,
        back_emf=params.motor.back_emf_constant_v_s_per_rad,
        supply_voltage=params.drive.supply_voltage_v,
        current_limit=params.drive.current_limit_a,
        current_bandwidth=2.0 * math.pi * params.drive.current_bandwidth_hz,
        gear_ratio=params.gearhead.ratio,
        pinion_inertia=params.friction.inertia_kgm2,
        pinion_radius=cap.pinion_radius_m,
        pulley_radius=cap.pulley_radius_m,
        k_cable=cap.cable_stiffness_n_per_m,
        k_spring_strand=cap.spring_strand_stiffness_n_per_m,
        preload=cap.preload_n,
        cable_damping=torsional_damping / cap.pulley_radius_m**2,
        coupled=1.0 if coupled else 0.0,
        platform_inertia=platform_inertia,
        foot_inertia=foot,
        gravity_torque=plat.mass_kg * GRAVITY_M_S2 * plat.com_distance_m,
        com_angle=plat.com_angle_rad,
        angle_limit=params.workspace.angle_limit_rad,
        stop_stiffness=params.workspace.end_stop_stiffness_nm_per_rad,
        stop_damping=params.workspace.end_stop_damping_nms_per_rad,
        ankle_stiffness=user.ankle_stiffness_nm_per_rad if user else 0.0,
        ankle_damping=user.ankle_damping_nms_per_rad if user else 0.0,
        rest_angle=user.rest_angle_rad if user else 0.0,
    )


class Stepping(NamedTuple):
    """Sub-steps of one control period and per-step coefficients (built by :func:`stepping`)."""

    n_sub: int
    h: float
    decay: float  # exp(-h R / L): the winding current's decay over a sub-step
    lag: float  # 1 - exp(-h w_c): the current loop's progress over a sub-step
    volts_per_amp: float  # R / (1 - decay)
    amps_per_volt: float  # (1 - decay) / R
    platform_rate: float  # h / platform inertia
    foot_rate: float  # foot inertia / h


def stepping(c: PlantConstants, fs: float, max_step_s: float) -> Stepping:
    """Split a control period at ``fs`` Hz into equal sub-steps no longer than ``max_step_s``."""
    if not fs > 0 or not max_step_s > 0:
        raise ParameterError(f"fs and max_step_s must be > 0; got {fs}, {max_step_s}")
    n_sub = max(1, math.ceil(1.0 / (fs * max_step_s) - 1e-9))
    h = 1.0 / (fs * n_sub)
    decay = math.exp(-h * c.resistance / c.inductance)
    return Stepping(
        n_sub=n_sub,
        h=h,
        decay=decay,
        lag=-math.expm1(-h * c.current_bandwidth),
        volts_per_amp=c.resistance / (1.0 - decay),
        amps_per_volt=(1.0 - decay) / c.resistance,
        platform_rate=h / c.platform_inertia,
        foot_rate=c.foot_inertia / h,
    )


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def plant_advance(
    c: PlantConstants,
    law: NDArray[np.float64],
    step: Stepping,
    x: NDArray[np.float64],
    current_command: float,
    current_offset: float,
    voluntary_torque: float,
) -> tuple[float, float, float]:
    """Advance the plant state ``x`` in place by one control period (``step.n_sub`` sub-steps).

    Parameters
    ----------
    c : PlantConstants
        From :func:`plant_constants`.
    law : ndarray
        Friction law, :func:`~anklelab.sim.capstan.friction_law.friction_array`.
    step : Stepping
        From :func:`stepping`.
    x : ndarray, shape (5,)
        State (see the module docstring), updated in place.
    current_command : float
        Current asked of the drive, A (clamped to the drive's limit).
    current_offset : float
        Error of the drive's current sensor over this period, A (the loop regulates the sensed
        current, so the real one is off by this much).
    voluntary_torque : float
        The user's voluntary ankle torque on the platform, N·m (dorsiflexing positive).

    Returns
    -------
    interaction_torque : float
        Mean torque of the foot on the platform over the period, N·m.
    friction_torque : float
        Mean friction torque at the pinion, N·m.
    voltage : float
        Mean motor voltage, V.
    """
    h, decay, lag = step.h, step.decay, step.lag
    target = min(max(current_command, -c.current_limit), c.current_limit)
    i, qp, wp, q, w = x[0], x[1], x[2], x[3], x[4]
    sum_interaction = 0.0
    sum_friction = 0.0
    sum_voltage = 0.0
    for _ in range(step.n_sub):
        emf = c.back_emf * c.gear_ratio * wp
        sensed = i + current_offset
        wanted = sensed + lag * (target - sensed) - current_offset
        v = step.volts_per_amp * (wanted - decay * i) + emf
        v = min(max(v, -c.supply_voltage), c.supply_voltage)
        i = decay * i + step.amps_per_volt * (v - emf)
        tension_difference = 0.0
        if c.coupled > 0.0:
            stretch = c.pinion_radius * qp - c.pulley_radius * q
            rate = 0.5 * c.cable_damping * (c.pinion_radius * wp - c.pulley_radius * w)
            taut = max(c.preload + c.k_cable * stretch + rate, 0.0)
            spring = max(c.preload - c.k_spring_strand * stretch - rate, 0.0)
            tension_difference = taut - spring
        motor = c.gear_ratio * c.torque_constant * i
        wp, friction = friction_step(
            wp, motor - c.pinion_radius * tension_difference, c.pinion_inertia, h, law
        )
        qp += h * wp
        if c.coupled > 0.0:
            ankle = -c.ankle_stiffness * (q - c.rest_angle) - c.ankle_damping * w + voluntary_torque
            torque = (
                c.pulley_radius * tension_difference
                - c.gravity_torque * np.sin(q + c.com_angle)
                + ankle
            )
            if q > c.angle_limit:
                torque -= c.stop_stiffness * (q - c.angle_limit) + c.stop_damping * w
            elif q < -c.angle_limit:
                torque -= c.stop_stiffness * (q + c.angle_limit) + c.stop_damping * w
            w_new = w + step.platform_rate * torque
            sum_interaction += ankle - step.foot_rate * (w_new - w)
            w = w_new
            q += h * w
        sum_friction += friction
        sum_voltage += v
    x[0], x[1], x[2], x[3], x[4] = i, qp, wp, q, w
    n = step.n_sub
    return sum_interaction / n, sum_friction / n, sum_voltage / n


@njit(cache=True, inline="always")
def encoder_angle(pinion_angle: float, gear_ratio: float, resolution: float) -> float:
    """Pinion angle as a motor encoder reports it: the motor angle floored to whole counts."""
    return np.floor(gear_ratio * pinion_angle / resolution) * resolution / gear_ratio
