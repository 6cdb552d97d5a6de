"""Parameter objects of the capstan-driven haptic ankle platform (paper 001).

Each class mirrors one table of ``capstan.toml``; field names carry SI units. Friction is
referred to the gearhead output shaft (the capstan pinion), as in paper 001's Table 2. Angles
are positive in dorsiflexion; the pinion turns clockwise (``cw``, positive) when the platform
dorsiflexes.
"""

from __future__ import annotations

import math

from pydantic import Field, model_validator

from anklelab._params import Parameters
from anklelab.errors import ParameterError

__all__ = [
    "CableParameters",
    "CapstanParameters",
    "DriveParameters",
    "EncoderParameters",
    "FrictionParameters",
    "GearheadParameters",
    "MotorParameters",
    "PersonParameters",
    "PersonSafetyParameters",
    "SafetyParameters",
    "TeleopParameters",
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


class PersonParameters(Parameters):
    """A person standing or stepping on the platform (the ankle's impedance itself comes from
    the twin's human ankle, ``perturberator.toml [human]``, scaled by ``[gait] body_mass_kg``).

    Attributes
    ----------
    standing_load_fraction, walking_load_fraction : float
        Fraction of the body weight on the platform while standing, and during a step's stance.
    cop_offset_m : float
        Centre of pressure anterior of the ankle axis in quiet standing.
    sway_cop_rms_m : float
        RMS of the standing centre-of-pressure sway; ``sway_band_hz`` its frequency band.
    standing_stiffness_time_s : float
        Stance time at which the human ankle's stiffness is taken for quiet standing.
    swing_fraction : float
        Swing phase as a fraction of the gait cycle (foot off the platform).
    posture_time_constant_s : float
        Time constant with which the ankle's rest angle follows a tilt (posture re-alignment).
    reflex_gain_nms_per_rad, reflex_delay_s, reflex_cutoff_hz : float
        Stretch reflex of the plantarflexors: delay, half-wave rectified stretch velocity,
        second-order low-pass (damping ratio 0.7), gain.
    """

    standing_load_fraction: float = Field(ge=0, le=1)
    walking_load_fraction: float = Field(ge=0, le=1)
    cop_offset_m: float = Field(ge=-0.1, le=0.2)
    sway_cop_rms_m: float = NonNegative
    sway_band_hz: tuple[float, float]
    standing_stiffness_time_s: float = NonNegative
    swing_fraction: float = Field(gt=0, lt=1)
    posture_time_constant_s: float = Positive
    reflex_gain_nms_per_rad: float = NonNegative
    reflex_delay_s: float = NonNegative
    reflex_cutoff_hz: float = Positive

    @model_validator(mode="after")
    def _band(self) -> PersonParameters:
        low, high = self.sway_band_hz
        if not 0 < low < high:
            raise ParameterError(
                f"person.sway_band_hz: expected 0 < low < high; got {self.sway_band_hz}"
            )
        return self


class PersonSafetyParameters(Parameters):
    """What the platform may impose on a person, and the fall-safe stop.

    Attributes
    ----------
    torque_limit_nm : float
        Largest motor torque beyond gravity compensation, at the platform axis.
    jerk_limit_rad_s3 : float
        Largest angular jerk the motor torque may ask of the platform and foot (its rate is
        limited to this jerk times their inertia).
    fall_torque_change_nm, fall_window_s, fall_baseline_s, fall_still_rad : float
        A fall: the magnitude of the estimated human torque averaged over the window drops by
        more than this below its average over the baseline before, while the platform turns by
        less than ``fall_still_rad`` over both.
    brake_damping_nms_per_rad, stop_time_s : float
        The fall-safe stop brakes like this damper for this long, then cuts the current.
    """

    torque_limit_nm: float = Positive
    jerk_limit_rad_s3: float = Positive
    fall_torque_change_nm: float = Positive
    fall_window_s: float = Positive
    fall_baseline_s: float = Positive
    fall_still_rad: float = Positive
    brake_damping_nms_per_rad: float = Positive
    stop_time_s: float = Positive


class TeleopParameters(Parameters):
    """Teleoperation: the remote robot's ankle joint, its ground, and the wave channel.

    Attributes
    ----------
    remote_inertia_kgm2, remote_damping_nms_per_rad : float
        The remote robot's foot-pitch joint.
    remote_kp_nm_per_rad, remote_kd_nms_per_rad : float
        Its local controller, which follows the velocity the channel asks for.
    ground_stiffness_nm_per_rad, ground_damping_nms_per_rad : float
        The remote foot's contact with the ground, about the ground's slope.
    wave_impedance_nms_per_rad : float
        The wave variables' characteristic impedance ``b``.
    """

    remote_inertia_kgm2: float = Positive
    remote_damping_nms_per_rad: float = NonNegative
    remote_kp_nm_per_rad: float = NonNegative
    remote_kd_nms_per_rad: float = NonNegative
    ground_stiffness_nm_per_rad: float = Positive
    ground_damping_nms_per_rad: float = NonNegative
    wave_impedance_nms_per_rad: float = Positive


class CapstanParameters(Parameters):
    """Every parameter of the capstan ankle platform.

    Loading checks that no safety limit lies beyond what the platform physically is: the
    software angle limit inside the end stops, the sensor range between the end stops and a
    vertical plate, the speed limit below the no-load speed the supply allows, the current trip
    above the drive's current limit but at most 50 % above it, and the person's torque limit
    within what the drive can give.
    """

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
    person: PersonParameters
    person_safety: PersonSafetyParameters
    teleop: TeleopParameters

    @property
    def total_ratio(self) -> float:
        """Motor-to-platform reduction ``r_g r_c``."""
        return self.gearhead.ratio * self.capstan.ratio

    @property
    def no_load_speed_rad_s(self) -> float:
        """Platform speed at which the back-EMF uses the whole supply voltage, rad/s."""
        motor = self.drive.supply_voltage_v / self.motor.back_emf_constant_v_s_per_rad
        return motor / self.total_ratio

    @property
    def peak_torque_nm(self) -> float:
        """Platform torque at the drive's current limit, N·m."""
        return self.drive.current_limit_a * self.motor.torque_constant_nm_per_a * self.total_ratio

    @model_validator(mode="after")
    def _within_physical_limits(self) -> CapstanParameters:
        problems = _beyond_physical_limits(self)
        if problems:
            raise ParameterError("\n  ".join(problems))
        return self


CURRENT_TRIP_MARGIN = 1.5
"""The over-current trip may lie at most this factor above the drive's current limit."""


def _beyond_physical_limits(p: CapstanParameters) -> list[str]:
    """Messages naming each safety limit that lies beyond the platform's physical limits."""
    s, workspace = p.safety, p.workspace.angle_limit_rad
    trip_max = CURRENT_TRIP_MARGIN * p.drive.current_limit_a
    checks = [
        (
            s.angle_limit_rad < workspace,
            f"safety.angle_limit_rad: {s.angle_limit_rad:g} rad must lie inside the workspace, "
            f"below workspace.angle_limit_rad = {workspace:g} rad (the end stops)",
        ),
        (
            workspace <= s.sensor_range_rad <= math.pi / 2,
            f"safety.sensor_range_rad: {s.sensor_range_rad:g} rad must lie between the end stops "
            f"(workspace.angle_limit_rad = {workspace:g} rad) and a vertical plate (pi/2 rad)",
        ),
        (
            s.velocity_limit_rad_s <= p.no_load_speed_rad_s,
            f"safety.velocity_limit_rad_s: {s.velocity_limit_rad_s:g} rad/s exceeds the "
            f"platform's no-load speed at {p.drive.supply_voltage_v:g} V, "
            f"{p.no_load_speed_rad_s:.3f} rad/s; such a limit could never trip under power",
        ),
        (
            p.drive.current_limit_a < s.current_trip_a <= trip_max,
            f"safety.current_trip_a: {s.current_trip_a:g} A must lie above the drive's current "
            f"limit (drive.current_limit_a = {p.drive.current_limit_a:g} A) and at most "
            f"{CURRENT_TRIP_MARGIN:g} times it ({trip_max:g} A)",
        ),
        (
            p.person_safety.torque_limit_nm <= p.peak_torque_nm,
            f"person_safety.torque_limit_nm: {p.person_safety.torque_limit_nm:g} N·m exceeds the "
            f"torque the drive can give, {p.peak_torque_nm:.1f} N·m",
        ),
    ]
    return [message for ok, message in checks if not ok]
