"""``anklelab simulate``: run experiments on the digital twins."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from anklelab._session_limits import MAX_TRIALS_PER_POINT, MAX_UNPERTURBED
from anklelab.commands._options import ForceOption, SeedOption, finite

app = typer.Typer(help="Simulate experiments on the digital twins.", no_args_is_help=True)


class Foot(StrEnum):
    """What walks on the Perturberator's plate."""

    prosthetic = "prosthetic"
    human = "human"


class SessionFormat(StrEnum):
    """How a simulated session is stored."""

    h5 = "h5"
    dir = "dir"


def _parameter_file(path: Path | None) -> list[Path]:
    return [] if path is None else [path]


@app.command("capstan-ident")
def capstan_ident(
    out: Annotated[Path, typer.Option("--out", "-o", help="Identification directory to write.")],
    seed: SeedOption = 0,
    params: Annotated[
        Path | None,
        typer.Option("--params", help="A capstan parameter file to use instead of the shipped."),
    ] = None,
    sample_rate: Annotated[
        float,
        typer.Option(
            "--sample-rate",
            min=1000.0,
            max=10000.0,
            callback=finite,
            help="Sample and control rate, Hz (1000-10000).",
        ),
    ] = 1000.0,
    force: ForceOption = False,
) -> None:
    """Spin-downs (4 speeds each way) and an open-loop torque chirp on the capstan twin.

    Writes an identification directory (session.toml, spindown/, chirp/; see the capstan
    guide) plus truth.json with the twin's values and run.json, ready for
    `anklelab identify friction`.
    """
    from anklelab.commands._files import output_directory
    from anklelab.commands._progress_bars import recording_progress
    from anklelab.experiments import (
        IdentProtocol,
        simulate_ident,
        write_ident_directory,
    )
    from anklelab.platforms import load_platform

    parameters = load_platform("capstan", params)
    command = "simulate capstan-ident"
    with (
        output_directory(
            out, command=command, force=force, inputs=_parameter_file(params), writes_session=True
        ) as run,
        recording_progress() as task,
    ):
        progress = task("simulating spin-downs and chirp")
        data = simulate_ident(parameters, IdentProtocol(sample_rate_hz=sample_rate), seed=seed)
        progress(1, 2)
        write_ident_directory(data, run.directory, overwrite=False)
        run.settings.update(seed=seed, sample_rate_hz=sample_rate)
        run.add_input(params)
        progress(2, 2)
    typer.echo(
        f"{out}: {len(data.spindown)} spin-down runs and {len(data.chirp)} chirp at "
        f"{sample_rate:g} Hz"
    )


@app.command("perturberator")
def perturberator(
    out: Annotated[Path, typer.Option("--out", "-o", help="Session to write (.h5 or directory).")],
    seed: SeedOption = 0,
    foot: Annotated[Foot, typer.Option(help="What walks on the plate.")] = Foot.prosthetic,
    trials_per_point: Annotated[
        int | None,
        typer.Option(
            min=1,
            max=MAX_TRIALS_PER_POINT,
            help=f"Perturbed trials per timing point, 1-{MAX_TRIALS_PER_POINT} (default: 100).",
        ),
    ] = None,
    unperturbed: Annotated[
        int | None,
        typer.Option(
            min=0,
            max=MAX_UNPERTURBED,
            help=f"Unperturbed walking trials, 0-{MAX_UNPERTURBED} (default: 400).",
        ),
    ] = None,
    format: Annotated[
        SessionFormat, typer.Option(help="h5 (native store) or dir (CSV session directory).")
    ] = SessionFormat.h5,
    params: Annotated[
        Path | None,
        typer.Option(
            "--params", help="A perturberator parameter file to use instead of the shipped."
        ),
    ] = None,
    artefacts: Annotated[
        bool,
        typer.Option(
            "--artefacts/--no-artefacts",
            help="Measurement artefacts and gait variability; --no-artefacts: ideal sensors "
            "and nominal gait.",
        ),
    ] = True,
    bench: Annotated[
        bool | None,
        typer.Option(
            "--bench/--no-bench",
            help="Include the prosthesis's bench tests (default: with the prosthetic foot only).",
        ),
    ] = None,
    force: ForceOption = False,
) -> None:
    """Paper 000's session on the Perturberator twin: calibration, walking and (prosthetic
    foot) bench tests.

    The session carries a truth group (parameters, reference stiffness per timing point and
    direction, true heel contacts and onsets, time courses) for validating analyses. A session
    directory (--format dir) also holds run.json, the record of the run.
    """
    from contextlib import ExitStack

    from anklelab.commands._files import array_bytes, check_space, output_directory, output_file
    from anklelab.commands._kernels import prepare_kernel
    from anklelab.commands._progress_bars import recording_progress
    from anklelab.data import save_session
    from anklelab.experiments.perturberator import simulate_perturberator
    from anklelab.platforms import load_platform

    parameters = load_platform("perturberator", params)
    inputs = _parameter_file(params)
    with ExitStack() as stack:
        if format is SessionFormat.dir:
            run = stack.enter_context(
                output_directory(
                    out,
                    command="simulate perturberator",
                    force=force,
                    inputs=inputs,
                    writes_session=True,
                )
            )
            target = run.directory
        else:
            target = stack.enter_context(output_file(out, force=force, inputs=inputs))
        task = stack.enter_context(recording_progress())
        prepare_kernel(parameters, task)
        session = simulate_perturberator(
            parameters,
            seed=seed,
            foot=foot.value,
            trials_per_point=trials_per_point,
            n_unperturbed=unperturbed,
            bench=bench,
            artefacts=artefacts,
            progress=task("simulating trials"),
        )
        check_space(out, array_bytes(session.calibration, session.walking, session.truth))
        save_session(
            session,
            target,
            format=format.value,
            overwrite=force and format is SessionFormat.h5,
            progress=task(f"writing {format.value}"),
        )
        if format is SessionFormat.dir:
            run.settings.update(
                seed=seed,
                foot=foot.value,
                trials_per_point=trials_per_point,
                unperturbed=unperturbed,
                artefacts=artefacts,
                bench=bench,
            )
            run.add_input(params)
    typer.echo(
        f"{out}: {len(session.calibration)} calibration, {len(session.walking)} walking and "
        f"{len(session.bench)} bench recordings ({foot.value} foot, seed {seed})"
    )
    from rich.console import Console
    from rich.table import Table

    table = Table(title="true reference per timing point (truth/reference)")
    for column in ("direction", "delay (ms)", "trials", "cop (m)", "stiffness (N·m/rad)",
                   "onset sd (ms)"):  # fmt: skip
        table.add_column(column, justify="right")
    assert session.truth is not None  # simulate_perturberator always records the truth
    for direction, points in session.truth["reference"].items():
        for delay, ref in points.items():
            table.add_row(
                direction, delay, str(ref["n_trials"]), f"{ref['cop_m']:.4f}",
                f"{ref['stiffness_nm_per_rad']:.1f}", f"{ref['onset_sd_ms']:.2f}",
            )  # fmt: skip
    Console().print(table)
