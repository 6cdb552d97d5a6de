"""Figures of the walking impedance analysis (paper 000, Figs. 5-8).

The impedance summaries (against timing point and lever arm) come from
:mod:`anklelab.report.figures_impedance`, drawn from what ``results.json`` holds.

Each function returns a matplotlib :class:`~matplotlib.figure.Figure` built without pyplot (no
global backend state; PNG rendering uses Agg), so importing this module does not import
matplotlib. :func:`save_walking_figures` writes them all as PNG files, atomically.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from anklelab._atomic import write_bytes_atomic
from anklelab.report._panels import LINE_IN, SMALL_LINE_IN, Margins, panel_grid, set_title
from anklelab.report.figures_impedance import impedance_figure
from anklelab.report.render import FigureRenderer, PendingFigures

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from anklelab.ident.irf import PlatformFilters
    from anklelab.pipelines.walking import WalkingResults

__all__ = [
    "WALKING_FIGURES",
    "filters_figure",
    "model_fit_figure",
    "save_walking_figures",
    "stance_figure",
    "submit_filters_figure",
    "walking_figure",
    "walking_figures",
]

_UNITS = {"angle": "N/rad", "velocity": "N·s/rad", "acceleration": "N·s²/rad"}
_COLORS = {"dorsi": "tab:blue", "plantar": "tab:orange"}
_DIRECTION_WORDS = {"dorsi": "dorsiflexion", "plantar": "plantarflexion"}
_TIMING_COLORS = ("tab:blue", "tab:green", "tab:orange", "tab:red", "tab:purple", "tab:brown")
# the channels come in pairs that carry the same signal on a symmetric plate (fx12/fx34,
# fz1/fz4, fz2/fz3): the first of a pair wide and pale, the second thin and dashed on top, so
# a line never hides another
_STYLES = ({"lw": 4.0, "alpha": 0.45, "ls": "-"}, {"lw": 1.3, "alpha": 1.0, "ls": "--"})
_PAIRS = {"fx12": 0, "fx34": 1, "fy14": 0, "fy23": 1, "fz1": 0, "fz4": 1, "fz2": 0, "fz3": 1}
_PAIR_COLORS = {"fx12": "tab:blue", "fx34": "tab:blue", "fy14": "tab:gray", "fy23": "tab:gray"}
_PAIR_COLORS |= {"fz1": "tab:red", "fz4": "tab:red", "fz2": "tab:green", "fz3": "tab:green"}
_LEGEND_IN = LINE_IN + 0.15
"""Room for one row of a figure legend below the panels, inches."""
_LEGEND_COLUMNS = 5
"""Entries in a row of a figure legend: five entries such as "perturbed at 475 ms" fill 11 in."""
_TITLE_COLUMNS = 4
"""Beyond this many timing points a model-fit panel's title takes three lines, not two."""
_PANEL_LEGEND_ROWS = 2
"""Rows of the legend below each filter panel (up to five entries, three columns)."""
# the stance channels the stance figure draws: name, axis label, scale
_STANCE_DRAWN = (
    ("angle", "ankle angle (deg)", np.degrees(1.0)),
    ("torque", "ankle torque (N·m)", 1.0),
)


def _legend_rows(entries: int) -> int:
    """Rows of a figure legend of ``entries`` below the panels (:data:`_LEGEND_COLUMNS` a row)."""
    return max(1, math.ceil(entries / _LEGEND_COLUMNS))


