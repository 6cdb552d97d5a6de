"""Figures of the capstan platform: identification fits, set-points, chirp tracking, observer,
haptic rendering, the display envelope, the Z-width, terrain scenes and teleoperation. Each
function writes one PNG and returns its path; matplotlib is imported only when a figure is
drawn (Agg backend). Legends sit beside or below the data, never on it; logarithmic axes are
labelled with plain numbers; every axis names its quantity and unit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from anklelab.control.envelope import DisplayEnvelope
    from anklelab.control.scene import SceneProfile
    from anklelab.data.capstan_ident import IdentData
    from anklelab.experiments.capstan import ChirpMetrics, StepMetrics
    from anklelab.experiments.capstan.envelope import EnvelopeCheck
    from anklelab.experiments.capstan.teleop import TeleopMetrics
    from anklelab.experiments.capstan.zwidth import ZWidthMeasurement
    from anklelab.ident.friction import FrictionIdentifier
    from anklelab.sim.capstan import SimulationResult

__all__ = [
    "chirp_tracking_figure",
    "envelope_figure",
    "friction_figures",
    "observer_figure",
    "render_figure",
    "scene_figure",
    "step_figure",
    "teleop_figure",
    "zwidth_figure",
]

PAPER_POINT = (3.0, 5.0)  # paper 001's chirp: 5 deg tracked well up to about 3 Hz


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=120)
    tmp.replace(path)
    _pyplot().close(fig)
    return path


def _legend_outside(ax: Any, **kwargs: Any) -> None:
    """A legend to the right of the axes, never over the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kwargs)


def _plain_log(axis: Any, ticks: Sequence[float]) -> None:
    """Label a logarithmic axis with plain numbers at ``ticks`` (no "3×10⁻¹")."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    axis.set_major_locator(FixedLocator(list(ticks)))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())


def _ticks(low: float, high: float) -> list[float]:
    candidates = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500]
    candidates += [1e3, 2e3, 5e3, 1e4, 2e4, 5e4, 1e5, 2e5, 5e5]
    return [t for t in candidates if low <= t <= high]


def friction_figures(model: FrictionIdentifier, data: IdentData, out: str | Path) -> list[Path]:
    """Spin-down fits, chirp fit and friction map of a fitted :class:`FrictionIdentifier`."""
    plt = _pyplot()
    out = Path(out)
    paths = []
    fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
    for k, fit in enumerate(model.spindown_fits_):
        ax.plot(
            fit.time_s,
            fit.velocity_rad_s,
            "-",
            lw=1.0,
            alpha=0.6,
            label="measured (one line per run)" if k == 0 else None,
        )
        ax.plot(
            fit.time_s,
            fit.fitted_rad_s,
            "--",
            color="k",
            lw=0.8,
            label="fitted exact solution" if k == 0 else None,
        )
    ax.set_xlabel("time after the torque cut (s)")
    ax.set_ylabel("pinion speed (rad/s)")
    ax.set_title(
        f"spin-down: exact solution fitted per direction (VAF {model.spindown_vaf_percent_:.2f} %)"
    )
    _legend_outside(ax)
    paths.append(_save(fig, out / "spindown_fit.png"))

    chirp = data.chirp[0]
    fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
    ax.plot(chirp.time_s, chirp.velocity_rad_s, lw=0.6, label="measured")
    ax.plot(chirp.time_s, model.chirp_prediction_, lw=0.6, label="identified model")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pinion speed (rad/s)")
    ax.set_title(f"open-loop torque chirp (VAF {model.chirp_vaf_percent_:.2f} %)")
    _legend_outside(ax)
    paths.append(_save(fig, out / "chirp_fit.png"))

    w, f = model.friction_map_
    fig, ax = plt.subplots(figsize=(8, 4.5), layout="constrained")
    ax.plot(w, f, ".", ms=2, alpha=0.4, label="measured, F = τ − J ω'")
    grid = np.linspace(-model.min_speed_rad_s, model.min_speed_rad_s, 801)
    grid = grid[grid != 0]
    ax.plot(grid, model.friction_torque(grid), "k-", lw=1, label="identified law")
    ax.set_xlabel("pinion speed (rad/s)")
    ax.set_ylabel("friction torque (N·m)")
    ax.set_title("low-speed friction map (Stribeck)")
    _legend_outside(ax, markerscale=4)
    paths.append(_save(fig, out / "friction_map.png"))
    return paths


def step_figure(
    runs: Sequence[tuple[SimulationResult, StepMetrics]], path: str | Path, *, pre_s: float = 0.2
) -> Path:
    """Set-point responses (measured angle and reference) in degrees."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
    for result, m in runs:
        t = result.time_s - pre_s
        label = f"{math.degrees(m.amplitude_rad):g} deg"
        (line,) = ax.plot(t, np.degrees(result["measured_angle_rad"]), lw=1.2, label=label)
        ax.plot(t, np.degrees(result["reference_rad"]), "--", color=line.get_color(), lw=0.8)
        if math.isfinite(m.rise_time_s) and math.isfinite(m.settling_time_5_s):
            ax.annotate(
                f"rise {m.rise_time_s * 1e3:.0f} ms, 5 % {m.settling_time_5_s * 1e3:.0f} ms",
                (t[-1], np.degrees(m.amplitude_rad)),
                ha="right",
                va="bottom",
                fontsize="small",
            )
    ax.axvline(0.3, color="0.6", lw=0.8, ls=":", label="paper 001's 300 ms")
    ax.set_xlabel("time after the set-point change (s)")
    ax.set_ylabel("platform angle (deg)")
    ax.set_title("set-point tracking (solid: encoder angle, dashed: reference)")
    _legend_outside(ax)
    return _save(fig, path)


