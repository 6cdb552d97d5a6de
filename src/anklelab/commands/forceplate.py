"""``anklelab forceplate``: GRF, COP and free moment tables from a C3D file or a session."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def forceplate(
    source: Annotated[
        Path,
        typer.Argument(
            metavar="FILE",
            help="A .c3d file (force platform types 2, 3, 4), or a session directory, .h5 or "
            ".mat file.",
        ),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Directory for the CSV tables.")],
    min_force: Annotated[
        float,
        typer.Option(
            "--min-force",
            min=0.0,
            help="Magnitude of the force normal to the plate below which the COP and the free "
            "moment are left empty, N.",
        ),
    ] = 10.0,
    force: Annotated[bool, typer.Option("--force", help="Replace OUT if it exists.")] = False,
) -> None:
    """Ground reaction force, centre of pressure and free moment, one CSV table per plate.

    A C3D file gives OUT/plate<N>.csv per force platform, in the file's global frame; a session
    gives OUT/calibration/<file> and OUT/walking/<file>, in the walking frame (x anterior, z
    up). Columns: time_s, grf_x_n, grf_y_n, grf_z_n, cop_x_m, cop_y_m, cop_z_m,
    free_moment_nm; GRF is the force of the plate on the body, positions are in metres.
    """
    from anklelab.commands._files import check_output
    from anklelab.data.grf import write_grf_tables

    check_output(out, "directory", [source])
    tables = write_grf_tables(source, out, min_force_n=min_force, overwrite=force)
    typer.echo(
        f"{out}: {len(tables)} table(s) from {source.name} ({', '.join(sorted(tables)[:4])}"
        f"{', ...' if len(tables) > 4 else ''})"
    )
