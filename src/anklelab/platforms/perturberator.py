"""Parameter objects of the Perturberator walking-perturbation platform (paper 000).

Each class mirrors one table of ``perturberator.toml``; field names carry SI units. Angles and
torques of the drivetrain are referred to the platform output (the hinge) unless a name says
``motor``.
"""

from __future__ import annotations

import itertools

from pydantic import Field, model_validator

from anklelab._params import Parameters
from anklelab.errors import ParameterError
from anklelab.forceplate import PlateGeometry

__all__ = [
    "BenchProtocol",
    "CalibrationProtocol",
    "DaqParameters",
    "ForcePlateParameters",
    "GaitParameters",
    "GoniometerParameters",
    "HingeParameters",
    "HumanAnkleParameters",
    "MotionPlanParameters",
    "MotorParameters",
    "PerturberatorParameters",
    "ProstheticFootParameters",
    "ServoParameters",
    "SubjectGeometry",
    "TransmissionParameters",
    "TriggerParameters",
    "WalkingProtocol",
]

Positive = Field(gt=0)
NonNegative = Field(ge=0)
Fraction = Field(ge=0, lt=1)


def _same_length(owner: str, **arrays: tuple[float, ...]) -> None:
    lengths = {name: len(values) for name, values in arrays.items()}
    if len(set(lengths.values())) > 1:
        listed = ", ".join(f"{owner}.{k} ({n})" for k, n in lengths.items())
        raise ParameterError(f"{listed}: expected arrays of equal length")


def _increasing(owner: str, name: str, values: tuple[float, ...]) -> None:
    if any(b <= a for a, b in itertools.pairwise(values)):
        raise ParameterError(f"{owner}.{name}: expected strictly increasing values; got {values}")


class MotorParameters(Parameters):
    """Servo motor (Kollmorgen AKM42H class): drive current limit, windings, holding brake."""

    rotor_inertia_kgm2: float = Positive
    gearhead_input_inertia_kgm2: float = NonNegative
    torque_constant_nm_per_a: float = Positive
    peak_current_a: float = Positive
    winding_resistance_ohm: float = Positive
    brake_engage_s: float = NonNegative


class TransmissionParameters(Parameters):
    """Gearing and compliant coupler between the motor and the hinge."""

    ratio: float = Positive
    peak_output_torque_nm: float = Positive
    coupler_rated_torque_nm: float = Positive
    series_stiffness_nm_per_rad: float = Positive
    series_damping_nms_per_rad: float = NonNegative
    viscous_nms_per_rad: float = NonNegative
    coulomb_nm: float = NonNegative
    coulomb_smoothing_rad_per_s: float = Positive


class HingeParameters(Parameters):
    """Hinge structure carrying the force plate, rotating about the (ankle-height) hinge axis."""

    inertia_kgm2: float = Positive
    viscous_nms_per_rad: float = NonNegative
    gravity_stiffness_nm_per_rad: float = NonNegative
    axis_anterior_m: float
    angle_limit_rad: float = Positive


class ServoParameters(Parameters):
    """Servo drive: loop rates, cascade gains and the closed-loop figures of the autotune."""

    position_loop_rate_hz: float = Positive
    velocity_loop_rate_hz: float = Positive
    current_loop_rate_hz: float = Positive
    natural_frequency_hz: float = Positive
    gain_margin_db: float = Positive
    phase_margin_deg: float = Field(gt=0, lt=180)
    encoder_resolution_rad: float = Positive
    analog_output_resolution_rad: float = Positive
    position_gain_per_s: float = Positive
    velocity_gain_nms_per_rad: float = Positive
    velocity_integral_hz: float = NonNegative
    current_bandwidth_hz: float = Positive
    velocity_limit_rad_per_s: float = Positive
    following_error_limit_rad: float = Positive
    encoder_timeout_samples: int = Field(ge=0)


class MotionPlanParameters(Parameters):
    """Step/direction motion plan emitted by the microcontroller."""

    steps_per_motor_rev: int = Field(gt=0)
    update_rate_hz: float = Positive


