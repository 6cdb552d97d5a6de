"""``anklelab identify``: identify platform models from recorded data."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from anklelab.commands._progress import recording_progress
from anklelab.data import load_session, session_hash
from anklelab.pipelines.walking import fit_platform_filters, load_walking_settings

app = typer.Typer(help="Identify platform models from recorded data.", no_args_is_help=True)


@app.command("platform-filters")
def platform_filters(
    session_path: Annotated[
        Path, typer.Argument(metavar="SESSION", help="Session directory, .h5 or .mat file.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="The filter file (JSON) to write.")],
    settings_file: Annotated[
        Path | None,
        typer.Option("--settings", help="TOML file of analysis settings (WalkingSettings keys)."),
    ] = None,
    inputs: Annotated[
        str | None,
        typer.Option(help="Input pathways, comma-separated: angle, velocity, acceleration."),
    ] = None,
    fit_trial: Annotated[
        int | None, typer.Option(help="Calibration trial (index) to fit on; others score.")
    ] = None,
) -> None:
    """Fit the platform filters (motor angle -> force channels) on a session's calibration.

    Fitted on one calibration trial and scored (VAF) on the others; the file can be passed to
    `anklelab analyze --filters`.
    """
    settings = load_walking_settings(
        settings_file,
        filter_inputs=tuple(name.strip() for name in inputs.split(",")) if inputs else None,
        calibration_fit_trial=fit_trial,
    )
    with recording_progress() as task:
        session = load_session(session_path, progress=task(f"reading {session_path.name}"))
    filters, vaf, by_channel = fit_platform_filters(session, settings)
    filters.save(
        out,
        session=session_hash(session_path),
        calibration_fit_trial=settings.calibration_fit_trial,
        vaf_percent_held_out=vaf.tolist(),
        vaf_percent_by_channel=dict(
            zip(filters.channels, by_channel.mean(axis=0).tolist(), strict=True)
        ),
    )
    table = Table(title=f"platform filters ({', '.join(filters.inputs)}; {filters.order_} terms)")
    table.add_column("held-out trial")
    table.add_column("VAF pooled %", justify="right")
    table.add_column("worst channel", justify="right")
    held_out = [i for i in range(len(session.calibration)) if i != settings.calibration_fit_trial]
    for i, pooled, channels in zip(
        held_out or [settings.calibration_fit_trial], vaf, by_channel, strict=True
    ):
        worst = int(np.argmin(channels))
        table.add_row(
            session.calibration[i].name,
            f"{pooled:.2f}",
            f"{filters.channels[worst]} {channels[worst]:.1f}",
        )
    console = Console()
    console.print(table)
    console.print(f"mean held-out VAF {np.mean(vaf):.2f} %; filters written to {out}")
