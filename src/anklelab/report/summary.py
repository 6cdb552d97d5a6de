"""What the top of a walking report shows: who and what was analysed, the key numbers, the
settings in words.

The numbers come from the walking results (as read back from ``results.json``); the run table
from the document itself. What an older anklelab did not write is shown as "—", never guessed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from anklelab.ident.bench import extrapolated
from anklelab.report.figures_impedance import (
    DIRECTIONS,
    IMPEDANCE,
    SD95,
    bench_at,
    interval,
    interval_kind,
)
from anklelab.report.html import Table

if TYPE_CHECKING:
    from anklelab.pipelines.walking import TimingPoint, WalkingResults
    from anklelab.pipelines.walking.results import Quantity

__all__ = ["impedance_summary_table", "notes", "readable_name", "run_rows", "settings_table"]

_UNITS = {"hz": "Hz", "ms": "ms", "n": "N", "rad": "rad", "m": "m", "s": "s", "percent": "%"}
_NAMES = {  # settings whose name alone does not say what they are
    "cutoff_hz": "low-pass cut-off (Hz)",
    "filter_order": "low-pass order",
    "derivative_window": "derivative window (samples)",
    "heel_contact_threshold_n": "heel-contact threshold (N)",
    "heel_contact_hold_ms": "heel-contact hold (ms)",
    "contact_cop_ms": "COP at contact, averaged over (ms)",
    "onset_min_amplitude_rad": "onset: least perturbation (rad)",
    "onset_tolerance_ms": "onset: tolerance against the manifest (ms)",
    "filter_inputs": "platform filter inputs",
    "n_lags": "platform filter length (lags)",
    "angle_lags": "angle pathway length (lags)",
    "filter_method": "platform filter estimator",
    "calibration_fit_trial": "calibration trial fitted (index)",
    "window_ms": "analysis window (ms)",
    "offset_reference_ms": "offset reference (ms)",
    "sensitivity_windows_ms": "sensitivity windows (ms)",
    "stiffness_model": "stiffness within the window",
    "bootstrap_reps": "bootstrap repetitions",
    "bootstrap_fraction": "bootstrap fraction of perturbed trials",
    "seed": "seed",
}


def readable_name(key: str) -> str:
    """A setting's key in words, its unit (from the key's suffix) in brackets.

    Examples
    --------
    >>> readable_name("cutoff_hz"), readable_name("max_gap_ms"), readable_name("trials")
    ('low-pass cut-off (Hz)', 'max gap (ms)', 'trials')
    """
    if key in _NAMES:
        return _NAMES[key]
    words = key.split("_")
    if len(words) > 1 and words[-1] in _UNITS:
        return f"{' '.join(words[:-1])} ({_UNITS[words[-1]]})"
    return " ".join(words)


def _value(value: Any) -> str:
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, Sequence) and not isinstance(value, str):
        return ", ".join(_value(v) for v in value) or "—"
    if isinstance(value, Mapping):
        return "; ".join(f"{readable_name(str(k))}: {_value(v)}" for k, v in value.items())
    return str(value)


def settings_table(settings: Mapping[str, Any], title: str = "Analysis settings") -> Table:
    """The settings as a two-column table, names in words.

    Examples
    --------
    >>> settings_table({"cutoff_hz": 20.0, "filter_inputs": ["angle", "acceleration"]}).rows
    [['low-pass cut-off (Hz)', '20'], ['platform filter inputs', 'angle, acceleration']]
    """
    return Table(
        title, ["setting", "value"], [[readable_name(k), _value(v)] for k, v in settings.items()]
    )


def run_rows(document: Mapping[str, Any], *, analysed: str) -> list[list[str]]:
    """Rows of the run table: subject, session, its SHA-256, date, anklelab version."""
    return [
        ["subject", str(document.get("subject") or "—")],
        ["session", str(document.get("session") or "—")],
        ["session SHA-256", str(document.get("session_sha256") or "—")],
        ["analysed", analysed],
        ["anklelab version", str(document.get("anklelab_version") or "—")],
    ]


def _interval(point: TimingPoint, quantity: Quantity) -> str:
    e = interval(point, quantity)
    if math.isnan(e.mean):
        return "—"
    fmt = quantity.format
    text = f"{e.mean:{fmt}}"
    if not (math.isnan(e.low) or math.isnan(e.high)):
        mark = "" if e.kind != SD95 else "*"
        text += f"\N{NO-BREAK SPACE}[{e.low:{fmt}},\N{NO-BREAK SPACE}{e.high:{fmt}}]{mark}"
    return text + (" (poorly determined)" if e.poorly_determined else "")


_CHANGE_WORDS = {"changes": ": changes", "undetermined": ": change undetermined"}
"""What the change diagnostic's verdict adds to the model's name (nothing when constant)."""


def _extended(results: WalkingResults, cop_m: float) -> str:
    """What marks a bench value read beyond the tested distances (``validation``'s
    ``bench_extrapolated``)."""
    return " (line extended)" if extrapolated(results.bench, cop_m) else ""


def impedance_summary_table(results: WalkingResults) -> Table:
    """One row per condition: lever arm, k, b, I with 95 % intervals, VAF, the stiffness model
    and the change diagnostic's verdict, bench, error."""
    points = results.timing_points
    bench = bench_at(results, [tp.cop_m for tp in points])
    rows = []
    for i, tp in enumerate(points):
        k = tp.stiffness.mean
        b = math.nan if bench is None else float(bench[i])
        rows.append(
            [
                DIRECTIONS.get(tp.direction, (tp.direction,))[0],
                f"{tp.delay_ms:g}",
                "—" if math.isnan(tp.cop_m) else f"{100 * tp.cop_m:.1f}",
                *(_interval(tp, q) for q in IMPEDANCE),
                "—" if math.isnan(tp.vaf.mean) else f"{tp.vaf.mean:.1f}",
                tp.stiffness_model + _CHANGE_WORDS.get(tp.stiffness_change_verdict, ""),
                "—" if math.isnan(b) else f"{b:.0f}{_extended(results, tp.cop_m)}",
                "—" if math.isnan(b) or math.isnan(k) else f"{100 * (k - b) / b:+.1f}",
            ]
        )
    kind = interval_kind(points) if points else ""
    return Table(
        f"Impedance per condition: mean [{kind}]",
        [
            "direction",
            "timing point (ms)",
            "lever arm (cm)",
            *(f"{q.name} ({q.unit})" for q in IMPEDANCE),
            "model VAF (%)",
            "stiffness within the window",
            "bench stiffness (N·m/rad)",
            "walking − bench (%)",
        ],
        rows,
    )


def notes(results: WalkingResults) -> list[str]:
    """What a reader must know before trusting the numbers, in words: the analysis' warnings
    (plausibility, dropped conditions), each condition's, and which quantities are poorly
    determined where (drawn hollow)."""
    found = [*results.warnings, *(w for tp in results.timing_points for w in tp.warnings)]
    n = len(results.timing_points)
    vague = []
    for q in IMPEDANCE:
        where = [tp.key for tp in results.timing_points if getattr(tp, q.name).poorly_determined]
        if where:
            at = f"all {n} conditions" if len(where) == n > 1 else ", ".join(where)
            vague.append(f"{q.name} at {at}")
    if vague:
        found.append(
            f"Poorly determined (the 95 % interval spans zero or is wider than ±50 % of the "
            f"estimate; drawn hollow, not to be read as precise numbers): {'; '.join(vague)}."
        )
    return [re.sub(r"\s+", " ", str(text)).strip() for text in found]
