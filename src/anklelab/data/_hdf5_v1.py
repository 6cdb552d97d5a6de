"""Reading the first HDF5 store layout, ``anklelab-h5/1`` (written by anklelab up to 0.1).

::

    /                       attribute format = "anklelab-h5/1"
    /session                the session.toml document (keys as attributes, tables as groups)
    /calibration/<file>     one group per recording, one float64 dataset per column
    /walking/<file>         same, with attributes trial (an integer, or text since labels are
                            text), perturbed, direction, delay_ms and any further manifest
                            columns (strings)
    /bench/<file>           same, with attributes test (a label like trial's), distance_m and
                            further manifest columns
    /truth                  optional ground-truth tree (groups, datasets, attributes)
    /provenance             provenance tree

Names that contain ``/`` or ``%`` are percent-escaped. New files use ``anklelab-h5/2``
(:mod:`anklelab.data.hdf5`); these are still read, with the same checks.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from anklelab.data._checks import (
    check_bench_tests,
    check_recording,
    check_walking_row,
    check_walking_trials,
    excerpt,
    info_from_mapping,
    section_columns,
)
from anklelab.data._progress import Progress, ticker
from anklelab.data._tree import read_h5_tree, unlink_name
from anklelab.data.session import (
    BENCH_MANIFEST_COLUMNS,
    WALKING_MANIFEST_COLUMNS,
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
    label_text,
)
from anklelab.errors import SessionFormatError

__all__ = ["read_v1"]

# manifest columns stored as attributes (the file name is the group's name)
_WALKING_ATTRS = tuple(c for c in WALKING_MANIFEST_COLUMNS if c != "file")
_BENCH_ATTRS = tuple(c for c in BENCH_MANIFEST_COLUMNS if c != "file")


def _columns(where: str, group: h5py.Group) -> dict[str, np.ndarray]:
    """Every dataset of a recording's group as a float64 column (low-level reads, ~3x faster
    than h5py's ``dataset[()]`` for many small columns)."""
    columns = {}
    for link in group:
        try:
            dataset = h5py.h5d.open(group.id, link.encode())
        except KeyError:
            dataset = None
        numeric = (h5py.h5t.FLOAT, h5py.h5t.INTEGER)
        if (
            dataset is None
            or len(dataset.shape) != 1
            or dataset.get_type().get_class() not in numeric
        ):
            raise SessionFormatError(
                f"{where}/{link}: expected a 1-D numeric dataset (one column), got "
                f"{excerpt(group[link])}"
            )
        values = np.empty(dataset.shape, dtype=np.float64)
        dataset.read(h5py.h5s.ALL, h5py.h5s.ALL, values)
        columns[unlink_name(link)] = values
    return columns


def _attr(where: str, attrs: dict[str, Any], key: str, kind: type) -> Any:
    if key not in attrs:
        raise SessionFormatError(f"{where}: attribute {key!r} is missing")
    value = attrs[key]
    ok = {
        bool: isinstance(value, np.bool_ | bool),
        str: isinstance(value, str),
        float: isinstance(value, np.floating | float),
    }[kind]
    if not ok:
        raise SessionFormatError(
            f"{where}: attribute {key!r} = {excerpt(value)}; expected a {kind.__name__}"
        )
    return kind(value)


def _label(where: str, attrs: dict[str, Any], key: str) -> str:
    """A trial or test label: text, or an integer (files written before labels were text)."""
    if key not in attrs:
        raise SessionFormatError(f"{where}: attribute {key!r} is missing")
    return label_text(attrs[key], f"{where}: attribute {key!r}")


def _extra(attrs: dict[str, Any], known: tuple[str, ...]) -> dict[str, str]:
    return {k: str(v) for k, v in attrs.items() if k not in known}


def _section(f: h5py.File, name: str) -> h5py.Group | None:
    item = f.get(name)
    if item is not None and not isinstance(item, h5py.Group):
        raise SessionFormatError(f"{f.filename}:/{name}: expected a group")
    return item


def read_v1(f: h5py.File, path: Path, progress: Progress | None) -> Session:
    """Read an open ``anklelab-h5/1`` file (already checked by :func:`check_h5_file`)."""
    if not isinstance(f.get("session"), h5py.Group):
        raise SessionFormatError(f"{path}:/session: group is missing")
    info = info_from_mapping(read_h5_tree(f["session"]), str(path), "/session/")
    fs = info.sample_rate_hz
    sections = {name: _section(f, name) for name in ("calibration", "walking", "bench")}
    tick = ticker(progress, sum(len(g) for g in sections.values() if g is not None))

    def recording(section: str, link: str, group: h5py.Group) -> tuple[str, Recording]:
        where = f"{path}:/{section}/{link}"
        if not isinstance(group, h5py.Group):
            raise SessionFormatError(f"{where}: expected a group (one recording)")
        columns = _columns(where, group)
        required, nullable = section_columns(info, section)
        check_recording(where, columns, required, fs, nullable=nullable)
        tick()
        return where, Recording(unlink_name(link), columns)

    calibration = []
    if (section := sections["calibration"]) is not None:
        for link, group in section.items():
            calibration.append(recording("calibration", link, group)[1])
    walking = []
    if (section := sections["walking"]) is not None:
        for link, group in section.items():
            where, rec = recording("walking", link, group)
            attrs = dict(group.attrs)
            trial = WalkingTrial(
                trial=_label(where, attrs, "trial"),
                recording=rec,
                perturbed=_attr(where, attrs, "perturbed", bool),
                direction=_attr(where, attrs, "direction", str),  # type: ignore[arg-type]
                delay_ms=_attr(where, attrs, "delay_ms", float),
                extra=_extra(attrs, _WALKING_ATTRS),
            )
            check_walking_row(where, trial.perturbed, trial.direction, trial.delay_ms)
            walking.append((trial, f"/walking/{link}"))
        check_walking_trials(str(path), walking)
    bench = []
    if (section := sections["bench"]) is not None:
        for link, group in section.items():
            where, rec = recording("bench", link, group)
            attrs = dict(group.attrs)
            test = BenchTest(
                test=_label(where, attrs, "test"),
                recording=rec,
                distance_m=_attr(where, attrs, "distance_m", float),
                extra=_extra(attrs, _BENCH_ATTRS),
            )
            bench.append((test, f"/bench/{link}"))
        check_bench_tests(str(path), bench)
    truth = read_h5_tree(f["truth"]) if "truth" in f else None
    provenance = read_h5_tree(f["provenance"]) if "provenance" in f else {}
    return Session(
        info=info,
        calibration=tuple(calibration),
        walking=tuple(t for t, _ in walking),
        bench=tuple(b for b, _ in bench),
        truth=truth,
        provenance=provenance,
        source=str(path),
    )
