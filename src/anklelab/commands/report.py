"""``anklelab report``: a self-contained HTML report of an analysis output directory."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

__all__ = ["report"]


def report(
    results_dir: Annotated[
        Path,
        typer.Argument(
            metavar="RESULTS_DIR",
            help="Written by `anklelab analyze` and/or `anklelab identify friction`.",
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="The HTML file (default RESULTS_DIR/report.html)."),
    ] = None,
) -> None:
    """Build a self-contained report.html (tables and figures, no network) from results.

    Reads results.json (walking impedance) and/or friction.json (capstan friction) and the
    figures the commands wrote beside them.
    """
    from anklelab.report.sections import results_report

    path, missing = results_report(results_dir, out)
    if missing:
        typer.echo(
            f"warning: figures not found in {results_dir}: {', '.join(missing)} "
            "(re-run the analysis with figures to include them)",
            err=True,
        )
    typer.echo(f"report written to {path}")
