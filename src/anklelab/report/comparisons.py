"""Paper versus twin: what each paper reported, what anklelab measured, the twin's truth.

:func:`perturberator_comparison` and :func:`capstan_comparison` line up, for the runs of
:mod:`anklelab.pipelines.demo`, the papers' numbers (:mod:`anklelab.report.paper_values`), the
measurements anklelab made on the twins and the twins' ground truth, with the error of a
measurement against the truth where the measurement estimates it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from anklelab.experiments.capstan import ChirpMetrics
from anklelab.ident.bench import BenchStiffness, interpolate_stiffness
from anklelab.pipelines.demo import (
    CHIRP,
    COMPENSATIONS,
    SETPOINTS_DEG,
    CapstanDemo,
    PerturberatorDemo,
)
from anklelab.report.paper_values import PAPER_000, PAPER_001, PaperValue

__all__ = ["COLUMNS", "Comparison", "capstan_comparison", "grouped", "perturberator_comparison"]

COLUMNS = ("quantity", "paper", "anklelab (twin)", "twin truth", "error %")
"""Columns of a comparison table (:meth:`Comparison.cells`)."""


@dataclass(frozen=True)
class Comparison:
    """One line of a paper / twin comparison.

    Attributes
    ----------
    group : str
        The experiment it belongs to (rows are shown grouped).
    quantity, unit : str
        What is compared and its unit.
    paper : PaperValue or None
        What the paper reported (None: the paper gives no number).
    measured : float
        anklelab's measurement on the twin (inf: not reached within the test, see ``note``).
    spread : float or None
        Its standard deviation (bootstrap, or across timing points).
    truth : float or None
        The twin's ground truth (None: the twin has no closed-form truth for it).
    estimate : bool
        ``measured`` estimates ``truth`` (then the error is reported); False when the truth is
        the same figure computed on the twin's true signals (e.g. the true platform angle).
    fmt : str
        Format of the numbers.
    note : str
        Shown for a non-finite measurement or truth (e.g. "beyond the 5 Hz sweep").

    Examples
    --------
    >>> paper = PAPER_000["stiffness_first_nm_per_rad"]
    >>> row = Comparison("walking", "stiffness", "N·m/rad", paper, 1290.0, 10.0, 1300.0, fmt=".0f")
    >>> row.cells()
    ['stiffness (N·m/rad)', '1277 (range start)', '1290 (sd 10)', '1300', '-0.8']
    >>> row = Comparison("chirp", "bandwidth", "Hz", None, float("inf"), note="> 5 Hz")
    >>> row.cells()[2], row.to_dict()["measured"]
    ('> 5 Hz', None)
    """

    group: str
    quantity: str
    unit: str
    paper: PaperValue | None
    measured: float
    spread: float | None = None
    truth: float | None = None
    estimate: bool = True
    fmt: str = ".4g"
    note: str = ""

    @property
    def error_percent(self) -> float | None:
        """``100 (measured - truth) / truth`` when ``measured`` estimates ``truth``."""
        if not self.estimate or self.truth is None or self.truth == 0:
            return None
        if not (math.isfinite(self.measured) and math.isfinite(self.truth)):
            return None
        return 100.0 * (self.measured - self.truth) / self.truth

    def _format(self, value: float | None, spread: float | None = None) -> str:
        if value is None:
            return "—"
        if not math.isfinite(value):
            return self.note or "not reached"
        text = f"{value:{self.fmt}}"
        return text if spread is None else f"{text} (sd {spread:{self.fmt}})"

    def cells(self) -> list[str]:
        """The row as text, in :data:`COLUMNS` order."""
        error = self.error_percent
        return [
            f"{self.quantity} ({self.unit})" if self.unit else self.quantity,
            self.paper.text if self.paper else "—",
            self._format(self.measured, self.spread),
            self._format(self.truth),
            "" if error is None else f"{error:+.1f}",
        ]

    def to_dict(self) -> dict[str, Any]:
        """For ``summary.json`` (non-finite numbers become None, with ``note``)."""

        def finite(value: float | None) -> float | None:
            return value if value is not None and math.isfinite(value) else None

        paper = self.paper
        return {
            "group": self.group,
            "quantity": self.quantity,
            "unit": self.unit,
            "paper": None if paper is None else paper.value,
            "paper_text": None if paper is None else paper.text,
            "paper_source": None if paper is None else paper.source,
            "measured": finite(self.measured),
            "measured_sd": self.spread,
            "truth": finite(self.truth),
            "error_percent": self.error_percent,
            "note": self.note,
        }


def grouped(rows: Sequence[Comparison]) -> dict[str, list[Comparison]]:
    """Rows by group, in order of first appearance."""
    groups: dict[str, list[Comparison]] = {}
    for row in rows:
        groups.setdefault(row.group, []).append(row)
    return groups


def _sd(values: ArrayLike) -> float:
    values = np.asarray(values, dtype=float)
    return float(np.std(values, ddof=1)) if values.size > 1 else 0.0


def _ends(i: int, n: int, first: str, last: str) -> PaperValue | None:
    """Paper 000's value for the first or last of ``n`` ordered rows (the ends of a range)."""
    if i == 0:
        return PAPER_000[first]
    if i == n - 1:
        return PAPER_000[last]
    return None


