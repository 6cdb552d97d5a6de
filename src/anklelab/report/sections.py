"""Report sections read from result directories, and the report of a user's own results.

A *results directory* is what ``anklelab analyze`` writes (``results.json``, DESIGN.md section 5,
plus its PNG figures) and/or what ``anklelab identify friction`` writes (``friction.json``,
DESIGN.md section 6, plus its figures). :func:`results_report` turns one into a self-contained
``report.html``; the demo's report reuses :func:`walking_sections` and :func:`friction_section`.

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
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from anklelab._runs import RUN_FILE, NotEmbeddable, RunManifest, read_inside
from anklelab._version import __version__
from anklelab.errors import ResultsFormatError
from anklelab.pipelines.walking import WalkingResults
from anklelab.report._documents import (
    FRICTION_KEYS,
    WALKING_KEYS,
    check_friction,
    check_walking,
    parse_document,
)
from anklelab.report.figures_impedance import SD95, interval_kind
from anklelab.report.html import PNG_SIGNATURE, Figure, Section, Table, write_report
from anklelab.report.summary import impedance_summary_table, notes, run_rows, settings_table

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
    "run_metadata",
    "walking_sections",
]

MAX_RESULT_BYTES = 64 << 20
MAX_FIGURE_BYTES = 32 << 20

FigureSpec = tuple[str, str, str]
"""``(file stem, title, caption)`` of a figure a command writes as ``<stem>.png``."""

WALKING_FIGURES: tuple[FigureSpec, ...] = (
    (
        "impedance_summary",
        "Stiffness, damping and inertia by timing point",
        "Each condition's estimate with its 95 % interval (the results' confidence interval, or "
        "mean ± 1.96 sd of the bootstrap where there is none, as the legend says), "
        "dorsiflexion left of each timing point and plantarflexion right of it; paper 000's "
        "walking stiffness at 100 and 475 ms and its inertia (stars, grey band); the testing "
        "machine's stiffness interpolated at each condition's lever arm (squares). Hollow grey "
        "markers with '?' are quantities the analysis flagged as poorly determined.",
    ),
    (
        "impedance_vs_lever_arm",
        "Stiffness, damping and inertia vs lever arm",
        "The same estimates against the lever arm (the θ²-weighted distance from the ankle "
        "centre to the centre of pressure over the window; the two directions drawn 1 mm either "
        "side of it), with the testing machine's stiffness at its actuator distances (squares) "
        "and paper 000's bench line, 1300 → 975 N·m/rad over 6–11 cm (triangles; paper 000, "
        "Fig. 8).",
    ),
    (
        "filters",
        "Platform filters",
        "What the unloaded platform puts on each force channel: the static gain of the angle "
        "pathway (the gravity tilt, bars) and the impulse response of the acceleration pathway "
        "(the top plate's inertia ringing with the drivetrain; paper 000, Figs. 3 and 6), fitted "
        "on one calibration trial. Channels that carry the same signal on the symmetric plate "
        "(fx12 and fx34; fz1 and fz4; fz2 and fz3) are drawn wide and pale, then thin and dashed, "
        "so both stay visible. The circle at the last lag is not part of the decaying response: "
        "with inputs low-passed at the analysis cut-off, the last weight stands in for the "
        "response beyond the filter's length (on the twin, setting it to zero lowers the "
        "held-out VAF from 99.8 % to 98.0 %).",
    ),
    (
        "stance_profiles",
        "Stance profiles",
        "Ankle angle (degrees) and torque after heel contact, one row per direction: the "
        "unperturbed trials (black) and each timing point's perturbed trials (colour), mean ± sd; "
        "the dotted lines are the mean detected onsets (paper 000, Fig. 5).",
    ),
    (
        "model_fit",
        "Measured vs model torque",
        "Perturbation torque over the analysis window (mean ± sd over the bootstrap averages) "
        "and the fitted I θ'' + b θ' + k θ, one row per direction and one column per timing "
        "point (paper 000, Fig. 7b).",
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


def _run_name(subject: str | None, session: str | None) -> str:
    """``"S03 — day1.h5"``; one of them when the other is missing or names the same.

    >>> _run_name("S03", "day1.h5"), _run_name("S03", "S03.h5"), _run_name(None, "s.h5")
    ('S03 — day1.h5', 'S03.h5', 's.h5')
    """
    if subject and session and Path(session).stem != subject:
        return f"{subject} — {session}"
    return session or subject or ""


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


def _analysed(path: Path) -> str:
    """When the result file was written (UTC), as the date of the analysis."""
    try:
        stamp = datetime.fromtimestamp(os.lstat(path).st_mtime, tz=UTC)
    except OSError:
        return "—"
    return stamp.strftime("%Y-%m-%d %H:%M UTC")


def _weak_channels(by_channel: dict[str, Any]) -> str:
    """Why a channel's own filter VAF below 50 % is harmless (lateral) or not (the others)."""
    weak = {c: v for c, v in by_channel.items() if isinstance(v, int | float) and v < 50.0}

    def listed(channels: dict[str, float]) -> str:
        return f"{', '.join(channels)} ({', '.join(f'{v:.1f} %' for v in channels.values())})"

    lateral = {c: v for c, v in weak.items() if c.startswith("fy")}
    poor = {c: v for c, v in weak.items() if c not in lateral}
    text = []
    if lateral:
        text.append(
            f"The platform filters explain little of the lateral channels {listed(lateral)} on "
            "their own: a sagittal perturbation puts almost no force on them, so what they hold "
            "is noise, and they add nothing to the pooled VAF, which weighs each channel by its "
            "variance."
        )
    if poor:
        text.append(
            f"The platform filters fit {listed(poor)} poorly: check that the calibration trials "
            "cover the walking perturbations and that nobody touched the plate (see the report "
            "guide)."
        )
    return " ".join(text)


