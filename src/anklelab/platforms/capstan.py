"""Parameter objects of the capstan-driven haptic ankle platform (paper 001).

Each class mirrors one table of ``capstan.toml``; field names carry SI units. Friction is
referred to the gearhead output shaft (the capstan pinion), as in paper 001's Table 2.
"""

from __future__ import annotations

import math

from pydantic import Field

from anklelab._params import Parameters

__all__ = [
    "CableParameters",
    "CapstanParameters",
    "FrictionParameters",
    "GearheadParameters",
    "MotorParameters",
    "TiltPlatformParameters",
    "WorkspaceParameters",
]

Positive = Field(gt=0)
NonNegative = Field(ge=0)


class MotorParameters(Parameters):
    """Brushed DC motor (Maxon RE30 class)."""

    rotor_inertia_kgm2: float = Positive
    resistance_ohm: float = Positive
    inductance_h: float = Positive
    torque_constant_nm_per_a: float = Positive
    speed_constant_rpm_per_v: float = Positive
    mechanical_time_constant_s: float = Positive
    nominal_torque_nm: float = Positive
    nominal_speed_rpm: float = Positive

    @property
    def back_emf_constant_v_s_per_rad(self) -> float:
        """Back-EMF constant K_b from the speed constant, V·s/rad."""
        return 60.0 / (2.0 * math.pi * self.speed_constant_rpm_per_v)


class GearheadParameters(Parameters):
    """Planetary gearhead between the motor and the capstan pinion."""

    ratio: float = Positive
    inertia_kgm2: float = Positive


class CableParameters(Parameters):
    """Cable (capstan) reduction from the pinion to the platform."""

    ratio: float = Positive


class TiltPlatformParameters(Parameters):
    """The tilting platform and its reported equivalent inertia."""

    inertia_kgm2: float = Positive
    equivalent_inertia_at_motor_kgm2: float = Positive
    nominal_ankle_torque_nm: float = Positive
    nominal_ankle_speed_rad_s: float = Positive


class FrictionParameters(Parameters):
    """Friction and inertia identified at the pinion shaft (paper 001, Table 2)."""

    inertia_kgm2: float = Positive
    viscous_cw_nms_per_rad: float = NonNegative
    viscous_ccw_nms_per_rad: float = NonNegative
    coulomb_cw_nm: float = NonNegative
    coulomb_ccw_nm: float = NonNegative
    stribeck_velocity_rad_s: float = Positive
    static_friction_nm: float = NonNegative


class WorkspaceParameters(Parameters):
    """Platform angle limits."""

    angle_limit_rad: float = Field(gt=0, lt=math.pi / 2)


class CapstanParameters(Parameters):
    """Every parameter of the capstan ankle platform."""

    motor: MotorParameters
    gearhead: GearheadParameters
    capstan: CableParameters
    platform: TiltPlatformParameters
    friction: FrictionParameters
    workspace: WorkspaceParameters
