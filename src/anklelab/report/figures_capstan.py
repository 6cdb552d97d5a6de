"""Figures of the capstan platform: identification fits, set-points, chirp tracking, observer,
haptic rendering. Each function writes one PNG and returns its path; matplotlib is imported
only when a figure is drawn (Agg backend).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from anklelab.data.capstan_ident import IdentData
    from anklelab.experiments.capstan import ChirpMetrics, StepMetrics
    from anklelab.ident.friction import FrictionIdentifier
    from anklelab.sim.capstan import SimulationResult

__all__ = [
    "chirp_tracking_figure",
    "friction_figures",
    "observer_figure",
    "render_figure",
    "step_figure",
]


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


def friction_figures(model: FrictionIdentifier, data: IdentData, out: str | Path) -> list[Path]:
    """Spin-down fits, chirp fit and friction map of a fitted :class:`FrictionIdentifier`."""
    plt = _pyplot()
    out = Path(out)
    paths = []
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for fit in model.spindown_fits_:
        (line,) = ax.plot(fit.time_s, fit.velocity_rad_s, ".", ms=2, alpha=0.5)
        ax.plot(fit.time_s, fit.fitted_rad_s, "-", color=line.get_color(), lw=1)
    ax.set_xlabel("time after the torque cut (s)")
    ax.set_ylabel("pinion speed (rad/s)")
    ax.set_title(
        f"spin-down: exact solution fitted per direction (VAF {model.spindown_vaf_percent_:.2f} %)"
    )
    paths.append(_save(fig, out / "spindown_fit.png"))

    chirp = data.chirp[0]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(chirp.time_s, chirp.velocity_rad_s, lw=0.6, label="measured")
    ax.plot(chirp.time_s, model.chirp_prediction_, lw=0.6, label="identified model")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pinion speed (rad/s)")
    ax.set_title(f"open-loop torque chirp (VAF {model.chirp_vaf_percent_:.2f} %)")
    ax.legend(loc="upper left")
    paths.append(_save(fig, out / "chirp_fit.png"))

    w, f = model.friction_map_
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(w, f, ".", ms=2, alpha=0.4, label="measured (F = tau - J w')")
    grid = np.linspace(-model.min_speed_rad_s, model.min_speed_rad_s, 801)
    grid = grid[grid != 0]
    fitted = model.friction_torque(grid)
    ax.plot(grid, fitted, "k-", lw=1, label="identified")
    ax.set_xlabel("pinion speed (rad/s)")
    ax.set_ylabel("friction torque (N·m)")
    ax.set_title("low-speed friction map (Stribeck)")
    ax.legend()
    paths.append(_save(fig, out / "friction_map.png"))
    return paths


def step_figure(
    runs: Sequence[tuple[SimulationResult, StepMetrics]], path: str | Path, *, pre_s: float = 0.2
) -> Path:
    """Set-point responses (measured angle and reference) in degrees."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for result, m in runs:
        t = result.time_s - pre_s
        (line,) = ax.plot(t, np.degrees(result["measured_angle_rad"]), lw=1.2)
        ax.plot(t, np.degrees(result["reference_rad"]), "--", color=line.get_color(), lw=0.8)
        ax.annotate(
            f"rise {m.rise_time_s * 1e3:.0f} ms, 5 % {m.settling_time_5_s * 1e3:.0f} ms",
            (t[-1], np.degrees(m.amplitude_rad)),
            ha="right",
            va="bottom",
            fontsize="small",
        )
    ax.axvline(0.3, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel("time after the set-point change (s)")
    ax.set_ylabel("platform angle (deg)")
    ax.set_title("set-point tracking (dotted: paper 001's 300 ms)")
    return _save(fig, path)


def chirp_tracking_figure(
    result: SimulationResult, metrics: ChirpMetrics, path: str | Path
) -> Path:
    """Chirp tracking in time and the measured closed-loop frequency response."""
    plt = _pyplot()
    fig, (top, gain, phase) = plt.subplots(3, 1, figsize=(8, 8))
    top.plot(result.time_s, np.degrees(result["reference_rad"]), lw=0.8, label="reference")
    top.plot(result.time_s, np.degrees(result["measured_angle_rad"]), lw=0.8, label="measured")
    top.set_xlabel("time (s)")
    top.set_ylabel("angle (deg)")
    top.legend(loc="upper left")
    gain.semilogx(metrics.frequency_hz, 20 * np.log10(metrics.gain), "o-", ms=3)
    gain.axhline(-3, color="0.6", ls=":")
    gain.set_ylabel("gain (dB)")
    phase.semilogx(metrics.frequency_hz, metrics.phase_deg, "o-", ms=3)
    phase.axhline(-45, color="0.6", ls=":")
    phase.set_ylabel("phase (deg)")
    phase.set_xlabel("frequency (Hz)")
    top_hz = metrics.frequency_hz[-1]

    def hz(value: float) -> str:
        return f"{value:.2f} Hz" if np.isfinite(value) else f"beyond {top_hz:.1f} Hz"

    gain.set_title(
        f"-3 dB: {hz(metrics.bandwidth_3db_hz)}, 45 deg lag: {hz(metrics.bandwidth_45deg_hz)}"
    )
    fig.tight_layout()
    return _save(fig, path)


def observer_figure(result: SimulationResult, path: str | Path, *, title: str = "") -> Path:
    """True interaction torque and the disturbance observer's estimate."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(result.time_s, result["interaction_torque_nm"], lw=0.8, label="true (twin)")
    ax.plot(result.time_s, result["estimated_torque_nm"], lw=0.8, label="observer")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("human torque on the platform (N·m)")
    ax.set_title(title or "disturbance observer")
    ax.legend(loc="upper left")
    return _save(fig, path)


def render_figure(
    result: SimulationResult, equilibrium: np.ndarray, path: str | Path, *, title: str = ""
) -> Path:
    """Rendered angle against the environment's equilibrium, and the human torque."""
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    top.plot(result.time_s, np.degrees(equilibrium), lw=0.8, label="equilibrium (terrain)")
    top.plot(result.time_s, np.degrees(result["angle_rad"]), lw=0.8, label="platform")
    top.set_ylabel("angle (deg)")
    top.legend(loc="upper left")
    bottom.plot(result.time_s, result["interaction_torque_nm"], lw=0.8, label="true")
    bottom.plot(result.time_s, result["estimated_torque_nm"], lw=0.8, label="observer")
    bottom.set_ylabel("human torque (N·m)")
    bottom.set_xlabel("time (s)")
    bottom.legend(loc="upper left")
    top.set_title(title or "haptic rendering")
    fig.tight_layout()
    return _save(fig, path)
