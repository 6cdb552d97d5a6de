"""The impedance summary figures, drawn from a ``results.json`` document.

:func:`impedance_figure` plots stiffness, damping and inertia of every condition against the
timing point (the report's key figure) or against the lever arm (paper 000, Fig. 8), with their
95 % intervals, paper 000's values and the testing machine's (bench) stiffness. It reads only
the document, so ``anklelab analyze`` and the demo draw the same figure from the same numbers
that ``results.json`` holds.

Intervals are the document's ``ci95`` where a quantity carries one, else mean ± 1.96 sd (the
bootstrap spread of 60 % subsets, which understates the standard error; labelled so). A
quantity flagged as poorly determined (``"poorly_determined": true`` on the quantity, or its
name in the condition's ``flags``) is drawn hollow and grey, and labelled.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np

from anklelab.ident.bench import BenchStiffness, interpolate_stiffness
from anklelab.report.paper_values import PAPER_000

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "QUANTITIES",
    "Estimate",
    "bench_at",
    "estimate",
    "impedance_figure",
    "interval_kind",
]

QUANTITIES = (
    ("stiffness_nm_per_rad", "stiffness", "N·m/rad"),
    ("damping_nms_per_rad", "damping", "N·m·s/rad"),
    ("inertia_kgm2", "inertia", "kg·m²"),
)
"""``(results.json key, name, unit)`` of the impedance quantities, in panel order."""

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


class Estimate(NamedTuple):
    """One quantity of one condition as the figures and tables show it.

    Attributes
    ----------
    mean, low, high : float
        Estimate and its interval (NaN where the document has none).
    kind : str
        :data:`CI95` (the document's ``ci95``) or :data:`SD95` (mean ± 1.96 sd).
    poorly_determined : bool
        Flagged in the document.
    """

    mean: float
    low: float
    high: float
    kind: str
    poorly_determined: bool


def _number(value: Any) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return math.nan
    return number if math.isfinite(number) else math.nan


def _flagged(point: Mapping[str, Any], key: str, name: str) -> bool:
    node = point.get(key)
    if isinstance(node, Mapping) and (node.get("poorly_determined") is True or node.get("flags")):
        return True
    flags = point.get("flags")
    if not isinstance(flags, Sequence) or isinstance(flags, str):
        return False
    for flag in flags:
        text = flag.get("quantity", "") if isinstance(flag, Mapping) else flag
        if isinstance(text, str) and (key in text or text.split()[:1] == [name]):
            return True
    return False


def estimate(point: Mapping[str, Any], key: str) -> Estimate:
    """The estimate of quantity ``key`` (a :data:`QUANTITIES` key) of one timing point.

    Examples
    --------
    >>> point = {"stiffness_nm_per_rad": {"mean": 1000.0, "sd": 10.0, "ci95": [975.0, 1030.0]},
    ...          "damping_nms_per_rad": {"mean": 2.0, "sd": 0.5}, "flags": ["damping_nms_per_rad"]}
    >>> estimate(point, "stiffness_nm_per_rad")
    Estimate(mean=1000.0, low=975.0, high=1030.0, kind='95 % CI', poorly_determined=False)
    >>> estimate(point, "damping_nms_per_rad")
    Estimate(mean=2.0, low=1.02, high=2.98, kind='mean ± 1.96 sd', poorly_determined=True)
    """
    name = next((n for k, n, _ in QUANTITIES if k == key), key)
    node = point.get(key)
    node = node if isinstance(node, Mapping) else {}
    mean = _number(node.get("mean"))
    flagged = _flagged(point, key, name)
    ci = node.get("ci95")
    if isinstance(ci, Sequence) and not isinstance(ci, str) and len(ci) == 2:
        low, high = _number(ci[0]), _number(ci[1])
        if not (math.isnan(low) or math.isnan(high)):
            return Estimate(mean, low, high, CI95, flagged)
    half = 1.96 * _number(node.get("sd"))
    return Estimate(mean, round(mean - half, 12), round(mean + half, 12), SD95, flagged)


def interval_kind(points: Sequence[Mapping[str, Any]]) -> str:
    """How the intervals of ``points`` were obtained, in words, for a legend or caption."""
    kinds = {estimate(tp, key).kind for tp in points for key, _, _ in QUANTITIES}
    if kinds == {CI95}:
        return CI95
    if kinds == {SD95}:
        return f"≈95 % ({SD95})"
    return f"{CI95}; {SD95} where the results give no CI"


def _bench_rows(document: Mapping[str, Any]) -> list[BenchStiffness]:
    rows = []
    for row in document.get("bench") or []:
        if isinstance(row, Mapping):
            distance, k = _number(row.get("distance_m")), _number(row.get("stiffness_nm_per_rad"))
            if not (math.isnan(distance) or math.isnan(k)):
                rows.append(BenchStiffness(distance, k, _number(row.get("r2")), 0))
    return sorted(rows)


def bench_at(document: Mapping[str, Any], cop_m: Sequence[float]) -> np.ndarray | None:
    """Bench stiffness interpolated at each lever arm (N·m/rad); None without bench tests."""
    rows = _bench_rows(document)
    return interpolate_stiffness(rows, np.asarray(cop_m, dtype=float)) if rows else None


def _points(document: Mapping[str, Any], direction: str) -> list[Mapping[str, Any]]:
    return [
        tp
        for tp in document.get("timing_points") or []
        if isinstance(tp, Mapping) and tp.get("direction") == direction
    ]


def _draw_estimates(
    ax: Axes, x: np.ndarray, values: list[Estimate], color: str, marker: str
) -> None:
    """Filled markers with interval bars; flagged ones hollow and grey, marked "?"."""
    for xi, e in zip(x, values, strict=True):
        flagged = e.poorly_determined
        shade = _FLAGGED if flagged else color
        ax.errorbar(
            xi,
            e.mean,
            yerr=[[e.mean - e.low], [e.high - e.mean]],
            fmt=marker,
            color=shade,
            markerfacecolor="white" if flagged else shade,
            capsize=3,
            ms=6,
            zorder=3,
        )
        if flagged:
            ax.annotate(
                "?",
                (xi, e.high),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                va="bottom",
                color=shade,
                fontsize="small",
            )


def _paper(ax: Axes, key: str, x_of: dict[float, float], handles: dict[str, Any]) -> None:
    """Paper 000's values: stiffness at the first and last timing point, the mean inertia."""
    if key == "stiffness_nm_per_rad":
        ends = [(100.0, "stiffness_first_nm_per_rad"), (475.0, "stiffness_last_nm_per_rad")]
        shown = [
            (x_of[d], PAPER_000[name].value) for d, name in ends if np.isfinite(x_of.get(d, np.nan))
        ]
        if shown:
            (line,) = ax.plot(*zip(*shown, strict=True), "k*", ms=10, zorder=4)
            handles["paper 000, walking (dorsiflexion)"] = line
    elif key == "inertia_kgm2":
        value = PAPER_000["inertia_kgm2"].value or math.nan
        band = ax.axhspan(value - 0.016, value + 0.016, color="0.85", zorder=0)
        ax.axhline(value, color="0.4", lw=1, ls="--", zorder=1)
        handles["paper 000, inertia (mean ± sd)"] = band


def impedance_figure(
    document: Mapping[str, Any], *, x: Literal["timing", "lever_arm"] = "timing"
) -> Figure:
    """Stiffness, damping and inertia per condition, with intervals, the paper and the bench.

    Parameters
    ----------
    document : mapping
        A ``results.json`` document.
    x : {"timing", "lever_arm"}
        Against the timing point (ms after heel contact), dorsiflexion and plantarflexion drawn
        side by side; or against the lever arm (cm) with the bench line, as paper 000's Fig. 8.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels in a row, one legend below them.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.0, 3.5), layout="constrained")
    axes = fig.subplots(1, 3)
    handles: dict[str, Any] = {}
    every = [tp for d in DIRECTIONS for tp in _points(document, d)]
    kind = interval_kind(every) if every else CI95
    offsets = _OFFSETS_MS if x == "timing" else _OFFSETS_CM
    for direction, (words, color, marker) in DIRECTIONS.items():
        points = _points(document, direction)
        if not points:
            continue
        delays = np.array([_number(tp.get("delay_ms")) for tp in points])
        cop = np.array([_number(tp.get("cop_m")) for tp in points])
        position = (delays if x == "timing" else 100.0 * cop) + offsets[direction]
        for ax, (key, _, _) in zip(axes, QUANTITIES, strict=True):
            _draw_estimates(ax, position, [estimate(tp, key) for tp in points], color, marker)
        handles[f"walking, {words}"] = axes[0].errorbar(
            [], [], yerr=[], fmt=marker, color=color, capsize=3
        )
        bench = bench_at(document, cop)
        if bench is not None and x == "timing":
            (line,) = axes[0].plot(
                delays + offsets["bench"], bench, "s", color="black", mfc="none", ms=7, zorder=2
            )
            handles["bench, interpolated at the lever arm"] = line
        if direction == "dorsi":
            # paper 000 gives its walking stiffness by timing point, not by lever arm
            shown = delays + offsets["paper"] if x == "timing" else np.full_like(delays, np.nan)
            x_of = dict(zip(delays.tolist(), shown.tolist(), strict=True))
            for ax, (key, _, _) in zip(axes, QUANTITIES, strict=True):
                _paper(ax, key, x_of, handles)
    if x == "lever_arm":
        rows = _bench_rows(document)
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
    if any(estimate(tp, key).poorly_determined for tp in every for key, _, _ in QUANTITIES):
        handles["poorly determined (hollow, grey, ?)"] = axes[0].errorbar(
            [], [], yerr=[], fmt="o", color=_FLAGGED, mfc="white", capsize=3
        )
    xlabel = (
        "timing point (ms after heel contact)"
        if x == "timing"
        else "lever arm: distance from the ankle centre to the centre of pressure (cm)"
    )
    for ax, (_, name, unit) in zip(axes, QUANTITIES, strict=True):
        ax.set_title(
            name.capitalize() + (" (paper 000: not reported)" if name == "damping" else "")
        )
        ax.set_ylabel(f"{name} ({unit})")
        ax.grid(True, color="0.92", lw=0.6)
        if x == "timing" and every:
            ax.set_xticks(sorted({_number(tp.get("delay_ms")) for tp in every}))
    fig.supxlabel(xlabel, fontsize="medium")
    if handles:
        fig.legend(
            list(handles.values()),
            list(handles),
            loc="outside upper center",
            ncols=min(3, len(handles)),
            fontsize="small",
            frameon=False,
            title=f"error bars: {kind}",
            title_fontsize="small",
        )
    return fig