class ForcePlateParameters(PlateGeometry):
    """The 8-channel force plate on the hinge: geometry, top-plate body, modes, drift, noise."""

    vertical_natural_frequency_hz: float = Positive
    horizontal_natural_frequency_hz: float = Positive
    damping_ratio: float = Field(gt=0, lt=1)
    drift_n_per_s: float = NonNegative
    noise_n: float = NonNegative
    top_plate_mass_kg: float = Positive
    top_plate_inertia_kgm2: float = Positive
    top_plate_com_x_m: float
    top_plate_com_z_m: float = Field(lt=0)
    yaw_rad: float = Field(ge=-0.1, le=0.1)
    range_vertical_n: float = Positive
    range_horizontal_n: float = Positive


class DaqParameters(Parameters):
    """Data acquisition: sample rate, converter resolution and the analog front end."""

    sample_rate_hz: float = Positive
    bits: int = Field(gt=1, le=32)
    input_range_v: float = Positive
    anti_alias_hz: float = Positive
    anti_alias_order: int = Field(gt=0, le=8)
    motor_angle_range_rad: float = Positive


class GoniometerParameters(Parameters):
    """Electrogoniometer on the ankle (calibrated against a protractor)."""

    sensitivity_rad_per_v: float = Positive
    sensitivity_ci95_rad_per_v: float = NonNegative
    sensitivity_error_fraction: float = Field(gt=-1, lt=1)
    precision_small_rad: float = NonNegative
    precision_full_scale_rad: float = NonNegative
    full_scale_rad: float = Positive


class CalibrationProtocol(Parameters):
    """Nobody on the plate: pseudorandom ramp-and-hold perturbations."""

    n_trials: int = Field(gt=0)
    trial_duration_s: float = Positive
    n_perturbations: int = Field(gt=0)
    amplitude_rad: float = Positive
    ramp_s: float = Positive
    hold_s: float = NonNegative
    max_gap_s: float = NonNegative
    quiet_s: float = NonNegative


class WalkingProtocol(Parameters):
    """Perturbed walking trials triggered from heel contact."""

    heel_contact_threshold_n: float = Positive
    timing_points_ms: tuple[float, ...] = Field(min_length=1)
    onset_sd_ms: tuple[float, ...] = Field(min_length=1)
    trials_per_point: int = Field(gt=0)
    n_unperturbed: int = Field(ge=0)
    amplitude_rad: float = Positive
    ramp_s: float = Positive
    hold_s: float = NonNegative
    return_s: float = Positive
    window_ms: float = Positive


class TriggerParameters(Parameters):
    """The microcontroller's heel-contact trigger and delay counter (source of onset jitter)."""

    input_offset_sd_n: float = NonNegative
    counter_error_sd_fraction: float = Fraction
    force_limit_n: float = Positive
    max_dropped_updates: int = Field(ge=1)


class BenchProtocol(Parameters):
    """Testing-machine stiffness tests of the prosthetic foot."""

    deflection_m: float = Positive
    duration_s: float = Positive
    tests_per_distance: int = Field(gt=0)
    distances_m: tuple[float, ...] = Field(min_length=1)
    stiffness_nm_per_rad: tuple[float, ...] = Field(min_length=1)
    load_cell_noise_n: float = NonNegative

    @model_validator(mode="after")
    def _law(self) -> BenchProtocol:
        _same_length("bench", distances_m=self.distances_m, stiffness=self.stiffness_nm_per_rad)
        _increasing("bench", "distances_m", self.distances_m)
        return self


class SubjectGeometry(Parameters):
    """Where the ankle centre sits relative to the plate, the hinge and the heel-contact COP.

    ``misalignment_*`` place the ankle centre relative to the hinge axis (anterior, and above
    it); the hinge height is set to ``ankle_height_m - misalignment_vertical_m``.
    """

    ankle_height_m: float = Positive
    heel_to_ankle_m: float = NonNegative
    misalignment_anterior_m: float
    misalignment_vertical_m: float
    shank_length_m: float = Positive
    leg_stiffness_n_per_m: float = NonNegative