def chirp_tracking_figure(
    result: SimulationResult, metrics: ChirpMetrics, path: str | Path
) -> Path:
    """Chirp tracking in time and the measured closed-loop frequency response."""
    plt = _pyplot()
    fig, (top, gain, phase) = plt.subplots(3, 1, figsize=(9, 8), layout="constrained")
    top.plot(result.time_s, np.degrees(result["reference_rad"]), lw=0.8, label="reference")
    top.plot(result.time_s, np.degrees(result["measured_angle_rad"]), lw=0.8, label="encoder angle")
    top.set_xlabel("time (s)")
    top.set_ylabel("platform angle (deg)")
    _legend_outside(top)
    f = metrics.frequency_hz
    gain.semilogx(f, 20 * np.log10(metrics.gain), "o-", ms=3)
    gain.axhspan(-1, 1, color="0.9", label="within 1 dB")
    gain.axhline(-3, color="0.6", ls=":", label="-3 dB")
    gain.set_ylabel("gain (dB)")
    _legend_outside(gain)
    phase.semilogx(f, metrics.phase_deg, "o-", ms=3)
    phase.axhspan(-20, 20, color="0.9", label="within 20 deg")
    phase.axhline(-45, color="0.6", ls=":", label="-45 deg")
    phase.set_ylabel("phase (deg)")
    phase.set_xlabel("frequency (Hz)")
    _legend_outside(phase)
    for ax in (gain, phase):
        _plain_log(ax.xaxis, _ticks(f.min(), f.max()))

    def hz(value: float) -> str:
        return f"{value:.2f} Hz" if np.isfinite(value) else f"beyond {f[-1]:.1f} Hz"

    gain.set_title(
        f"tracks within 1 dB / 20 deg up to {hz(metrics.tracking_limit_hz)}; -3 dB: "
        f"{hz(metrics.bandwidth_3db_hz)}"
    )
    return _save(fig, path)


def observer_figure(result: SimulationResult, path: str | Path, *, title: str = "") -> Path:
    """True interaction torque and the disturbance observer's estimate."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 4), layout="constrained")
    ax.plot(result.time_s, result["interaction_torque_nm"], lw=0.8, label="true (twin)")
    ax.plot(result.time_s, result["estimated_torque_nm"], lw=0.8, label="observer")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("human torque on the platform (N·m)")
    ax.set_title(title or "disturbance observer")
    _legend_outside(ax)
    return _save(fig, path)


def render_figure(
    result: SimulationResult, equilibrium: np.ndarray, path: str | Path, *, title: str = ""
) -> Path:
    """Rendered angle against the environment's equilibrium, and the human torque."""
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True, layout="constrained")
    top.plot(result.time_s, np.degrees(equilibrium), lw=0.8, label="equilibrium (terrain)")
    top.plot(result.time_s, np.degrees(result["angle_rad"]), lw=0.8, label="platform")
    top.set_ylabel("angle (deg)")
    _legend_outside(top)
    bottom.plot(result.time_s, result["interaction_torque_nm"], lw=0.8, label="true (twin)")
    bottom.plot(result.time_s, result["estimated_torque_nm"], lw=0.8, label="observer")
    bottom.set_ylabel("human torque (N·m)")
    bottom.set_xlabel("time (s)")
    _legend_outside(bottom)
    top.set_title(title or "haptic rendering")
    return _save(fig, path)


