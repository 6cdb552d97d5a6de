"""Ground reaction force tables: GRF, COP and free moment from a C3D file or a session.

``anklelab forceplate`` writes one CSV table per force plate of a C3D file (``plate<N>.csv``, in
the file's global frame) or per recording of a session (``calibration/<file>``,
``walking/<file>``, in the walking frame: x anterior, y left, z up, the plate surface at z = 0),
with the columns :data:`GRF_COLUMNS`. GRF is the force of the plate on the body; the COP and the
free moment are empty where the force normal to the plate is below the threshold (and the free
moment is empty for a ``grf_cop`` session, which does not record it). ``forceplate.json``
records the anklelab version, the input's name and SHA-256 and the threshold.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from anklelab._atomic import atomic_directory
from anklelab._version import __version__
from anklelab.errors import SessionFormatError

__all__ = ["DEFAULT_MIN_FORCE_N", "GRF_COLUMNS", "grf_tables", "write_grf_tables"]

GRF_COLUMNS = (
    "time_s",
    "grf_x_n",
    "grf_y_n",
    "grf_z_n",
    "cop_x_m",
    "cop_y_m",
    "cop_z_m",
    "free_moment_nm",
)
DEFAULT_MIN_FORCE_N = 10.0
"""Below this force normal to the plate the COP and free moment are left empty, N."""
MANIFEST = "forceplate.json"

Table = dict[str, NDArray[np.float64]]


def _c3d_tables(path: Path, min_force_n: float) -> dict[str, Table]:
    from anklelab.data.c3d import plate_load, read_c3d

    c3d = read_c3d(path)
    if not c3d.plates:
        raise SessionFormatError(f"{path}: no force platforms (FORCE_PLATFORM:USED is 0)")
    loads = [(plate, plate_load(c3d, plate, min_force_n=min_force_n)) for plate in c3d.plates]
    tables = {}
    for plate, load in loads:
        columns = (c3d.time_s, *load.grf, *load.cop, load.free_moment)
        tables[f"plate{plate.number}.csv"] = dict(zip(GRF_COLUMNS, columns, strict=True))
    return tables


def _session_tables(path: Path, min_force_n: float) -> dict[str, Table]:
    from anklelab.data.store import load_session

    session = load_session(path)
    plate = session.info.force_plate
    sections = {
        "calibration": session.calibration,
        "walking": [t.recording for t in session.walking],
    }
    tables = {}
    for section, recordings in sections.items():
        for rec in recordings:
            load = plate.lab_load(rec.stack(plate.channels), min_fz_n=min_force_n)
            if plate.type == "grf_cop":
                unloaded = np.abs(load.grf_z) < min_force_n
                load_cop = [np.where(unloaded, np.nan, c) for c in (load.cop_x, load.cop_y)]
            else:
                load_cop = [load.cop_x, load.cop_y]
            cop_z = np.where(np.isfinite(load_cop[0]), 0.0, np.nan)
            columns = (rec.time_s, load.grf_x, load.grf_y, load.grf_z, *load_cop, cop_z)
            name = rec.name if rec.name.endswith(".csv") else f"{rec.name}.csv"
            if f"{section}/{name}" in tables:
                raise SessionFormatError(
                    f"{path}: {section}: two recordings would both be written as {name!r} "
                    f"(one named {rec.name!r}); rename one"
                )
            tables[f"{section}/{name}"] = dict(
                zip(GRF_COLUMNS, (*columns, load.free_moment), strict=True)
            )
    return tables


def grf_tables(source: str | Path, *, min_force_n: float = DEFAULT_MIN_FORCE_N) -> dict[str, Table]:
    """The GRF tables of a C3D file or a session, by relative output path.

    Parameters
    ----------
    source : str or Path
        A ``.c3d`` file, or a session (directory, ``.h5`` or ``.mat``).
    min_force_n : float
        COP and free moment are NaN where the force normal to the plate is below this, N.
    """
    source = Path(source)
    if not (np.isfinite(min_force_n) and min_force_n >= 0):
        raise SessionFormatError(f"min_force_n: expected a force >= 0 N, got {min_force_n!r}")
    if source.suffix.lower() == ".c3d":
        return _c3d_tables(source, min_force_n)
    return _session_tables(source, min_force_n)


def _csv(table: Mapping[str, NDArray[np.float64]]) -> str:
    buffer = io.StringIO()
    data = np.column_stack([table[c] for c in GRF_COLUMNS])
    np.savetxt(buffer, data, fmt="%.10g", delimiter=",", header=",".join(GRF_COLUMNS), comments="")
    return buffer.getvalue().replace("nan", "")


def write_grf_tables(
    source: str | Path,
    out: str | Path,
    *,
    min_force_n: float = DEFAULT_MIN_FORCE_N,
    overwrite: bool = False,
) -> dict[str, Table]:
    """Compute :func:`grf_tables` and write them under ``out``, atomically.

    ``out`` must neither lie inside ``source`` nor hold it; an existing ``out`` is replaced
    only with ``overwrite`` and only if it is an earlier output (it holds ``forceplate.json``).
    Every table lands inside ``out``, whatever the session's recording names say.

    Returns
    -------
    dict
        The tables written.
    """
    from anklelab.data.store import session_hash

    source, out = Path(source), Path(out)
    if out.resolve().is_relative_to(source.resolve()):
        raise SessionFormatError(f"{out}: the output would land inside the input {source}")
    if source.resolve().is_relative_to(out.resolve()):
        raise SessionFormatError(f"{out}: holds the input {source}; write elsewhere")
    if out.exists() and not overwrite:
        raise SessionFormatError(f"{out}: already exists; pass --force to replace it")
    tables = grf_tables(source, min_force_n=min_force_n)
    manifest = {
        "anklelab_version": __version__,
        "source": source.name,
        "source_sha256": session_hash(source),
        "settings": {"min_force_n": float(min_force_n)},
        "columns": list(GRF_COLUMNS),
        "files": sorted(tables),
    }
    try:
        with atomic_directory(out, overwrite=overwrite, marker=MANIFEST) as tmp:
            for name, table in tables.items():
                if not (tmp / name).resolve().is_relative_to(tmp.resolve()):
                    raise SessionFormatError(f"{source}: table {name!r} would land outside {out}")
                (tmp / name).parent.mkdir(parents=True, exist_ok=True)
                (tmp / name).write_text(_csv(table), encoding="utf-8")
            (tmp / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    except FileExistsError as exc:
        raise SessionFormatError(str(exc)) from None
    return tables
