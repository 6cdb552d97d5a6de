"""The tree of a MATLAB, HDF5 or C3D file: names, shapes, dtypes and C3D parameters.

``anklelab inspect FILE`` prints it so that a mapping can be written for the file:

- a MATLAB file as the mapping sees it (structs, struct arrays with their fields, arrays with
  shape and type, text), v5/v7 and v7.3 alike;
- an HDF5 file's groups, datasets (shape, dtype) and attributes; links are shown, never
  followed;
- a C3D file's rates, analog channels (label, unit, range), force platforms, events and every
  parameter; a parameter that keeps the file from being imported (``POINT:UNITS = 'in'``, a
  non-finite ``ORIGIN``) is a note, and the rest is shown.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from anklelab.data._files import not_a_file
from anklelab.errors import SessionFormatError

__all__ = ["inspect_file"]

_MAX_ITEMS = 6  # values shown of a parameter or attribute


def _short(value: Any) -> str:
    """A value in one short line."""
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if isinstance(value, str):
        return repr(value if len(value) <= 60 else value[:57] + "...")
    if isinstance(value, list):
        shown = ", ".join(_short(v) for v in value[:_MAX_ITEMS])
        return f"[{shown}{', ...' if len(value) > _MAX_ITEMS else ''}] ({len(value)})"
    array = np.asarray(value)
    if array.size == 1 and array.dtype.kind in "biuf":
        return f"{array.item():.6g}" if array.dtype.kind == "f" else str(array.item())
    if array.dtype.kind in "biuf":
        flat = ", ".join(f"{v:.6g}" for v in array.ravel()[:_MAX_ITEMS])
        more = ", ..." if array.size > _MAX_ITEMS else ""
        return f"{'x'.join(map(str, array.shape))} {array.dtype}: {flat}{more}"
    return f"{type(value).__name__} {array.shape}"


# --- MATLAB -----------------------------------------------------------------------------------


def _matlab_node(name: str, value: Any, depth: int) -> Iterator[str]:
    pad = "  " * depth
    if isinstance(value, Mapping):
        yield f"{pad}{name}  struct"
        for key, item in value.items():
            if not str(key).startswith("__"):
                yield from _matlab_node(str(key), item, depth + 1)
    elif isinstance(value, list) and value and all(isinstance(v, Mapping) for v in value):
        fields = [tuple(v) for v in value]
        same = all(f == fields[0] for f in fields)
        yield f"{pad}{name}  1x{len(value)} struct array" + ("" if same else " (fields differ)")
        yield from _matlab_node(f"{name}(1)", value[0], depth + 1)
    elif isinstance(value, list):
        yield f"{pad}{name}  cell 1x{len(value)}"
        for k, item in enumerate(value[:_MAX_ITEMS]):
            yield from _matlab_node(f"{name}{{{k + 1}}}", item, depth + 1)
    elif isinstance(value, str):
        yield f"{pad}{name}  char {_short(value)}"
    else:
        array = np.asarray(value)
        if array.dtype == object:
            yield f"{pad}{name}  {array.dtype} array {array.shape}"
        elif array.size == 1:
            yield f"{pad}{name}  {array.dtype} scalar {_short(array)}"
        else:
            yield f"{pad}{name}  {array.dtype} {'x'.join(map(str, array.shape))}"


def _matlab(path: Path) -> Iterator[str]:
    from anklelab.data.matlab import _load

    yield f"{path}: MATLAB file (as a mapping sees it: n x 1 arrays are vectors)"
    for name, value in _load(path).items():
        if not name.startswith("__"):
            yield from _matlab_node(name, value, 1)


# --- HDF5 -------------------------------------------------------------------------------------


def _hdf5(path: Path) -> Iterator[str]:
    import h5py

    def attributes(item: Any, pad: str) -> Iterator[str]:
        for key, value in item.attrs.items():
            yield f"{pad}  @{key} = {_short(value)}"

    def walk(group: Any, depth: int) -> Iterator[str]:
        pad = "  " * depth
        for name in group:
            link = group.get(name, getlink=True)
            if isinstance(link, h5py.SoftLink | h5py.ExternalLink):
                target = getattr(link, "filename", "")
                yield f"{pad}{name}  -> link to {target}{link.path} (not followed)"
                continue
            item = group[name]
            if isinstance(item, h5py.Group):
                yield f"{pad}{name}/"
                yield from attributes(item, pad)
                yield from walk(item, depth + 1)
            else:
                yield f"{pad}{name}  {item.dtype} {'x'.join(map(str, item.shape)) or 'scalar'}"
                yield from attributes(item, pad)

    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise SessionFormatError(f"{path}: cannot open as HDF5 ({exc})") from None
    with f:
        yield f"{path}: HDF5 file"
        yield from attributes(f, "")
        yield from walk(f, 1)


# --- C3D --------------------------------------------------------------------------------------


def _c3d(path: Path) -> Iterator[str]:
    from anklelab.data.c3d import read_c3d

    c3d = read_c3d(path, lenient=True)
    yield f"{path}: C3D file"
    units = f"in metres x {c3d.length_scale:g}" if math.isfinite(c3d.length_scale) else "unknown"
    yield (
        f"  analog {c3d.analog_rate_hz:g} Hz, {c3d.n_samples} samples from {c3d.start_s:g} s; "
        f"points {c3d.point_rate_hz:g} Hz; POINT units {units}"
    )
    for problem in c3d.problems:
        yield f"  note: {problem} (left out below; the parameters are shown as they are)"
    yield f"  analog channels ({len(c3d.labels)}):"
    for k, (label, unit) in enumerate(zip(c3d.labels, c3d.units, strict=True)):
        values = c3d.analogs[k]
        low, high = (float(values.min()), float(values.max())) if values.size else (0.0, 0.0)
        yield f"    {k + 1:3d} {label!r} [{unit or '-'}] {low:.6g} .. {high:.6g}"
    yield f"  force platforms ({len(c3d.plates)}):"
    for plate in c3d.plates:
        labels = ", ".join(c3d.labels[c] for c in plate.channels)
        yield f"    {plate.number}: type {plate.type}, channels {labels}"
        yield f"       origin (m) {_short(plate.origin_m)}; centre (m) {_short(plate.centre_m)}"
    yield f"  events ({len(c3d.events)}):"
    for event in c3d.events:
        yield f"    {event.time_s:.4f} s  {event.label!r} ({event.context or '-'})"
    yield "  parameters:"
    for group, parameters in c3d.parameters.items():
        yield f"    {group}"
        for name, value in parameters.items():
            yield f"      {name} = {_short(value)}"


def inspect_file(path: str | Path) -> list[str]:
    """The lines of the file's tree (by its suffix: ``.mat``, ``.c3d``, else HDF5).

    Raises
    ------
    SessionFormatError
        The file is missing or cannot be read as its kind.
    """
    path = Path(path)
    if problem := not_a_file(path):
        raise SessionFormatError(f"{path}: {problem}; expected a .mat, .c3d or HDF5 file")
    suffix = path.suffix.lower()
    reader = {".mat": _matlab, ".c3d": _c3d}.get(suffix, _hdf5)
    return list(reader(path))
