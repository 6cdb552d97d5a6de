"""Session distributions ("kinds") and :func:`draw_config`, which samples one session from them.

README.md lists every range with its source. In short: each kind fixes the foot, the noise
level and the plate family; every kind draws the plate geometry and mass, the hinge yaw, the
servo and transmission, the COP path at heel strike, the gait variability, the onset jitter
and the number of trials.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from validation.cleanroom.config import (
    ANTERIOR_AXES,
    TRUNCATE_SD,
    Config,
    DriveConfig,
    GaitConfig,
    HumanAnkle,
    NoiseConfig,
    PlateConfig,
    ProstheticFoot,
    ProtocolConfig,
)

__all__ = ["KINDS", "draw_config"]

#: Paper 000 §2.1: 12 N·m per arc minute.
PAPER_TRANSMISSION_NM_PER_RAD = 12 * 60 * 180 / math.pi


@dataclass(frozen=True)
class _Kind:
    """What a kind fixes; everything else is drawn from the common ranges."""

    foot: str  # "prosthetic", "human" or "either"
    prosthetic_stiffness_6cm: tuple[float, float]
    noise_scale: tuple[float, float]
    plate_family: str  # "paper", "other" or "any"
    mountings: tuple[str, ...]


KINDS: dict[str, _Kind] = {
    "nominal": _Kind("prosthetic", (1150.0, 1450.0), (1.0, 1.5), "paper", ("+x",)),
    "stiff_prosthetic": _Kind("prosthetic", (1700.0, 2300.0), (1.0, 1.5), "other", ("+x",)),
    "noisy": _Kind("prosthetic", (750.0, 1000.0), (2.5, 3.0), "paper", ("+x",)),
    "mounted_y": _Kind("prosthetic", (1150.0, 1450.0), (1.0, 1.5), "paper", ("+y", "-y", "-x")),
    "human": _Kind("human", (0.0, 0.0), (1.0, 2.0), "paper", ("+x",)),
    "random": _Kind("either", (700.0, 2300.0), (1.0, 3.0), "any", ANTERIOR_AXES),
}

_PLATE_FAMILIES = {  # (a, b, az0, top-plate mass) ranges, m and kg
    "paper": ((0.10, 0.14), (0.18, 0.22), (-0.050, -0.035), (8.0, 16.0)),
    "other": ((0.18, 0.25), (0.08, 0.12), (-0.065, -0.050), (18.0, 30.0)),
    "any": ((0.08, 0.25), (0.08, 0.25), (-0.070, -0.030), (6.0, 30.0)),
}


def draw_config(
    kind: str,
    seed: int | np.random.Generator,
    *,
    trials_per_point: int | None = None,
    unperturbed_ratio: float = 4.0,
    n_calibration: int = 5,
    calibration_duration_s: float = 20.0,
    sample_rate_hz: float = 1000.0,
    bench: bool = True,
) -> Config:
    """Draw one session's configuration from the distribution ``kind``.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`: ``"nominal"``, ``"stiff_prosthetic"``, ``"noisy"``,
        ``"mounted_y"``, ``"human"``, ``"random"``.
    seed : int or numpy.random.Generator
        Fixes the draw.
    trials_per_point : int, optional
        Perturbed trials per timing point (default: drawn from 40–100).
    unperturbed_ratio : float
        Unperturbed trials per perturbed trial of one timing point (paper 000: ~4).
    n_calibration : int
        Calibration trials (paper 000: 5).
    calibration_duration_s : float
        Length of each calibration trial, s (paper 000: ~20 s).
    sample_rate_hz : float
        DAQ rate, Hz (paper 000: 1 kHz).
    bench : bool
        Include testing-machine tests for prosthetic feet (paper 000 §2.3).

    Returns
    -------
    Config

    Examples
    --------
    >>> config = draw_config("human", 3, trials_per_point=10)
    >>> config.foot.model, config.protocol.n_unperturbed
    ('human', 40)
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    if unperturbed_ratio < 0:
        raise ValueError(f"unperturbed_ratio: expected a number >= 0, got {unperturbed_ratio!r}")
    spec = KINDS[kind]
    rng = np.random.default_rng(seed)
    u = rng.uniform
    foot_model = spec.foot if spec.foot != "either" else rng.choice(["prosthetic", "human"])
    human = foot_model == "human"
    mass = u(55.0, 95.0) if human else u(60.0, 95.0)
    foot = _draw_human(rng, mass) if human else _draw_prosthetic(rng, spec)
    gait = _draw_gait(rng, human, mass)
    tpp = trials_per_point if trials_per_point is not None else int(rng.integers(40, 101))
    jitter_base, jitter_growth = u(0.0025, 0.004), u(0.0, 0.002)
    delays = (100.0, 225.0, 350.0, 475.0)
    protocol = ProtocolConfig(
        sample_rate_hz=sample_rate_hz,
        trials_per_point=tpp,
        n_unperturbed=round(unperturbed_ratio * tpp),
        n_calibration=n_calibration,
        calibration_duration_s=calibration_duration_s,
        trigger_latency_s=u(0.0, 0.003),
        onset_jitter_sd_s=tuple(jitter_base + jitter_growth * (d - 100) / 375 for d in delays),
        timing_points_ms=delays,
        bench_distances_m=()
        if human or not bench
        else tuple(d + u(-0.005, 0.005) for d in (0.06, 0.085, 0.11)),
    )
    gait = _fit_stance(gait, protocol)
    plate = _draw_plate(rng, spec, foot.ankle_height_m)
    noise = NoiseConfig(scale=u(*spec.noise_scale))
    return Config(protocol, plate, _draw_drive(rng), foot, gait, noise, kind=kind)


