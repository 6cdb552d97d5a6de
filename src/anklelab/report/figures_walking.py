"""Figures of the walking impedance analysis (paper 000, Figs. 5-8).

Each function returns a matplotlib :class:`~matplotlib.figure.Figure` built without pyplot (no
global backend state; PNG rendering uses Agg), so importing this module does not import
matplotlib. :func:`save_walking_figures` writes them all as PNG files, atomically.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from anklelab._atomic import write_bytes_atomic
from anklelab.report.html import figure_png

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from anklelab.ident.irf import PlatformFilters
    from anklelab.pipelines.walking import WalkingResults

__all__ = [
    "filters_figure",
    "model_fit_figure",
    "save_walking_figures",
    "stance_figure",
    "stiffness_figure",
    "walking_figures",
]

_UNITS = {"angle": "N/rad", "velocity": "N·s/rad", "acceleration": "N·s²/rad"}
_COLORS = {"dorsi": "tab:blue", "plantar": "tab:orange"}


def _figure(rows: int, cols: int, width: float = 4.0, height: float = 2.6) -> tuple[Figure, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * cols, height * rows), layout="constrained")
    return fig, fig.subplots(rows, cols, squeeze=False)


def filters_figure(filters: PlatformFilters) -> Figure:
    """Platform filters per input pathway: horizontal channels left, vertical right.

    A pathway one lag long (the angle's, by default) is a static gain: one bar per channel.
    """
    fig, axes = _figure(len(filters.inputs), 2)
    for row, (name, n_lags) in enumerate(zip(filters.inputs, filters.lags, strict=True)):
        for col, vertical in enumerate((False, True)):
            ax = axes[row, col]
            picked = [c for c, ch in enumerate(filters.channels) if ch.startswith("fz") == vertical]
            ax.set_title(f"{name} → {'vertical' if vertical else 'horizontal'} channels")
            ax.axhline(0.0, color="0.7", lw=0.5)
            if n_lags == 1:
                labels = [filters.channels[c] for c in picked]
                ax.bar(labels, filters.irf_[picked, row, 0], color="tab:gray")
                ax.set_ylabel(f"static gain ({_UNITS[name]})")
                continue
            lag_ms = np.arange(n_lags) / filters.fs_ * 1000.0
            for c in picked:
                weights = filters.irf_[c, row, :n_lags] * filters.fs_
                ax.plot(lag_ms, weights, label=filters.channels[c], lw=1)
            ax.set_xlabel("lag (ms)")
            ax.set_ylabel(f"impulse response ({_UNITS[name]}/s)")
            ax.legend(fontsize="small", ncols=2)
    return fig


def _band(ax: Any, t: Any, data: Any, color: str, label: str) -> None:
    mean, sd = data.mean(axis=0), data.std(axis=0)
    ax.plot(t, mean, color=color, lw=1.5, label=label)
    ax.fill_between(t, mean - sd, mean + sd, color=color, alpha=0.25, lw=0)


def stance_figure(results: WalkingResults) -> Figure:
    """Ankle angle and torque after heel contact, perturbed vs unperturbed (paper 000, Fig. 5)."""
    points = results.timing_points
    fig, axes = _figure(max(1, len(points)), 2, width=4.5)
    stance = results.stance
    t_ms = stance.times * 1000.0
    none = stance["none"]
    for row, tp in enumerate(points):
        group = stance[tp.key]
        for col, (channel, unit) in enumerate((("angle", "rad"), ("torque", "N·m"))):
            ax = axes[row, col]
            _band(ax, t_ms, none.get_data(channel), "black", f"unperturbed (n={len(none)})")
            _band(
                ax,
                t_ms,
                group.get_data(channel),
                _COLORS[tp.direction],
                f"{tp.key} (n={len(group)})",
            )
            ax.axvline(np.mean(tp.onset_ms), color="0.4", ls=":", lw=1)
            ax.set_xlabel("time after heel contact (ms)")
            ax.set_ylabel(f"ankle {channel} ({unit})")
            ax.legend(fontsize="small")
    return fig


def model_fit_figure(results: WalkingResults) -> Figure:
    """Perturbation torque measured vs the 2nd-order model per condition (paper 000, Fig. 7b)."""
    points = results.timing_points
    cols = min(4, max(1, len(points)))
    rows = -(-max(1, len(points)) // cols)
    fig, axes = _figure(rows, cols, width=3.6)
    for ax, tp in zip(axes.flat, points, strict=False):
        t_ms = tp.time_s * 1000.0
        _band(ax, t_ms, tp.torque, _COLORS[tp.direction], "measured")
        ax.plot(t_ms, tp.model_torque.mean(axis=0), "k--", lw=1.2, label="model")
        ax.set_title(
            f"{tp.key}: k={tp.stiffness.mean:.0f} N·m/rad, VAF {tp.vaf.mean:.1f} %",
            fontsize="medium",
        )
        ax.set_xlabel("time after onset (ms)")
        ax.set_ylabel("torque (N·m)")
        ax.legend(fontsize="small")
    for ax in list(axes.flat)[len(points) :]:
        ax.set_visible(False)
    return fig


def stiffness_figure(results: WalkingResults) -> Figure:
    """Walking stiffness (95 % intervals) against lever arm with the bench line (paper 000,
    Fig. 8)."""
    fig, axes = _figure(1, 1, width=5.5, height=4.0)
    ax = axes[0, 0]
    if results.bench:
        d = np.array([row.distance_m for row in results.bench]) * 100.0
        k = np.array([row.stiffness_nm_per_rad for row in results.bench])
        ax.plot(d, k, "ks-", label="bench (testing machine)")
    for direction, color in _COLORS.items():
        points = [tp for tp in results.timing_points if tp.direction == direction]
        if points:
            k = np.array([tp.stiffness.mean for tp in points])
            interval = np.array([tp.stiffness.ci95 for tp in points]).T
            ax.errorbar(
                [tp.cop_m * 100.0 for tp in points],
                k,
                yerr=np.abs(interval - k),
                fmt="o",
                color=color,
                capsize=3,
                label=f"walking, {direction}",
            )
    ax.set_xlabel("lever arm / actuator distance (cm)")
    ax.set_ylabel("stiffness (N·m/rad)")
    ax.legend()
    return fig


def walking_figures(results: WalkingResults) -> dict[str, Figure]:
    """Every walking figure, by file stem."""
    return {
        "filters": filters_figure(results.filters),
        "stance_profiles": stance_figure(results),
        "model_fit": model_fit_figure(results),
        "stiffness_vs_lever_arm": stiffness_figure(results),
    }


def save_walking_figures(results: WalkingResults, directory: str | Path) -> list[Path]:
    """Write every walking figure as ``DIRECTORY/<name>.png`` (atomically); returns the paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return [
        write_bytes_atomic(directory / f"{name}.png", figure_png(fig))
        for name, fig in walking_figures(results).items()
    ]
