"""``anklelab simulate``: run experiments on the digital twins."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

app = typer.Typer(help="Simulate experiments on the digital twins.", no_args_is_help=True)


@app.command("capstan-ident")
def capstan_ident(
    out: Annotated[Path, typer.Option("--out", "-o", help="Identification directory to write.")],
    seed: Annotated[int, typer.Option(help="Random seed (encoder offsets, current noise).")] = 0,
    params: Annotated[
        Path | None,
        typer.Option(help="A capstan parameter file to use instead of the shipped one."),
    ] = None,
    sample_rate: Annotated[float, typer.Option(help="Sample and control rate, Hz.")] = 1000.0,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing session directory.")] = False,
) -> None:
    """Spin-downs (4 speeds each way) and an open-loop torque chirp on the capstan twin.

    Writes DESIGN.md section 6's directory (plus truth.json with the twin's values), ready for
    `anklelab identify friction`.
    """
    from anklelab.commands._progress import recording_progress
    from anklelab.experiments.capstan_ident import (
        IdentProtocol,
        simulate_ident,
        write_ident_directory,
    )
    from anklelab.platforms import load_platform

    parameters = load_platform("capstan", params)
    with recording_progress() as task:
        progress = task("simulating spin-downs and chirp")
        data = simulate_ident(parameters, IdentProtocol(sample_rate_hz=sample_rate), seed=seed)
        progress(1, 2)
        write_ident_directory(data, out, overwrite=overwrite)
        progress(2, 2)
    typer.echo(
        f"{out}: {len(data.spindown)} spin-down runs and {len(data.chirp)} chirp at "
        f"{sample_rate:g} Hz"
    )