def _draw_prosthetic(rng: np.random.Generator, spec: _Kind) -> ProstheticFoot:
    """Paper 000's bench: 1300 → 975 N·m/rad (ratio 0.75) over 6–11 cm; inertia 0.30 kg·m²."""
    u = rng.uniform
    k6 = u(*spec.prosthetic_stiffness_6cm)
    return ProstheticFoot(
        stiffness_nm_per_rad=(k6, k6 * u(0.68, 0.85)),
        damping_nms_per_rad=u(1.0, 5.0),
        inertia_kgm2=u(0.20, 0.40),
        ankle_height_m=u(0.07, 0.10),
        heel_to_ankle_m=u(0.03, 0.06),
        bench_nonlinearity=u(0.0, 0.04),
    )


def _draw_human(rng: np.random.Generator, mass: float) -> HumanAnkle:
    """Walking ankle impedance of a ``mass`` kg subject: stiffness from 2–4 N·m/rad/kg 100 ms
    after heel contact, rising over stance; damping 0.02–0.05 N·m·s/rad/kg (README.md)."""
    u = rng.uniform
    return HumanAnkle(
        stiffness_100ms_nm_per_rad=mass * u(2.0, 4.0),
        rise_per_150ms=u(0.0, 0.6),
        lever_arm_slope_per_m=u(-4.0, 4.0) if rng.random() < 0.5 else 0.0,
        damping_nms_per_rad=mass * u(0.02, 0.05),
        inertia_kgm2=u(0.02, 0.08),
        ankle_height_m=u(0.06, 0.09),
        heel_to_ankle_m=u(0.04, 0.07),
    )


