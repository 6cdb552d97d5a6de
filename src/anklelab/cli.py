"""The ``anklelab`` command. Each command group lives in its own module under ``commands``."""

from __future__ import annotations

from typing import Annotated

import typer

from anklelab import __version__
from anklelab.commands import (
    analyze,
    batch,
    capstan,
    demo,
    design,
    identify,
    importer,
    platform,
    report,
    session,
    simulate,
    study,
)
from anklelab.errors import AnklelabError

app = typer.Typer(
    help="anklelab: digital twins, control and identification for ankle actuation platforms.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
app.add_typer(platform.app, name="platform")
app.add_typer(session.app, name="session")
app.command("import")(importer.import_session)
app.command("analyze")(analyze.analyze)
app.add_typer(identify.app, name="identify")
app.add_typer(simulate.app, name="simulate")
app.add_typer(capstan.app, name="capstan")
app.command("demo")(demo.demo)
app.command("report")(report.report)
app.command("study")(study.study)
app.command("design")(design.design)
app.command("batch")(batch.batch)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"anklelab {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Show the version.")
    ] = False,
) -> None:
    """anklelab: digital twins, control and identification for ankle actuation platforms."""


def run() -> None:
    """Entry point: typer reports usage errors; domain errors become one line and exit code 2."""
    try:
        app()
    except AnklelabError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise SystemExit(2) from None
