"""``anklelab import``: convert a session directory or MATLAB file into the native HDF5 store."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from anklelab.commands._options import ForceOption, session_input
from anklelab.commands._progress import recording_progress


def import_session(
    source: Annotated[
        Path,
        typer.Argument(
            metavar="SOURCE",
            help="Session directory (CSV files and session.toml) or MATLAB .mat file.",
        ),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="The HDF5 file to write.")],
    force: ForceOption = False,
) -> None:
    """Validate a session and write it as one native HDF5 file (atomically)."""
    from anklelab.commands._files import array_bytes, check_space, output_file
    from anklelab.data import load_session, save_session

    session_input(source)
    with output_file(out, force=force, inputs=[source]), recording_progress() as task:
        session = load_session(source, progress=task(f"reading {source.name}"))
        check_space(out, array_bytes(session.calibration, session.walking, session.bench))
        save_session(
            session, out, format="h5", overwrite=force, progress=task(f"writing {out.name}")
        )
    typer.echo(
        f"{out}: {len(session.calibration)} calibration, {len(session.walking)} walking, "
        f"{len(session.bench)} bench recordings (source sha256 "
        f"{session.provenance.get('source_sha256', '-')[:12]}…)"
    )
