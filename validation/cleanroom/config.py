"""Every physical and protocol parameter of one clean-room session, as frozen dataclasses.

A :class:`Config` fixes the *distributions* a session is drawn from (platform, foot, gait,
noise, protocol); :func:`validation.cleanroom.generate` then draws the per-trial variation
from a seed. Frames and signs (README.md, "Frames"): the hinge frame W moves with the plate, x
anterior (walking direction, perpendicular to the hinge axis), y right, z down, origin at the
plate centre in the sensor plane; the Kistler plate frame P is W turned about z by the mounting
and the hinge yaw. Angles are dorsiflexion positive.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np

__all__ = [
    "ANTERIOR_AXES",
    "Config",
    "DriveConfig",
    "GaitConfig",
    "HumanAnkle",
    "NoiseConfig",
    "PlateConfig",
    "ProstheticFoot",
    "ProtocolConfig",
]

AnteriorAxis = Literal["+x", "-x", "+y", "-y"]
ANTERIOR_AXES: tuple[AnteriorAxis, ...] = ("+x", "-x", "+y", "-y")
#: Trial-to-trial normal draws are clipped at this many standard deviations.
TRUNCATE_SD = 3.5
#: Rotation (rad) about the plate's z (down) axis from the hinge frame to the plate frame.
MOUNTING_ANGLE_RAD = {"+x": 0.0, "+y": -math.pi / 2, "-x": math.pi, "-y": math.pi / 2}


def _check(condition: bool, name: str, expected: str, value: object) -> None:
    if not condition:
        raise ValueError(f"{name}: expected {expected}, got {value!r}")


def _positive(owner: object, *names: str) -> None:
    for name in names:
        value = getattr(owner, name)
        _check(value > 0 and math.isfinite(value), name, "a finite number > 0", value)


def _non_negative(owner: object, *names: str) -> None:
    for name in names:
        value = getattr(owner, name)
        _check(value >= 0 and math.isfinite(value), name, "a finite number >= 0", value)


@dataclass(frozen=True)
class ProtocolConfig:
    """The experiment as paper 000 §2.2 and §2.4.1 describe it (times in s, angles in rad).

    Attributes
    ----------
    sample_rate_hz : float
        DAQ rate of every recording, Hz (paper: 1 kHz).
    oversample : int
        Internal simulation steps per DAQ sample; the DAQ takes every ``oversample``-th value
        (no anti-alias filter, like the paper's USB-6218). The discretisation is exact for
        inputs that are linear between steps, so 1 is accurate; more resolves the plate's
        sensor modes between samples at proportionally more cost.
    trial_duration_s : float
        Length of each walking file, s.
    contact_time_s : (float, float)
        Range of the initial foot contact time within a walking file, s.
    timing_points_ms : tuple of float
        Intended perturbation delays after heel contact, ms.
    trials_per_point : int
        Perturbed trials per timing point; each is dorsi or plantar with equal probability.
    n_unperturbed : int
        Unperturbed walking trials.
    n_calibration : int
        Calibration trials (nobody on the plate).
    calibration_duration_s : float
        Length of each calibration trial, s.
    calibration_gap_s : (float, float)
        Range of the random pause between calibration moves, s.
    calibration_rest_s : float
        Quiet time at the start and end of each calibration trial, s.
    amplitude_rad : float
        Perturbation amplitude, rad (paper: 0.035).
    ramp_s : float
        Ramp duration, s (paper: 75 ms).
    calibration_hold_s : float
        Hold between the ramp and the ramp back in calibration moves, s (paper: 100 ms).
    walking_hold_s : float
        Hold before the ramp back in walking perturbations, s.
    heel_contact_threshold_n : float
        Vertical force that starts the trigger counter, N (paper: 25 N).
    trigger_latency_s : float
        Constant delay from the threshold crossing to the start of the motion plan, s.
    onset_jitter_sd_s : tuple of float
        Standard deviation of the onset about ``delay + latency`` for each timing point, s.
    bench_distances_m : tuple of float
        Testing-machine actuator distances from the ankle's centre of rotation, m (empty: no
        bench tests).
    bench_tests_per_distance : int
        Bench tests at each distance (paper: 5).
    bench_displacement_m : float
        Actuator displacement of one bench test, m (paper: 1.5 cm over 10 s).
    bench_duration_s : float
        Duration of one bench test, s.
    """

    sample_rate_hz: float = 1000.0
    oversample: int = 1
    trial_duration_s: float = 1.1
    contact_time_s: tuple[float, float] = (0.10, 0.14)
    timing_points_ms: tuple[float, ...] = (100.0, 225.0, 350.0, 475.0)
    trials_per_point: int = 100
    n_unperturbed: int = 400
    n_calibration: int = 5
    calibration_duration_s: float = 20.0
    calibration_gap_s: tuple[float, float] = (0.05, 0.45)
    calibration_rest_s: float = 0.5
    amplitude_rad: float = 0.035
    ramp_s: float = 0.075
    calibration_hold_s: float = 0.100
    walking_hold_s: float = 0.075
    heel_contact_threshold_n: float = 25.0
    trigger_latency_s: float = 0.001
    onset_jitter_sd_s: tuple[float, ...] = (0.0033, 0.0032, 0.0042, 0.0052)
    bench_distances_m: tuple[float, ...] = ()
    bench_tests_per_distance: int = 5
    bench_displacement_m: float = 0.015
    bench_duration_s: float = 10.0

    def __post_init__(self) -> None:
        _positive(self, "sample_rate_hz", "trial_duration_s", "calibration_duration_s")
        _positive(self, "amplitude_rad", "ramp_s", "heel_contact_threshold_n")
        _positive(self, "bench_displacement_m", "bench_duration_s")
        _non_negative(self, "calibration_hold_s", "walking_hold_s", "trigger_latency_s")
        _non_negative(self, "calibration_rest_s")
        for name in ("oversample", "n_calibration", "bench_tests_per_distance"):
            value = getattr(self, name)
            _check(isinstance(value, int) and value >= 1, name, "an integer >= 1", value)
        for name in ("trials_per_point", "n_unperturbed"):
            value = getattr(self, name)
            _check(isinstance(value, int) and value >= 0, name, "an integer >= 0", value)
        _check(len(self.timing_points_ms) > 0, "timing_points_ms", "at least one", ())
        _check(
            len(self.onset_jitter_sd_s) == len(self.timing_points_ms),
            "onset_jitter_sd_s",
            f"one value per timing point ({len(self.timing_points_ms)})",
            self.onset_jitter_sd_s,
        )
        lo, hi = self.contact_time_s
        _check(0.1 <= lo <= hi, "contact_time_s", "0.1 <= low <= high (s)", self.contact_time_s)
        lo, hi = self.calibration_gap_s
        _check(0 <= lo <= hi, "calibration_gap_s", "0 <= low <= high (s)", self.calibration_gap_s)
        move = 2 * self.ramp_s + self.calibration_hold_s
        _check(
            self.calibration_duration_s >= 2 * self.calibration_rest_s + move,
            "calibration_duration_s",
            f"room for one move ({2 * self.calibration_rest_s + move:g} s)",
            self.calibration_duration_s,
        )
        _check(all(d > 0 for d in self.bench_distances_m), "bench_distances_m", "> 0", ())

    @property
    def walking_move_s(self) -> float:
        """Duration of a walking perturbation from onset to the end of the ramp back, s."""
        return 2 * self.ramp_s + self.walking_hold_s

    @property
    def latest_onset_s(self) -> float:
        """Latest possible onset after heel contact (delay, latency, clipped jitter), s."""
        return max(
            delay / 1000 + self.trigger_latency_s + TRUNCATE_SD * sd
            for delay, sd in zip(self.timing_points_ms, self.onset_jitter_sd_s, strict=True)
        )


@dataclass(frozen=True)
class PlateConfig:
    """The force plate, its top plate's mass properties and its sensor dynamics.

    Attributes
    ----------
    a_m, b_m : float
        Sensor offsets from the plate centre along the plate's x and y, m.
    az0_m : float
        Plate surface offset from the sensor plane along the plate's z (down), m (< 0).
    anterior_axis : {"+x", "-x", "+y", "-y"}
        Plate axis that points in the walking direction (before the hinge yaw).
    yaw_rad : float
        Yaw of the plate axes relative to the hinge frame about z (down), rad.
    hinge_x_m : float
        Hinge axis position along the walking direction, from the plate centre, m.
    hinge_height_m : float
        Height of the hinge axis above the plate surface, m.
    top_mass_kg : float
        Mass of everything above the sensors (top plate and cover), kg.
    com_forward_m, com_depth_m, com_lateral_m : float
        Top-plate centre of mass relative to the hinge axis: in front of it, below it, to the
        right, m.
    top_inertia_kgm2 : float
        Top-plate moment of inertia about its centre of mass and the hinge direction, kg·m².
    vertical_frequency_hz, horizontal_frequency_hz : float
        Natural frequencies of the plate on its sensors (paper: ~300 and ~500 Hz); 0 makes the
        sensors rigid (no dynamics).
    sensor_damping_ratio : float
        Damping ratio of both sensor modes.
    """

    a_m: float = 0.12
    b_m: float = 0.20
    az0_m: float = -0.045
    anterior_axis: AnteriorAxis = "+x"
    yaw_rad: float = 0.0
    hinge_x_m: float = 0.0
    hinge_height_m: float = 0.08
    top_mass_kg: float = 12.0
    com_forward_m: float = 0.02
    com_depth_m: float = 0.10
    com_lateral_m: float = 0.0
    top_inertia_kgm2: float = 0.2
    vertical_frequency_hz: float = 300.0
    horizontal_frequency_hz: float = 500.0
    sensor_damping_ratio: float = 0.05

    def __post_init__(self) -> None:
        _positive(self, "a_m", "b_m", "hinge_height_m")
        _non_negative(self, "top_mass_kg", "top_inertia_kgm2", "com_depth_m")
        _non_negative(self, "vertical_frequency_hz", "horizontal_frequency_hz")
        _positive(self, "sensor_damping_ratio")
        _check(self.az0_m < 0, "az0_m", "< 0 (surface above the sensor plane)", self.az0_m)
        _check(
            self.anterior_axis in ANTERIOR_AXES,
            "anterior_axis",
            str(ANTERIOR_AXES),
            self.anterior_axis,
        )
        _check(abs(self.yaw_rad) < 0.2, "yaw_rad", "|yaw| < 0.2 rad", self.yaw_rad)

    @property
    def plate_angle_rad(self) -> float:
        """Total rotation from the hinge frame W to the plate frame P about z (down), rad."""
        return MOUNTING_ANGLE_RAD[self.anterior_axis] + self.yaw_rad


@dataclass(frozen=True)
class DriveConfig:
    """Servo, transmission and moving platform, all referred to the platform output.

    Attributes
    ----------
    motor_inertia_kgm2 : float
        Motor and gearbox input inertia times the gear ratio squared, kg·m².
    servo_frequency_hz, servo_damping_ratio : float
        Natural frequency and damping of the motor-side position loop (paper: ~200 Hz).
    servo_integral_ratio : float
        Integral corner frequency over the loop's natural frequency.
    transmission_stiffness_nm_per_rad : float
        Torsional stiffness of the gearbox and coupler in series, N·m/rad (paper: 12 N·m per
        arc minute = 41 253 N·m/rad).
    transmission_damping_ratio : float
        Damping ratio of the load-side torsion mode.
    structure_inertia_kgm2 : float
        Hinge structure and plate base (below the sensors) about the hinge axis, kg·m².
    structure_gravity_nm_per_rad : float
        Gravity restoring stiffness of the structure hanging below the hinge, N·m/rad.
    bearing_damping_nms_per_rad : float
        Viscous friction of the hinge bearings, N·m·s/rad.
    """

    motor_inertia_kgm2: float = 0.7
    servo_frequency_hz: float = 200.0
    servo_damping_ratio: float = 0.6
    servo_integral_ratio: float = 0.06
    transmission_stiffness_nm_per_rad: float = 12 * 60 * 180 / math.pi
    transmission_damping_ratio: float = 0.12
    structure_inertia_kgm2: float = 0.35
    structure_gravity_nm_per_rad: float = 25.0
    bearing_damping_nms_per_rad: float = 0.5

    def __post_init__(self) -> None:
        _positive(self, "motor_inertia_kgm2", "servo_frequency_hz", "servo_damping_ratio")
        _positive(self, "transmission_stiffness_nm_per_rad", "transmission_damping_ratio")
        _positive(self, "structure_inertia_kgm2")
        _non_negative(self, "servo_integral_ratio", "structure_gravity_nm_per_rad")
        _non_negative(self, "bearing_damping_nms_per_rad")


@dataclass(frozen=True)
class _Foot:
    """What every foot model shares: damping, inertia and the subject's ankle geometry.

    Attributes
    ----------
    damping_nms_per_rad : float
        Ankle damping b, N·m·s/rad.
    inertia_kgm2 : float
        Inertia I of the foot and the segments coupled to it, kg·m².
    ankle_height_m : float
        Height dz of the ankle centre above the plate surface, m.
    heel_to_ankle_m : float
        Anterior distance from the heel-contact COP to the ankle centre, m.
    """

    damping_nms_per_rad: float = 2.0
    inertia_kgm2: float = 0.3
    ankle_height_m: float = 0.08
    heel_to_ankle_m: float = 0.04

    def __post_init__(self) -> None:
        _non_negative(self, "damping_nms_per_rad")
        _positive(self, "inertia_kgm2", "ankle_height_m", "heel_to_ankle_m")


@dataclass(frozen=True)
class ProstheticFoot(_Foot):
    """A passive prosthetic foot whose stiffness depends on the lever arm of the load.

    ``k(dx)`` is linear through ``(lever_arms_m[0], stiffness_nm_per_rad[0])`` and
    ``(lever_arms_m[1], stiffness_nm_per_rad[1])`` (paper 000's bench: 1300 → 975 N·m/rad over
    6–11 cm), evaluated at the nominal lever arm ``dx`` with ``dx`` clipped to
    ``lever_arm_range_m``, and never below ``min_fraction`` of the first stiffness.

    Attributes
    ----------
    lever_arms_m : (float, float)
        Two lever arms that define the line, m.
    stiffness_nm_per_rad : (float, float)
        Stiffness at those lever arms, N·m/rad.
    lever_arm_range_m : (float, float)
        Lever arms outside this range use its ends, m.
    min_fraction : float
        Floor of the stiffness as a fraction of ``stiffness_nm_per_rad[0]``.
    bench_nonlinearity : float
        Testing-machine force deviation from the line (a cubic, orthogonal to the line), as a
        fraction of the largest force of a test.
    """

    model: Literal["prosthetic"] = "prosthetic"
    lever_arms_m: tuple[float, float] = (0.06, 0.11)
    stiffness_nm_per_rad: tuple[float, float] = (1300.0, 975.0)
    lever_arm_range_m: tuple[float, float] = (0.0, 0.18)
    min_fraction: float = 0.3
    bench_nonlinearity: float = 0.02

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(
            self.lever_arms_m[0] < self.lever_arms_m[1],
            "lever_arms_m",
            "increasing",
            self.lever_arms_m,
        )
        _check(min(self.stiffness_nm_per_rad) > 0, "stiffness_nm_per_rad", "> 0", ())
        _non_negative(self, "bench_nonlinearity", "min_fraction")


@dataclass(frozen=True)
class HumanAnkle(_Foot):
    """A human-like ankle whose stiffness rises over stance.

    ``k(t) = k100 · (1 + rise_per_150ms) ** ((t - t_hc - 0.1 s) / 0.15 s)
    · max(min_factor, 1 + lever_arm_slope_per_m · (dx - lever_arm_ref_m))``: the same relative
    rise over any 150 ms after heel contact ``t_hc``, optionally scaled by the nominal lever arm.

    Attributes
    ----------
    stiffness_100ms_nm_per_rad : float
        Stiffness 100 ms after heel contact at the reference lever arm, N·m/rad.
    rise_per_150ms : float
        Relative stiffness increase over any 150 ms (0.5: +50 %).
    lever_arm_slope_per_m : float
        Relative stiffness change per metre of lever arm, 1/m (0: no COP dependence).
    lever_arm_ref_m : float
        Lever arm at which the COP factor is 1, m.
    min_factor : float
        Floor of the COP factor.
    """

    model: Literal["human"] = "human"
    damping_nms_per_rad: float = 3.0
    inertia_kgm2: float = 0.06
    heel_to_ankle_m: float = 0.05
    stiffness_100ms_nm_per_rad: float = 250.0
    rise_per_150ms: float = 0.5
    lever_arm_slope_per_m: float = 0.0
    lever_arm_ref_m: float = 0.08
    min_factor: float = 0.3

    def __post_init__(self) -> None:
        super().__post_init__()
        _positive(self, "stiffness_100ms_nm_per_rad", "min_factor")
        _check(self.rise_per_150ms > -1, "rise_per_150ms", "> -1", self.rise_per_150ms)


@dataclass(frozen=True)
class GaitConfig:
    """Walking on the plate: GRF, COP path and ankle angle (README.md, "Walking trials").

    Forces are in body weights (BW), times in s after initial contact, COP in m along the walking
    direction; ``*_cv`` are trial-to-trial coefficients of variation, ``*_sd`` standard
    deviations (normal draws clipped at 3.5 sd).

    Attributes
    ----------
    body_mass_kg, stance_s, stance_cv, force_cv : float
        Subject mass (kg), mean stance duration (s) and their trial-to-trial variation.
    vertical_peak_bw, vertical_harmonics : float, (float, float, float)
        Peak vertical GRF (BW) and the shape coefficients (a2, a3, a5) of
        ``sin πs + a2 sin 2πs + a3 sin 3πs + a5 sin 5πs``.
    impact_bw, impact_time_s : float
        Heel-strike impact pulse: height (BW) and time to its peak (s).
    braking_bw, propulsion_bw, braking_fraction, ap_impact_bw : float
        Anterior GRF lobes (BW), the stance fraction where braking ends, an anterior impact.
    lateral_bw, free_moment_arm_m : float
        Medial GRF (BW) and free moment per unit vertical force (m).
    heel_rocker_speed_m_s, heel_rocker_time_s, midstance_cop_speed_m_s, cop_cv : float
        COP speed right after contact and its decay time, mid-stance COP speed, their variation.
    forefoot_accel_m_s2, heel_rise_fraction, foot_length_m : float
        COP acceleration after heel rise (m/s²), its stance fraction, the cap of the COP path.
    cop_transient_m, cop_transient_sd_m, cop_transient_time_s : float
        Initial COP transient ``A (u/τ) exp(1 - u/τ)``: mean and sd of A (m) and τ (s).
    lateral_cop_drift_m, foot_lateral_m, foot_lateral_sd_m : float
        Medial COP drift over stance and the foot's lateral placement right of the plate centre.
    ankle_hinge_offset_m, ankle_hinge_offset_sd_m : float
        Ankle centre in front of the hinge axis: mean and trial-to-trial sd, m.
    ankle_angle_scale, ankle_angle_cv : float
        Scale of the human ankle-angle curve and its trial-to-trial variation.
    """

    body_mass_kg: float = 80.0
    stance_s: float = 0.85
    stance_cv: float = 0.02
    force_cv: float = 0.03
    vertical_peak_bw: float = 1.1
    vertical_harmonics: tuple[float, float, float] = (0.03, 0.22, 0.0)
    impact_bw: float = 0.0
    impact_time_s: float = 0.02
    braking_bw: float = 0.15
    propulsion_bw: float = 0.17
    braking_fraction: float = 0.5
    ap_impact_bw: float = 0.0
    lateral_bw: float = 0.05
    free_moment_arm_m: float = 0.002
    heel_rocker_speed_m_s: float = 1.2
    heel_rocker_time_s: float = 0.06
    midstance_cop_speed_m_s: float = 0.13
    cop_cv: float = 0.04
    forefoot_accel_m_s2: float = 1.5
    heel_rise_fraction: float = 0.75
    foot_length_m: float = 0.26
    cop_transient_m: float = 0.0
    cop_transient_sd_m: float = 0.001
    cop_transient_time_s: float = 0.008
    lateral_cop_drift_m: float = 0.015
    foot_lateral_m: float = 0.0
    foot_lateral_sd_m: float = 0.01
    ankle_hinge_offset_m: float = 0.0
    ankle_hinge_offset_sd_m: float = 0.01
    ankle_angle_scale: float = 1.0
    ankle_angle_cv: float = 0.05

    def __post_init__(self) -> None:
        _positive(self, "body_mass_kg", "stance_s", "vertical_peak_bw", "heel_rocker_time_s")
        _positive(self, "impact_time_s", "cop_transient_time_s", "foot_length_m")
        _non_negative(self, "stance_cv", "force_cv", "cop_cv", "ankle_angle_cv")
        _non_negative(self, "heel_rocker_speed_m_s", "midstance_cop_speed_m_s")
        _non_negative(self, "forefoot_accel_m_s2", "impact_bw", "braking_bw", "propulsion_bw")
        _check(
            0.2 <= self.braking_fraction <= 0.8,
            "braking_fraction",
            "in [0.2, 0.8]",
            self.braking_fraction,
        )
        _check(
            0.3 <= self.heel_rise_fraction <= 1,
            "heel_rise_fraction",
            "in [0.3, 1]",
            self.heel_rise_fraction,
        )
        a2, a3, a5 = self.vertical_harmonics
        _check(
            abs(a2) + abs(a5) < 0.2 and 0 <= a3 < 0.45,
            "vertical_harmonics",
            "|a2| + |a5| < 0.2 and 0 <= a3 < 0.45 (a positive double hump)",
            self.vertical_harmonics,
        )


@dataclass(frozen=True)
class NoiseConfig:
    """Measurement imperfections at ``scale`` times a paper-like level (README.md, "Noise and DAQ").

    Every amplitude below is multiplied by ``scale``; ``scale = 0`` gives exact signals (no
    noise, drift, offsets, hum or quantisation).
    """

    scale: float = 1.0
    force_noise_n: float = 0.1
    force_drift_n_per_s: float = 0.01
    force_offset_n: float = 0.5
    hum_n: float = 0.05
    hum_hz: float = 60.0
    fz_lsb_n: float = 5000.0 / 65536
    fxy_lsb_n: float = 2500.0 / 65536
    motor_angle_noise_rad: float = 2e-6
    motor_angle_lsb_rad: float = 1e-4 / 70
    goniometer_noise_rad: float = 2e-4
    goniometer_gain_sd: float = 2.6e-3 / 0.09
    goniometer_lsb_rad: float = 21.0 / 65536
    goniometer_offset_sd_rad: float = 0.02
    bench_force_noise_n: float = 5.0

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            _check(value >= 0 and math.isfinite(value), name, "a finite number >= 0", value)


@dataclass(frozen=True)
class Config:
    """One session's full description: protocol, plate, drive, foot, gait and noise.

    ``kind`` is the label of the distribution the config was drawn from (``"custom"`` for a
    hand-made one). :meth:`to_dict` gives the nested dict stored in ``truth["config"]``.
    """

    protocol: ProtocolConfig = field(default_factory=ProtocolConfig)
    plate: PlateConfig = field(default_factory=PlateConfig)
    drive: DriveConfig = field(default_factory=DriveConfig)
    foot: ProstheticFoot | HumanAnkle = field(default_factory=ProstheticFoot)
    gait: GaitConfig = field(default_factory=GaitConfig)
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    kind: str = "custom"

    def __post_init__(self) -> None:
        protocol, gait = self.protocol, self.gait
        shortest_stance = gait.stance_s * (1 - TRUNCATE_SD * gait.stance_cv)
        needed = protocol.latest_onset_s + protocol.walking_move_s + 0.04
        _check(
            shortest_stance >= needed,
            "gait.stance_s",
            f"a stance long enough for the last perturbation to end 40 ms before toe-off "
            f"(>= {needed / (1 - TRUNCATE_SD * gait.stance_cv):.3f} s)",
            gait.stance_s,
        )
        last_end = protocol.contact_time_s[1] + 0.05 + needed
        _check(
            last_end <= protocol.trial_duration_s,
            "protocol.trial_duration_s",
            f"room for the last perturbation after the latest heel contact (>= {last_end:.3f} s)",
            protocol.trial_duration_s,
        )

    def to_dict(self) -> dict[str, Any]:
        """Nested dict of every parameter: numbers as floats, sequences as numpy arrays."""
        return _plain(asdict(self))


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, tuple | list):
        return np.asarray(value, dtype=float)
    if isinstance(value, bool | int | float):
        return float(value)
    return value
