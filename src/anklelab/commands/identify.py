"""``anklelab identify``: identify platform models from recorded data."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from anklelab._atomic import write_json_atomic
from anklelab.commands._options import (
    ForceOption,
    SessionArgument,
    SettingsOption,
    finite,
    session_input,
)
from anklelab.commands._progress_bars import recording_progress

app = typer.Typer(help="Identify platform models from recorded data.", no_args_is_help=True)


FILTER_INPUTS = ("angle", "velocity", "acceleration")


def _filter_inputs(value: str | None) -> tuple[str, ...] | None:
    """Option callback: the comma-separated input pathways, each one of FILTER_INPUTS."""
    if value is None:
        return None
    names = tuple(name.strip() for name in value.split(","))
    unknown = [name for name in names if name not in FILTER_INPUTS]
    if unknown or not names:
        raise typer.BadParameter(
            f"expected names from {', '.join(FILTER_INPUTS)} separated by commas, got {value!r}"
        )
    return names


@app.command("platform-filters")
def platform_filters(
    session_path: SessionArgument,
    out: Annotated[Path, typer.Option("--out", "-o", help="The filter file (JSON) to write.")],
    settings_file: SettingsOption = None,
    inputs: Annotated[
        str | None,
        typer.Option(
            metavar="LIST",
            callback=_filter_inputs,
            help=f"Input pathways, comma-separated, from: {', '.join(FILTER_INPUTS)}.",
        ),
    ] = None,
    fit_trial: Annotated[
        int | None,
        typer.Option(min=0, help="Calibration trial (index from 0) to fit on; others score."),
    ] = None,
    force: ForceOption = False,
) -> None:
    """Fit the platform filters (motor angle -> force channels) on a session's calibration.

    Fitted on one calibration trial and scored (VAF) on the others; the file can be passed to
    `anklelab analyze --filters`.
    """
    from anklelab.commands._files import output_file
    from anklelab.data import load_session_hashed
    from anklelab.pipelines.walking import fit_platform_filters, load_walking_settings

    session_input(session_path)
    settings = load_walking_settings(
        settings_file, filter_inputs=inputs, calibration_fit_trial=fit_trial
    )
    named = [p for p in (session_path, settings_file) if p is not None]
    with output_file(out, force=force, inputs=named):
        with recording_progress() as task:
            session, sha256 = load_session_hashed(
                session_path, progress=task(f"reading {session_path.name}")
            )
        filters, vaf, by_channel = fit_platform_filters(session, settings)
        filters.save(
            out,
            session=sha256,
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
        worst = int(channels.argmin())
        table.add_row(
            session.calibration[i].name,
            f"{pooled:.2f}",
            f"{filters.channels[worst]} {channels[worst]:.1f}",
        )
    console = Console()
    console.print(table)
    console.print(f"mean held-out VAF {vaf.mean():.2f} %; filters written to {out}")


@app.command("friction")
def friction(
    ident_dir: Annotated[
        Path, typer.Argument(metavar="DIR", help="Capstan identification directory.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")],
    min_speed: Annotated[
        float,
        typer.Option(
            min=0.0,
            callback=finite,
            help="Fit spin-downs with the exact solution above this speed, rad/s.",
        ),
    ] = 10.0,
    stribeck_exponent: Annotated[
        float,
        typer.Option(
            min=0.1,
            max=10.0,
            callback=finite,
            help="Exponent of the Stribeck decay (assumed, not fitted), 0.1-10.",
        ),
    ] = 2.0,
    zero_torque: Annotated[
        float,
        typer.Option(
            min=0.0,
            callback=finite,
            help="|torque| (N·m) at or below which a spin-down is coasting.",
        ),
    ] = 0.0,
    figures: Annotated[
        bool, typer.Option("--figures/--no-figures", help="Write the fit figures.")
    ] = True,
    force: ForceOption = False,
) -> None:
    """Identify the capstan pinion's inertia and friction (paper 001, Table 2).

    Reads DIR (spin-downs and an open-loop torque chirp; see the capstan guide), writes
    OUT/friction.json, with --figures the spin-down, chirp and friction-map plots, and
    OUT/run.json (the record of the run). OUT is written whole or not at all.
    """
    from anklelab._params import dotted_leaves
    from anklelab.commands._files import check_input, output_directory
    from anklelab.data import session_hash
    from anklelab.data.capstan_ident import read_ident_directory
    from anklelab.errors import SessionFormatError
    from anklelab.ident.friction import FrictionIdentifier

    what = "an identification directory"
    check_input(ident_dir, what=what, kinds=("directory",), error=SessionFormatError)
    with (
        output_directory(out, command="identify friction", force=force, inputs=[ident_dir]) as run,
        recording_progress() as task,
    ):
        progress = task(f"reading {ident_dir.name}")
        data = read_ident_directory(ident_dir)
        progress(1, 2)
        model = FrictionIdentifier(
            min_speed_rad_s=min_speed,
            stribeck_exponent=stribeck_exponent,
            zero_torque_nm=zero_torque,
        ).fit(data)
        progress(2, 2)
        result = model.to_dict()
        write_json_atomic(run.directory / "friction.json", result)
        if figures:
            from anklelab.report.figures_capstan import friction_figures

            friction_figures(model, data, run.directory)
        run.settings.update(
            min_speed_rad_s=min_speed,
            stribeck_exponent=stribeck_exponent,
            zero_torque_nm=zero_torque,
            figures=figures,
        )
        run.add_input(ident_dir, session_hash(ident_dir))
    table = Table(title=f"pinion-shaft friction and inertia from {ident_dir}")
    for column in ("parameter", "identified", *(("truth", "error %") if data.truth else ())):
        table.add_column(column, justify="right" if column != "parameter" else "left")
    flat = dotted_leaves(result)
    truth = dotted_leaves(data.truth) if data.truth else {}
    for key, value in flat.items():
        if key.startswith("fit."):
            continue
        cells = [key, f"{value:.5g}"]
        if data.truth and key in truth:
            cells += [f"{truth[key]:.5g}", f"{100 * (value - truth[key]) / truth[key]:+.2f}"]
        table.add_row(*cells)
    console = Console()
    console.print(table)
    console.print(
        f"spin-down VAF {model.spindown_vaf_percent_:.2f} %, chirp VAF "
        f"{model.chirp_vaf_percent_:.2f} %; written to {out / 'friction.json'}"
    )
