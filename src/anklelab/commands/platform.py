"""``anklelab platform``: inspect platform parameter sets."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from anklelab.platforms import PLATFORMS, load_platform

app = typer.Typer(help="Inspect platform parameter sets and their sources.", no_args_is_help=True)


def _leaves(node: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    rows: list[tuple[str, Any]] = []
    for key, value in node.items():
        dotted = f"{prefix}.{key}" if prefix else key
        rows += _leaves(value, dotted) if isinstance(value, dict) else [(dotted, value)]
    return rows


@app.command("show")
def show(
    name: Annotated[str, typer.Argument(help=f"Platform: {', '.join(PLATFORMS)}.")],
    file: Annotated[Path | None, typer.Option(help="A parameter file to load instead.")] = None,
) -> None:
    """List every parameter of a platform with its value and source."""
    params = load_platform(name, file)
    table = Table(title=f"{name} parameters")
    for column in ("parameter", "value", "source"):
        table.add_column(column)
    for key, value in _leaves(params.model_dump()):
        table.add_row(key, repr(value), params.sources.get(key, ""))
    Console().print(table)


@app.command("check")
def check(
    name: Annotated[str, typer.Argument(help=f"Platform: {', '.join(PLATFORMS)}.")],
    file: Annotated[Path, typer.Argument(help="The parameter file to validate.")],
) -> None:
    """Validate a parameter file; exits non-zero with a message naming the bad key."""
    load_platform(name, file)
    typer.echo(f"{file}: valid {name} parameters")


@app.command("bode")
def bode(
    file: Annotated[
        Path | None, typer.Option(help="A perturberator parameter file to use instead.")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the figures as JSON.")] = False,
    plot: Annotated[Path | None, typer.Option(help="Write a Bode plot to this file.")] = None,
) -> None:
    """Measure the Perturberator servo's position loop on the twin with a small PRBS.

    Reports the closed loop's natural frequency (where it lags 90 deg) and -3 dB bandwidth and
    the open loop's gain and phase margins, all estimated from simulated signals (paper 000:
    about 200 Hz, 8 dB, 45 deg).
    """
    import json

    from anklelab.experiments.perturberator_bode import measure_servo_bode

    result = measure_servo_bode(load_platform("perturberator", file))
    if plot is not None:
        result.plot(plot)
    figures = result.summary()
    if as_json:
        typer.echo(json.dumps(figures, indent=2))
        return
    table = Table(title="Perturberator position loop (measured on the twin)")
    table.add_column("figure")
    table.add_column("value", justify="right")
    for key, value in figures.items():
        table.add_row(key, f"{value:.4g}")
    Console().print(table)