# ------------------------------------------------------------------------------- paper 000


def _truth(demo: PerturberatorDemo) -> Mapping[str, Any]:
    if demo.session.truth is None:
        raise ValueError("the demo's session has no truth group (not simulated by the twin?)")
    return demo.session.truth


def perturberator_comparison(demo: PerturberatorDemo) -> list[Comparison]:
    """Paper 000 vs the Perturberator twin: servo loop, filters, walking impedance, bench."""
    results, truth, bode = demo.results, _truth(demo), demo.bode
    servo, walk = "servo position loop (PRBS)", "walking, dorsiflexion"
    rows = [
        Comparison(
            servo,
            "natural frequency (90° lag)",
            "Hz",
            PAPER_000["servo_natural_frequency_hz"],
            bode.natural_frequency_hz,
            fmt=".0f",
        ),
        Comparison(
            servo,
            "gain margin",
            "dB",
            PAPER_000["servo_gain_margin_db"],
            bode.gain_margin_db,
            fmt=".1f",
        ),
        Comparison(
            servo,
            "phase margin",
            "deg",
            PAPER_000["servo_phase_margin_deg"],
            bode.phase_margin_deg,
            fmt=".0f",
        ),
        Comparison(
            "platform filters",
            "VAF, held-out trials",
            "%",
            PAPER_000["filter_vaf_percent"],
            float(np.mean(results.filter_vaf)),
            _sd(results.filter_vaf),
            fmt=".1f",
        ),
    ]
    dorsi = [tp for tp in results.timing_points if tp.direction == "dorsi"]
    reference = [truth["reference"]["dorsi"][f"{tp.delay_ms:g}"] for tp in dorsi]
    for i, (tp, ref) in enumerate(zip(dorsi, reference, strict=True)):
        rows.append(
            Comparison(
                walk,
                f"stiffness {tp.delay_ms:g} ms (cop {100 * tp.cop_m:.1f} cm)",
                "N·m/rad",
                _ends(i, len(dorsi), "stiffness_first_nm_per_rad", "stiffness_last_nm_per_rad"),
                tp.stiffness.mean,
                tp.stiffness.sd,
                ref["stiffness_nm_per_rad"],
                fmt=".0f",
            )
        )
    for tp, ref in zip(dorsi, reference, strict=True):
        rows.append(
            Comparison(
                walk,
                f"onset sd {tp.delay_ms:g} ms",
                "ms",
                PAPER_000.get(f"onset_sd_ms_{tp.delay_ms:g}"),
                _sd(tp.onset_ms),
                truth=ref["onset_sd_ms"],
                fmt=".1f",
            )
        )
    vaf = [tp.vaf.mean for tp in dorsi]
    inertia = [tp.inertia.mean for tp in dorsi]
    rows += [
        Comparison(
            walk,
            "model VAF, mean over timing points",
            "%",
            PAPER_000["model_vaf_percent"],
            float(np.mean(vaf)),
            _sd(vaf),
            fmt=".1f",
        ),
        Comparison(
            walk,
            "inertia, mean over timing points",
            "kg·m²",
            PAPER_000["inertia_kgm2"],
            float(np.mean(inertia)),
            _sd(inertia),
            float(np.mean([ref["inertia_kgm2"] for ref in reference])),
            fmt=".3f",
        ),
    ]
    for window in results.settings.sensitivity_windows_ms:
        change = [
            100 * abs(tp.window_stiffness[f"{window:g}"] / tp.stiffness.mean - 1) for tp in dorsi
        ]
        rows.append(
            Comparison(
                walk,
                f"|stiffness change|, {window:g} ms window",
                "%",
                PAPER_000.get(f"window_{window:g}_change_percent"),
                float(np.mean(change)),
                _sd(change),
                fmt=".1f",
            )
        )
    return rows + _bench_rows(demo)


