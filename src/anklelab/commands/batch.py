"""``anklelab batch``: many recorded sessions, one settings file, one group table."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._options import ForceOption, SettingsOption
from anklelab.commands.study import (
    FiguresOption,
    RetriesOption,
    SchedulerOption,
    WorkersOption,
    resumable_output,
    warning_lines,
)

__all__ = ["batch"]


def batch(
    sessions: Annotated[  # as typed: Path would drop the './' a message must show
        list[str],
        typer.Argument(metavar="SESSIONS...", help="Session directories, .h5 or .mat files."),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")],
    settings_file: SettingsOption = None,
    scheduler: SchedulerOption = None,
    workers: WorkersOption = None,
    retries: RetriesOption = 0,
    force: ForceOption = False,
    figures: FiguresOption = True,
) -> None:
    """Analyse every session with the same settings; per-session results and a group table.

    Writes OUT/sessions/NAME/results.json and results.csv per session, OUT/group.parquet and
    .csv (one row per session, timing point and quantity, with the subject), OUT/pooled.parquet
    and .csv (mean over subjects with a 95 % interval), OUT/figures/ and OUT/run.json. A
    session that cannot be analysed is reported with its reason; the others go on. OUT appears
    when the batch completes; run the same command again to resume a batch that was stopped.
    """
    from anklelab.commands._options import session_input
    from anklelab.commands._progress_bars import recording_progress
    from anklelab.pipelines.walking import load_walking_settings
    from anklelab.studies import run_batch
    from anklelab.studies.batch import session_names
    from anklelab.studies.execute import check_scheduler

    for path in sessions:
        session_input(Path(path))
    session_names(sessions)  # a session given twice is refused before any output
    check_scheduler(scheduler, workers)
    settings = load_walking_settings(settings_file)
    inputs = [*map(Path, sessions), *([settings_file] if settings_file else [])]
    with (
        warning_lines(),
        resumable_output(out, command="batch", force=force, inputs=inputs) as (run, store),
        recording_progress() as task,
    ):
        result = run_batch(
            sessions, run.directory, settings=settings, store=store, scheduler=scheduler,
            workers=workers, retries=retries, figures=figures, progress=task("sessions"),
        )  # fmt: skip
        run.settings.update(settings.model_dump(mode="json"), figures=figures)
        for source, sha256 in result.inputs.items():
            run.add_input(Path(source), sha256)
        run.add_input(settings_file)
    group = result.group
    analysed = group[group["status"] == "ok"] if "status" in group else group.iloc[:0]
    n_subjects = analysed["subject"].nunique() if len(analysed) else 0
    typer.echo(
        f"{len(sessions) - len(result.failed)} of {len(sessions)} sessions analysed "
        f"({n_subjects} subject{'' if n_subjects == 1 else 's'}); group table in "
        f"{out / 'group.csv'}"
    )
    for name, error in result.failed.items():
        typer.echo(f"warning: {name}: {error}", err=True)
    if result.failed:
        raise typer.Exit(1)
