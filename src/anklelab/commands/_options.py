"""Arguments and options that several commands share (one declaration, one help text)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

SessionArgument = Annotated[
    Path, typer.Argument(metavar="SESSION", help="Session directory, .h5 or .mat file.")
]
SettingsOption = Annotated[
    Path | None,
    typer.Option("--settings", help="TOML file of analysis settings (WalkingSettings keys)."),
]
ForceOption = Annotated[
    bool,
    typer.Option(
        "--force",
        help="Replace an existing output. A directory is replaced only if it is an output of "
        "the same command (its run.json says so); never a session of yours.",
    ),
]
SeedOption = Annotated[
    int, typer.Option("--seed", min=0, help="Random seed; the same seed gives the same result.")
]


def finite(value: float | None) -> float | None:
    """Option callback: reject NaN and infinities (click's ranges let NaN through)."""
    if value is not None and not math.isfinite(value):
        raise typer.BadParameter(f"expected a finite number, got {value}")
    return value


def session_input(path: Path) -> Path:
    """``path`` if it can be a session (a directory or a regular file); else a clear error."""
    from anklelab.commands._files import check_input
    from anklelab.errors import SessionFormatError

    return check_input(path, what="a session directory, .h5 or .mat file", error=SessionFormatError)
