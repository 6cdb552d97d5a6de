"""``anklelab demo``: both papers' experiments on the digital twins, compared with the papers."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich import box
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from anklelab.commands._options import ForceOption, SeedOption
from anklelab.commands._progress import recording_progress

if TYPE_CHECKING:
    from anklelab.report.comparisons import Comparison

__all__ = ["demo"]


def _table(title: str, rows: Sequence[Comparison]) -> Table:
    """Rows under a bold heading per group; numbers never wrap."""
    from anklelab.report.comparisons import COLUMNS, grouped

    table = Table(title=title, box=box.SIMPLE_HEAD, title_justify="left", title_style="bold")
    for k, column in enumerate(COLUMNS):
        table.add_column(column, justify="left" if k == 0 else "right", no_wrap=k > 1)
    for group, members in grouped(rows).items():
        table.add_row(f"[bold]{group}[/bold]", end_section=False)
        for row in members:
            table.add_row(*(escape(cell) for cell in row.cells()))
        table.add_section()
    return table


def demo(
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Directory for sessions, results and report.")
    ] = Path("demo-output"),
    quick: Annotated[
        bool, typer.Option("--quick", help="Small trial counts: a check in seconds.")
    ] = False,
    seed: SeedOption = 0,
    force: ForceOption = False,
) -> None:
    """Run both papers' experiments on the digital twins and compare with the papers.

    Paper 000 (Perturberator): simulate the session, measure the servo loop, identify the
    platform filters, analyse walking and compare with the bench. Paper 001 (capstan): identify
    friction, set-point and chirp control without and with compensation, torque observer.
    Writes OUT/ (sessions, results.json, friction.json, summary.json, report.html, run.json),
    whole or not at all, and prints, per paper, what the paper reported, what anklelab
    measured and the twin's truth.
    """
    from anklelab.commands._files import output_directory
    from anklelab.pipelines.demo import DemoSettings, run_capstan, run_perturberator
    from anklelab.report.demo import write_demo_report

    settings = DemoSettings.quick(seed) if quick else DemoSettings(seed=seed)
    with (
        output_directory(out, command="demo", force=force) as run,
        recording_progress(transient=False) as task,
    ):
        perturberator = run_perturberator(run.directory, settings, task=task)
        capstan = run_capstan(run.directory, settings, task=task)
        step = task("report: figures, summary.json, report.html")
        report, summary, comparisons = write_demo_report(
            run.directory, settings, perturberator, capstan
        )
        run.settings.update(settings.model_dump(mode="json"))
        step(1, 1)
    console = Console()
    if not console.is_terminal:  # a log file or pipe: wide enough for the tables not to wrap
        console = Console(width=120)
    console.print(_table("Paper 000, the Perturberator", comparisons["paper_000"]))
    console.print(_table("Paper 001, the capstan platform", comparisons["paper_001"]))
    console.print(
        f"Sessions and results in {out}/ (perturberator/, capstan/); "
        f"all values in {out / summary.name}; open {out / report.name} in a browser."
    )
