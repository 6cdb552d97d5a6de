"""``anklelab report``: a self-contained HTML report of an analysis output directory."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._options import ForceOption

__all__ = ["report"]


def report(
    results_dir: Annotated[
        Path,
        typer.Argument(
            metavar="DIR",
            help="Written by `anklelab analyze` and/or `anklelab identify friction`.",
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="The HTML file (default DIR/report.html)."),
    ] = None,
    force: ForceOption = False,
) -> None:
    """Build a self-contained report.html (tables and figures, no network) from results.

    Reads results.json (walking impedance) and/or friction.json (capstan friction) and the
    figures the commands wrote beside them. Only files the run wrote are used (those listed in
    its run.json, unchanged since): regular files inside DIR, figures with the PNG signature.
    """
    from anklelab.commands._files import check_input, output_file
    from anklelab.errors import ResultsFormatError
    from anklelab.report.sections import results_report

    check_input(
        results_dir, what="a results directory", kinds=("directory",), error=ResultsFormatError
    )
    target = results_dir / "report.html" if out is None else out
    read = [results_dir / name for name in ("results.json", "friction.json", "run.json")]
    read += list(results_dir.glob("*.png"))
    with output_file(target, force=force, inputs=read):
        path, notes = results_report(results_dir, target, overwrite=force)
    for note in notes:
        typer.echo(f"warning: {note}", err=True)
    typer.echo(f"report written to {path}")
