"""Arguments and options that several commands share (one declaration, one help text)."""

from __future__ import annotations

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
