"""The demo's figures, ``summary.json`` and ``report.html``.

The figures are written beside the data they show (``OUT/perturberator``, ``OUT/capstan``) by the
walking and capstan figure functions, then embedded in the report with the comparison tables of
:mod:`anklelab.demo.comparisons`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path

from anklelab._atomic import write_json_atomic
from anklelab._version import __version__
from anklelab.demo.comparisons import (
    COLUMNS,
    Comparison,
    capstan_comparison,
    grouped,
    perturberator_comparison,
)
from anklelab.demo.run import COMPENSATIONS, CapstanDemo, DemoSettings, PerturberatorDemo
from anklelab.report.html import Figure, Section, Table, write_report
from anklelab.report.sections import friction_section, walking_sections
from anklelab.report.summary import settings_table

__all__ = ["capstan_figures", "perturberator_figures", "write_demo_report"]


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
            text_columns=(len(COLUMNS) - 1, len(COLUMNS)),
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
    summary_path = write_json_atomic(out / "summary.json", summary)
    bode = perturberator_figures(perturberator)
    control = capstan_figures(capstan)
    friction_dir = capstan.directory / "friction"
    sections = [
        Section(
            "Paper 000: the Perturberator on its twin",
            "The twin simulated paper 000's session (calibration, perturbed walking, testing "
            "machine); anklelab analysed it as it would a lab's. 'twin truth' is what a perfect "
            "estimator returns (the session's truth group); the servo loop and filter VAF have "
            "no closed-form truth. 'against the paper' says why a value departs from the "
            "paper's, or marks a miss.",
            _tables(comparisons["paper_000"]),
            bode,
            details=[settings_table(settings.model_dump(), "Demo settings")],
        ),
        *walking_sections(
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
        "run": "quick (small trial counts)"
        if settings == DemoSettings.quick(settings.seed)
        else "full",
        "seed": settings.seed,
        "written": datetime.now(tz=UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "anklelab version": __version__,
    }
    report = write_report(
        out / "report.html",
        "anklelab demo: papers 000 and 001 reproduced on the digital twins",
        sections,
        metadata,
    )
    return report, summary_path, comparisons