def envelope_figure(
    envelope: DisplayEnvelope, check: EnvelopeCheck | None, path: str | Path
) -> Path:
    """The display envelope: each limit, their minimum, the twin's, paper 001's point and a
    typical terrain's slope amplitudes (walking at 1 m/s over moderately rough ground)."""
    plt = _pyplot()
    f = envelope.frequency_hz
    fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
    names = {
        "workspace": "workspace limit",
        "speed": "speed limit",
        "torque": "torque limit",
        "voltage": "supply-voltage limit",
    }
    for key, label in names.items():
        ax.loglog(f, np.degrees(envelope.bounds[key]), ":", lw=1, label=label)
    ax.loglog(f, np.degrees(envelope.amplitude_rad), "k-", lw=2, label="envelope (model)")
    if check is not None:
        ax.loglog(
            f, np.degrees(check.simulated_rad), "o", ms=5, mfc="none", label="found on the twin"
        )
    terrain_f, terrain_deg = _terrain_slope_spectrum(np.geomspace(f.min(), f.max(), 200))
    ax.loglog(terrain_f, terrain_deg, "-", color="tab:green", lw=1.5, label="terrain slope (1 m/s)")
    ax.loglog(*PAPER_POINT, "r*", ms=12, label="paper 001: 5 deg at 3 Hz")
    if math.isfinite(envelope.fidelity_hz) and envelope.fidelity_hz < f.max():
        ax.axvline(envelope.fidelity_hz, color="0.5", ls="--", lw=0.8, label="loop bandwidth")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("amplitude (deg)")
    bottom = max(np.degrees(envelope.amplitude_rad).min() / 5, 1e-3)
    ax.set_ylim(bottom, 200)
    _plain_log(ax.xaxis, _ticks(f.min(), f.max()))
    _plain_log(ax.yaxis, _ticks(bottom, 200))
    ax.set_title("display envelope: the largest sinusoid the platform renders")
    _legend_outside(ax)
    return _save(fig, path)


