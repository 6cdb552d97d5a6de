"""Parameter objects of the Perturberator walking-perturbation platform (paper 000).

Each class mirrors one table of ``perturberator.toml``; field names carry SI units.
"""

from __future__ import annotations

from pydantic import Field

from anklelab._params import Parameters
from anklelab.forceplate import PlateGeometry

__all__ = [
    "BenchProtocol",
    "CalibrationProtocol",
    "DaqParameters",
    "ForcePlateParameters",
    "GoniometerParameters",
    "MotionPlanParameters",
    "PerturberatorParameters",
    "ServoParameters",
    "SubjectGeometry",
    "TransmissionParameters",
    "WalkingProtocol",
]

Positive = Field(gt=0)
NonNegative = Field(ge=0)


class TransmissionParameters(Parameters):
    """Gearing and compliant coupler between the motor and the hinge."""

    ratio: float = Positive
    peak_output_torque_nm: float = Positive
    coupler_rated_torque_nm: float = Positive
    series_stiffness_nm_per_rad: float = Positive


class ServoParameters(Parameters):
    """Servo drive loop rates and the closed-loop targets reported for the autotune."""

    position_loop_rate_hz: float = Positive
    velocity_loop_rate_hz: float = Positive
    current_loop_rate_hz: float = Positive
    natural_frequency_hz: float = Positive
    gain_margin_db: float = Positive
    phase_margin_deg: float = Field(gt=0, lt=180)
    encoder_resolution_rad: float = Positive
    analog_output_resolution_rad: float = Positive


class MotionPlanParameters(Parameters):
    """Step/direction motion plan emitted by the microcontroller."""

    steps_per_motor_rev: int = Field(gt=0)
    update_rate_hz: float = Positive


class ForcePlateParameters(PlateGeometry):
    """The 8-channel force plate on the hinge: geometry plus dynamics and drift."""

    vertical_natural_frequency_hz: float = Positive
    horizontal_natural_frequency_hz: float = Positive
    drift_n_per_s: float = NonNegative


class DaqParameters(Parameters):
    """Data acquisition: sample rate and converter resolution."""

    sample_rate_hz: float = Positive
    bits: int = Field(gt=1, le=32)
    input_range_v: float = Positive


class GoniometerParameters(Parameters):
    """Electrogoniometer on the ankle (calibrated against a protractor)."""

    sensitivity_rad_per_v: float = Positive
    sensitivity_ci95_rad_per_v: float = NonNegative
    precision_small_rad: float = NonNegative
    precision_full_scale_rad: float = NonNegative


class CalibrationProtocol(Parameters):
    """Nobody on the plate: pseudorandom ramp-and-hold perturbations."""

    n_trials: int = Field(gt=0)
    trial_duration_s: float = Positive
    n_perturbations: int = Field(gt=0)
    amplitude_rad: float = Positive
    ramp_s: float = Positive
    hold_s: float = NonNegative
    max_gap_s: float = NonNegative


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


class BenchProtocol(Parameters):
    """Testing-machine stiffness tests of the prosthetic foot."""

    deflection_m: float = Positive
    duration_s: float = Positive
    tests_per_distance: int = Field(gt=0)
    distances_m: tuple[float, ...] = Field(min_length=1)
    stiffness_nm_per_rad: tuple[float, ...] = Field(min_length=1)


class SubjectGeometry(Parameters):
    """Where the ankle centre sits relative to the plate and the heel-contact COP."""

    ankle_height_m: float = Positive
    heel_to_ankle_m: float = NonNegative


class PerturberatorParameters(Parameters):
    """Every parameter of the Perturberator platform and its protocols."""

    transmission: TransmissionParameters
    servo: ServoParameters
    motion_plan: MotionPlanParameters
    force_plate: ForcePlateParameters
    daq: DaqParameters
    goniometer: GoniometerParameters
    calibration: CalibrationProtocol
    walking: WalkingProtocol
    bench: BenchProtocol
    geometry: SubjectGeometry
