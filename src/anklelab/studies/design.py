"""Experiment design on the twin: how many perturbed trials per timing point?

A study preset. Pilot sessions of the foot the user describes are simulated at a few trial
counts (several seeds each, the unperturbed trials scaled along, as in paper 000's 400 for 100
per point) and analysed as lab data. For every condition (direction and timing point) the
stiffness interval the analysis reports (its ``ci95``, else ``mean ± 1.96 sd``: see
:mod:`anklelab.studies.rows`) is fitted by ``half-width = c / sqrt(m)``, ``m`` the condition's
perturbed trials (random averages shrink as ``1 / sqrt(m)``). Each pilot interval gives one
``c = half-width · sqrt(m)``; the condition's ``c`` is their median weighted by ``m``, so that
the pilot's larger sessions, whose intervals are the better determined and the nearest to the
answer, count the most, and one wide interval of a few trials does not set the curve. Intervals
the analysis flags as poorly determined, and those of fewer than 3 trials, are left out. A small
pilot pins ``c`` only to some ±15 %, and the trials needed go as ``c²``: the design takes ``c``'s
one-sided 80 % upper confidence bound given how the condition's pilot intervals scatter
(:func:`_c_bound`), or the median if that is larger.
Each trial of a timing point is dorsiflexing or plantarflexing at random, so a condition gets a
binomial share of the ``n`` trials per timing point; the design holds for the share a condition
gets in 9 sessions of 10 (the binomial's 10th percentile ``m10(n)``, about
``n/2 - 0.64 sqrt(n)``): ``half-width(n) = c / sqrt(m10(n))``, up to the twin's 1000 trials per
timing point. Then:

- **interval**: the smallest ``n`` whose predicted half-width is within ``±X %`` of the
  stiffness in *every* condition;
- **power**: to detect a ``Y %`` stiffness change between two timing points (a two-sided test at
  5 %, each estimate with the standard error ``half-width / 1.96`` of the widest condition),
  ``power(n) = Φ(Y / (√2 se(n)) − 1.96) + Φ(−Y / (√2 se(n)) − 1.96)``; the smallest ``n``
  reaching the target power.

The recommendation is the larger of the two; a target that needs more than 1000 trials per
timing point is out of reach. Parts of an interval that more trials do not shrink (timing, the
coupler's twist, the window) make ``c / sqrt(m)`` optimistic far beyond the pilot, and a
small pilot's scatter moves it either way: a recommendation more than twice the largest pilot
count is said to be extrapolated, in a warning. The pilot's actual errors against the twin's
truth are reported next to the intervals: an interval is only worth its width if it covers the
truth.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from anklelab._session_limits import MAX_TRIALS_PER_POINT
from anklelab.errors import AnklelabWarning, ParameterError
from anklelab.studies.spec import Study, study_from_mapping
from anklelab.studies.study import StudyRun, run_study

__all__ = ["Design", "DesignError", "check_targets", "design_trials", "pilot_study"]


class DesignError(ParameterError):
    """The pilot sessions ran but cannot answer the question asked (a target out of reach, no
    usable interval): running them again would not either."""


@dataclass(frozen=True)
class Design:
    """The answer of :func:`design_trials`.

    Attributes
    ----------
    recommended : int
        Perturbed trials per timing point (the larger of the next two).
    for_interval, for_power : int
        Enough for the interval target in every condition; enough for the power target.
    curve : dict
        ``trials_per_point`` (2 to at most 1000), ``half_width_percent`` (widest condition, %),
        ``power``; the targets; ``pilot``: per pilot count, the widest interval the fit used
        and the widest the fit gives the same intervals (each the mean over sessions, %), the
        intervals ``left_out`` (poorly determined or of fewer than 3 trials), the RMS error
        against the truth (%) and the sessions.
    conditions : list of dict
        Per condition: ``direction``, ``delay_ms``, the fitted ``c_percent`` (%, the half-width
        of one trial's interval), its one-sided 80 % upper bound ``c_bound_percent`` (which the
        curve uses), the ``intervals`` it was fitted to and the ``trials_needed`` per timing
        point.
    interval_kind : str
        Which interval the analysis reported (``ci95`` or ``mean±1.96sd``).
    study : StudyRun
        The pilot study.
    """

    recommended: int
    for_interval: int
    for_power: int
    curve: dict[str, Any]
    conditions: list[dict[str, Any]]
    interval_kind: str
    study: StudyRun

    def to_dict(self) -> dict[str, Any]:
        """``design.json``."""
        return {
            "recommended_trials_per_point": self.recommended,
            "for_interval": self.for_interval,
            "for_power": self.for_power,
            "interval_kind": self.interval_kind,
            "conditions": self.conditions,
            "curve": self.curve,
        }


def design_trials(
    out: Path,
    *,
    foot: str = "prosthetic",
    params_file: Path | None = None,
    interval_percent: float = 3.0,
    change_percent: float = 10.0,
    power: float = 0.8,
    pilot: Sequence[int] = (20, 40, 80),
    seeds: int = 2,
    analysis: dict[str, Any] | None = None,
    n_calibration: int | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    store: Path | None = None,
    figures: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> Design:
    """Run the pilot study into ``out`` and answer how many trials per timing point.

    Parameters
    ----------
    out : Path
        Output directory (the pilot study's tables, ``design.json``, ``figures/design.png``).
    foot : {"prosthetic", "human"}
        What walks on the plate.
    params_file : Path, optional
        A Perturberator parameter file describing the foot (its ``bench`` law and
        ``prosthetic`` table, or ``human`` table), the platform and the protocol.
    interval_percent : float
        Target half-width of the stiffness interval, % of the stiffness (X in ±X %).
    change_percent : float
        Stiffness change between timing points to detect, % (Y).
    power : float
        Target power for that change (0 < power < 1).
    pilot : sequence of int
        Trials per timing point of the pilot sessions (at least two distinct counts).
    seeds : int
        Pilot sessions per count.
    analysis : dict, optional
        Analysis settings (WalkingSettings keys).
    n_calibration : int, optional
        Calibration trials of the pilot sessions (default: the parameter set's).
    scheduler, workers, store, figures, progress
        As for :func:`anklelab.studies.run_study`.
    """
    counts = check_targets(interval_percent, change_percent, power, pilot, seeds)
    study = pilot_study(
        counts, foot=foot, params_file=params_file, seeds=seeds, analysis=analysis,
        n_calibration=n_calibration,
    )  # fmt: skip
    run = run_study(
        study, out, store=store, scheduler=scheduler, workers=workers, figures=False,
        progress=progress,
    )  # fmt: skip
    rows = run.results[
        (run.results["status"] == "ok") & (run.results["quantity"] == "stiffness_nm_per_rad")
    ]
    if rows.empty:
        failures = "; ".join(sorted(set(run.failed["error"]))) or "no stiffness estimates"
        raise DesignError(f"design: every pilot session failed ({failures})")
    design = _answer(rows, run, interval_percent, change_percent, power)
    if figures:
        from anklelab.studies.figures import design_figure

        design_figure(design.curve, out / "figures" / "design.png")
    import json

    from anklelab._atomic import write_text_atomic
    from anklelab._json import json_ready

    text = json.dumps(json_ready(design.to_dict()), indent=2, allow_nan=False)
    write_text_atomic(out / "design.json", text)
    return design


def check_targets(
    interval_percent: float, change_percent: float, power: float, pilot: Sequence[int], seeds: int
) -> list[int]:
    """Check :func:`design_trials`'s targets before any work; the distinct pilot counts."""
    if not (math.isfinite(interval_percent) and interval_percent > 0):
        raise ParameterError(f"--interval: expected a half-width > 0 %, got {interval_percent:g}")
    if not (math.isfinite(change_percent) and change_percent > 0):
        raise ParameterError(f"--change: expected a change > 0 %, got {change_percent:g}")
    if not 0 < power < 1:
        raise ParameterError(f"--power: expected 0 < power < 1, got {power:g}")
    counts = sorted({int(n) for n in pilot})
    if len(counts) < 2 or counts[0] < 2 or counts[-1] > MAX_TRIALS_PER_POINT:
        raise ParameterError(
            f"--pilot: expected two or more counts from 2 to {MAX_TRIALS_PER_POINT} trials per "
            f"timing point, got {list(pilot)}"
        )
    if seeds < 1:
        raise ParameterError(f"--seeds: expected >= 1, got {seeds}")
    return counts


def pilot_study(
    counts: Sequence[int],
    *,
    foot: str = "prosthetic",
    params_file: Path | None = None,
    seeds: int = 2,
    analysis: dict[str, Any] | None = None,
    n_calibration: int | None = None,
) -> Study:
    """The pilot study of :func:`design_trials` (its parameters), checked as a study file is:
    a command builds it before it stages its output, so that nothing is written if it fails.

    ``counts`` are the pilot's trials per timing point (see :func:`check_targets`).
    """
    document: dict[str, Any] = {
        "name": "design",
        "seeds": seeds,
        "twin": {"foot": foot, "bench": False, "unperturbed_per_point": _ratio(params_file)}
        | ({"n_calibration": n_calibration} if n_calibration else {}),
        "analysis": dict(analysis or {}),
        "grid": {"twin.trials_per_point": list(counts)},
    }
    if params_file is not None:
        document["params_file"] = str(Path(params_file).resolve())
    return study_from_mapping(document, origin="design")


def _ratio(params_file: Path | None) -> float:
    """Unperturbed trials per perturbed trial of one timing point in the parameter set."""
    from anklelab.platforms import load_platform

    walking = load_platform("perturberator", params_file).walking
    return walking.n_unperturbed / walking.trials_per_point


def _answer(rows: Any, run: StudyRun, target: float, change: float, power: float) -> Design:
    from scipy.stats import binom, norm

    # per condition, against its own trial count (each trial of a timing point is dorsi or
    # plantar at random: a condition gets about half); a bootstrap of fewer than 3 trials has
    # no spread to measure, and a poorly determined interval no width to trust
    usable = rows[
        (rows["n_perturbed"] >= 3)
        & (rows["half_width_percent"] > 0)
        & ~rows["poorly_determined"].astype(bool)
    ]
    grid = np.arange(2, MAX_TRIALS_PER_POINT + 1)
    share = np.maximum(binom.ppf(0.1, grid, 0.5), 1.0)  # a condition's trials, 9 sessions in 10
    conditions, curves = [], []
    for (direction, delay), group in usable.groupby(["direction", "delay_ms"], sort=True):
        m = group["n_perturbed"].to_numpy(float)
        each = group["half_width_percent"].to_numpy(float) * np.sqrt(m)
        c = _weighted_median(each, m)
        bound = max(c, _c_bound(each, m))
        predicted = bound / np.sqrt(share)
        if not predicted[-1] <= target:
            raise DesignError(
                f"design: ±{target:g} % is out of reach at {direction}/{delay:g}: its interval, "
                f"±{bound:.1f} % / sqrt(trials of the condition), needs more than the twin's "
                f"{MAX_TRIALS_PER_POINT} trials per timing point; ask for a wider --interval"
            )
        conditions.append(
            {"direction": direction, "delay_ms": float(delay), "c_percent": c,
             "c_bound_percent": bound, "intervals": len(group),
             "trials_needed": int(grid[np.argmax(predicted <= target)])}
        )  # fmt: skip
        curves.append(predicted)
    if not conditions:
        raise DesignError("design: the pilot sessions are too small; give larger --pilot counts")
    asked = set(zip(rows["direction"], rows["delay_ms"].astype(float), strict=True))
    if left := sorted(asked - {(c["direction"], c["delay_ms"]) for c in conditions}):
        warnings.warn(
            f"design: {', '.join(f'{d}/{t:g}' for d, t in left)}: no pilot interval the fit can "
            "use (each poorly determined, or of fewer than 3 trials): left out of the design; "
            "give larger --pilot counts",
            AnklelabWarning,
            stacklevel=3,
        )
    for_interval = max(cond["trials_needed"] for cond in conditions)
    half = np.max(curves, axis=0)  # the widest condition's
    shift = change / (math.sqrt(2) * half / 1.96)
    power_curve = norm.cdf(shift - 1.96) + norm.cdf(-shift - 1.96)
    if not power_curve[-1] >= power:
        raise DesignError(
            f"design: a power of {power:g} to detect a {change:g} % change is out of reach: it "
            f"needs more than the twin's {MAX_TRIALS_PER_POINT} trials per timing point (the "
            f"widest interval is ±{half[-1]:.2f} % there); ask for a larger --change or a "
            "smaller --power"
        )
    for_power = int(grid[np.argmax(power_curve >= power)])
    recommended = max(for_interval, for_power)
    largest = int(rows["twin.trials_per_point"].max())
    if recommended > _EXTRAPOLATED * largest:
        warnings.warn(
            f"design: the recommended {recommended} trials per timing point are more than "
            f"{_EXTRAPOLATED:g} times the largest pilot ({largest}): the curve is extrapolated "
            "there, by c / sqrt(m), and may be off either way (what more trials do not shrink "
            "makes it optimistic; the pilot's scatter, either); check it with a pilot nearer to "
            f"it (--pilot {largest},{recommended})",
            AnklelabWarning,
            stacklevel=3,
        )
    shown = grid <= max(2 * recommended, largest + 1)
    curve = {
        "trials_per_point": grid[shown].tolist(),
        "half_width_percent": half[shown].tolist(),
        "power": power_curve[shown].tolist(),
        "target_percent": target,
        "change_percent": change,
        "target_power": power,
        "recommended": recommended,
        "pilot": _pilot(rows, usable, {(c["direction"], c["delay_ms"]): c for c in conditions}),
    }
    kind = "/".join(sorted(set(rows["interval_kind"])))
    return Design(recommended, for_interval, for_power, curve, conditions, kind, run)


_EXTRAPOLATED = 2.0
"""A recommendation beyond this many times the largest pilot count is named as extrapolated."""


def _pilot(rows: Any, usable: Any, fitted: dict[tuple[str, float], dict]) -> dict[str, list]:
    """Per pilot count: the widest interval the fit used, and the widest the fit gives the same
    intervals (``c / sqrt(m)``, each with its own trials), each the mean over sessions, in %;
    how many intervals were left out; the RMS error against the truth (%); the sessions."""
    counts = sorted(int(n) for n in rows["twin.trials_per_point"].unique())
    keys = zip(usable["direction"], usable["delay_ms"].astype(float), strict=True)
    usable = usable.assign(
        fitted=np.array([fitted[key]["c_percent"] for key in keys])
        / np.sqrt(usable["n_perturbed"].to_numpy(float))
    )
    widest = usable.groupby(["twin.trials_per_point", "seed"])[["half_width_percent", "fitted"]]
    mean = widest.max().groupby(level=0).mean().reindex(counts)
    pilot = rows.groupby("twin.trials_per_point")
    used = usable.groupby("twin.trials_per_point").size().reindex(counts, fill_value=0)
    return {
        "trials_per_point": counts,
        "half_width_percent": mean["half_width_percent"].tolist(),
        "fitted_half_width_percent": mean["fitted"].tolist(),
        "left_out": (pilot.size() - used).tolist(),
        "rms_error_percent": pilot["error_percent"]
        .apply(lambda e: float(np.sqrt(np.nanmean(e.to_numpy(float) ** 2))))
        .tolist(),
        "sessions": pilot["seed"].nunique().tolist(),
    }


def _c_bound(values: np.ndarray, weights: np.ndarray) -> float:
    """A one-sided 80 % upper confidence bound of a condition's ``c`` from its pilot intervals'
    ``values`` (%): their weighted mean on the log scale plus Student's ``t(0.8, K - 1)`` times
    its standard error, ``K`` the effective number of intervals; the largest value for a single
    interval, whose scatter nothing shows.

    >>> round(_c_bound(np.array([10.0, 12.5, 8.0, 11.0]), np.ones(4)), 2)
    11.23
    >>> _c_bound(np.array([10.0]), np.ones(1))
    10.0
    """
    from scipy.stats import t

    effective = weights.sum() ** 2 / (weights**2).sum()
    if effective < 2:
        return float(values.max())
    logs = np.log(values)
    mean = np.average(logs, weights=weights)
    variance = np.average((logs - mean) ** 2, weights=weights) * effective / (effective - 1)
    return math.exp(mean + t.ppf(0.8, effective - 1) * math.sqrt(variance / effective))


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The value with at most half the weight below it and half above (the lower of two).

    >>> _weighted_median(np.array([10.0, 1.0, 2.0]), np.array([1.0, 1.0, 1.0]))
    2.0
    >>> _weighted_median(np.array([30.0, 10.0]), np.array([4.0, 20.0]))
    10.0
    """
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cumulative, cumulative[-1] / 2)])