def _bench_rows(demo: PerturberatorDemo) -> list[Comparison]:
    results, truth = demo.results, _truth(demo)
    if not results.bench:
        return []
    group = "bench tests; walking vs bench"
    law = [
        BenchStiffness(float(d), float(k), 1.0, 1)
        for d, k in zip(
            truth["bench"]["distances_m"], truth["bench"]["stiffness_nm_per_rad"], strict=True
        )
    ]
    rows = [
        Comparison(
            group,
            f"bench stiffness at {100 * row.distance_m:g} cm",
            "N·m/rad",
            _ends(
                i,
                len(results.bench),
                "bench_stiffness_near_nm_per_rad",
                "bench_stiffness_far_nm_per_rad",
            ),
            row.stiffness_nm_per_rad,
            truth=float(interpolate_stiffness(law, row.distance_m)),
            fmt=".0f",
        )
        for i, row in enumerate(results.bench)
    ]
    r2 = [row.r2 for row in results.bench]
    rows.append(
        Comparison(
            group, "bench R²", "", PAPER_000["bench_r2"], float(np.mean(r2)), _sd(r2), fmt=".3f"
        )
    )
    validation = results.validation()
    if validation:
        signed = np.array([v["error_percent"] for v in validation])
        true_errors = []
        for v in validation:
            ref = truth["reference"]["dorsi"][f"{v['delay_ms']:g}"]
            bench = float(interpolate_stiffness(law, ref["cop_m"]))
            true_errors.append(abs(ref["stiffness_nm_per_rad"] - bench) / bench * 100)
        rows.append(
            Comparison(
                group,
                f"|walking − bench| mean (signed {signed.min():+.1f}…{signed.max():+.1f})",
                "%",
                PAPER_000["walking_vs_bench_error_percent"],
                float(np.mean(np.abs(signed))),
                _sd(np.abs(signed).tolist()),
                float(np.mean(true_errors)),
                estimate=False,
                fmt=".1f",
            )
        )
    return rows


# ------------------------------------------------------------------------------- paper 001


_FRICTION = (  # label, unit, friction.json keys, PAPER_001 key, format
    ("inertia J", "kg·m²", ("inertia_kgm2",), "inertia_kgm2", ".3e"),
    ("viscous b, cw", "N·m·s/rad", ("viscous_nms_per_rad", "cw"), "viscous_cw_nms_per_rad", ".3e"),
    (
        "viscous b, ccw",
        "N·m·s/rad",
        ("viscous_nms_per_rad", "ccw"),
        "viscous_ccw_nms_per_rad",
        ".3e",
    ),
    ("Coulomb T_c, cw", "N·m", ("coulomb_nm", "cw"), "coulomb_cw_nm", ".4f"),
    ("Coulomb T_c, ccw", "N·m", ("coulomb_nm", "ccw"), "coulomb_ccw_nm", ".4f"),
    (
        "Stribeck velocity ω_s",
        "rad/s",
        ("stribeck_velocity_rad_s",),
        "stribeck_velocity_rad_s",
        ".2f",
    ),
    ("static friction T_s", "N·m", ("static_friction_nm",), "static_friction_nm", ".4f"),
)


