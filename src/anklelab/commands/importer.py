"""``anklelab import``: convert a session directory or MATLAB file into the native HDF5 store."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._progress_bars import recording_progress
from anklelab.errors import AnklelabError


def import_session(
    source: Annotated[
        Path, typer.Argument(help="Session directory (DESIGN.md section 4) or MATLAB .mat file.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="The HDF5 file to write.")],
    force: Annotated[bool, typer.Option("--force", help="Overwrite OUT if it exists.")] = False,
) -> None:
    """Validate a session and write it as one native HDF5 file (atomically)."""
    from anklelab.data import load_session, save_session

    if out.exists() and not force:
        raise AnklelabError(f"{out}: already exists; pass --force to overwrite it")
    with recording_progress() as task:
        session = load_session(source, progress=task(f"reading {source.name}"))
        save_session(session, out, format="h5", progress=task(f"writing {out.name}"))
    typer.echo(
        f"{out}: {len(session.calibration)} calibration, {len(session.walking)} walking, "
        f"{len(session.bench)} bench recordings (source sha256 "
        f"{session.provenance.get('source_sha256', '-')[:12]}…)"
    )
