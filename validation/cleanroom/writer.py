"""Write a session as the CSV directory of DESIGN §4, with code of its own.

This writer shares nothing with anklelab's: it follows the format as documented (DESIGN §4,
docs/guide/own-data.md), so reading its output with ``anklelab.data.load_session`` checks
anklelab's reader independently. Numbers are written with Python's shortest round-trip repr,
so they read back bit for bit. The directory appears atomically: it is written under a
temporary name beside the target and renamed into place.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from anklelab.data import BenchTest, Recording, Session, WalkingTrial

__all__ = ["write_session_dir"]

FORMAT = "anklelab-session/1"


def _text(value: object) -> str:
    """A CSV cell: floats by shortest round-trip repr, NaN as an empty cell."""
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return str(value)


def _write_csv(path: Path, header: Sequence[str], rows: Iterable[Sequence[object]]) -> None:
    lines = [",".join(header)]
    lines += [",".join(_text(cell) for cell in row) for row in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _write_recording(path: Path, recording: Recording) -> None:
    names = list(recording.columns)
    table = np.column_stack([np.asarray(recording.columns[name], dtype=float) for name in names])
    lines = [",".join(names)]
    lines += [",".join(map(repr, row)) for row in table.tolist()]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _toml_value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        number = float(value)
        if math.isnan(number):
            return "nan"
        if math.isinf(number):
            return "inf" if number > 0 else "-inf"
        return repr(number)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)  # a valid TOML basic string
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(item) for item in value) + "]"
    raise TypeError(f"session.toml: cannot write a {type(value).__name__} value")


def _toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _toml(tables: Mapping[str, Any]) -> str:
    """TOML text of top-level keys and (nested) tables of plain values."""
    lines: list[str] = []

    def emit(prefix: str, table: Mapping[str, Any]) -> None:
        scalars = {k: v for k, v in table.items() if not isinstance(v, Mapping)}
        if prefix:
            lines.extend(["", f"[{prefix}]"])
        lines.extend(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in scalars.items())
        for key, value in table.items():
            if isinstance(value, Mapping):
                emit(f"{prefix}.{_toml_key(key)}" if prefix else _toml_key(key), value)

    emit("", tables)
    return "\n".join(lines) + "\n"


def _json_default(value: object) -> object:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write a {type(value).__name__} to JSON")


def _write_json(path: Path, data: Mapping[str, Any]) -> None:
    path.write_text(json.dumps(data, default=_json_default, indent=1) + "\n", encoding="utf-8")


def _write_section(
    folder: Path,
    manifest: str,
    entries: Sequence[WalkingTrial | BenchTest],
    columns: tuple[str, ...],
    row: Callable[[Any], list[object]],
) -> None:
    """A folder with its manifest (``columns``, then any extra ones) and one file per entry."""
    if not entries:
        return
    folder.mkdir()
    extra = sorted({key for entry in entries for key in entry.extra})
    rows = ([*row(entry), *(entry.extra.get(key, "") for key in extra)] for entry in entries)
    _write_csv(folder / manifest, [*columns, *extra], rows)
    for entry in entries:
        _write_recording(folder / entry.recording.name, entry.recording)


def _fill(root: Path, session: Session) -> None:
    info = session.info
    plate = info.force_plate
    toml = {
        "format": FORMAT,
        "platform": info.platform,
        "sample_rate_hz": info.sample_rate_hz,
        "subject": info.subject,
        **{key: value for key, value in info.extra.items()},
        "force_plate": {
            "a_m": plate.a_m,
            "b_m": plate.b_m,
            "az0_m": plate.az0_m,
            "anterior_axis": plate.anterior_axis,
        },
        "geometry": {
            "ankle_height_m": info.ankle_height_m,
            "heel_to_ankle_m": info.heel_to_ankle_m,
        },
    }
    (root / "session.toml").write_text(_toml(toml), encoding="utf-8")
    if session.calibration:
        (root / "calibration").mkdir()
        for recording in session.calibration:
            _write_recording(root / "calibration" / recording.name, recording)
    _write_section(
        root / "walking",
        "trials.csv",
        session.walking,
        ("trial", "file", "perturbed", "direction", "delay_ms"),
        lambda t: [t.trial, t.recording.name, int(t.perturbed), t.direction, t.delay_ms],
    )
    _write_section(
        root / "bench",
        "tests.csv",
        session.bench,
        ("test", "file", "distance_m"),
        lambda t: [t.test, t.recording.name, t.distance_m],
    )
    if session.truth is not None:
        _write_json(root / "truth.json", session.truth)
    if session.provenance:
        _write_json(root / "provenance.json", session.provenance)


def write_session_dir(
    session: Session, path: str | os.PathLike[str], *, force: bool = False
) -> Path:
    """Write ``session`` as a CSV session directory at ``path``.

    Parameters
    ----------
    session : anklelab.data.Session
        The session (e.g. from :func:`validation.cleanroom.generate`).
    path : path-like
        The directory to create.
    force : bool
        Replace an existing ``path``; without it an existing path is an error.

    Returns
    -------
    pathlib.Path
        The directory written.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``force`` is false.
    """
    target = Path(path)
    if target.exists() and not force:
        raise FileExistsError(f"{target}: already exists (use force=True to replace it)")
    target.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        staging.chmod(0o755)  # mkdtemp's 0o700 would stay with the renamed directory
        _fill(staging, session)
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
            os.replace(target, old / target.name)
            os.replace(staging, target)
            shutil.rmtree(old)
        else:
            os.replace(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return target