def run_metadata(document: dict[str, Any], directory: Path) -> dict[str, str]:
    """The report's header table for a ``results.json`` document: subject, session, date."""
    return dict(run_rows(document, analysed=_analysed(directory / "results.json")))


def walking_sections(
    document: dict[str, Any],
    directory: Path,
    *,
    title: str = "Walking impedance",
    figures: FigureSet | None = None,
) -> list[Section]:
    """A ``results.json`` document and its figures: the summary, then the details.

    The summary is the key figure (stiffness, damping and inertia by timing point) with one
    table and the notes a reader must see first (warnings, poorly determined quantities); the
    details hold the platform filters, the bench, window sensitivity and the other figures.
    ``figures`` defaults to those found in ``directory`` (regular PNG files inside it).

    Raises
    ------
    ResultsFormatError
        The document lacks what the sections show, naming the file and the key.
    """
    path = directory / "results.json"
    document = check_walking(document, path)
    results = WalkingResults.from_dict(document, where=str(path))
    filters = document["platform_filters"]
    points = document["timing_points"]
    windows = sorted({key for tp in points for key in tp.get("window_sensitivity", {})}, key=float)
    rows = []
    for tp in points:
        sensitivity = tp.get("window_sensitivity", {})
        rows.append(
            [
                f"{tp['direction']}/{tp['delay_ms']:g}",
                tp.get("n_perturbed", "—"),
                tp.get("n_unperturbed", "—"),
                _mean_sd(tp["stiffness_nm_per_rad"], ".0f"),
                _mean_sd(tp.get("damping_nms_per_rad"), ".2f"),
                _mean_sd(tp.get("inertia_kgm2"), ".3f"),
                _mean_sd(tp.get("vaf_percent"), ".1f"),
                *(
                    _number(sensitivity.get(w, {}).get("stiffness_nm_per_rad"), ".0f")
                    for w in windows
                ),
            ]
        )
    by_channel = filters.get("vaf_percent_by_channel", {})
    tables = [
        Table(
            "Platform filters (held-out calibration trials)",
            [
                "filter length (lags)",
                "VAF, all channels pooled (%)",
                *(f"{c} (%)" for c in by_channel),
            ],
            [
                [
                    _number(filters.get("n_lags"), "d"),
                    _mean_sd(
                        {
                            "mean": filters.get("vaf_percent_mean"),
                            "sd": filters.get("vaf_percent_sd"),
                        },
                        ".1f",
                    ),
                    *(_number(v, ".1f") for v in by_channel.values()),
                ]
            ],
        ),
        Table(
            "Trials and bootstrap spread per condition (mean (sd) over bootstrap averages)",
            [
                "condition",
                "perturbed trials",
                "unperturbed trials",
                "stiffness (N·m/rad)",
                "damping (N·m·s/rad)",
                "inertia (kg·m²)",
                "model VAF (%)",
                *(f"stiffness, {w} ms window (N·m/rad)" for w in windows),
            ],
            rows,
        ),
    ]
    if document.get("bench"):
        tables.append(
            Table(
                "Testing machine (bench)",
                ["actuator distance (cm)", "stiffness (N·m/rad)", "R²", "tests"],
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
    found = read_figures(ResultFiles(directory), WALKING_FIGURES) if figures is None else figures
    summary_titles = {title for _, title, _ in WALKING_FIGURES[:1]}
    vaf = filters.get("vaf_percent_mean")
    text = (
        f"{len(points)} conditions; the platform filters explain {_number(vaf, '.1f')} % of "
        "the unloaded platform's forces (held-out calibration trials)."
    )
    if results.bench:
        text += (
            " Walking − bench: the estimate against the testing machine at the same lever arm "
            '(paper 000: 3.6 to 8.4 %); a bench value marked "line extended" lies beyond the '
            "tested distances."
        )
    if SD95 in interval_kind(results.timing_points):
        text += (
            " Intervals marked * are mean ± 1.96 sd of the bootstrap (results written without "
            "confidence intervals), which understates the uncertainty (see the report guide)."
        )
    text += _figures_text(found)
    settings = document.get("settings")
    summary = Section(
        title,
        text,
        [impedance_summary_table(results)],
        [f for f in found.figures if f.title in summary_titles],
        notes=notes(results),
        figures_first=True,
    )
    details = Section(
        f"{title}: details",
        _weak_channels(by_channel),
        tables,
        [f for f in found.figures if f.title not in summary_titles],
        details=[settings_table(settings)] if isinstance(settings, dict) else [],
    )
    return [summary, details]


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
        Written by ``anklelab analyze`` (``results.json``), ``anklelab identify friction``
        (``friction.json``) and/or ``anklelab capstan`` commands (``steps.json``, ...).
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
    from anklelab.report.sections_capstan import capstan_sections

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
    sections: list[Section] = []
    title, metadata = "Capstan friction and inertia", {}
    for name, required, specs in (
        ("results.json", WALKING_KEYS, WALKING_FIGURES),
        ("friction.json", FRICTION_KEYS, FRICTION_FIGURES),
    ):
        if not os.path.lexists(directory / name):
            continue
        document = _load(files, name, required)
        found = read_figures(files, specs)
        if name == "results.json":
            sections += walking_sections(document, directory, figures=found)
            metadata = run_metadata(document, directory)
            named = _run_name(document.get("subject"), document.get("session"))
            title = f"Walking impedance: {named}" if named else "Walking impedance"
        else:
            sections.append(friction_section(document, directory, figures=found))
        if found.missing:
            notes.append(
                f"figures not found in {directory}: {', '.join(found.missing)} "
                "(re-run the analysis with figures to include them)"
            )
        notes += found.refused
    capstan, capstan_notes = capstan_sections(files)
    sections += capstan
    notes += capstan_notes
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
    if metadata.get("anklelab version") != __version__:
        metadata["report written by anklelab"] = __version__
    metadata["results directory"] = str(directory.resolve())
    if manifest is not None:
        metadata["run"] = (
            f"{manifest.run_id} (`anklelab {manifest.command}`, "
            f"anklelab {manifest.anklelab_version})"
        )
    return write_report(out, title, sections, metadata, overwrite=overwrite), notes