def _legend_below(fig: Figure, ax: Any) -> None:
    """One legend for the figure, below every panel (it never covers data), in the
    ``_legend_rows`` rows of :data:`_LEGEND_IN` the figure's bottom margin keeps for it."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(
        handles,
        labels,
        loc="lower center",
        bbox_to_anchor=(0.5, 0.0),
        ncols=min(len(labels), _LEGEND_COLUMNS),
        frameon=False,
    )


def filters_figure(filters: PlatformFilters) -> Figure:
    """Platform filters per input pathway: horizontal channels left, vertical right.

    A pathway one lag long (the angle's, by default) is a static gain: one bar per channel.
    A longer pathway is drawn against lag, its last lag as a separate marker: that weight stands
    for the part of the response the filter's length cuts off (see the report guide), not for
    the decaying response itself.
    """
    legend_in = _PANEL_LEGEND_ROWS * SMALL_LINE_IN + LINE_IN  # x label, then the legend
    legends = [n_lags > 1 for n_lags in filters.lags]  # a filter drawn by lag has a legend below
    margins = Margins(
        bottom=Margins.bottom + legend_in * legends[-1],
        between_rows=0.6 + (legend_in + 0.25) * any(legends[:-1]),
    )
    fig, axes = panel_grid(len(filters.inputs), 2, 11.0, 3.1 * len(filters.inputs), margins)
    for row, (name, n_lags) in enumerate(zip(filters.inputs, filters.lags, strict=True)):
        for col, vertical in enumerate((False, True)):
            ax = axes[row, col]
            picked = [c for c, ch in enumerate(filters.channels) if ch.startswith("fz") == vertical]
            set_title(ax, f"{name} → {'vertical' if vertical else 'horizontal'} force channels")
            ax.axhline(0.0, color="0.7", lw=0.5)
            if n_lags == 1:
                labels = [filters.channels[c] for c in picked]
                ax.bar(labels, filters.irf_[picked, row, 0], color="tab:gray")
                ax.set_ylabel(f"static gain ({_UNITS[name]})")
                continue
            lag_ms = np.arange(n_lags) / filters.fs_ * 1000.0
            for c in picked:
                channel = filters.channels[c]
                weights = filters.irf_[c, row, :n_lags] * filters.fs_
                style = _STYLES[_PAIRS.get(channel, 0)]
                color = _PAIR_COLORS.get(channel)
                (line,) = ax.plot(lag_ms[:-1], weights[:-1], label=channel, color=color, **style)
                ax.plot(lag_ms[-1], weights[-1], "o", mfc="none", color=line.get_color(), ms=6)
            ax.plot([], [], "o", mfc="none", color="0.3", label="last lag: the cut-off tail")
            ax.set_xlabel("lag (ms)")
            ax.set_ylabel(f"impulse response ({_UNITS[name]}/s)")
            panel_in = ax.get_position().height * fig.get_figheight()
            ax.legend(  # under the panel's x label
                fontsize="small",
                ncols=3,
                loc="upper center",
                bbox_to_anchor=(0.5, -(Margins.bottom - 0.05) / panel_in),
                frameon=False,
            )
    return fig


def _band(
    ax: Any, t: Any, data: Any, color: str, label: str, scale: float = 1.0, zorder: float = 2
) -> None:
    mean, sd = scale * data.mean(axis=0), scale * data.std(axis=0)
    ax.plot(t, mean, color=color, lw=1.3, label=label, zorder=zorder)
    ax.fill_between(t, mean - sd, mean + sd, color=color, alpha=0.2, lw=0)


def stance_figure(results: WalkingResults) -> Figure:
    """Ankle angle (deg) and torque after heel contact, perturbed vs unperturbed (paper 000,
    Fig. 5): one row per direction, every timing point in its own colour over the unperturbed
    mean ± sd, the dotted lines at the mean detected onsets."""
    directions = [d for d in _COLORS if any(tp.direction == d for tp in results.timing_points)]
    delays = sorted({tp.delay_ms for tp in results.timing_points})
    rows, legend = max(1, len(directions)), _legend_rows(len(delays) + 1)
    margins = Margins(bottom=Margins.bottom + legend * _LEGEND_IN, between_rows=0.45)
    fig, axes = panel_grid(
        rows, 2, 11.0, 0.6 + 2.7 * rows + (legend - 1) * _LEGEND_IN, margins, sharex=True
    )
    stance = results.stance
    t_ms = stance.times * 1000.0
    none = stance["none"]
    colors = dict(zip(delays, _TIMING_COLORS * (1 + len(delays) // 6), strict=False))
    for row, direction in enumerate(directions):
        for col, (channel, label, scale) in enumerate(_STANCE_DRAWN):
            ax = axes[row, col]
            # the unperturbed mean is drawn on top: before its onset a perturbed curve should
            # run under it, and where one departs from it, both stay visible
            _band(
                ax,
                t_ms,
                none.get_data(channel),
                "black",
                f"unperturbed (n={len(none)})",
                scale,
                zorder=5,
            )
            for tp in (tp for tp in results.timing_points if tp.direction == direction):
                group = stance[tp.key]
                color = colors[tp.delay_ms]
                _band(
                    ax,
                    t_ms,
                    group.get_data(channel),
                    color,
                    f"perturbed at {tp.delay_ms:g} ms",
                    scale,
                )
                ax.axvline(np.mean(tp.onset_ms), color=color, ls=":", lw=1)
            set_title(ax, f"{_DIRECTION_WORDS[direction]}: {label.split(' (')[0]}")
            ax.set_ylabel(label)
            if row == len(directions) - 1:  # the panels above share its time axis
                ax.set_xlabel("time after heel contact (ms)")
    if directions:
        _legend_below(fig, axes[0, 0])
    return fig


def model_fit_figure(results: WalkingResults) -> Figure:
    """Perturbation torque measured vs the 2nd-order model per condition (paper 000, Fig. 7b):
    one row per direction, one column per timing point."""
    points = results.timing_points
    directions = [d for d in _COLORS if any(tp.direction == d for tp in points)]
    delays = sorted({tp.delay_ms for tp in points})
    rows, columns = max(1, len(directions)), max(1, len(delays))
    title_lines = 3 if columns > _TITLE_COLUMNS else 2  # narrow panels: one line more
    title_in = title_lines * LINE_IN + 0.15
    margins = Margins(  # inner panels carry no y tick labels
        top=title_in,
        bottom=Margins.bottom + _LEGEND_IN,
        between_rows=title_in + 0.1,
        between_columns=0.2,
    )
    height = 0.7 + (2.5 + (title_lines - 2) * LINE_IN) * rows
    fig, axes = panel_grid(rows, columns, 11.0, height, margins, sharex=True, sharey="row")
    for ax in axes.flat:
        ax.set_visible(False)
    for tp in points:
        ax = axes[directions.index(tp.direction), delays.index(tp.delay_ms)]
        ax.set_visible(True)
        t_ms = tp.time_s * 1000.0
        _band(ax, t_ms, tp.torque, _COLORS[tp.direction], "measured (mean ± sd)")
        ax.plot(t_ms, tp.model_torque.mean(axis=0), "k--", lw=1.2, label="model I θ'' + b θ' + k θ")
        lines = [
            f"{_DIRECTION_WORDS[tp.direction]}, {tp.delay_ms:g} ms",
            f"k = {tp.stiffness.mean:.0f} N·m/rad",
            f"VAF {tp.vaf.mean:.1f} %",
        ]
        if title_lines == 2:
            lines[1:] = [", ".join(lines[1:])]
        set_title(ax, "\n".join(lines), fontsize="medium")
    _label_outer_panels(axes, "time after onset (ms)", "torque (N·m)")
    if points:
        _legend_below(fig, next(ax for ax in axes.flat if ax.get_visible()))
    return fig


def _label_outer_panels(axes: Any, xlabel: str, ylabel: str) -> None:
    """Tick labels and axis labels on the outer visible panels of a grid whose rows share y and
    whose columns share x: y on the first visible panel of each row, x on the last visible
    panel of each column (``label_outer`` would leave a row without a scale when its first
    condition is missing)."""
    shown = np.array([[ax.get_visible() for ax in row] for row in axes])
    for (r, c), ax in np.ndenumerate(axes):
        first, last = not shown[r, :c].any(), not shown[r + 1 :, c].any()
        ax.yaxis.set_tick_params(labelleft=first)
        ax.set_ylabel(ylabel if first else "")
        ax.xaxis.set_tick_params(labelbottom=last)
        ax.set_xlabel(xlabel if last else "")


WALKING_FIGURES = (
    "impedance_summary",
    "filters",
    "stance_profiles",
    "model_fit",
    "impedance_vs_lever_arm",
)
"""Every walking figure's name (its file stem), in report order."""


def walking_figure(results: WalkingResults, name: str) -> Figure:
    """The walking figure called ``name`` (one of :data:`WALKING_FIGURES`)."""
    if name == "impedance_summary":
        return impedance_figure(results)
    if name == "impedance_vs_lever_arm":
        return impedance_figure(results, x="lever_arm")
    if name == "filters":
        return filters_figure(results.filters)
    if name == "stance_profiles":
        return stance_figure(results)
    if name == "model_fit":
        return model_fit_figure(results)
    raise ValueError(f"name: expected one of {', '.join(WALKING_FIGURES)}, got {name!r}")


def walking_figures(results: WalkingResults) -> dict[str, Figure]:
    """Every walking figure, by file stem."""
    return {name: walking_figure(results, name) for name in WALKING_FIGURES}


def submit_filters_figure(filters: PlatformFilters, renderer: FigureRenderer) -> PendingFigures:
    """Start drawing the ``filters`` figure in ``renderer``'s workers and return at once: the
    filters are fitted first, so their figure is drawn while the rest of the analysis runs."""
    return renderer.submit(_filters_figure, filters, ["filters"])


def _filters_figure(filters: PlatformFilters, name: str) -> Figure:
    return filters_figure(filters)


def save_walking_figures(
    results: WalkingResults,
    directory: str | Path,
    renderer: FigureRenderer | None = None,
    *,
    submitted: PendingFigures | None = None,
) -> list[Path]:
    """Write every walking figure as ``DIRECTORY/<name>.png`` (atomically); returns the paths.

    ``renderer`` draws them in its worker processes (see :class:`~.render.FigureRenderer`);
    without one they are drawn here, one after another. ``submitted``: figures already on their
    way (from :func:`submit_filters_figure`), which are not drawn again.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    # the workers are sent only the stance channels drawn (the rest are 4/5 of the results)
    stance = results.stance
    picked = None if stance is None else stance.pick([name for name, *_ in _STANCE_DRAWN])
    drawn = replace(results, stance=picked)
    early = submitted.names if submitted is not None else ()
    names = [name for name in WALKING_FIGURES if name not in early]
    pending = (renderer or FigureRenderer(processes=1)).submit(walking_figure, drawn, names)
    pngs = (submitted.result() if submitted is not None else {}) | pending.result()
    return [write_bytes_atomic(directory / f"{name}.png", pngs[name]) for name in WALKING_FIGURES]
