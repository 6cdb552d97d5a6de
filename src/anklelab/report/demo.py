"""The demo's comparisons with the papers, its figures, ``summary.json`` and ``report.html``.

For each paper, :func:`perturberator_comparison` and :func:`capstan_comparison` line up what the
paper reported (:mod:`anklelab.report.paper_values`), what anklelab measured on the twin (from
the runs of :mod:`anklelab.pipelines.demo`) and the twin's ground truth, with the error of the
measurement against the truth where the measurement estimates it.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from anklelab._atomic import write_text_atomic
from anklelab._version import __version__
from anklelab.experiments.capstan import ChirpMetrics
from anklelab.ident.bench import BenchStiffness, interpolate_stiffness
from anklelab.pipelines.demo import (
    CHIRP,
    COMPENSATIONS,
    SETPOINTS_DEG,
    CapstanDemo,
    DemoSettings,
    PerturberatorDemo,
)
from anklelab.report.html import Figure, Section, Table, write_report
from anklelab.report.paper_values import PAPER_000, PAPER_001, PaperValue
from anklelab.report.sections import friction_section, walking_section

__all__ = [
    "COLUMNS",
    "Comparison",
    "capstan_comparison",
    "grouped",
    "perturberator_comparison",
    "write_demo_report",
]

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


def _sd(values: Sequence[float]) -> float:
    return float(np.std(values, ddof=1)) if len(values) > 1 else 0.0


def _ends(key: str, i: int, n: int, first: str, last: str) -> PaperValue | None:
    """The paper's value for the first or last of ``n`` ordered rows (a reported range)."""
    return (
        PAPER_000[f"{key}_{first}"]
        if i == 0
        else PAPER_000[f"{key}_{last}"]
        if i == n - 1
        else None
    )


# ------------------------------------------------------------------------------- paper 000


def perturberator_comparison(demo: PerturberatorDemo) -> list[Comparison]:
    """Paper 000 vs the Perturberator twin: servo loop, filters, walking impedance, bench."""
    results, truth, bode = demo.results, demo.session.truth, demo.bode
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
                _ends("stiffness", i, len(dorsi), "first_nm_per_rad", "last_nm_per_rad"),
                float(np.mean(tp.stiffness)),
                _sd(tp.stiffness),
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
    vaf = [float(np.mean(tp.vaf)) for tp in dorsi]
    inertia = [float(np.mean(tp.inertia)) for tp in dorsi]
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
            100 * abs(tp.window_stiffness[f"{window:g}"] / np.mean(tp.stiffness) - 1)
            for tp in dorsi
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
    results, truth = demo.results, demo.session.truth
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
            _ends("bench_stiffness", i, len(results.bench), "near_nm_per_rad", "far_nm_per_rad"),
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


# --------------------------------------------------------------------------------- outputs


def _slug(name: str) -> str:
    return re.sub(r"\W+", "_", name).strip("_")


def _png(path: Path, title: str, caption: str) -> Figure:
    return Figure(title, path.read_bytes(), caption)


def perturberator_figures(demo: PerturberatorDemo) -> list[Figure]:
    """Write the Bode plot and the walking figures into ``demo.directory``; the Bode figure."""
    from anklelab.report.figures_walking import save_walking_figures

    save_walking_figures(demo.results, demo.directory)
    bode = demo.bode.plot(demo.directory / "bode.png")
    caption = (
        "Servo position loop measured on the twin with a small PRBS: closed loop T = encoder / "
        "command with its second-order fit, and the open loop L (paper 000, Fig. 2)."
    )
    return [_png(bode, "Closed-loop Bode plot", caption)]


