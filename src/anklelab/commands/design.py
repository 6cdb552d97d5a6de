"""``anklelab design``: how many perturbed trials per timing point an experiment needs."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._options import ForceOption, SettingsOption, finite
from anklelab.commands.study import (
    SchedulerOption,
    WorkersOption,
    resumable_output,
    warning_lines,
)

__all__ = ["design"]


class Foot(StrEnum):
    prosthetic = "prosthetic"
    human = "human"


def design(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")],
    foot: Annotated[Foot, typer.Option(help="What walks on the plate.")] = Foot.prosthetic,
    params: Annotated[
        Path | None,
        typer.Option(
            "--params",
            help="Perturberator parameter file describing the foot (bench law or human table), "
            "platform and protocol (default: the shipped one).",
        ),
    ] = None,
    interval: Annotated[
        float,
        typer.Option(
            help="Target stiffness interval half-width, % (±X %; above 0).",
            metavar="PERCENT",
            callback=finite,
        ),
    ] = 3.0,
    change: Annotated[
        float,
        typer.Option(
            help="Stiffness change between timing points to detect, % (above 0).",
            metavar="PERCENT",
            callback=finite,
        ),
    ] = 10.0,
    power: Annotated[
        float,
        typer.Option(
            help="Power to detect that change (strictly between 0 and 1).",
            metavar="FRACTION",
            callback=finite,
        ),
    ] = 0.8,
    pilot: Annotated[
        str,
        typer.Option(
            help="Trials per timing point of the pilot sessions, comma-separated.",
            metavar="N,N,...",
        ),
    ] = "20,40,80",
    seeds: Annotated[int, typer.Option(help="Pilot sessions per count.", min=1)] = 2,
    settings_file: SettingsOption = None,
    scheduler: SchedulerOption = None,
    workers: WorkersOption = None,
    force: ForceOption = False,
) -> None:
    """Trials per timing point for a stiffness interval of ±X % and the power to detect a Y %
    change between timing points, from pilot sessions of the twin.

    Prints the curve and the recommended number; writes OUT/design.json,
    OUT/figures/design.png, the pilot study's tables and OUT/run.json.
    """
    from anklelab.commands._kernels import prepare_kernel
    from anklelab.commands._progress_bars import recording_progress
    from anklelab.errors import ParameterError
    from anklelab.pipelines.walking import load_walking_settings
    from anklelab.platforms import load_platform
    from anklelab.studies import design_trials
    from anklelab.studies.design import DesignError, check_targets, pilot_study
    from anklelab.studies.execute import check_scheduler

    try:
        counts = [int(n) for n in pilot.split(",")]
    except ValueError:
        raise ParameterError(f"--pilot: expected counts like 10,20,40, got {pilot!r}") from None
    counts = check_targets(interval, change, power, counts, seeds)
    check_scheduler(scheduler, workers)
    parameters = load_platform("perturberator", params)
    analysis = {}
    if settings_file is not None:  # checked now, not in every pilot session
        analysis = load_walking_settings(settings_file).model_dump(mode="json")
    # the whole pilot study is checked before the output is staged
    pilot_study(counts, foot=foot.value, params_file=params, seeds=seeds, analysis=analysis)
    inputs = [p for p in (params, settings_file) if p is not None]
    with (
        warning_lines(),
        resumable_output(
            out, command="design", force=force, inputs=inputs, discard_on=(DesignError,)
        ) as (run, store),
        recording_progress() as task,
    ):
        if scheduler is None:
            prepare_kernel(parameters, task)
        result = design_trials(
            run.directory, foot=foot.value, params_file=params, interval_percent=interval,
            change_percent=change, power=power, pilot=counts, seeds=seeds, analysis=analysis,
            store=store, scheduler=scheduler, workers=workers, progress=task("pilot sessions"),
        )  # fmt: skip
        run.settings.update(
            foot=foot.value, interval_percent=interval, change_percent=change, power=power,
            pilot=counts, seeds=seeds, analysis=analysis,
        )  # fmt: skip
        run.add_input(params)
        run.add_input(settings_file)
    _print_curve(result.curve, result.interval_kind)
    typer.echo(
        f"recommended: {result.recommended} perturbed trials per timing point "
        f"({result.for_interval} for ±{interval:g} % in every condition, {result.for_power} for "
        f"{power:.0%} power to detect a {change:g} % change); details in {out}"
    )


def _print_curve(curve: dict, kind: str) -> None:
    import numpy as np
    from rich import box
    from rich.console import Console
    from rich.table import Table

    table = Table(box=box.SIMPLE_HEAD, title="stiffness interval and power per trials per point",
                  caption=f"interval: {kind}, widest condition")  # fmt: skip
    for column in ("trials per point", "half-width %", "power %", ""):
        table.add_column(column, justify="right")
    n = np.asarray(curve["trials_per_point"])
    best = curve["recommended"]
    spread = np.unique(np.geomspace(n[0], n[-1], 8).round().astype(int))
    # the recommended count takes the place of a row within 10 % of it (no 122 beside 123)
    picks = sorted({*spread[np.abs(spread - best) > 0.1 * best], best})
    for value in picks:
        i = int(np.searchsorted(n, value))
        mark = "recommended" if value == curve["recommended"] else ""
        table.add_row(str(value), f"{curve['half_width_percent'][i]:.2f}",
                      f"{100 * curve['power'][i]:.0f}", mark)  # fmt: skip
    Console().print(table)
    pilot = curve["pilot"]
    for n_pilot, width, fitted, left_out, rms in zip(
        pilot["trials_per_point"], pilot["half_width_percent"],
        pilot["fitted_half_width_percent"], pilot["left_out"], pilot["rms_error_percent"],
        strict=True,
    ):  # fmt: skip
        vague = f"; {left_out} poorly determined left out" if left_out else ""
        typer.echo(f"pilot {n_pilot:4d} trials per point: half-width {width:.2f} % (fit "
                   f"{fitted:.2f} %{vague}), RMS error against the truth {rms:.2f} %")  # fmt: skip