def _draw_gait(rng: np.random.Generator, human: bool, mass: float) -> GaitConfig:
    u = rng.uniform
    rocker_length, rocker_time = u(0.07, 0.10), u(0.03, 0.05)
    return GaitConfig(
        body_mass_kg=mass,
        stance_s=u(0.80, 0.90) if human else u(0.84, 0.95),
        stance_cv=u(0.01, 0.025),
        force_cv=u(0.02, 0.05),
        vertical_peak_bw=u(1.05, 1.20) if human else u(1.02, 1.12),
        vertical_harmonics=(
            u(-0.02, 0.06),
            u(0.18, 0.30) if human else u(0.10, 0.20),
            u(-0.04, 0.04),
        ),
        impact_bw=u(0.05, 0.30) if human else u(0.0, 0.08),
        impact_time_s=u(0.012, 0.03),
        braking_bw=u(0.10, 0.20),
        propulsion_bw=u(0.10, 0.22),
        braking_fraction=u(0.45, 0.55),
        ap_impact_bw=u(-0.05, 0.08),
        lateral_bw=u(0.03, 0.07),
        free_moment_arm_m=u(0.0, 0.004),
        heel_rocker_speed_m_s=rocker_length / rocker_time,
        heel_rocker_time_s=rocker_time,
        midstance_cop_speed_m_s=u(0.09, 0.16),
        cop_cv=u(0.02, 0.06),
        forefoot_accel_m_s2=u(1.0, 3.0),
        heel_rise_fraction=u(0.72, 0.82),
        foot_length_m=u(0.24, 0.29),
        cop_transient_m=u(-0.008, 0.008),
        cop_transient_sd_m=u(0.0005, 0.003),
        cop_transient_time_s=u(0.004, 0.015),
        lateral_cop_drift_m=u(0.005, 0.02),
        foot_lateral_m=u(-0.03, 0.03),
        foot_lateral_sd_m=u(0.005, 0.015),
        ankle_hinge_offset_m=u(-0.015, 0.015),
        ankle_hinge_offset_sd_m=u(0.005, 0.015),
        ankle_angle_scale=u(0.8, 1.2),
        ankle_angle_cv=u(0.03, 0.08),
    )


def _fit_stance(gait: GaitConfig, protocol: ProtocolConfig) -> GaitConfig:
    """Lengthen the stance where needed so the last perturbation ends 40 ms before toe-off."""
    needed = (protocol.latest_onset_s + protocol.walking_move_s + 0.041) / (
        1 - TRUNCATE_SD * gait.stance_cv
    )
    if gait.stance_s >= needed:
        return gait
    return replace(gait, stance_s=needed)


def _draw_plate(rng: np.random.Generator, spec: _Kind, ankle_height_m: float) -> PlateConfig:
    """Sensor geometry and top-plate mass per plate family; the hinge set to the ankle height
    with spacers (within 1.5 cm), yawed 0–3°; sensor modes near paper 000's 300 / 500 Hz."""
    u = rng.uniform
    a_range, b_range, az0_range, mass_range = _PLATE_FAMILIES[spec.plate_family]
    a, b, az0, mass = u(*a_range), u(*b_range), u(*az0_range), u(*mass_range)
    mounting = str(rng.choice(spec.mountings))
    hinge_height = ankle_height_m + u(-0.015, 0.015)
    com_height = -az0 * u(0.3, 0.6)  # above the sensor plane, below the surface
    along = 2 * (a if mounting in ("+x", "-x") else b) + u(0.04, 0.08)  # plate length, m
    return PlateConfig(
        a_m=a,
        b_m=b,
        az0_m=az0,
        anterior_axis=mounting,
        yaw_rad=math.radians(u(0.0, 3.0)) * rng.choice([-1.0, 1.0]),
        hinge_x_m=u(-0.03, 0.03),
        hinge_height_m=hinge_height,
        top_mass_kg=mass,
        com_forward_m=u(0.0, 0.05),
        com_depth_m=hinge_height + (-az0 - com_height),
        com_lateral_m=u(-0.01, 0.01),
        top_inertia_kgm2=mass * (along**2 + az0**2) / 12,
        vertical_frequency_hz=u(270.0, 330.0),
        horizontal_frequency_hz=u(450.0, 550.0),
        sensor_damping_ratio=u(0.03, 0.10),
    )


def _draw_drive(rng: np.random.Generator) -> DriveConfig:
    """Paper 000 §2.1 and DESIGN §7: ~200 Hz position loop, 12 N·m/arcmin transmission."""
    u = rng.uniform
    return DriveConfig(
        motor_inertia_kgm2=u(0.4, 1.0),
        servo_frequency_hz=u(120.0, 250.0),
        servo_damping_ratio=u(0.35, 0.8),
        servo_integral_ratio=u(0.03, 0.10),
        transmission_stiffness_nm_per_rad=PAPER_TRANSMISSION_NM_PER_RAD * u(0.75, 1.3),
        transmission_damping_ratio=u(0.2, 0.4),
        structure_inertia_kgm2=u(0.2, 0.6),
        structure_gravity_nm_per_rad=u(10.0, 60.0),
        bearing_damping_nms_per_rad=u(0.2, 2.0),
    )
