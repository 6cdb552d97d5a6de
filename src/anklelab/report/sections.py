"""Report sections read from result directories, and the report of a user's own results.

A *results directory* is what ``anklelab analyze`` writes (``results.json``, DESIGN.md section 5,
plus its PNG figures) and/or what ``anklelab identify friction`` writes (``friction.json``,
DESIGN.md section 6, plus its figures). :func:`results_report` turns one into a self-contained
``report.html``; the demo's report reuses :func:`walking_section` and :func:`friction_section`.

The report embeds only what the run wrote. A directory with a run manifest (``run.json``) gives
its result files and figures only if the manifest lists them and their SHA-256 matches; every
file must be a regular file inside the directory (not a symbolic link) and a figure must carry
the PNG signature. A directory without a manifest (an older anklelab's output) is reported under
the same file checks, with a warning. A figure that is missing (``--no-figures``) or refused is
named in the section's text and in the returned notes instead.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from anklelab._runs import RUN_FILE, NotEmbeddable, RunManifest, read_inside
from anklelab._version import __version__
from anklelab.errors import ResultsFormatError
from anklelab.report._documents import (
    FRICTION_KEYS,
    WALKING_KEYS,
    check_friction,
    check_walking,
    parse_document,
)
from anklelab.report.html import PNG_SIGNATURE, Figure, Section, Table, write_report

__all__ = [
    "FRICTION_FIGURES",
    "WALKING_FIGURES",
    "FigureSet",
    "FigureSpec",
    "ResultFiles",
    "friction_section",
    "load_results",
    "read_figures",
    "results_report",
    "walking_section",
]

MAX_RESULT_BYTES = 64 << 20
MAX_FIGURE_BYTES = 32 << 20

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
        "Pinion speed after the torque cut (dots) and the exact solution of "
        "J ω' + b ω = -T_c sign(ω) fitted per direction (paper 001, Fig. 6).",
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


@dataclass(frozen=True)
class ResultFiles:
    """The files of a results directory that a report may use (see the module docstring).

    Attributes
    ----------
    directory : Path
    manifest : RunManifest or None
        The directory's ``run.json``; ``None`` for a directory without one.
    """

    directory: Path
    manifest: RunManifest | None = None

    def read(self, name: str, *, limit: int) -> bytes:
        """The bytes of ``name``; :class:`NotEmbeddable` says why a file may not be used."""
        if self.manifest is not None:
            return self.manifest.read(name, limit=limit)
        return read_inside(self.directory, name, limit=limit)


def load_results(path: Path, required: Sequence[str]) -> dict[str, Any]:
    """Read a result JSON file (a regular file) and check its top-level ``required`` keys.

    Raises
    ------
    ResultsFormatError
        Naming the file and what is wrong with it.
    """
    return _load(ResultFiles(path.parent), path.name, required)


def _load(files: ResultFiles, name: str, required: Sequence[str]) -> dict[str, Any]:
    try:
        data = files.read(name, limit=MAX_RESULT_BYTES)
    except NotEmbeddable as exc:
        raise ResultsFormatError(str(exc)) from None
    return parse_document(data, files.directory / name, required)


@dataclass(frozen=True)
class FigureSet:
    """The figures of a section: those embedded, those missing, and those refused (why)."""

    figures: list[Figure] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)


def read_figures(files: ResultFiles, specs: Sequence[FigureSpec]) -> FigureSet:
    """The PNG figures of ``specs`` that ``files`` may give, in order."""
    found = FigureSet()
    for stem, title, caption in specs:
        name = f"{stem}.png"
        if not os.path.lexists(files.directory / name):
            found.missing.append(name)
            continue
        try:
            png = files.read(name, limit=MAX_FIGURE_BYTES)
            if not png.startswith(PNG_SIGNATURE):
                raise NotEmbeddable(f"{files.directory / name}: not a PNG image")
        except NotEmbeddable as exc:
            found.refused.append(f"{exc}; not embedded")
            continue
        found.figures.append(Figure(title, png, caption))
    return found


def _mean_sd(node: dict[str, Any] | None, fmt: str) -> str:
    if not node or node.get("mean") is None:
        return "—"
    sd = node.get("sd")
    return f"{node['mean']:{fmt}}" + ("" if sd is None else f" ({sd:{fmt}})")


def _number(value: Any, fmt: str) -> str:
    return "—" if value is None else f"{value:{fmt}}"


def _figures_text(found: FigureSet) -> str:
    text = ""
    if found.missing:
        text += f"\n\nFigures not found in the directory: {', '.join(found.missing)}."
    if found.refused:
        text += f"\n\nFigures not embedded: {'; '.join(found.refused)}."
    return text


def walking_section(
    document: dict[str, Any],
    directory: Path,
    *,
    title: str = "Walking impedance",
    figures: FigureSet | None = None,
) -> Section:
    """Tables of a ``results.json`` document and the walking figures.

    ``figures`` defaults to those found in ``directory`` (regular PNG files inside it).
    """
    document = check_walking(document, directory / "results.json")
    filters = document["platform_filters"]
    points = document["timing_points"]
    settings = document.get("settings", {})
    windows = sorted({key for tp in points for key in tp.get("window_sensitivity", {})}, key=float)
    rows = []
    for tp in points:
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
    found = read_figures(ResultFiles(directory), WALKING_FIGURES) if figures is None else figures
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
        "cop: lever arm." + _figures_text(found)
    )
    return Section(title, text, tables, found.figures)


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
    document: dict[str, Any],
    directory: Path,
    *,
    title: str = "Friction and inertia",
    figures: FigureSet | None = None,
) -> Section:
    """The identified parameters of a ``friction.json`` document and the fit figures.

    ``figures`` defaults to those found in ``directory`` (regular PNG files inside it).
    """
    document = check_friction(document, directory / "friction.json")
    rows = []
    for name, keys, unit in _FRICTION_ROWS:
        node = document
        for key in keys:
            node = node[key]
        rows.append([name, unit, f"{node:.4g}"])
    fit = document.get("fit", {})
    found = read_figures(ResultFiles(directory), FRICTION_FIGURES) if figures is None else figures
    text = (
        "Identified at the gearhead output shaft (the capstan pinion), positive clockwise. "
        f"Spin-down fit VAF {_number(fit.get('spindown_vaf_percent'), '.2f')} %, "
        f"chirp (full model) VAF {_number(fit.get('chirp_vaf_percent'), '.2f')} %."
        + _figures_text(found)
    )
    return Section(
        title,
        text,
        [Table("Identified parameters", ["parameter", "unit", "value"], rows)],
        found.figures,
    )


def results_report(
    directory: str | Path, out: str | Path | None = None, *, overwrite: bool = True
) -> tuple[Path, list[str]]:
    """Write a self-contained report of a results directory.

    Parameters
    ----------
    directory : str or Path
        Written by ``anklelab analyze`` (``results.json``) and/or ``anklelab identify friction``
        (``friction.json``).
    out : str or Path, optional
        The HTML file (default ``DIRECTORY/report.html``).
    overwrite : bool
        Replace an existing ``out``.

    Returns
    -------
    path : Path
        The report written.
    notes : list of str
        Warnings: no run manifest, figures missing or not embedded (and why).

    Raises
    ------
    ResultsFormatError
        ``directory`` is not a directory, or holds neither result file, or a result file is
        malformed, not a regular file, or not the one its run wrote.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise ResultsFormatError(f"{directory}: not a directory; expected a results directory")
    manifest = RunManifest.load(directory)
    files = ResultFiles(directory, manifest)
    notes = []
    if manifest is None:
        notes.append(
            f"{directory}: no {RUN_FILE} (an older anklelab's output, or not anklelab's); "
            "its files cannot be checked against the run that wrote them"
        )
    sections = []
    for name, required, check, specs, build in (
        ("results.json", WALKING_KEYS, check_walking, WALKING_FIGURES, walking_section),
        ("friction.json", FRICTION_KEYS, check_friction, FRICTION_FIGURES, friction_section),
    ):
        if not os.path.lexists(directory / name):
            continue
        document = check(_load(files, name, required), directory / name)
        found = read_figures(files, specs)
        sections.append(build(document, directory, figures=found))
        if found.missing:
            notes.append(
                f"figures not found in {directory}: {', '.join(found.missing)} "
                "(re-run the analysis with figures to include them)"
            )
        notes += found.refused
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
            f"{directory}: no results.json (written by `anklelab analyze`) or friction.json "
            f"(written by `anklelab identify friction`); expected an analysis output directory"
            f"{hint}"
        )
    out = directory / "report.html" if out is None else Path(out)
    metadata: dict[str, Any] = {
        "anklelab version": __version__,
        "results directory": directory.resolve(),
    }
    if manifest is not None:
        metadata |= {"run": f"{manifest.run_id} (`anklelab {manifest.command}`, "
                     f"anklelab {manifest.anklelab_version})"}  # fmt: skip
    title = f"anklelab report: {directory.name}"
    return write_report(out, title, sections, metadata, overwrite=overwrite), notes
