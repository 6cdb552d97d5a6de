"""``anklelab analyze``: walking impedance from a session (paper 000), results and figures."""

from __future__ import annotations

import csv
import io
import json
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import numpy as np
import typer
from rich import box
from rich.console import Console
from rich.table import Table

from anklelab._atomic import write_text_atomic
from anklelab.commands._options import SessionArgument, SettingsOption
from anklelab.commands._progress_bars import recording_progress

if TYPE_CHECKING:
    from anklelab.data.session import Session
    from anklelab.pipelines.walking import WalkingResults

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
                "delay_ms": None if np.isnan(trial.delay_ms) else trial.delay_ms,
                "kept": int(not reasons),
                "heel_contact_s": meta.get("heel_contact_s"),
                "onset_s": None if i is None or np.isnan(meta["onset_s"]) else meta["onset_s"],
                "onset_ms": None if i is None or np.isnan(meta["onset_ms"]) else meta["onset_ms"],
                "drop_reason": "; ".join(reasons),
            }
        )
    return rows


def _summary(results: WalkingResults) -> Table:
    table = Table(
        box=box.SIMPLE_HEAD,
        title="walking impedance, bootstrap mean (sd)",
        caption="cop: lever arm, cm; k: N·m/rad; b: N·m·s/rad; I: kg·m²",
    )
    for column in ("condition", "n", "cop", "k", "b", "I", "VAF %"):
        table.add_column(column, justify="right", no_wrap=True)
    for tp in results.timing_points:
        cells = [
            f"{np.mean(v):{fmt}} ({np.std(v, ddof=1) if v.size > 1 else 0.0:{fmt}})"
            for v, fmt in (
                (tp.stiffness, ".0f"),
                (tp.damping, ".2f"),
                (tp.inertia, ".3f"),
            )
        ]
        vaf = f"{np.mean(tp.vaf):.1f}"
        table.add_row(tp.key, str(tp.n_perturbed), f"{tp.cop_m * 100:.2f}", *cells, vaf)
    return table


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
        int | None, typer.Option(help="Bootstrap seed (overrides the settings).")
    ] = None,
    figures: Annotated[
        bool, typer.Option("--figures/--no-figures", help="Write PNG figures.")
    ] = True,
) -> None:
    """Ankle stiffness, damping and inertia per timing point and direction, with bootstrap.

    Writes OUT/results.json (DESIGN.md section 5), OUT/results.csv (one row per timing point and
    direction), OUT/trials.csv (detections and drop reasons per trial) and OUT/*.png figures.
    """
    from anklelab.data import load_session, session_hash
    from anklelab.errors import AnklelabWarning
    from anklelab.ident.irf import PlatformFilters
    from anklelab.pipelines.walking import STEPS, analyze_walking, load_walking_settings

    settings = load_walking_settings(settings_file, seed=seed)
    filters = PlatformFilters.load(filters_file) if filters_file else None
    with recording_progress() as task:
        session = load_session(session_path, progress=task(f"reading {session_path.name}"))
        step = task("analysing")
        total = len(STEPS) + 1 + figures
        names = list(STEPS)
        with warnings.catch_warnings():  # its warnings are printed below, with the summary
            warnings.simplefilter("ignore", AnklelabWarning)
            results = analyze_walking(
                session,
                settings,
                filters=filters,
                progress=lambda name: step(names.index(name), total),
            )
        step(len(STEPS), total)
        out.mkdir(parents=True, exist_ok=True)
        document = results.to_dict(
            session=Path(session_path).name, session_sha256=session_hash(session_path)
        )
        write_text_atomic(out / "results.json", json.dumps(document, indent=2))
        write_csv(out / "results.csv", results.table())
        write_csv(out / "trials.csv", trials_table(session, results))
        if figures:
            from anklelab.report.figures_walking import save_walking_figures

            save_walking_figures(results, out)
        step(total, total)
    console = Console()
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
    point_warnings = [message for tp in results.timing_points for message in tp.warnings]
    for message in (*results.warnings, *point_warnings):
        console.print(f"warning: {message}", style="yellow", markup=False)