def _leaf(tree: dict[str, Any], keys: tuple[str, ...]) -> float:
    node: Any = tree
    for key in keys:
        node = node[key]
    return float(node)


def _at(metrics: ChirpMetrics, frequency_hz: float, name: str) -> float:
    values = 20 * np.log10(metrics.gain) if name == "gain_db" else metrics.phase_deg
    return float(np.interp(frequency_hz, metrics.frequency_hz, values))


def capstan_comparison(demo: CapstanDemo) -> list[Comparison]:
    """Paper 001 vs the capstan twin: Table 2, set-points, chirp, observer."""
    identified = demo.friction.to_dict()
    truth = demo.ident.truth or {}
    group = "friction and inertia, pinion shaft"
    rows = [
        Comparison(
            group,
            name,
            unit,
            PAPER_001[paper],
            _leaf(identified, keys),
            truth=_leaf(truth, keys) if truth else None,
            fmt=fmt,
        )
        for name, unit, keys, paper, fmt in _FRICTION
    ]
    rows += [
        Comparison(
            group, "spin-down fit VAF", "%", None, demo.friction.spindown_vaf_percent_, fmt=".2f"
        ),
        Comparison(
            group,
            "chirp VAF of the identified model",
            "%",
            None,
            demo.friction.chirp_vaf_percent_,
            fmt=".2f",
        ),
    ]
    for name in COMPENSATIONS:
        group = f"set-points, compensation: {name}"
        rows += [
            Comparison(
                group,
                f"{degrees:g}°: settled within 5 %",
                "ms",
                PAPER_001["setpoint_time_s"],
                1e3 * run.measured.settling_time_5_s,
                truth=1e3 * run.true.settling_time_5_s,
                estimate=False,
                fmt=".0f",
                note="not settled",
            )
            for degrees, run in zip(SETPOINTS_DEG, demo.steps[name], strict=True)
        ]
    beyond = f"> {CHIRP['f1_hz']:g} (sweep end)"
    for name in COMPENSATIONS:
        group = f"5° chirp, compensation: {name}"
        run = demo.chirps[name]
        rows += [
            Comparison(
                group,
                "−3 dB bandwidth",
                "Hz",
                PAPER_001["chirp_bandwidth_hz"],
                run.measured.bandwidth_3db_hz,
                truth=run.true.bandwidth_3db_hz,
                estimate=False,
                fmt=".2f",
                note=beyond,
            ),
            Comparison(
                group,
                "gain at 3 Hz",
                "dB",
                None,
                _at(run.measured, 3.0, "gain_db"),
                truth=_at(run.true, 3.0, "gain_db"),
                estimate=False,
                fmt="+.2f",
            ),
            Comparison(
                group,
                "phase at 3 Hz",
                "deg",
                None,
                _at(run.measured, 3.0, "phase_deg"),
                truth=_at(run.true, 3.0, "phase_deg"),
                estimate=False,
                fmt=".1f",
            ),
        ]
    group = "torque observer vs true torque"
    for task, (_, m) in demo.observers.items():
        rows += [
            Comparison(
                group,
                f"VAF, platform {task}ing",
                "%",
                PAPER_001["observer"],
                m.vaf_percent,
                fmt=".1f",
            ),
            Comparison(group, f"delay, platform {task}ing", "ms", None, 1e3 * m.delay_s, fmt=".0f"),
        ]
    return rows
