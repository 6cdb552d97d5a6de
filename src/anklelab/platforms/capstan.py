"""Parameter objects of the capstan-driven haptic ankle platform (paper 001).

Each class mirrors one table of ``capstan.toml``; field names carry SI units. Friction is
referred to the gearhead output shaft (the capstan pinion), as in paper 001's Table 2. Angles
are positive in dorsiflexion; the pinion turns clockwise (``cw``, positive) when the platform
dorsiflexes.
"""

from __future__ import annotations

import math

from pydantic import Field

from anklelab._params import Parameters

__all__ = [
    "CableParameters",
    "CapstanParameters",
    "DriveParameters",
    "EncoderParameters",
    "FrictionParameters",
    "GearheadParameters",
    "MotorParameters",
    "SafetyParameters",
    "TiltPlatformParameters",
    "UserParameters",
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


class DriveParameters(Parameters):
    """Current-controlled servo drive: supply, current limit, current loop, current sensing."""

    supply_voltage_v: float = Positive
    current_limit_a: float = Positive
    current_bandwidth_hz: float = Positive
    current_noise_a: float = NonNegative


class GearheadParameters(Parameters):
    """Planetary gearhead between the motor and the capstan pinion."""

    ratio: float = Positive
    inertia_kgm2: float = Positive


class CableParameters(Parameters):
    """Capstan cable drive from the pinion to the platform's quarter-circle pulley.

    The cable runs as two strands between pinion and pulley; one end is anchored to the
    pulley, the other through the tensioning spring, so one strand is the cable alone and the
    other the cable in series with the spring. Both carry the preload.
    """

    ratio: float = Positive
    pinion_radius_m: float = Positive
    cable_stiffness_n_per_m: float = Positive
    spring_stiffness_n_per_m: float = Positive
    preload_n: float = Positive
    damping_ratio: float = NonNegative

    @property
    def pulley_radius_m(self) -> float:
        """Radius of the platform's pulley, m (pinion radius times the capstan ratio)."""
        return self.pinion_radius_m * self.ratio

    @property
    def spring_strand_stiffness_n_per_m(self) -> float:
        """Axial stiffness of the strand with the spring in series, N/m."""
        k, s = self.cable_stiffness_n_per_m, self.spring_stiffness_n_per_m
        return k * s / (k + s)

    @property
    def torsional_stiffness_nm_per_rad(self) -> float:
        """Small-motion stiffness of the drive at the platform axis, N·m/rad."""
        return (self.cable_stiffness_n_per_m + self.spring_strand_stiffness_n_per_m) * (
            self.pulley_radius_m**2
        )


class TiltPlatformParameters(Parameters):
    """The tilting platform, its reported equivalent inertia and its centre of mass.

    The feed-forward gravity torque is ``m g l sin(theta + alpha)`` (paper 001, eq. 3), with
    ``alpha`` the angle between the plate normal and the line from the centre of mass to the
    axis, measured in the dorsiflexion sense.
    """

    inertia_kgm2: float = Positive
    equivalent_inertia_at_motor_kgm2: float = Positive
    nominal_ankle_torque_nm: float = Positive
    nominal_ankle_speed_rad_s: float = Positive
    mass_kg: float = Positive
    com_distance_m: float = NonNegative
    com_angle_rad: float = Field(ge=-math.pi, le=math.pi)


class FrictionParameters(Parameters):
    """Friction and inertia identified at the pinion shaft (paper 001, Table 2).

    Kinetic friction ``sign(w) [Tc + (Ts - Tc) exp(-(|w|/ws)^sigma)] + b w`` with
    direction-dependent ``Tc`` and ``b``; at rest the shaft sticks while the applied torque
    stays within ``±Ts``.
    """

    inertia_kgm2: float = Positive
    viscous_cw_nms_per_rad: float = NonNegative
    viscous_ccw_nms_per_rad: float = NonNegative
    coulomb_cw_nm: float = NonNegative
    coulomb_ccw_nm: float = NonNegative
    stribeck_velocity_rad_s: float = Positive
    static_friction_nm: float = NonNegative
    stribeck_exponent: float = Field(gt=0, le=4)


class EncoderParameters(Parameters):
    """Incremental encoder on the motor shaft."""

    counts_per_motor_rev: int = Field(gt=0)

    @property
    def resolution_rad(self) -> float:
        """One count, rad of motor shaft."""
        return 2.0 * math.pi / self.counts_per_motor_rev


class WorkspaceParameters(Parameters):
    """Platform angle limits and the mechanical end stops there."""

    angle_limit_rad: float = Field(gt=0, lt=math.pi / 2)
    end_stop_stiffness_nm_per_rad: float = Positive
    end_stop_damping_nms_per_rad: float = NonNegative


class SafetyParameters(Parameters):
    """Software limits enforced by the controller's safety monitor."""

    angle_limit_rad: float = Field(gt=0, lt=math.pi / 2)
    velocity_limit_rad_s: float = Positive
    current_trip_a: float = Positive
    sensor_range_rad: float = Positive
    max_stale_ticks: int = Field(ge=1)


class UserParameters(Parameters):
    """The user's foot and ankle on the platform (relaxed, seated)."""

    foot_inertia_kgm2: float = NonNegative
    ankle_stiffness_nm_per_rad: float = NonNegative
    ankle_damping_nms_per_rad: float = NonNegative
    rest_angle_rad: float = Field(ge=-math.pi / 2, le=math.pi / 2)


class CapstanParameters(Parameters):
    """Every parameter of the capstan ankle platform."""

    motor: MotorParameters
    drive: DriveParameters
    gearhead: GearheadParameters
    capstan: CableParameters
    platform: TiltPlatformParameters
    friction: FrictionParameters
    encoder: EncoderParameters
    workspace: WorkspaceParameters
    safety: SafetyParameters
    user: UserParameters

    @property
    def total_ratio(self) -> float:
        """Motor-to-platform reduction ``r_g r_c``."""
        return self.gearhead.ratio * self.capstan.ratio
