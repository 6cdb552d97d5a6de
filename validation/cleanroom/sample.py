"""Write one clean-room session directory: ``python -m validation.cleanroom.sample``.

Example::

    python -m validation.cleanroom.sample --kind human --seed 3 --out human_3
    anklelab analyze human_3 --out human_3_results
"""

from __future__ import annotations

import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

app = typer.Typer(add_completion=False, help=__doc__.splitlines()[0])


class Kind(StrEnum):
    """The session distributions of :data:`validation.cleanroom.KINDS`."""

    nominal = "nominal"
    stiff_prosthetic = "stiff_prosthetic"
    noisy = "noisy"
    mounted_y = "mounted_y"
    human = "human"
    random = "random"


@app.command()
def main(
    out: Annotated[Path, typer.Option("--out", help="Session directory to write.")],
    kind: Annotated[Kind, typer.Option("--kind", help="Session distribution.")] = Kind.nominal,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Fixes the session.")] = 0,
    trials_per_point: Annotated[
        int | None,
        typer.Option(
            "--trials-per-point",
            min=1,
            help="Perturbed trials per timing point [default: drawn, 40–100].",
        ),
    ] = None,
    unperturbed_ratio: Annotated[
        float,
        typer.Option(
            "--unperturbed-ratio",
            min=0,
            help="Unperturbed trials per perturbed trial of one timing point.",
        ),
    ] = 4.0,
    calibration_trials: Annotated[
        int, typer.Option("--calibration-trials", min=1, help="Calibration trials of 20 s.")
    ] = 5,
    bench: Annotated[
        bool, typer.Option("--bench/--no-bench", help="Testing-machine tests of prosthetic feet.")
    ] = True,
    sample_rate: Annotated[
        float, typer.Option("--sample-rate", min=1, help="DAQ rate, Hz.")
    ] = 1000.0,
    force: Annotated[
        bool, typer.Option("--force/--no-force", help="Replace an existing --out.")
    ] = False,
) -> None:
    """Draw a session of KIND, simulate it and write it as a CSV session directory."""
    from validation.cleanroom import draw_config, generate, write_session_dir

    if out.exists() and not force:
        typer.echo(f"error: {out}: already exists (use --force to replace it)", err=True)
        raise typer.Exit(2)
    start = time.perf_counter()
    try:
        config = draw_config(
            kind.value,
            seed,
            trials_per_point=trials_per_point,
            unperturbed_ratio=unperturbed_ratio,
            n_calibration=calibration_trials,
            sample_rate_hz=sample_rate,
            bench=bench,
        )
    except ValueError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    session = generate(config, seed)
    write_session_dir(session, out, force=force)
    typer.echo(
        f"{out}: {kind.value} session, seed {seed}: {len(session.calibration)} calibration, "
        f"{len(session.walking)} walking, {len(session.bench)} bench recordings "
        f"({time.perf_counter() - start:.1f} s)"
    )


if __name__ == "__main__":
    app()
