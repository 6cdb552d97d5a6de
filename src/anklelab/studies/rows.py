"""Result rows from a ``results.json`` document: estimate, interval, truth, error, coverage.

Rows follow the results schema (:mod:`anklelab.pipelines.walking.results`): each timing point
is read back with :meth:`TimingPoint.from_dict`, and every quantity it reports (stiffness,
damping, inertia, VAF, the within-window stiffness change and, with the linear model, the
stiffness slope) becomes one row holding its :class:`Estimate`: the estimate (``mean``), the
paper's ``sd`` (sd over 60 % subsets), the 95 % interval ``ci95_low``/``ci95_high`` and
``poorly_determined``; the lever arm ``cop_m`` (a number, no interval) is one more row. Per
timing point the rows carry its ``stiffness_model`` and whether the stiffness changes within
the window.

The interval is the analysis's ``ci95`` (``interval_kind = "ci95"``). A document without one
(an older anklelab, or a quantity the resampling left undetermined) falls back to
``mean ± 1.96 sd`` (``interval_kind = "mean±1.96sd"``: with paper 000's 60 % subsample sd this
is narrower than a 95 % confidence interval; the coverage column shows by how much).
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["COP", "interval", "timing_point_rows"]

COP = "cop_m"
"""The lever arm's key: reported as a number, without an interval."""


def interval(mean: float, sd: float, ci95: tuple[float, float]) -> tuple[float, float, str]:
    """``(low, high, kind)``: ``ci95`` when finite, else ``mean ± 1.96 sd``.

    Examples
    --------
    >>> interval(100.0, 5.0, (math.nan, math.nan))
    (90.2, 109.8, 'mean±1.96sd')
    >>> interval(100.0, 5.0, (88.0, 113.0))
    (88.0, 113.0, 'ci95')
    """
    low, high = ci95
    if math.isfinite(low) and math.isfinite(high):
        return float(low), float(high), "ci95"
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
        The twin's truth (``Session.truth["reference"]``): per direction and ``f"{delay:g}"``;
        empty for recorded data.

    Returns
    -------
    list of dict
        Keys: ``direction``, ``delay_ms``, ``n_perturbed``, ``stiffness_model``,
        ``stiffness_changes``, ``stiffness_change_verdict``, ``quantity`` (its ``results.json``
        key), ``truth``, ``estimate``, ``sd``, ``ci95_low``, ``ci95_high``, ``interval_kind``,
        ``poorly_determined`` (None for ``cop_m``; True, with no sd and no interval, for a
        condition of one trial), ``error``, ``error_percent``, ``half_width_percent``,
        ``covered`` (truth inside the interval; None without an interval or a truth),
        ``warnings``.
    """
    from anklelab.pipelines.walking.results import TimingPoint

    rows = []
    for i, node in enumerate(document["timing_points"]):
        tp = TimingPoint.from_dict(node, f"timing_points[{i}]")
        truth = reference.get(tp.direction, {}).get(f"{tp.delay_ms:g}", {})
        point = {
            "direction": tp.direction,
            "delay_ms": tp.delay_ms,
            "n_perturbed": tp.n_perturbed,
            "stiffness_model": tp.stiffness_model,
            "stiffness_changes": tp.stiffness_changes,
            "stiffness_change_verdict": tp.stiffness_change_verdict,
        }
        quantities: list[tuple[str, Any]] = [(q.key, e) for q, e in tp.estimates().items()]
        for key, estimate in [*quantities, (COP, None)]:
            true = _number(truth.get(key))
            if estimate is None:
                value, sd, low, high, kind, vague = tp.cop_m, math.nan, math.nan, math.nan, "", None
            elif tp.n_perturbed < 2:  # one trial: no spread, no interval, nothing determined
                value, kind, vague = estimate.mean, "", True
                sd = low = high = math.nan
            else:
                value, sd = estimate.mean, estimate.sd
                low, high, kind = interval(value, sd, estimate.ci95)
                vague = estimate.poorly_determined
            error = value - true
            bounded = bool(kind) and math.isfinite(low) and math.isfinite(high)
            rows.append(
                point
                | {
                    "quantity": key,
                    "truth": true,
                    "estimate": value,
                    "sd": sd,
                    "ci95_low": low,
                    "ci95_high": high,
                    "interval_kind": kind,
                    "poorly_determined": vague,
                    "error": error,
                    "error_percent": 100.0 * error / true if true else math.nan,
                    "half_width_percent": 50.0 * (high - low) / abs(value)
                    if bounded and value
                    else math.nan,
                    "covered": bool(low <= true <= high)
                    if bounded and math.isfinite(true)
                    else None,
                    "warnings": "; ".join(tp.warnings),
                }
            )
    return rows


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)
