"""Result rows from a ``results.json`` document: estimate, interval, truth, error, coverage.

Rows are read from the document's keys (DESIGN §5), not from Python objects, so that a study
follows the results schema wherever the analysis goes. Per quantity the interval is the
document's ``ci95`` when it has one (``interval_kind = "ci95"``), else ``mean ± 1.96 sd``
(``interval_kind = "mean±1.96sd"``: with paper 000's 60 % subsample sd this is narrower than a
95 % confidence interval; its coverage column shows by how much). Flags the analysis sets on a
quantity (``flags``, or ``poorly_determined``) are carried along as text.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["QUANTITIES", "interval", "timing_point_rows"]

QUANTITIES = ("stiffness_nm_per_rad", "damping_nms_per_rad", "inertia_kgm2", "cop_m")
"""Quantities a row can hold: the three impedance parameters and the lever arm."""


def interval(summary: dict[str, Any]) -> tuple[float, float, str]:
    """``(low, high, kind)`` of a quantity's summary (``{"mean", "sd"[, "ci95"]}``).

    Examples
    --------
    >>> interval({"mean": 100.0, "sd": 5.0})
    (90.2, 109.8, 'mean±1.96sd')
    >>> interval({"mean": 100.0, "sd": 5.0, "ci95": [88.0, 113.0]})
    (88.0, 113.0, 'ci95')
    """
    ci = summary.get("ci95")
    if ci is not None and len(ci) == 2 and None not in ci:
        return float(ci[0]), float(ci[1]), "ci95"
    mean, sd = _number(summary.get("mean")), _number(summary.get("sd"))
    return mean - 1.96 * sd, mean + 1.96 * sd, "mean±1.96sd"


def timing_point_rows(
    document: dict[str, Any], reference: dict[str, dict[str, dict[str, float]]]
) -> list[dict[str, Any]]:
    """One row per timing point (direction, delay) and quantity of ``document``.

    Parameters
    ----------
    document : dict
        A ``results.json`` document.
    reference : dict
        The twin's truth (``Session.truth["reference"]``): per direction and ``f"{delay:g}"``.

    Returns
    -------
    list of dict
        Keys: ``direction``, ``delay_ms``, ``n_perturbed``, ``quantity``, ``truth``,
        ``estimate``, ``sd``, ``low``, ``high``, ``interval_kind``, ``error``,
        ``error_percent``, ``half_width_percent``, ``covered`` (truth inside the interval; None
        without an interval), ``flags``, ``warnings``.
    """
    rows = []
    for tp in document["timing_points"]:
        truth = reference.get(tp["direction"], {}).get(f"{tp['delay_ms']:g}", {})
        warnings = "; ".join(tp.get("warnings", []))
        for quantity in QUANTITIES:
            value = tp.get(quantity)
            if isinstance(value, dict):
                estimate, sd = _number(value.get("mean")), _number(value.get("sd"))
                low, high, kind = interval(value)
                flags = _flags(value)
            else:
                estimate, sd, low, high, kind, flags = (
                    _number(value),
                    math.nan,
                    math.nan,
                    math.nan,
                    "",
                    "",
                )
            true = _number(truth.get(quantity))
            error = estimate - true
            rows.append(
                {
                    "direction": tp["direction"],
                    "delay_ms": float(tp["delay_ms"]),
                    "n_perturbed": int(tp["n_perturbed"]),
                    "quantity": quantity,
                    "truth": true,
                    "estimate": estimate,
                    "sd": sd,
                    "low": low,
                    "high": high,
                    "interval_kind": kind,
                    "error": error,
                    "error_percent": 100.0 * error / true if true else math.nan,
                    "half_width_percent": 50.0 * (high - low) / abs(estimate)
                    if kind and estimate
                    else math.nan,
                    "covered": bool(low <= true <= high) if kind and math.isfinite(true) else None,
                    "flags": flags,
                    "warnings": warnings,
                }
            )
    return rows


def _flags(summary: dict[str, Any]) -> str:
    flags = [str(f) for f in summary.get("flags", [])]
    if summary.get("poorly_determined"):
        flags.append("poorly_determined")
    return "; ".join(dict.fromkeys(flags))


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)
