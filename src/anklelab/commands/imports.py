"""``anklelab import``: sessions into the native HDF5 store, from any lab format.

``anklelab import SOURCE --out S.h5`` (a session directory or MATLAB session file) stays the
default; ``anklelab import c3d DIR --map M.toml --out S.h5`` and ``anklelab import matlab FILE
--map M.toml --out S.h5`` read lab files through a mapping.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer.core import TyperGroup

from anklelab.commands import importer
from anklelab.commands._progress_bars import recording_progress
from anklelab.errors import ParameterError, SessionFormatError

if TYPE_CHECKING:
    from anklelab.data.session import Session


class _DefaultToSession(TyperGroup):
    """A group whose first argument, when it names no subcommand, goes to ``session``."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = ["session", *args]
        return super().parse_args(ctx, args)


app = typer.Typer(
    cls=_DefaultToSession,
    help="Validate a session and store it as one native HDF5 file: `anklelab import SOURCE "
    "--out S.h5` for a session directory or MATLAB session file, or from C3D or any MATLAB "
    "layout through a mapping (subcommands c3d, matlab).",
    no_args_is_help=True,
)
app.command("session")(importer.import_session)

MapOption = Annotated[
    Path,
    typer.Option(
        "--map", metavar="MAPPING", help="Mapping TOML (see the guide 'Lab data formats')."
    ),
]
OutOption = Annotated[Path, typer.Option("--out", "-o", help="The HDF5 file to write.")]
ForceOption = Annotated[bool, typer.Option("--force", help="Replace OUT if it exists.")]


def _import(out: Path, force: bool, inputs: Sequence[Path], read: Callable[[], Session]) -> None:
    """Check ``out`` as ``anklelab import`` does (not an input, not inside one and holding none,
    no symbolic link, writable, not being written by another process), then read and write."""
    from anklelab.commands._files import array_bytes, check_space, output_file
    from anklelab.data import save_session

    with output_file(out, force=force, inputs=inputs), recording_progress() as task:
        session = read()
        check_space(out, array_bytes(session.calibration, session.walking, session.bench))
        save_session(
            session, out, format="h5", overwrite=force, progress=task(f"writing {out.name}")
        )
    typer.echo(
        f"{out}: {len(session.calibration)} calibration, {len(session.walking)} walking, "
        f"{len(session.bench)} bench recordings ({session.info.force_plate.type} plate)"
    )


def _mapping_input(mapping: Path) -> None:
    from anklelab.commands._files import check_input

    check_input(mapping, what="a mapping TOML file", kinds=("file",), error=ParameterError)


@app.command("c3d")
def import_c3d(
    directory: Annotated[
        Path, typer.Argument(metavar="DIR", help="Directory of per-trial C3D files.")
    ],
    mapping: MapOption,
    out: OutOption,
    force: ForceOption = False,
) -> None:
    """A session from per-trial C3D files: plate, motor and goniometer channels and the trial
    list (a CSV or the files' events) as the mapping says."""
    from anklelab.commands._files import check_input
    from anklelab.data.c3d_import import c3d_import_inputs, import_c3d

    check_input(
        directory, what="a directory of C3D files", kinds=("directory",), error=SessionFormatError
    )
    _mapping_input(mapping)
    inputs = [directory, *c3d_import_inputs(directory, mapping)]
    _import(out, force, inputs, lambda: import_c3d(directory, mapping))


@app.command("matlab")
def import_matlab(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="A MATLAB .mat file.")],
    mapping: MapOption,
    out: OutOption,
    subject: Annotated[
        str | None,
        typer.Option(
            help="The subject to import when the mapping matches several.", metavar="NAME"
        ),
    ] = None,
    force: ForceOption = False,
) -> None:
    """A session from a MATLAB file of any layout: struct paths (with wildcards over subjects,
    directions and timing points), units, scale factors and sign flips from the mapping."""
    from anklelab.commands._files import check_input
    from anklelab.data.matlab_map import import_matlab

    check_input(file, what="a MATLAB .mat file", kinds=("file",), error=SessionFormatError)
    _mapping_input(mapping)
    _import(out, force, [file, mapping], lambda: import_matlab(file, mapping, subject=subject))
