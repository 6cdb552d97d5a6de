"""Render a terrain scene (:mod:`anklelab.control.scene`) on the twin, and the rendering error
by component.

- The **slope** component, low-passed at :data:`SPLIT_HZ` (zero phase; the foot rolls over a
  step's edge in a fraction of a second), and further (the cut-off halved until it does) so
  that it never asks for more than 80 % of the speed limit, is a position reference tracked
  with the inverse-dynamics feed-forward.
- The **bumps** component is superimposed, first scaled band by band (octaves from 0.5 Hz) so
  that its peak stays within 90 % of the display envelope (:mod:`anklelab.control.envelope`) at
  the band's top frequency.
- On **compliant patches** the reference is the terrain's angle plus the admittance's virtual
  deflection, driven by the disturbance observer's estimate of the person's torque
  (:class:`~anklelab.experiments.capstan.CapstanSetup.for_rendering`).

The person guard limits the torque and jerk; its fall detector is off (the terrain changes the
ankle's torque as fast as a fall): a stop request ends the walk safely.

The errors compare the twin's true angle with the terrain: below and above
:data:`SPLIT_HZ` on rigid ground (slope and bumps), and on each patch the stiffness and damping
the foot felt (least squares of the interaction torque on the deflection and its derivatives).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from anklelab.control.haptics import VirtualEnvironment
from anklelab.control.scene import Scene, SceneProfile, scene_profile
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.experiments.capstan.envelope import analytic_envelope
from anklelab.iir import butterworth_sos, sosfiltfilt
from anklelab.sim.capstan import SimulationResult, voluntary_torque

__all__ = ["SPLIT_HZ", "PatchMetrics", "SceneMetrics", "fit_bumps_to_envelope", "render_scene"]

SPLIT_HZ = 2.0
ENVELOPE_MARGIN = 0.9
SPEED_MARGIN = 0.8
PATCH_SETTLE_S = 0.3


@dataclass(frozen=True)
class PatchMetrics:
    """What the foot felt on one compliant patch.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad : float
        Commanded.
    felt_stiffness_nm_per_rad, felt_damping_nms_per_rad : float
        Fitted from the twin's true deflection and interaction torque.
    stiffness_error_percent, damping_error_percent : float
        Relative to the commanded values (NaN for a commanded damping of 0).
    """

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float
    felt_stiffness_nm_per_rad: float
    felt_damping_nms_per_rad: float
    stiffness_error_percent: float
    damping_error_percent: float


@dataclass(frozen=True)
class SceneMetrics:
    """The rendering error by component.

    Attributes
    ----------
    slope_rms_rad, slope_rms_error_rad : float
        RMS of the slope component and of the error below ``SPLIT_HZ``, on rigid ground.
    bumps_rms_rad, bumps_rms_error_rad : float
        RMS of the rendered (scaled) bumps and of the error above ``SPLIT_HZ``, rigid ground.
    bump_scales : dict of str to float
        The factor each octave band of the bumps was scaled by to fit the envelope (1: none).
    patches : list of PatchMetrics
        One per compliant patch.
    fault : int
        The latched fault code (0: none).
    """

    slope_rms_rad: float
    slope_rms_error_rad: float
    bumps_rms_rad: float
    bumps_rms_error_rad: float
    bump_scales: dict[str, float]
    patches: list[PatchMetrics]
    fault: int


def fit_bumps_to_envelope(
    bumps: NDArray[np.float64], fs: float, envelope: object
) -> tuple[NDArray[np.float64], dict[str, float]]:
    """Scale each octave band of ``bumps`` so that its peak stays within the envelope.

    ``envelope`` is a callable giving the largest amplitude (rad) at frequencies (Hz).
    """
    spectrum = np.fft.rfft(bumps)
    f = np.fft.rfftfreq(bumps.size, 1.0 / fs)
    edges = [0.0, 0.5]
    while edges[-1] * 2 < fs / 2:
        edges.append(edges[-1] * 2)
    edges.append(fs / 2 + 1.0)
    scaled = np.zeros_like(spectrum)
    scales: dict[str, float] = {}
    for lo, hi in itertools.pairwise(edges):
        band = (f >= lo) & (f < hi)
        if not band.any():
            continue
        part = np.where(band, spectrum, 0.0)
        peak = np.max(np.abs(np.fft.irfft(part, n=bumps.size)))
        top = min(hi, fs / 2)
        limit = ENVELOPE_MARGIN * float(envelope(np.array([max(top, 0.1)]))[0])  # type: ignore[operator]
        scale = 1.0 if peak <= limit or peak == 0 else limit / peak
        if peak > 0:
            scales[f"{lo:g}-{top:g} Hz"] = scale
        scaled += scale * part
    return np.fft.irfft(scaled, n=bumps.size), scales


def _fit_patch(
    deflection: NDArray[np.float64], torque: NDArray[np.float64], fs: float
) -> tuple[float, float]:
    speed = np.gradient(deflection, 1.0 / fs)
    acceleration = np.gradient(speed, 1.0 / fs)
    design = np.column_stack([deflection, speed, acceleration])
    k, b, _ = np.linalg.lstsq(design, torque, rcond=None)[0]
    return float(k), float(b)


def _percent(felt: float, wanted: float) -> float:
    return 100.0 * (felt - wanted) / wanted if wanted else math.nan


def render_scene(
    scene: Scene, setup: CapstanSetup | None = None, *, seed: int | np.random.Generator = 0
) -> tuple[SimulationResult, SceneMetrics, SceneProfile]:
    """Render ``scene`` on the twin (see the module notes).

    Parameters
    ----------
    scene : Scene
        The terrain, speed, patches and person.
    setup : CapstanSetup, optional
        Platform and controller; its person is replaced by the scene's. Default: the shipped
        platform at 1 kHz, set up for rendering.
    seed : int or Generator
        The person's voluntary pushes and sway, and sensor noise.

    Returns
    -------
    result : SimulationResult
    metrics : SceneMetrics
    profile : SceneProfile
        The terrain in time as rendered (the slope low-passed, the bumps scaled to the
        envelope).
    """
    base = CapstanSetup.for_rendering() if setup is None else setup
    person = None if scene.person == "seated" else scene.person
    setup = dataclasses.replace(
        base,
        person=person,
        with_user=scene.person == "seated",
        feedforward=True,
        lag_compensation=True,
        fall_detection=False,
    )
    profile = scene_profile(scene, setup.fs)
    limit = setup.params.safety.angle_limit_rad
    if np.max(np.abs(profile.slope_rad)) > 0.9 * limit:
        raise ParameterError(
            f"scene {scene.name!r}: the terrain tilts the foot by up to "
            f"{math.degrees(np.max(np.abs(profile.slope_rad))):.1f} deg, beyond 90 % of the "
            f"platform's {math.degrees(limit):.1f} deg limit"
        )

    grid = np.geomspace(0.05, setup.fs / 2, 200)
    amplitudes = analytic_envelope(setup, grid).amplitude_rad

    def envelope(f: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.interp(np.log(f), np.log(grid), amplitudes)

    top_speed = SPEED_MARGIN * setup.params.safety.velocity_limit_rad_s
    cutoff = SPLIT_HZ
    slope = sosfiltfilt(butterworth_sos(2, cutoff, setup.fs), profile.slope_rad)
    while np.max(np.abs(np.gradient(slope, 1.0 / setup.fs))) > top_speed and cutoff > 0.05:
        cutoff /= 2
        slope = sosfiltfilt(butterworth_sos(2, cutoff, setup.fs), profile.slope_rad)
    bumps, scales = fit_bumps_to_envelope(profile.bumps_rad, setup.fs, envelope)
    profile = dataclasses.replace(profile, slope_rad=slope, bumps_rad=bumps)
    terrain = slope + bumps
    speed = np.gradient(terrain, 1.0 / setup.fs)
    rng = np.random.default_rng(seed)
    pushes = voluntary_torque(
        terrain.size / setup.fs, setup.fs, rms_nm=scene.voluntary_torque_rms_nm, seed=rng
    )
    env = VirtualEnvironment(
        stiffness_nm_per_rad=math.inf,
        damping_nms_per_rad=0.0,
        inertia_kgm2=profile.inertia_kgm2,
        angle_limit_rad=limit,
    )
    result = simulate_closed_loop(
        setup,
        terrain.size,
        mode="admittance",
        reference=terrain,
        reference_speed=speed,
        reference_acceleration=np.gradient(speed, 1.0 / setup.fs),
        environment=env,
        stiffness=profile.stiffness_nm_per_rad,
        damping=profile.damping_nms_per_rad,
        voluntary=pushes,
        seed=rng,
    )
    error = result["angle_rad"] - terrain
    slow = sosfiltfilt(butterworth_sos(2, SPLIT_HZ, setup.fs), error)
    rigid = profile.patch < 0
    patches = []
    for k, patch in enumerate(scene.compliant):
        on = np.flatnonzero(profile.patch == k)[round(PATCH_SETTLE_S * setup.fs) :]
        if on.size < 3:
            continue
        felt_k, felt_b = _fit_patch(error[on], result["interaction_torque_nm"][on], setup.fs)
        patches.append(
            PatchMetrics(
                patch.stiffness_nm_per_rad,
                patch.damping_nms_per_rad,
                felt_k,
                felt_b,
                _percent(felt_k, patch.stiffness_nm_per_rad),
                _percent(felt_b, patch.damping_nms_per_rad),
            )
        )

    def rms(x: NDArray[np.float64]) -> float:
        return float(np.sqrt(np.mean(x**2))) if x.size else math.nan

    metrics = SceneMetrics(
        slope_rms_rad=rms(profile.slope_rad[rigid]),
        slope_rms_error_rad=rms(slow[rigid]),
        bumps_rms_rad=rms(bumps[rigid]),
        bumps_rms_error_rad=rms((error - slow)[rigid]),
        bump_scales=scales,
        patches=patches,
        fault=int(result["fault"].max()),
    )
    return result, metrics, profile
