"""``anklelab inspect``: the tree of a MATLAB, HDF5 or C3D file, to write a mapping from."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def inspect(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="A .mat, .c3d or HDF5 (.h5) file.")],
) -> None:
    """Print a file's tree: names, shapes and types, and a C3D file's channels, force platforms,
    events and parameters."""
    from anklelab.data.inspect import inspect_file

    typer.echo("\n".join(inspect_file(file)))
