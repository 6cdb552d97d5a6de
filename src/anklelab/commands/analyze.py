"""``anklelab analyze``: walking impedance from a session (paper 000), results and figures."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich import box
from rich.console import Console
from rich.table import Table

from anklelab._atomic import write_text_atomic
from anklelab.commands._options import (
    ForceOption,
    SessionArgument,
    SettingsOption,
    session_input,
)
from anklelab.commands._progress_bars import recording_progress

if TYPE_CHECKING:
    from anklelab.data.session import Session
    from anklelab.pipelines.walking import WalkingResults
    from anklelab.report.render import FigureRenderer, PendingFigures

__all__ = ["analyze", "trials_table", "write_csv"]


def write_csv(path: Path, rows: Sequence[dict[str, Any]]) -> Path:
    """Write dict rows (same keys) as CSV, atomically; ``None`` becomes an empty cell."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]) if rows else [], lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return write_text_atomic(path, buffer.getvalue())


def trials_table(session: Session, results: WalkingResults) -> list[dict[str, Any]]:
    """One row per walking trial: what was detected and, if it was dropped, why."""
    stance = results.stance
    position = {int(p): i for i, p in enumerate(stance.selection)}
    rows = []
    for p, (trial, reasons) in enumerate(zip(session.walking, stance.drop_log, strict=True)):
        i = position.get(p)
        meta = (
            {k: stance.metadata[k][i] for k in ("heel_contact_s", "onset_s", "onset_ms")}
            if i is not None
            else {}
        )
        rows.append(
            {
                "trial": trial.trial,
                "file": trial.recording.name,
                "perturbed": int(trial.perturbed),
                "direction": trial.direction,
                "delay_ms": None if math.isnan(trial.delay_ms) else trial.delay_ms,
                "kept": int(not reasons),
                "heel_contact_s": meta.get("heel_contact_s"),
                "onset_s": None if i is None or math.isnan(meta["onset_s"]) else meta["onset_s"],
                "onset_ms": None if i is None or math.isnan(meta["onset_ms"]) else meta["onset_ms"],
                "drop_reason": "; ".join(reasons),
            }
        )
    return rows


_CHANGE_MARKS = {"changes": " Δ", "undetermined": " Δ?"}


def _summary(results: WalkingResults) -> Table:
    """Estimate and 95 % interval per quantity and timing point; poorly determined ones in
    brackets only (never as a precise number)."""
    from anklelab.pipelines.walking.results import QUANTITIES

    table = Table(
        box=box.SIMPLE_HEAD,
        title="walking impedance: estimate [95 % interval]",
        caption="cop: lever arm, cm; model: stiffness constant or changing within the window; "
        "Δ: stiffness changes within the window; Δ?: the data cannot tell whether it changes "
        f"by ±{100 * results.settings.change_threshold:g} %; ≈: poorly determined (interval "
        "spans zero or exceeds ±50 %)"
        + ("; I: one for the session" if results.settings.inertia_model == "session" else ""),
    )
    columns = ["condition", "n", "cop", "model"] + [f"{q.symbol} ({q.unit})" for q in QUANTITIES]
    for column in columns:
        table.add_column(column, justify="right", no_wrap=True)
    for tp in results.timing_points:
        cells = []
        for q in QUANTITIES:
            e = getattr(tp, q.name)
            low, high = e.ci95
            interval = f"[{low:{q.format}}, {high:{q.format}}]"
            cells.append(
                f"≈ {interval}" if e.poorly_determined else f"{e.mean:{q.format}} {interval}"
            )
        model = tp.stiffness_model + _CHANGE_MARKS.get(tp.stiffness_change_verdict, "")
        table.add_row(tp.key, str(tp.n_perturbed), f"{tp.cop_m * 100:.2f}", model, *cells)
    return table


def _poorly_determined(results: WalkingResults) -> str:
    """Which quantities are poorly determined at how many points ("" if none)."""
    from anklelab.pipelines.walking.results import QUANTITIES

    n = len(results.timing_points)
    counts = {
        q.name: sum(getattr(tp, q.name).poorly_determined for tp in results.timing_points)
        for q in QUANTITIES
    }
    return ", ".join(f"{name} at {k} of {n} points" for name, k in counts.items() if k)


def _angle_gains(results: WalkingResults) -> str:
    """The ankle angle's gains against the plate's rotation across the conditions, measured and
    as the estimates use them ("" where none was measured)."""
    measured = [tp.angle_gain for tp in results.timing_points if math.isfinite(tp.angle_gain)]
    if not measured:
        return ""
    used = [tp.angle_gain_pooled for tp in results.timing_points if math.isfinite(tp.angle_gain)]
    line = f"ankle angle / plate rotation: {min(measured):.3f} to {max(measured):.3f} by condition"
    if results.settings.angle_gain == "pooled":
        line += f", pooled to {min(used):.3f} to {max(used):.3f}"
    return line + " (angle_gain in results.json)"


