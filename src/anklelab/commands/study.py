"""``anklelab study``: a grid or random sample of simulated sessions, analysed, on Dask."""

from __future__ import annotations

import shutil
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from anklelab.commands._options import ForceOption

if TYPE_CHECKING:
    import pandas as pd

    from anklelab.commands._files import Run

__all__ = [
    "FiguresOption",
    "RetriesOption",
    "SchedulerOption",
    "WorkersOption",
    "resumable_output",
    "study",
    "warning_lines",
]

SchedulerOption = Annotated[
    str | None,
    typer.Option(
        "--scheduler",
        metavar="ADDRESS",
        help="Where to run: 'local-cluster' (a Dask LocalCluster over TCP on this machine) or "
        "the address of a running Dask scheduler (tcp://HOST:8786). Default: Dask's local "
        "scheduler over this machine's CPUs.",
    ),
]
WorkersOption = Annotated[
    int | None,
    typer.Option(help="Worker processes on this machine (default: one per CPU).", min=1),
]
RetriesOption = Annotated[
    int, typer.Option(help="Extra tries of a task that fails, before it is reported.", min=0)
]
FiguresOption = Annotated[bool, typer.Option("--figures/--no-figures", help="Write PNG figures.")]


def study(
    study_file: Annotated[
        Path, typer.Argument(metavar="STUDY", help="Study file (TOML): see the studies guide.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")],
    scheduler: SchedulerOption = None,
    workers: WorkersOption = None,
    retries: RetriesOption = 1,
    force: ForceOption = False,
    figures: FiguresOption = True,
) -> None:
    """Simulate and analyse every cell of a study (twin settings x analysis settings x seeds).

    Writes OUT/results.parquet and .csv (one row per session, timing point and quantity: truth,
    estimate, 95 % interval, the paper's sd, error, coverage, poorly determined, stiffness
    model), OUT/summary.parquet and .csv (bias, sd, RMSE, coverage per cell), OUT/cells.csv
    (status, error and times per session), OUT/cells/ (each session's result), OUT/figures/ and
    OUT/run.json. OUT appears when the study completes; run the same command again to resume
    a study that was stopped, or, once it has completed, to compute its failed sessions again.
    """
    from anklelab.commands._files import check_input
    from anklelab.commands._kernels import prepare_kernel
    from anklelab.commands._progress_bars import recording_progress
    from anklelab.platforms import load_platform
    from anklelab.studies import ResultStore, load_study, run_study
    from anklelab.studies.execute import check_scheduler, failed_tasks

    spec = load_study(check_input(study_file, what="a study file (TOML)", kinds=("file",)))
    check_scheduler(scheduler, workers)
    keys = [cell.key for cell in spec.cells()]
    with warning_lines():  # a kept session that is unreadable is named as it is read
        retry = [] if force else failed_tasks(out, "study", keys)
        with (
            resumable_output(
                out, command="study", force=force or bool(retry), inputs=[study_file]
            ) as (run, store),
            recording_progress() as task,
        ):  # fmt: skip
            if retry:  # the same study completed with failures: keep its other sessions
                kept = [key for key in keys if key not in retry]
                ResultStore(out / "cells").copy_into(kept, store)
                typer.echo(
                    f"{out}: computing its {len(retry)} failed session"
                    f"{'' if len(retry) == 1 else 's'} again ({len(kept)} kept)"
                )
            if scheduler is None:  # local workers share this machine's kernel cache
                prepare_kernel(load_platform("perturberator"), task)
            result = run_study(
                spec, run.directory, store=store, scheduler=scheduler, workers=workers,
                retries=retries, figures=figures, progress=task(f"{spec.name}: sessions"),
            )  # fmt: skip
            run.settings.update(study=spec.describe(), retries=retries, figures=figures)
            run.add_input(study_file)
            if spec.params_file is not None:
                run.add_input(Path(spec.params_file["path"]), spec.params_file["sha256"])
    _print_summary(result.summary, spec.varied, result.results)
    typer.echo(
        f"{len(result.cells)} sessions ({result.resumed} already done, {result.ran} run); "
        f"results in {out}"
    )
    _report_failures(result.failed)