class GaitParameters(Parameters):
    """Stance phase on the plate: ground reaction force, COP progression, variability."""

    body_mass_kg: float = Positive
    stance_s: float = Positive
    stance_sd_fraction: float = Fraction
    loading_s: float = Positive
    loading_sd_fraction: float = Fraction
    unloading_s: float = Positive
    vertical_base_bw: float = Positive
    vertical_hump_bw: float = NonNegative
    force_sd_fraction: float = Fraction
    braking_bw: float = NonNegative
    propulsion_bw: float = NonNegative
    lateral_bw: float = NonNegative
    cop_knots_fraction: tuple[float, ...] = Field(min_length=2)
    cop_knots_m: tuple[float, ...] = Field(min_length=2)
    cop_sd_fraction: float = Fraction
    foot_flat_fraction: float = Fraction
    heel_off_fraction: float = Fraction
    placement_sd_m: float = NonNegative
    lateral_position_m: float
    pre_contact_s: float = Positive
    pre_contact_jitter_s: float = NonNegative
    trial_duration_s: float = Positive

    @model_validator(mode="after")
    def _knots(self) -> GaitParameters:
        _same_length(
            "gait", cop_knots_fraction=self.cop_knots_fraction, cop_knots_m=self.cop_knots_m
        )
        _increasing("gait", "cop_knots_fraction", self.cop_knots_fraction)
        if not self.foot_flat_fraction < self.heel_off_fraction:
            raise ValueError("gait.foot_flat_fraction must be below gait.heel_off_fraction")
        return self


class ProstheticFootParameters(Parameters):
    """Solid-ankle prosthetic foot: stiffness follows the bench law of the COP lever arm."""

    damping_nms_per_rad: float = NonNegative
    inertia_kgm2: float = Positive
    shell_compliance_rad_per_nm: float = NonNegative
    shell_damping_nms_per_rad: float = NonNegative


class HumanAnkleParameters(Parameters):
    """Human ankle: stiffness and damping varying through stance (published walking values)."""

    knots_s: tuple[float, ...] = Field(min_length=2)
    stiffness_nm_per_rad_per_kg: tuple[float, ...] = Field(min_length=2)
    damping_nms_per_rad_per_kg: float = NonNegative
    stiffness_lever_arm_gain_per_m: float
    reference_lever_arm_m: float
    inertia_kgm2: float = Positive
    angle_knots_fraction: tuple[float, ...] = Field(min_length=2)
    angle_knots_rad: tuple[float, ...] = Field(min_length=2)

    @model_validator(mode="after")
    def _knots(self) -> HumanAnkleParameters:
        _same_length("human", knots_s=self.knots_s, stiffness=self.stiffness_nm_per_rad_per_kg)
        _same_length("human", angle_knots=self.angle_knots_fraction, angle=self.angle_knots_rad)
        _increasing("human", "knots_s", self.knots_s)
        _increasing("human", "angle_knots_fraction", self.angle_knots_fraction)
        return self


class PerturberatorParameters(Parameters):
    """Every parameter of the Perturberator platform, its subject and its protocols."""

    motor: MotorParameters
    transmission: TransmissionParameters
    hinge: HingeParameters
    servo: ServoParameters
    motion_plan: MotionPlanParameters
    force_plate: ForcePlateParameters
    daq: DaqParameters
    goniometer: GoniometerParameters
    calibration: CalibrationProtocol
    walking: WalkingProtocol
    trigger: TriggerParameters
    bench: BenchProtocol
    geometry: SubjectGeometry
    gait: GaitParameters
    prosthetic: ProstheticFootParameters
    human: HumanAnkleParameters

    @model_validator(mode="after")
    def _within_stance(self) -> PerturberatorParameters:
        """The last timing point's perturbation and analysis window end before toe-off."""
        walk = self.walking
        last = max(walk.timing_points_ms) / 1000.0
        move = walk.ramp_s + walk.hold_s + walk.return_s
        end = last + max(move, walk.window_ms / 1000.0)
        if end > self.gait.stance_s:
            raise ValueError(
                f"walking.timing_points_ms: the last ({1000 * last:g} ms after heel contact) "
                f"with its perturbation ({1000 * move:g} ms) or the analysis window "
                f"({walk.window_ms:g} ms) ends {1000 * end:g} ms after heel contact, after "
                f"toe-off (gait.stance_s = {self.gait.stance_s:g} s)"
            )
        return self