def capstan_figures(demo: CapstanDemo) -> list[Figure]:
    """Write the identification and control figures under ``demo.directory``; the control ones."""
    from anklelab.report.figures_capstan import (
        chirp_tracking_figure,
        friction_figures,
        observer_figure,
        step_figure,
    )

    friction_figures(demo.friction, demo.ident, demo.directory / "friction")
    figures = []
    for name in COMPENSATIONS:
        runs = [(run.result, run.measured) for run in demo.steps[name]]
        path = step_figure(runs, demo.directory / f"setpoints_{_slug(name)}.png")
        figures.append(
            _png(
                path,
                f"Set-point tracking, compensation: {name}",
                f"5, 10 and 15° set-points (encoder angle, dashed: reference); "
                f"compensation: {name} (paper 001, Fig. 4).",
            )
        )
    for name in COMPENSATIONS:
        run = demo.chirps[name]
        path = chirp_tracking_figure(
            run.result, run.measured, demo.directory / f"chirp_{_slug(name)}.png"
        )
        figures.append(
            _png(
                path,
                f"Chirp tracking, compensation: {name}",
                "5° chirp, 0.2 → 5 Hz over 10 s: angles and the measured closed-loop "
                f"response; compensation: {name} (paper 001, Fig. 5).",
            )
        )
    for task, (result, m) in demo.observers.items():
        path = observer_figure(
            result,
            demo.directory / f"observer_{task}.png",
            title=f"disturbance observer while the platform {task}s (VAF {m.vaf_percent:.1f} %)",
        )
        figures.append(
            _png(
                path,
                f"Observer torque vs truth, platform {task}ing",
                "The user's torque on the platform: the twin's truth and the "
                "disturbance observer's estimate from current and encoder.",
            )
        )
    return figures


def _tables(rows: Sequence[Comparison]) -> list[Table]:
    return [
        Table(
            group,
            [*COLUMNS, "paper source"],
            [[*row.cells(), row.paper.source if row.paper else ""] for row in members],
        )
        for group, members in grouped(rows).items()
    ]


def write_demo_report(
    out: str | Path,
    settings: DemoSettings,
    perturberator: PerturberatorDemo,
    capstan: CapstanDemo,
) -> tuple[Path, Path, dict[str, list[Comparison]]]:
    """Write the figures, ``OUT/summary.json`` and ``OUT/report.html``.

    Returns
    -------
    report, summary : Path
        The files written.
    comparisons : dict
        ``{"paper_000": [...], "paper_001": [...]}``.
    """
    out = Path(out)
    comparisons = {
        "paper_000": perturberator_comparison(perturberator),
        "paper_001": capstan_comparison(capstan),
    }
    summary = {
        "anklelab_version": __version__,
        "settings": settings.model_dump(),
        "seeds": {
            "perturberator_session": settings.seed,
            "bootstrap": settings.seed,
            "capstan": settings.seed,
        },
        "outputs": {
            "perturberator_session": "perturberator/session.h5",
            "walking_results": "perturberator/results.json",
            "servo_bode": "perturberator/servo_bode.json",
            "capstan_ident": "capstan/ident",
            "friction": "capstan/friction/friction.json",
            "capstan_control": "capstan/control.json",
            "report": "report.html",
        },
        **{paper: [row.to_dict() for row in rows] for paper, rows in comparisons.items()},
    }
    summary_path = write_text_atomic(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    bode = perturberator_figures(perturberator)
    control = capstan_figures(capstan)
    friction_dir = capstan.directory / "friction"
    sections = [
        Section(
            "Paper 000: the Perturberator on its twin",
            "The twin simulated paper 000's session (calibration, perturbed walking, testing "
            "machine); anklelab analysed it as it would a lab's. 'twin truth' is what a perfect "
            "estimator returns (the session's truth group); the servo loop and filter VAF have "
            "no closed-form truth.",
            _tables(comparisons["paper_000"]),
            bode,
        ),
        walking_section(
            perturberator.document,
            perturberator.directory,
            title="Walking impedance (perturberator/results.json)",
        ),
        Section(
            "Paper 001: the capstan platform on its twin",
            "Friction and inertia identified from simulated spin-down and torque-chirp tests "
            "(truth: the twin's parameters, Table 2); set-points and chirp under PID control "
            "without compensation and with gravity plus the identified friction compensated "
            "(truth: the same figure on the twin's true angle); the disturbance observer, built "
            "on the identified model, against the twin's true human torque.",
            _tables(comparisons["paper_001"]),
            control,
        ),
        friction_section(
            capstan.friction.to_dict(),
            friction_dir,
            title="Capstan friction identification (capstan/friction/friction.json)",
        ),
    ]
    metadata = {
        "anklelab version": __version__,
        "seed": settings.seed,
        "settings": ", ".join(f"{k}={v}" for k, v in settings.model_dump().items()),
    }
    report = write_report(
        out / "report.html",
        "anklelab demo: papers 000 and 001 reproduced on the digital twins",
        sections,
        metadata,
    )
    return report, summary_path, comparisons
