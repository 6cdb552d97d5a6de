"""``anklelab session``: inspect a session (directory, HDF5 or MATLAB file)."""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from anklelab.commands._options import SessionArgument, session_input
from anklelab.commands._progress_bars import recording_progress

app = typer.Typer(help="Inspect sessions.", no_args_is_help=True)


def _seconds(durations: dict[str, float] | None) -> str:
    if durations is None:
        return "-"
    return (
        f"{durations['min']:.3g}–{durations['max']:.3g} s "
        f"(median {durations['median']:.3g} s, total {durations['total']:.4g} s)"
    )


def _count(n: int, noun: str) -> str:
    """``"1 trial"``, ``"2 trials"``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _bench(bench: dict[str, Any]) -> str:
    distances = ", ".join(f"{d:g}" for d in bench["distances_m"])
    return _count(bench["n"], "test") + (f" at {distances} m" if distances else "")


def _table(summary: dict[str, Any]) -> Table:
    info = summary["info"]
    walking = summary["walking"]
    table = Table(show_header=False, box=None)
    table.add_column(style="bold")
    table.add_column(overflow="fold")  # a hash folds onto the next line, never cut short
    rows = [
        ("platform", info["platform"]),
        ("subject", info["subject"]),
        ("sample rate", f"{info['sample_rate_hz']:g} Hz"),
        ("force plate", ", ".join(f"{k} = {v}" for k, v in info["force_plate"].items())),
        ("geometry", ", ".join(f"{k} = {v}" for k, v in info["geometry"].items())),
        ("calibration", _count(summary["calibration"]["n"], "trial")),
        ("  durations", _seconds(summary["calibration"]["duration_s"])),
        (
            "walking",
            f"{_count(walking['n'], 'trial')}: {walking['n_perturbed']} perturbed, "
            f"{walking['n_unperturbed']} unperturbed",
        ),
        *(
            (f"  {p['direction']} {p['delay_ms']:g} ms", _count(p["n"], "trial"))
            for p in walking["timing_points"]
        ),
        ("  durations", _seconds(walking["duration_s"])),
        ("bench", _bench(summary["bench"])),
        ("truth", ", ".join(summary["truth_keys"]) if summary["truth"] else "absent"),
        *((f"provenance.{k}", str(v)) for k, v in summary["provenance"].items()),
    ]
    for key, value in rows:
        table.add_row(key, str(value))
    return table


@app.command("info")
def info(
    path: SessionArgument,
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
) -> None:
    """Validate a session and summarise it: platform, rate, trials per timing point, truth."""
    from anklelab.data import load_session, summarize

    session_input(path)
    with recording_progress() as task:
        summary = summarize(load_session(path, progress=task(f"reading {path.name}")))
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
    else:
        Console().print(_table(summary))
