"""Figures of studies, designs and batches (matplotlib, imported only when drawing)."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["design_figure", "group_figures", "study_figures"]

_LABELS = {
    "stiffness_nm_per_rad": "stiffness",
    "damping_nms_per_rad": "damping",
    "inertia_kgm2": "inertia",
    "cop_m": "lever arm",
}


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def study_figures(
    summary: pd.DataFrame, varied: Sequence[str], directory: Path, *, title: str
) -> list[Path]:
    """Stiffness error (bias ± seed-to-seed sd, and RMSE, in % of the truth) against each varied
    setting, one line per timing point; without a varied setting, against the timing point."""
    plt = _pyplot()
    directory.mkdir(parents=True, exist_ok=True)
    rows = summary[summary["quantity"] == "stiffness_nm_per_rad"]
    rows = rows.assign(**{key: rows[key].map(_tick) for key in varied})
    written = []
    keys: list[str | None] = [*varied] if varied else [None]
    for key in keys:
        x_key = key or "delay_ms"
        others = [k for k in varied if k != key]
        fig, (ax_bias, ax_rmse) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
        lines = [("all", rows)] if key is None else list(rows.groupby(["direction", "delay_ms"]))
        # one place per value for every line (a line may lack some: a grid of timing points)
        where, ticks = _positions(sorted(rows[x_key].unique()))
        for label, group in lines:
            table = group.groupby(x_key, sort=True)[["bias_percent", "sd_percent", "rmse_percent"]]
            mean = table.mean()
            xs = [where[value] for value in mean.index]
            name = "" if key is None else f"{label[0]} {label[1]:g} ms"
            ax_bias.errorbar(xs, mean["bias_percent"], yerr=mean["sd_percent"], marker="o",
                             capsize=3, label=name)  # fmt: skip
            ax_rmse.plot(xs, mean["rmse_percent"], marker="o", label=name)
        if ticks is not None:
            for ax in (ax_bias, ax_rmse):
                ax.set_xticks(list(where.values()), ticks)
        xlabel = "timing point, ms after heel contact" if key is None else _label(key)
        ax_bias.axhline(0.0, color="0.6", lw=0.8)
        ax_bias.set(xlabel=xlabel, ylabel="stiffness error, % of truth (mean ± sd over seeds)")
        ax_rmse.set(xlabel=xlabel, ylabel="stiffness RMSE, % of truth")
        ax_rmse.set_ylim(bottom=0)
        if key is not None:
            ax_rmse.legend(fontsize="small", title="timing point")
        note = f" (averaged over {', '.join(map(_label, others))})" if others else ""
        fig.suptitle(f"{title}: stiffness error{note}", fontsize="medium")
        path = directory / f"stiffness_error_vs_{_slug(x_key)}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def design_figure(curve: dict[str, Any], path: Path) -> Path:
    """Interval half-width and power against trials per timing point, with the pilot points and
    the recommendation."""
    plt = _pyplot()
    n = np.asarray(curve["trials_per_point"], dtype=float)
    fig, (ax_w, ax_p) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    ax_w.plot(n, curve["half_width_percent"], label="predicted (widest condition)")
    pilot = curve["pilot"]
    ax_w.plot(pilot["trials_per_point"], pilot["half_width_percent"], "o",
              label="pilot sessions (widest interval, mean)")  # fmt: skip
    ax_w.plot(pilot["trials_per_point"], pilot["fitted_half_width_percent"], "x", color="C1",
              label="the fit of the same intervals")  # fmt: skip
    ax_w.axhline(curve["target_percent"], color="C3", ls="--", label="target")
    ax_p.plot(n, np.asarray(curve["power"]) * 100)
    ax_p.axhline(curve["target_power"] * 100, color="C3", ls="--")
    for ax in (ax_w, ax_p):
        ax.axvline(curve["recommended"], color="0.4", ls=":", label="recommended")
        ax.set_xlabel("perturbed trials per timing point")
    ax_w.set(ylabel="stiffness interval half-width, % (95 %)", ylim=(0, None))
    ax_p.set(ylabel=f"power to detect a {curve['change_percent']:g} % change, %", ylim=(0, 101))
    ax_w.legend(fontsize="small")
    fig.suptitle(f"trials per timing point: {curve['recommended']} recommended", fontsize="medium")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def group_figures(group: pd.DataFrame, pooled: pd.DataFrame, directory: Path) -> list[Path]:
    """Stiffness against timing point: one line per subject (and direction), and pooled (mean
    of the subjects' means with its 95 % interval)."""
    plt = _pyplot()
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    rows = group[group["quantity"] == "stiffness_nm_per_rad"]
    for (subject, direction), part in rows.groupby(["subject", "direction"]):
        mean = part.groupby("delay_ms")["estimate"].mean()
        ax.plot(mean.index, mean.to_numpy(), marker="o", ls="-" if direction == "dorsi" else "--",
                label=f"{subject} {direction}")  # fmt: skip
    ax.set(xlabel="timing point, ms after heel contact", ylabel="stiffness, N·m/rad")
    ax.legend(fontsize="small", ncol=2)
    ax.set_title("stiffness per subject (mean of the subject's sessions)", fontsize="medium")
    written.append(directory / "stiffness_by_subject.png")
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    pooled = pooled[pooled["quantity"] == "stiffness_nm_per_rad"]
    for direction, part in pooled.groupby("direction"):
        lo = part["mean"] - part["ci95_low"]
        hi = part["ci95_high"] - part["mean"]
        ax.errorbar(part["delay_ms"], part["mean"], yerr=[lo.fillna(0), hi.fillna(0)],
                    marker="o", capsize=3, label=direction)  # fmt: skip
    ax.set(xlabel="timing point, ms after heel contact", ylabel="stiffness, N·m/rad")
    ax.legend(fontsize="small")
    ax.set_title("pooled: mean over subjects, 95 % interval (t)", fontsize="medium")
    written.append(directory / "stiffness_pooled.png")
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)
    return written


def _tick(value: Any) -> Any:
    """A setting as the figures group it: a list or table (``timing_points_ms``) as its text."""
    return str(value) if isinstance(value, list | tuple | dict) else value


def _positions(values: list[Any]) -> tuple[dict[Any, float], list[str] | None]:
    """Each value's place on the axis, and the tick labels: numbers are their own places;
    anything else is placed 0, 1, 2... and labelled."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return {v: float(v) for v in values}, None
    return {v: float(i) for i, v in enumerate(values)}, [str(v) for v in values]


def _label(key: str) -> str:
    """The full key, its unit apart (two keys may share their last part).

    >>> _label("params.geometry.misalignment_anterior_m")
    'params.geometry.misalignment anterior (m)'
    """
    head, _, leaf = key.rpartition(".")
    words = leaf.replace("_", " ")
    for suffix, unit in (("_m", "m"), ("_ms", "ms"), ("_hz", "Hz"), ("_rad", "rad"),
                         ("_rad_per_nm", "rad/(N·m)"), ("_s", "s")):  # fmt: skip
        if leaf.endswith(suffix) and not leaf.endswith("_per" + suffix):
            words = f"{leaf[: -len(suffix)].replace('_', ' ')} ({unit})"
            break
    return f"{head}.{words}" if head else words


def _slug(key: str) -> str:
    """The full key as part of a file name (``analysis.window_ms`` and
    ``params.walking.window_ms`` are two figures)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", key).strip("_.")
