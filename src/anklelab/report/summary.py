"""What the top of a walking report shows: who and what was analysed, the key numbers, the
settings in words.

Everything is read from a ``results.json`` document, defensively: keys that an older (or a
newer) anklelab does not write are shown as "—", never guessed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

from anklelab.report.figures_impedance import (
    DIRECTIONS,
    QUANTITIES,
    SD95,
    bench_at,
    estimate,
    interval_kind,
)
from anklelab.report.html import Table

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


def _interval(point: Mapping[str, Any], key: str, fmt: str) -> str:
    e = estimate(point, key)
    if math.isnan(e.mean):
        return "—"
    text = f"{e.mean:{fmt}}"
    if not (math.isnan(e.low) or math.isnan(e.high)):
        mark = "" if e.kind != SD95 else "*"
        text += f"\N{NO-BREAK SPACE}[{e.low:{fmt}},\N{NO-BREAK SPACE}{e.high:{fmt}}]{mark}"
    return text + (" (poorly determined)" if e.poorly_determined else "")


def impedance_summary_table(document: Mapping[str, Any]) -> Table:
    """One row per condition: lever arm, k, b, I with 95 % intervals, VAF, bench, error."""
    points = [tp for tp in document.get("timing_points") or [] if isinstance(tp, Mapping)]
    cop = [
        tp.get("cop_m") if isinstance(tp.get("cop_m"), int | float) else math.nan for tp in points
    ]
    bench = bench_at(document, cop)
    formats = {"stiffness_nm_per_rad": ".0f", "damping_nms_per_rad": ".2f", "inertia_kgm2": ".3f"}
    rows = []
    for i, tp in enumerate(points):
        vaf = tp.get("vaf_percent") if isinstance(tp.get("vaf_percent"), Mapping) else {}
        k = estimate(tp, "stiffness_nm_per_rad").mean
        b = math.nan if bench is None else float(bench[i])
        rows.append(
            [
                DIRECTIONS.get(tp.get("direction"), (str(tp.get("direction", "?")),))[0],
                f"{tp.get('delay_ms', math.nan):g}",
                "—" if math.isnan(cop[i]) else f"{100 * cop[i]:.1f}",
                *(_interval(tp, key, formats[key]) for key, _, _ in QUANTITIES),
                "—" if vaf.get("mean") is None else f"{vaf['mean']:.1f}",
                "—" if math.isnan(b) else f"{b:.0f}",
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
            "stiffness (N·m/rad)",
            "damping (N·m·s/rad)",
            "inertia (kg·m²)",
            "model VAF (%)",
            "bench stiffness (N·m/rad)",
            "walking − bench (%)",
        ],
        rows,
    )


def notes(document: Mapping[str, Any]) -> list[str]:
    """What a reader must know before trusting the numbers: warnings and flags, in words."""
    found = [str(w) for w in document.get("warnings") or []]
    for tp in document.get("timing_points") or []:
        if not isinstance(tp, Mapping):
            continue
        where = f"{tp.get('direction', '?')} {tp.get('delay_ms', math.nan):g} ms"
        found += [f"{where}: {w}" for w in tp.get("warnings") or []]
        flagged = [name for key, name, _ in QUANTITIES if estimate(tp, key).poorly_determined]
        if flagged:
            found.append(f"{where}: {', '.join(flagged)} poorly determined (drawn hollow)")
    return [re.sub(r"\s+", " ", text).strip() for text in found]
