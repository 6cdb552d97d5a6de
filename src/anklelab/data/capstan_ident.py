"""The capstan platform's friction and inertia identification directory (DESIGN.md section 6).

::

    ident_dir/
      session.toml          format = "anklelab-session/1", platform = "capstan", sample_rate_hz
      spindown/runs.csv     columns: run, file
      spindown/<file>.csv   columns: time_s, velocity_rad_s, torque_nm (torque 0 from the coast on)
      chirp/<file>.csv      columns: time_s, torque_nm, velocity_rad_s (open-loop torque chirp)
      truth.json            optional: the twin's friction and inertia (simulated data only)

Everything is at the gearhead output (the capstan pinion), positive clockwise. The CSV files and
the manifest are read and checked by the session directory's readers (finite values, time
strictly increasing at ``sample_rate_hz``; messages name file, column and line).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab._atomic import atomic_directory
from anklelab.data._files import MAX_JSON_BYTES
from anklelab.data._text import excerpt
from anklelab.data.directory import (
    SessionReader,
    _manifest,
    _manifest_rows,
    read_csv_recording,
    read_session_toml,
    write_csv_recording,
)
from anklelab.data.session import SESSION_FORMAT, Recording
from anklelab.errors import SessionFormatError

__all__ = [
    "CHIRP_COLUMNS",
    "SPINDOWN_COLUMNS",
    "IdentData",
    "IdentRun",
    "read_ident_directory",
    "write_ident_directory",
]

SPINDOWN_COLUMNS = ("time_s", "velocity_rad_s", "torque_nm")
CHIRP_COLUMNS = ("time_s", "torque_nm", "velocity_rad_s")
RUNS_COLUMNS = ("run", "file")


@dataclass(frozen=True)
class IdentRun:
    """One recording at the pinion: time (s), velocity (rad/s, cw positive), torque (N·m)."""

    name: str
    time_s: NDArray[np.float64]
    velocity_rad_s: NDArray[np.float64]
    torque_nm: NDArray[np.float64]


@dataclass(frozen=True)
class IdentData:
    """An identification session: spin-down runs and torque chirps.

    Attributes
    ----------
    sample_rate_hz : float
        Sample rate of every file, Hz.
    spindown : tuple of IdentRun
        Spin-down runs in ``runs.csv`` order.
    chirp : tuple of IdentRun
        Open-loop torque chirps (file-name order).
    truth : mapping or None
        Simulated sessions: the twin's values, keyed like ``friction.json``.
    """

    sample_rate_hz: float
    spindown: tuple[IdentRun, ...]
    chirp: tuple[IdentRun, ...]
    truth: dict[str, Any] | None = None


def _session_toml(reader: SessionReader) -> float:
    file = reader.root / "session.toml"
    meta = read_session_toml(reader, file)
    expected = {"format": SESSION_FORMAT, "platform": "capstan"}
    for key, value in expected.items():
        if meta.get(key) != value:
            raise SessionFormatError(
                f"{file}: {key} = {excerpt(meta.get(key))}; expected {value!r}"
            )
    fs = meta.get("sample_rate_hz")
    if isinstance(fs, bool) or not isinstance(fs, int | float) or not fs > 0:
        raise SessionFormatError(f"{file}: sample_rate_hz = {excerpt(fs)}; expected a number > 0")
    return float(fs)


def _run(reader: SessionReader, path: Path, columns: tuple[str, ...], fs: float) -> IdentRun:
    rec = read_csv_recording(path, columns, fs, reader=reader)
    return IdentRun(path.name, rec["time_s"], rec["velocity_rad_s"], rec["torque_nm"])


def _spindown_files(reader: SessionReader, folder: Path) -> list[Path]:
    paths = []
    for _, where, row, path, _ in _manifest_rows(reader, folder, "runs.csv", RUNS_COLUMNS):
        if not row["run"]:
            raise SessionFormatError(f"{where}, column 'run': empty; expected a run label")
        paths.append(path)
    return paths


def read_ident_directory(path: str | Path) -> IdentData:
    """Read and validate an identification directory (see the module docstring).

    Raises
    ------
    SessionFormatError
        Naming the file, column and line of the first problem.
    """
    path = Path(path)
    if not path.is_dir():
        raise SessionFormatError(f"{path}: not a directory; expected an identification session")
    reader = SessionReader(path)
    fs = _session_toml(reader)
    spindown = tuple(
        _run(reader, p, SPINDOWN_COLUMNS, fs) for p in _spindown_files(reader, path / "spindown")
    )
    chirp_dir = path / "chirp"
    chirps = sorted(chirp_dir.glob("*.csv")) if chirp_dir.is_dir() else []
    if not chirps:
        raise SessionFormatError(f"{chirp_dir}: no CSV files; expected at least one torque chirp")
    chirp = tuple(_run(reader, p, CHIRP_COLUMNS, fs) for p in chirps)
    truth_file = path / "truth.json"
    truth = None
    if truth_file.exists():
        text = reader.text(truth_file, MAX_JSON_BYTES, "a JSON file")
        try:
            truth = json.loads(text)
        except (json.JSONDecodeError, RecursionError):
            raise SessionFormatError(
                f"{truth_file}: not valid JSON; expected a JSON object"
            ) from None
    return IdentData(fs, spindown, chirp, truth)


def write_ident_directory(data: IdentData, path: str | Path, *, overwrite: bool = True) -> Path:
    """Write ``data`` as an identification directory, atomically."""
    path = Path(path)
    with atomic_directory(path, overwrite=overwrite) as tmp:
        (tmp / "session.toml").write_text(
            f'format = "{SESSION_FORMAT}"\nplatform = "capstan"\n'
            f"sample_rate_hz = {data.sample_rate_hz!r}\n"
        )
        for folder, runs, columns in (
            ("spindown", data.spindown, SPINDOWN_COLUMNS),
            ("chirp", data.chirp, CHIRP_COLUMNS),
        ):
            (tmp / folder).mkdir()
            for run in runs:
                values = {
                    "time_s": run.time_s,
                    "velocity_rad_s": run.velocity_rad_s,
                    "torque_nm": run.torque_nm,
                }
                write_csv_recording(
                    tmp / folder / run.name, Recording(run.name, {c: values[c] for c in columns})
                )
        rows = [{"run": str(k + 1), "file": run.name} for k, run in enumerate(data.spindown)]
        (tmp / "spindown" / "runs.csv").write_text(_manifest(rows, RUNS_COLUMNS))
        if data.truth is not None:
            (tmp / "truth.json").write_text(json.dumps(data.truth, indent=2) + "\n")
    return path
