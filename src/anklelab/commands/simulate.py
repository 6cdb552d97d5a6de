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
    from anklelab.experiments import (
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


@app.command("perturberator")
def perturberator(
    out: Annotated[Path, typer.Option("--out", "-o", help="Session to write (.h5 or directory).")],
    seed: Annotated[int, typer.Option(help="Random seed; the same seed gives the same bytes.")] = 0,
    foot: Annotated[str, typer.Option(help="What walks on the plate: prosthetic or human.")] = (
        "prosthetic"
    ),
    trials_per_point: Annotated[
        int | None, typer.Option(help="Perturbed trials per timing point (default: 100).")
    ] = None,
    unperturbed: Annotated[
        int | None, typer.Option(help="Unperturbed walking trials (default: 400).")
    ] = None,
    format: Annotated[str, typer.Option(help="h5 (native store) or dir (CSV directory).")] = "h5",
    params: Annotated[
        Path | None,
        typer.Option(help="A perturberator parameter file to use instead of the shipped one."),
    ] = None,
    no_artefacts: Annotated[
        bool, typer.Option("--no-artefacts", help="Ideal sensors and nominal gait.")
    ] = False,
    bench: Annotated[
        bool | None,
        typer.Option(
            "--bench/--no-bench",
            help="Include the prosthesis's bench tests (default: with the prosthetic foot only).",
        ),
    ] = None,
) -> None:
    """Paper 000's session on the Perturberator twin: calibration, walking and (prosthetic
    foot) bench tests.

    The session carries a truth group (parameters, reference stiffness per timing point and
    direction, true heel contacts and onsets, time courses) for validating analyses.
    """
    from anklelab.commands._progress import recording_progress
    from anklelab.data import save_session
    from anklelab.errors import ParameterError
    from anklelab.experiments.perturberator import simulate_perturberator
    from anklelab.platforms import load_platform

    if format not in ("h5", "dir"):
        raise ParameterError(f"--format: expected 'h5' or 'dir', got {format!r}")
    if foot not in ("prosthetic", "human"):
        raise ParameterError(f"--foot: expected 'prosthetic' or 'human', got {foot!r}")
    parameters = load_platform("perturberator", params)
    with recording_progress() as task:
        session = simulate_perturberator(
            parameters,
            seed=seed,
            foot=foot,
            trials_per_point=trials_per_point,
            n_unperturbed=unperturbed,
            bench=bench,
            artefacts=not no_artefacts,
            progress=task("simulating trials"),
        )
        save_session(session, out, format=format, progress=task(f"writing {format}"))  # type: ignore[arg-type]
    typer.echo(
        f"{out}: {len(session.calibration)} calibration, {len(session.walking)} walking and "
        f"{len(session.bench)} bench recordings ({foot} foot, seed {seed})"
    )
    from rich.console import Console
    from rich.table import Table

    table = Table(title="true reference per timing point (truth/reference)")
    for column in ("direction", "delay (ms)", "trials", "cop (m)", "stiffness (N·m/rad)",
                   "onset sd (ms)"):  # fmt: skip
        table.add_column(column, justify="right")
    for direction, points in session.truth["reference"].items():
        for delay, ref in points.items():
            table.add_row(
                direction, delay, str(ref["n_trials"]), f"{ref['cop_m']:.4f}",
                f"{ref['stiffness_nm_per_rad']:.1f}", f"{ref['onset_sd_ms']:.2f}",
            )  # fmt: skip
    Console().print(table)