@contextmanager
def warning_lines() -> Iterator[None]:
    """Within the block, each warning is one ``warning: MESSAGE`` line on stderr, as the
    command's own notes are (not Python's ``FILE:LINE: Category: message`` and source line)."""

    def show(message: Warning | str, *args: object, **kwargs: object) -> None:
        typer.echo(f"warning: {' '.join(str(message).split())}", err=True)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


@contextmanager
def resumable_output(
    out: Path,
    *,
    command: str,
    force: bool,
    inputs: Sequence[Path],
    discard_on: tuple[type[BaseException], ...] = (),
) -> Iterator[tuple[Run, Path]]:
    """The checked, locked output directory of ``command`` and the store its tasks resume from.

    Yields the run (see :func:`anklelab.commands._files.output_directory`: OUT is built under a
    temporary name and appears, with its run.json, only when the command completes) and the
    store of finished tasks kept beside OUT (:func:`anklelab.studies.checkpoint_for`), which
    outlives a stopped run and is removed once OUT is in place, or when the command fails with
    one of ``discard_on``: errors that running the same tasks again would meet again.
    """
    from anklelab.commands._files import output_directory
    from anklelab.studies import checkpoint_for

    store = checkpoint_for(out)
    try:
        with output_directory(out, command=command, force=force, inputs=inputs) as run:
            yield run, store
    except discard_on:
        shutil.rmtree(store, ignore_errors=True)
        raise
    shutil.rmtree(store, ignore_errors=True)


def _print_summary(summary: pd.DataFrame, varied: list[str], results: pd.DataFrame) -> None:
    from rich import box
    from rich.console import Console
    from rich.table import Table

    rows = summary[summary["quantity"] == "stiffness_nm_per_rad"]
    lost = summary[summary["n_sessions"] == 0]  # points whose every session failed
    if rows.empty and lost.empty:
        return
    kinds = "/".join(sorted({k for kind in rows["interval_kind"] for k in kind.split("/") if k}))
    table = Table(
        box=box.SIMPLE_HEAD,
        title="stiffness error over seeds, % of truth",
        caption=f"point: d(orsi)/p(lantar) and timing point, ms; max: largest |error|; "
        f"cover: share of the intervals ({kinds}) holding the truth",
    )
    for key in varied:
        table.add_column(key, justify="right", overflow="fold")
    for column in ("point", "n", "bias", "sd", "RMSE", "max", "cover"):
        table.add_column(column, justify="right", no_wrap=True)
    for _, row in rows.iterrows():
        table.add_row(
            *(f"{row[k]:g}" if isinstance(row[k], float) else str(row[k]) for k in varied),
            f"{row['direction'][0]}{row['delay_ms']:g}",
            str(row["n_sessions"]),
            f"{row['bias_percent']:+.2f}",
            *(f"{row[c]:.2f}" for c in ("sd_percent", "rmse_percent", "abs_error_percent_max")),
            f"{row['coverage']:.2f}",
        )
    for _, row in lost.iterrows():
        table.add_row(
            *(f"{row[k]:g}" if isinstance(row[k], float) else str(row[k]) for k in varied),
            f"all {row['n_failed']} failed", "0", *([""] * 5),
        )  # fmt: skip
    console = Console()
    if not console.is_terminal:  # a log or a pipe: never fold the full keys of the header
        console.width = max(console.width, 200)
    console.print(table)


def _report_failures(failed: pd.DataFrame) -> None:
    """Name the failed cells (they are in the tables too) and exit with code 1."""
    if failed.empty:
        return
    for _, row in failed.head(5).iterrows():
        typer.echo(f"warning: cell {row['cell']} (seed {row['seed']}) failed: {row['error']}",
                   err=True)  # fmt: skip
    typer.echo(f"warning: {len(failed)} sessions failed (see cells.csv)", err=True)
    raise typer.Exit(1)
