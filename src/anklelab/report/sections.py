"""Report sections read from result directories, and the report of a user's own results.

A *results directory* is what ``anklelab analyze`` writes (``results.json``, DESIGN.md section 5,
plus its PNG figures) and/or what ``anklelab identify friction`` writes (``friction.json``,
DESIGN.md section 6, plus its figures). :func:`results_report` turns one into a self-contained
``report.html``; the demo's report reuses :func:`walking_section` and :func:`friction_section`.

Figures are taken from the directory as written by those commands; a figure that is missing
(e.g. ``--no-figures``) is listed in the section's text instead.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from anklelab._version import __version__
from anklelab.errors import ResultsFormatError
from anklelab.report.html import Figure, Section, Table, write_report
from anklelab.report.sections_capstan import capstan_sections

__all__ = [
    "FRICTION_FIGURES",
    "WALKING_FIGURES",
    "FigureSpec",
    "friction_section",
    "load_results",
    "missing_figures",
    "png_figures",
    "results_report",
    "walking_section",
]

FigureSpec = tuple[str, str, str]
"""``(file stem, title, caption)`` of a figure a command writes as ``<stem>.png``."""

WALKING_FIGURES: tuple[FigureSpec, ...] = (
    (
        "filters",
        "Platform filters",
        "Impulse responses from the motor angle's pathways to each force channel, fitted on one "
        "calibration trial (paper 000, Figs. 3 and 6).",
    ),
    (
        "stance_profiles",
        "Stance profiles",
        "Ankle angle and torque after heel contact, unperturbed (black) and perturbed, mean ± sd; "
        "the dotted line is the mean detected onset (paper 000, Fig. 5).",
    ),
    (
        "model_fit",
        "Measured vs model torque",
        "Perturbation torque over the analysis window (mean ± sd over bootstrap averages) and "
        "the fitted I θ'' + b θ' + k θ (paper 000, Fig. 7b).",
    ),
    (
        "stiffness_vs_lever_arm",
        "Stiffness vs lever arm",
        "Walking stiffness (bootstrap mean ± sd) against the lever arm cop_m, with the "
        "testing-machine (bench) stiffness against actuator distance (paper 000, Fig. 8).",
    ),
)
"""The figures ``anklelab analyze`` writes."""

FRICTION_FIGURES: tuple[FigureSpec, ...] = (
    (
        "spindown_fit",
        "Spin-down fits",
        "Pinion speed after the torque cut (thin lines, one per run) and the exact solution of "
        "J ω' + b ω = -T_c sign(ω) fitted per direction (dashed; paper 001, Fig. 6).",
    ),
    (
        "chirp_fit",
        "Open-loop torque chirp",
        "Measured pinion speed and the identified model's simulated speed under the same torque "
        "(paper 001, Fig. 7).",
    ),
    (
        "friction_map",
        "Low-speed friction map",
        "Friction torque τ - J ω' against speed and the identified Coulomb-viscous-Stribeck law.",
    ),
)
"""The figures ``anklelab identify friction`` writes."""


def load_results(path: Path, required: Sequence[str]) -> dict[str, Any]:
    """Read a result JSON file and check that its top-level ``required`` keys are present.

    Raises
    ------
    ResultsFormatError
        Naming the file and what is wrong with it.
    """
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ResultsFormatError(f"{path}: not valid JSON: {exc}") from None
    if not isinstance(document, dict):
        raise ResultsFormatError(f"{path}: expected a JSON object, got {type(document).__name__}")
    missing = [key for key in required if key not in document]
    if missing:
        raise ResultsFormatError(
            f"{path}: missing key(s) {', '.join(missing)}; is this an anklelab result file?"
        )
    return document


def _require(node: Any, path: Path, where: str, keys: Sequence[str]) -> dict[str, Any]:
    """``node`` as a mapping holding ``keys``; else an error naming the file and the key."""
    if not isinstance(node, dict):
        raise ResultsFormatError(f"{path}: {where}: expected an object, got {node!r:.40}")
    for key in keys:
        if key not in node:
            dotted = f"{where}.{key}" if where else key
            raise ResultsFormatError(f"{path}: {dotted}: required key is missing")
    return node


def missing_figures(directory: Path, specs: Sequence[FigureSpec]) -> list[str]:
    """File names of the figures of ``specs`` that are not in ``directory``."""
    return [f"{stem}.png" for stem, _, _ in specs if not (directory / f"{stem}.png").is_file()]


def png_figures(directory: Path, specs: Sequence[FigureSpec]) -> list[Figure]:
    """The figures of ``specs`` found in ``directory``, in order."""
    return [
        Figure(title, (directory / f"{stem}.png").read_bytes(), caption)
        for stem, title, caption in specs
        if (directory / f"{stem}.png").is_file()
    ]


def _mean_sd(node: dict[str, Any] | None, fmt: str) -> str:
    if not node or node.get("mean") is None:
        return "—"
    sd = node.get("sd")
    return f"{node['mean']:{fmt}}" + ("" if sd is None else f" ({sd:{fmt}})")


def _number(value: Any, fmt: str) -> str:
    return "—" if value is None else f"{value:{fmt}}"


def _missing_text(missing: Sequence[str]) -> str:
    return f"\n\nFigures not found in the directory: {', '.join(missing)}." if missing else ""


def walking_section(
    document: dict[str, Any], directory: Path, *, title: str = "Walking impedance"
) -> Section:
    """Tables of a ``results.json`` document and the walking figures found in ``directory``."""
    path = directory / "results.json"
    filters = _require(document, path, "", ("platform_filters",))["platform_filters"]
    points = document.get("timing_points")
    if not isinstance(points, list):
        raise ResultsFormatError(f"{path}: timing_points: expected a list, got {points!r:.40}")
    settings = document.get("settings", {})
    windows = sorted({key for tp in points for key in tp.get("window_sensitivity", {})}, key=float)
    rows = []
    for i, tp in enumerate(points):
        _require(tp, path, f"timing_points[{i}]", ("delay_ms", "direction", "stiffness_nm_per_rad"))
        cells = [
            f"{tp['direction']}/{tp['delay_ms']:g}",
            tp.get("n_perturbed", "—"),
            tp.get("n_unperturbed", "—"),
            _number(100 * tp["cop_m"] if tp.get("cop_m") is not None else None, ".2f"),
            _mean_sd(tp["stiffness_nm_per_rad"], ".0f"),
            _mean_sd(tp.get("damping_nms_per_rad"), ".2f"),
            _mean_sd(tp.get("inertia_kgm2"), ".3f"),
            _mean_sd(tp.get("vaf_percent"), ".1f"),
        ]
        sensitivity = tp.get("window_sensitivity", {})
        cells += [
            _number(sensitivity.get(w, {}).get("stiffness_nm_per_rad"), ".0f") for w in windows
        ]
        rows.append(cells)
    tables = [
        Table(
            "Impedance per timing point and direction (bootstrap mean (sd))",
            [
                "condition",
                "perturbed",
                "unperturbed",
                "cop (cm)",
                "k (N·m/rad)",
                "b (N·m·s/rad)",
                "I (kg·m²)",
                "VAF (%)",
                *(f"k, {w} ms window" for w in windows),
            ],
            rows,
        ),
        Table(
            "Platform filters (held-out calibration trials)",
            ["lags", "VAF pooled (%)", *filters.get("vaf_percent_by_channel", {})],
            [
                [
                    filters.get("n_lags", "—"),
                    _mean_sd(
                        {
                            "mean": filters.get("vaf_percent_mean"),
                            "sd": filters.get("vaf_percent_sd"),
                        },
                        ".1f",
                    ),
                    *(f"{v:.1f}" for v in filters.get("vaf_percent_by_channel", {}).values()),
                ]
            ],
        ),
    ]
    if document.get("bench"):
        tables.append(
            Table(
                "Testing machine (bench)",
                ["distance (cm)", "k (N·m/rad)", "R²", "tests"],
                [
                    [
                        f"{100 * b['distance_m']:.1f}",
                        f"{b['stiffness_nm_per_rad']:.0f}",
                        f"{b['r2']:.3f}",
                        b.get("n_tests", "—"),
                    ]
                    for b in document["bench"]
                ],
            )
        )
    if document.get("validation"):
        tables.append(
            Table(
                "Walking (dorsiflexion) vs bench at the same lever arm",
                ["timing point (ms)", "cop (cm)", "bench k (N·m/rad)", "error (%)"],
                [
                    [
                        f"{v['delay_ms']:g}",
                        f"{100 * v['cop_m']:.2f}",
                        f"{v['bench_stiffness_nm_per_rad']:.0f}",
                        f"{v['error_percent']:+.1f}",
                    ]
                    for v in document["validation"]
                ],
            )
        )
    figures, missing = (
        png_figures(directory, WALKING_FIGURES),
        missing_figures(directory, WALKING_FIGURES),
    )
    s = {
        key: settings.get(key, "?")
        for key in ("cutoff_hz", "window_ms", "bootstrap_reps", "bootstrap_fraction", "seed")
    }
    text = (
        f"Session {document.get('session', '?')} (SHA-256 {document.get('session_sha256', '?')}), "
        f"analysed by anklelab "
        f"{document.get('anklelab_version', '?')}: low-pass {s['cutoff_hz']} Hz, window "
        f"{s['window_ms']} ms, bootstrap {s['bootstrap_reps']} × {s['bootstrap_fraction']} of the "
        f"perturbed trials (seed {s['seed']}). k: stiffness, b: damping, I: inertia, "
        "cop: lever arm." + _missing_text(missing)
    )
    return Section(title, text, tables, figures)


_FRICTION_ROWS = (
    ("inertia J", ("inertia_kgm2",), "kg·m²"),
    ("viscous b, cw", ("viscous_nms_per_rad", "cw"), "N·m·s/rad"),
    ("viscous b, ccw", ("viscous_nms_per_rad", "ccw"), "N·m·s/rad"),
    ("Coulomb T_c, cw", ("coulomb_nm", "cw"), "N·m"),
    ("Coulomb T_c, ccw", ("coulomb_nm", "ccw"), "N·m"),
    ("Stribeck velocity ω_s", ("stribeck_velocity_rad_s",), "rad/s"),
    ("static friction T_s", ("static_friction_nm",), "N·m"),
)


def friction_section(
    document: dict[str, Any], directory: Path, *, title: str = "Friction and inertia"
) -> Section:
    """The identified parameters of a ``friction.json`` document and the fit figures."""
    path = directory / "friction.json"
    rows = []
    for name, keys, unit in _FRICTION_ROWS:
        node = document
        for depth, key in enumerate(keys):
            node = _require(node, path, ".".join(keys[:depth]), (key,))[key]
        rows.append([name, unit, f"{node:.4g}"])
    fit = document.get("fit", {})
    figures = png_figures(directory, FRICTION_FIGURES)
    missing = missing_figures(directory, FRICTION_FIGURES)
    text = (
        "Identified at the gearhead output shaft (the capstan pinion), positive clockwise. "
        f"Spin-down fit VAF {_number(fit.get('spindown_vaf_percent'), '.2f')} %, "
        f"chirp (full model) VAF {_number(fit.get('chirp_vaf_percent'), '.2f')} %."
        + _missing_text(missing)
    )
    return Section(
        title, text, [Table("Identified parameters", ["parameter", "unit", "value"], rows)], figures
    )


def results_report(directory: str | Path, out: str | Path | None = None) -> tuple[Path, list[str]]:
    """Write a self-contained report of a results directory.

    Parameters
    ----------
    directory : str or Path
        Written by ``anklelab analyze`` (``results.json``), ``anklelab identify friction``
        (``friction.json``) and/or ``anklelab capstan`` commands (``steps.json``, ...).
    out : str or Path, optional
        The HTML file (default ``DIRECTORY/report.html``).

    Returns
    -------
    path : Path
        The report written.
    missing : list of str
        Figure files that were expected but not found.

    Raises
    ------
    ResultsFormatError
        ``directory`` is not a directory, or holds neither result file, or a file is malformed.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise ResultsFormatError(f"{directory}: not a directory; expected a results directory")
    sections, missing = [], []
    walking, friction = directory / "results.json", directory / "friction.json"
    if walking.is_file():
        document = load_results(walking, ("platform_filters", "timing_points"))
        sections.append(walking_section(document, directory))
        missing += missing_figures(directory, WALKING_FIGURES)
    if friction.is_file():
        document = load_results(friction, ("inertia_kgm2", "coulomb_nm", "viscous_nms_per_rad"))
        sections.append(friction_section(document, directory))
        missing += missing_figures(directory, FRICTION_FIGURES)
    capstan, capstan_missing = capstan_sections(directory)
    sections += capstan
    missing += capstan_missing
    if not sections:
        nested = sorted(
            str(path.parent.relative_to(directory))
            for pattern in (
                "*/results.json",
                "*/friction.json",
                "*/*/results.json",
                "*/*/friction.json",
            )
            for path in directory.glob(pattern)
        )
        hint = f"; found result files in: {', '.join(nested)}" if nested else ""
        raise ResultsFormatError(
            f"{directory}: no results.json (written by `anklelab analyze`), friction.json "
            f"(written by `anklelab identify friction`) or result of an `anklelab capstan` "
            f"command; expected an analysis output directory{hint}"
        )
    out = directory / "report.html" if out is None else Path(out)
    metadata = {"anklelab version": __version__, "results directory": directory.resolve()}
    return write_report(out, f"anklelab report: {directory.name}", sections, metadata), missing