def _renderer(figures: bool) -> FigureRenderer | contextlib.nullcontext[None]:
    """Figure workers, started now so that they import matplotlib while the analysis runs."""
    if not figures:
        return contextlib.nullcontext()
    from anklelab.report.render import FigureRenderer

    return FigureRenderer(["anklelab.report.figures_walking"])


def analyze(
    session_path: SessionArgument,
    out: Annotated[Path, typer.Option("--out", "-o", help="Directory for results and figures.")],
    settings_file: SettingsOption = None,
    filters_file: Annotated[
        Path | None,
        typer.Option(
            "--filters", help="Platform filters from `anklelab identify platform-filters`."
        ),
    ] = None,
    seed: Annotated[
        int | None, typer.Option(min=0, help="Bootstrap seed (overrides the settings).")
    ] = None,
    figures: Annotated[
        bool, typer.Option("--figures/--no-figures", help="Write PNG figures.")
    ] = True,
    force: ForceOption = False,
) -> None:
    """Ankle stiffness, damping and inertia per timing point and direction, with bootstrap.

    Writes OUT/results.json (see the result-files guide), OUT/results.csv (one row per timing
    point and direction), OUT/trials.csv (detections and drop reasons per trial), OUT/*.png
    figures and OUT/run.json (the record of the run: settings, input hashes, files written).
    OUT is written whole or not at all.
    """
    from anklelab.commands._files import output_directory
    from anklelab.pipelines.walking import load_walking_settings

    session_input(session_path)
    settings = load_walking_settings(settings_file, seed=seed)
    inputs = [p for p in (session_path, settings_file, filters_file) if p is not None]
    with contextlib.ExitStack() as stack:
        run = stack.enter_context(
            output_directory(out, command="analyze", force=force, inputs=inputs)
        )
        # the arguments checked, the figure workers start: they import matplotlib while this
        # process imports the analysis and reads the session (and are ended if that fails)
        renderer = stack.enter_context(_renderer(figures))
        from anklelab.data import input_name, load_session_hashed
        from anklelab.errors import AnklelabWarning
        from anklelab.ident.irf import PlatformFilters
        from anklelab.pipelines.walking import STEPS, analyze_walking

        filters = PlatformFilters.load(filters_file) if filters_file else None
        task = stack.enter_context(recording_progress())
        session, sha256 = load_session_hashed(
            session_path, progress=task(f"reading {session_path.name}")
        )
        step = task("analysing")
        total = len(STEPS) + 1 + figures
        names = list(STEPS)
        early: list[PendingFigures] = []  # the filters' figure, drawn while the analysis runs

        def draw_filters(fitted: PlatformFilters) -> None:
            from anklelab.report.figures_walking import submit_filters_figure

            assert renderer is not None  # called only when figures are drawn
            early.append(submit_filters_figure(fitted, renderer))

        with warnings.catch_warnings():  # its warnings are printed below, with the summary
            warnings.simplefilter("ignore", AnklelabWarning)
            results = analyze_walking(
                session,
                settings,
                filters=filters,
                progress=lambda name: step(names.index(name), total),
                filters_ready=draw_filters if figures else None,
            )
        step(len(STEPS), total)
        document = results.to_dict(
            session=input_name(session_path), session_sha256=sha256, subject=session.info.subject
        )
        write_text_atomic(run.directory / "results.json", json.dumps(document, indent=2))
        write_csv(run.directory / "results.csv", results.table())
        write_csv(run.directory / "trials.csv", trials_table(session, results))
        if figures:
            from anklelab.report.figures_walking import save_walking_figures

            submitted = early[0] if early else None
            save_walking_figures(results, run.directory, renderer, submitted=submitted)
        run.settings.update(settings.model_dump(mode="json"), figures=figures)
        run.add_input(session_path, sha256)
        run.add_input(settings_file)
        run.add_input(filters_file)
        step(total, total)
    console = Console()
    if not console.is_terminal:  # a log or a pipe: never fold the table's rows
        console.width = max(console.width, 200)
    console.print(_summary(results))
    counts = results.drop_counts()
    reasons = "; ".join(f"{n} {kind}" for kind, n in counts.items())
    vaf = document["platform_filters"]["vaf_percent_mean"]
    console.print(
        f"platform filters: held-out VAF {'-' if vaf is None else f'{vaf:.2f}'} %; "
        f"{sum(counts.values())} of {len(session.walking)} walking trials dropped"
        f"{f' ({reasons})' if reasons else ''} (see trials.csv); results in {out}",
        markup=False,
    )
    if gains := _angle_gains(results):
        console.print(gains, markup=False, soft_wrap=True)
    vague = _poorly_determined(results)
    if vague:
        line = f"≈ poorly determined: {vague} (intervals in results.json)"
        console.print(line, markup=False, soft_wrap=True)
    point_warnings = [message for tp in results.timing_points for message in tp.warnings]
    for message in (*results.warnings, *point_warnings):  # one line each, for grep and copying
        console.print(f"warning: {message}", style="yellow", markup=False, soft_wrap=True)