def _terrain_slope_spectrum(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Slope amplitude per octave (deg) of ground of ISO 8608 class B roughness walked at 1 m/s:
    height PSD ``G(n) = 64e-6 (n / 0.1)^-2`` m^3 (n cycles/m), i.e. a slope PSD flat at
    ``(2 pi)^2 64e-6 0.01`` per cycle/m; averaged by a 0.25 m foot."""
    speed, foot = 1.0, 0.25
    n = f / speed
    slope_psd = (2 * np.pi) ** 2 * 64e-6 * 0.1**2  # (rad^2) per (cycle/m)
    foot_filter = np.minimum(1.0, 1.0 / (np.pi * n * foot))  # the foot's averaging, enveloped
    octave = n / np.sqrt(2)  # bandwidth of an octave around n
    amplitude = np.sqrt(2 * slope_psd * octave) * foot_filter
    return f, np.degrees(amplitude)


def zwidth_figure(z: ZWidthMeasurement, path: str | Path) -> Path:
    """The Z-width: analytic boundaries (both modes) and the twin's, against virtual damping."""
    plt = _pyplot()
    a = z.analytic
    b = z.damping_nms_per_rad
    fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
    dense = np.linspace(0, max(b.max(), 1e-3), 200)
    viscous = np.maximum(
        2 * (a.platform_damping_nms_per_rad + a.ankle_damping_nms_per_rad - a.leak * dense), 0
    )
    scale = a.viscous_nm_per_rad[0] / max(viscous[0], 1e-12) if viscous[0] else 1.0
    ax.semilogy(
        dense, np.maximum(viscous * scale, 1.0), "-", label="analytic: sampled-viscous mode"
    )
    ax.axhline(a.quantization_nm_per_rad, color="tab:orange", label="analytic: quantisation mode")
    markers = {
        "stomp": ("s", "twin: stomp (40 N·m, 30 ms)"),
        "nudge": ("o", "twin: nudge (10 N·m, 40 ms)"),
    }
    for push, values in z.measured_nm_per_rad.items():
        marker, label = markers[push]
        ax.semilogy(b, values, marker, mfc="none", ms=7, label=label)
    ax.set_xlabel("virtual damping B (N·m·s/rad)")
    ax.set_ylabel("largest stiffness K (N·m/rad)")
    ax.set_ylim(100, 3e5)
    _plain_log(ax.yaxis, _ticks(100, 3e5))
    ax.set_title("Z-width of impedance rendering (stable below the markers)")
    _legend_outside(ax)
    return _save(fig, path)


def scene_figure(
    result: SimulationResult, profile: SceneProfile, path: str | Path, *, title: str = ""
) -> Path:
    """A rendered scene: terrain and platform angle, the tracking error, the person's torque."""
    plt = _pyplot()
    t = result.time_s
    terrain = profile.slope_rad + profile.bumps_rad
    fig, (top, middle, bottom) = plt.subplots(
        3, 1, figsize=(9, 8), sharex=True, layout="constrained"
    )
    top.plot(t, np.degrees(profile.slope_rad), lw=1.0, label="slope component")
    top.plot(t, np.degrees(terrain), lw=0.6, label="terrain (slope + bumps)")
    top.plot(t, np.degrees(result["angle_rad"]), lw=0.6, label="platform")
    patches = profile.patch >= 0
    if patches.any():
        top.fill_between(
            t,
            0,
            1,
            where=patches,
            color="tab:green",
            alpha=0.15,
            transform=top.get_xaxis_transform(),
            label="compliant patch",
        )
    top.set_ylabel("angle (deg)")
    _legend_outside(top)
    middle.plot(t, np.degrees(result["angle_rad"] - terrain), lw=0.6, color="tab:red")
    middle.set_ylabel("platform minus terrain (deg)")
    bottom.plot(t, result["interaction_torque_nm"], lw=0.6, label="true (twin)")
    bottom.plot(t, result["estimated_torque_nm"], lw=0.6, label="observer")
    bottom.set_ylabel("person's torque (N·m)")
    bottom.set_xlabel("time (s)")
    _legend_outside(bottom)
    top.set_title(title or "terrain scene")
    return _save(fig, path)


def teleop_figure(
    runs: Sequence[tuple[SimulationResult, TeleopMetrics]],
    delays_ms: Sequence[float],
    path: str | Path,
    *,
    title: str = "",
) -> Path:
    """Tracking error against delay, and the longest delay's run in time."""
    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
    metrics = [m for _, m in runs]
    d = np.asarray(delays_ms, dtype=float)
    left.plot(
        d, [math.degrees(m.position_rms_error_rad) for m in metrics], "o-", label="angle (deg)"
    )
    left.plot(d, [m.force_rms_error_nm for m in metrics], "s-", label="torque (N·m)")
    unstable = [k for k, m in enumerate(metrics) if not m.stable]
    if unstable:
        left.plot(
            d[unstable],
            [math.degrees(metrics[k].position_rms_error_rad) for k in unstable],
            "rx",
            ms=10,
            label="unstable",
        )
    left.set_xlabel("one-way delay (ms)")
    left.set_ylabel("rms tracking error")
    left.set_title(title or "teleoperation")
    left.legend(loc="upper left", fontsize="small")
    left.set_ylim(bottom=0)
    result = runs[-1][0]
    right.plot(result.time_s, np.degrees(result["remote_angle_rad"]), lw=0.8, label="remote foot")
    right.plot(result.time_s, np.degrees(result["angle_rad"]), lw=0.8, label="platform")
    right.set_xlabel("time (s)")
    right.set_ylabel("angle (deg)")
    right.set_title(f"at {d[-1]:g} ms")
    _legend_outside(right)
    return _save(fig, path)
