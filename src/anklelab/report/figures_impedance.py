"""The impedance summary figures, drawn from walking results.

:func:`impedance_figure` plots stiffness, damping and inertia of every condition against the
timing point (the report's key figure) or against the lever arm (paper 000, Fig. 8), with their
95 % intervals, paper 000's values and the testing machine's (bench) stiffness. It reads only
what ``results.json`` holds (:meth:`WalkingResults.from_dict` gives the same figure as the
analysis that wrote the file).

Intervals are each estimate's ``ci95`` where it has one, else mean ± 1.96 sd (the bootstrap
spread of 60 % subsets, which understates the standard error; labelled so; results written by
an anklelab without intervals). A quantity that is poorly determined (its ``poorly_determined``
flag: the interval spans zero or is wider than ±50 %) is drawn hollow and grey, and labelled.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from anklelab.ident.bench import interpolate_stiffness
from anklelab.pipelines.walking.results import QUANTITIES as _ALL
from anklelab.report._panels import SMALL_LINE_IN, Margins, panel_grid, set_title, set_top_margin
from anklelab.report.paper_values import PAPER_000

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from anklelab.pipelines.walking import TimingPoint, WalkingResults
    from anklelab.pipelines.walking.results import Quantity

__all__ = [
    "IMPEDANCE",
    "Interval",
    "bench_at",
    "impedance_figure",
    "interval",
    "interval_kind",
]

IMPEDANCE = tuple(q for q in _ALL if q.name in ("stiffness", "damping", "inertia"))
"""The impedance quantities of the results' schema, in panel order."""

DIRECTIONS = {
    "dorsi": ("dorsiflexion", "tab:blue", "o"),
    "plantar": ("plantarflexion", "tab:orange", "D"),
}
"""Direction key: (name in words, colour, marker)."""

_OFFSETS_MS = {"paper": -40.0, "dorsi": -17.0, "bench": 0.0, "plantar": 17.0}
"""Where each series sits beside its timing point, ms (no marker hides another)."""
_OFFSETS_CM = {"dorsi": -0.1, "plantar": 0.1}
"""Against the lever arm, the two directions are drawn 1 mm either side of their own."""
CI95 = "95 % CI"
SD95 = "mean ± 1.96 sd"
_FLAGGED = "0.55"


class Interval(NamedTuple):
    """One quantity of one condition as the figures and tables show it.

    Attributes
    ----------
    mean, low, high : float
        Estimate and its interval (NaN where there is none).
    kind : str
        :data:`CI95` (the estimate's ``ci95``) or :data:`SD95` (mean ± 1.96 sd).
    poorly_determined : bool
        The estimate's flag.
    """

    mean: float
    low: float
    high: float
    kind: str
    poorly_determined: bool


def interval(point: TimingPoint, quantity: Quantity) -> Interval:
    """The estimate of ``quantity`` (one of :data:`IMPEDANCE`) at ``point`` with its interval.

    Examples
    --------
    >>> from anklelab.pipelines.walking.results import Estimate
    >>> from types import SimpleNamespace
    >>> point = SimpleNamespace(stiffness=Estimate(1000.0, 10.0, (975.0, 1030.0)),
    ...                         damping=Estimate(2.0, 0.5))
    >>> interval(point, IMPEDANCE[0])
    Interval(mean=1000.0, low=975.0, high=1030.0, kind='95 % CI', poorly_determined=False)
    >>> interval(point, IMPEDANCE[1])
    Interval(mean=2.0, low=1.02, high=2.98, kind='mean ± 1.96 sd', poorly_determined=False)
    """
    e = getattr(point, quantity.name)
    low, high = e.ci95
    if math.isfinite(low) and math.isfinite(high):
        return Interval(e.mean, low, high, CI95, e.poorly_determined)
    half = 1.96 * e.sd
    return Interval(
        e.mean, round(e.mean - half, 12), round(e.mean + half, 12), SD95, e.poorly_determined
    )


def interval_kind(points: Sequence[TimingPoint]) -> str:
    """How the intervals of ``points`` were obtained, in words, for a legend or caption."""
    kinds = {interval(tp, q).kind for tp in points for q in IMPEDANCE}
    if kinds <= {CI95}:
        return CI95
    if kinds == {SD95}:
        return f"≈95 % ({SD95})"
    return f"{CI95}; {SD95} where the results give no CI"


def bench_at(results: WalkingResults, cop_m: ArrayLike) -> np.ndarray | None:
    """Bench stiffness interpolated at each lever arm (N·m/rad); None without bench tests."""
    rows = sorted(results.bench)
    return interpolate_stiffness(rows, np.asarray(cop_m, dtype=float)) if rows else None


def _points(results: WalkingResults, direction: str) -> list[TimingPoint]:
    return [tp for tp in results.timing_points if tp.direction == direction]


def _draw_estimates(
    ax: Axes, x: np.ndarray, values: list[Interval], color: str, marker: str
) -> None:
    """Filled markers with interval bars; flagged ones hollow and grey, marked "?".

    The bar spans the interval as given: a resampling interval need not contain the estimate.
    """
    for xi, e in zip(x, values, strict=True):
        flagged = e.poorly_determined
        shade = _FLAGGED if flagged else color
        ax.errorbar(
            xi,
            (e.low + e.high) / 2,
            yerr=(e.high - e.low) / 2,
            fmt="none",
            ecolor=shade,
            capsize=3,
            zorder=3,
        )
        ax.plot(
            xi,
            e.mean,
            marker,
            color=shade,
            markerfacecolor="white" if flagged else shade,
            ms=6,
            zorder=3,
        )
        if flagged:
            ax.annotate(
                "?",
                (xi, np.nanmax([e.high, e.mean])),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                va="bottom",
                color=shade,
                fontsize="small",
            )


