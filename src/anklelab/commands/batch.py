"""``anklelab batch``: many recorded sessions, one settings file, one group table."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._options import SettingsOption
from anklelab.commands.study import (
    ForceOption,
    RetriesOption,
    SchedulerOption,
    WorkersOption,
)

__all__ = ["batch"]


def batch(
    sessions: Annotated[
        list[Path],
        typer.Argument(metavar="SESSIONS...", help="Session directories, .h5 or .mat files."),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")],
    settings_file: SettingsOption = None,
    scheduler: SchedulerOption = None,
    workers: WorkersOption = None,
    retries: RetriesOption = 0,
    force: ForceOption = False,
    figures: Annotated[
        bool, typer.Option("--figures/--no-figures", help="Write PNG figures.")
    ] = True,
) -> None:
    """Analyse every session with the same settings; per-session results and a group table.

    Writes OUT/sessions/NAME/results.json and results.csv per session, OUT/group.parquet and
    .csv (one row per session, timing point and quantity, with the subject), OUT/pooled.parquet
    and .csv (mean over subjects with a 95 % interval) and OUT/figures/. A session that cannot
    be analysed is reported with its reason; the others go on.
    """
    from anklelab.commands._progress import recording_progress
    from anklelab.pipelines.walking import load_walking_settings
    from anklelab.studies import run_batch

    settings = load_walking_settings(settings_file)
    with recording_progress() as task:
        run = run_batch(
            sessions, out, settings=settings, scheduler=scheduler, workers=workers,
            retries=retries, force=force, figures=figures, progress=task("sessions"),
        )  # fmt: skip
    n_subjects = run.group.loc[run.group["status"] == "ok", "subject"].nunique()
    typer.echo(
        f"{len(sessions) - len(run.failed)} of {len(sessions)} sessions analysed "
        f"({n_subjects} subjects); group table in {out / 'group.csv'}"
    )
    for name, error in run.failed.items():
        typer.echo(f"warning: {name}: {error}", err=True)
    if run.failed:
        raise typer.Exit(1)