def _paper(ax: Axes, name: str, x_of: dict[float, float], handles: dict[str, Any]) -> None:
    """Paper 000's values: stiffness at the first and last timing point, the mean inertia."""
    if name == "stiffness":
        ends = [(100.0, "stiffness_first_nm_per_rad"), (475.0, "stiffness_last_nm_per_rad")]
        shown = [
            (x_of[d], PAPER_000[name].value) for d, name in ends if np.isfinite(x_of.get(d, np.nan))
        ]
        if shown:
            (line,) = ax.plot(*zip(*shown, strict=True), "k*", ms=10, zorder=4)
            handles["paper 000, walking (dorsiflexion)"] = line
    elif name == "inertia":
        value = PAPER_000["inertia_kgm2"].value or math.nan
        band = ax.axhspan(value - 0.016, value + 0.016, color="0.85", zorder=0)
        ax.axhline(value, color="0.4", lw=1, ls="--", zorder=1)
        handles["paper 000, inertia (mean ± sd)"] = band


def impedance_figure(
    results: WalkingResults, *, x: Literal["timing", "lever_arm"] = "timing"
) -> Figure:
    """Stiffness, damping and inertia per condition, with intervals, the paper and the bench.

    Paper 000's values (a prosthetic foot on its testing machine) are drawn beside a session
    with bench tests only: beside a human ankle's they are no reference and crowd the scale.

    Parameters
    ----------
    results : WalkingResults
        The analysis' results, or those read back from ``results.json``.
    x : {"timing", "lever_arm"}
        Against the timing point (ms after heel contact), dorsiflexion and plantarflexion drawn
        side by side; or against the lever arm (cm) with the bench line, as paper 000's Fig. 8.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels in a row, one legend below them.
    """
    fig, axes = panel_grid(1, 3, 11.0, 3.5, Margins(bottom=0.6))  # tick labels, then supxlabel
    axes = axes[0]
    handles: dict[str, Any] = {}
    every = [tp for d in DIRECTIONS for tp in _points(results, d)]
    kind = interval_kind(every) if every else CI95
    offsets = _OFFSETS_MS if x == "timing" else _OFFSETS_CM
    for direction, (words, color, marker) in DIRECTIONS.items():
        points = _points(results, direction)
        if not points:
            continue
        delays = np.array([tp.delay_ms for tp in points])
        cop = np.array([tp.cop_m for tp in points])
        position = (delays if x == "timing" else 100.0 * cop) + offsets[direction]
        for ax, q in zip(axes, IMPEDANCE, strict=True):
            _draw_estimates(ax, position, [interval(tp, q) for tp in points], color, marker)
        handles[f"walking, {words}"] = axes[0].errorbar(
            [], [], yerr=[], fmt=marker, color=color, capsize=3
        )
        bench = bench_at(results, cop)
        if bench is not None and x == "timing":
            (line,) = axes[0].plot(
                delays + offsets["bench"], bench, "s", color="black", mfc="none", ms=7, zorder=2
            )
            handles["bench, interpolated at the lever arm"] = line
        if direction == "dorsi" and results.bench:
            # paper 000 gives its walking stiffness by timing point, not by lever arm
            shown = delays + offsets["paper"] if x == "timing" else np.full_like(delays, np.nan)
            x_of = dict(zip(delays.tolist(), shown.tolist(), strict=True))
            for ax, q in zip(axes, IMPEDANCE, strict=True):
                _paper(ax, q.name, x_of, handles)
    if x == "lever_arm":
        rows = sorted(results.bench)
        if rows:
            (line,) = axes[0].plot(
                [100.0 * r.distance_m for r in rows],
                [r.stiffness_nm_per_rad for r in rows],
                "ks-",
                mfc="none",
                ms=7,
                lw=1,
                zorder=2,
            )
            handles["bench (testing machine)"] = line
            near, far = (
                PAPER_000["bench_stiffness_near_nm_per_rad"],
                PAPER_000["bench_stiffness_far_nm_per_rad"],
            )
            (line,) = axes[0].plot(
                [6.0, 11.0], [near.value, far.value], "^:", color="0.5", lw=1.5, ms=7
            )
            handles["paper 000, bench (6–11 cm)"] = line
    if any(getattr(tp, q.name).poorly_determined for tp in every for q in IMPEDANCE):
        handles["poorly determined (hollow, grey, ?)"] = axes[0].errorbar(
            [], [], yerr=[], fmt="o", color=_FLAGGED, mfc="white", capsize=3
        )
    xlabel = (
        "timing point (ms after heel contact)"
        if x == "timing"
        else "lever arm: distance from the ankle centre to the centre of pressure (cm)"
    )
    for ax, q in zip(axes, IMPEDANCE, strict=True):
        set_title(
            ax,  # above the "?" a top interval carries
            q.name.capitalize() + (" (paper 000: not reported)" if q.name == "damping" else ""),
            pad=12,
        )
        ax.set_ylabel(f"{q.name} ({q.unit})")
        ax.grid(True, color="0.92", lw=0.6)
        if x == "timing" and every:
            ax.set_xticks(sorted({tp.delay_ms for tp in every}))
    fig.supxlabel(xlabel, fontsize="medium", y=0.02)
    if handles:
        columns = min(3, len(handles))
        legend_rows = 1 + math.ceil(len(handles) / columns)  # the title, then the entries
        set_top_margin(axes, Margins.top + legend_rows * SMALL_LINE_IN + 0.25)  # titles padded
        fig.legend(
            list(handles.values()),
            list(handles),
            loc="upper center",
            bbox_to_anchor=(0.5, 1.0),
            ncols=columns,
            fontsize="small",
            frameon=False,
            title=f"error bars: {kind}",
            title_fontsize="small",
        )
    return fig
