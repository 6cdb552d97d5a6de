"""MATLAB importer: a ``.mat`` file holding one struct ``session`` (v5/v7 or v7.3).

The layout is the session directory's, as MATLAB structs (field names are the column and
manifest names; vectors may be rows or columns)::

    session                  scalar struct
      .format                'anklelab-session/1'
      .platform              'perturberator'
      .sample_rate_hz        1000
      .subject               'S01'
      .force_plate           struct: a_m, b_m, az0_m, anterior_axis ('+x' ...)
      .geometry              struct: ankle_height_m, heel_to_ankle_m
      .calibration           1xN struct array: time_s, motor_angle, plate channels [, file]
      .walking               1xN struct array: trial (label: text or an integer), perturbed
                             (0/1 or logical), direction ('dorsi'|'plantar'|'none'), delay_ms
                             (NaN or [] when unperturbed), time_s, motor_angle, ankle_angle,
                             plate channels [, file]
      .bench                 1xN struct array: test (label), distance_m, time_s,
                             displacement_m, force_n [, file]
      (any other field)      kept in SessionInfo.extra

In MATLAB::

    session.walking(1) = struct('trial', 1, 'perturbed', 1, 'direction', 'dorsi', ...
        'delay_ms', 225, 'time_s', t, 'motor_angle', m, 'ankle_angle', a, 'fx12', fx12, ...);
    save('session.mat', 'session')            % or save(..., '-v7.3')

The plate channels are those of ``force_plate.type`` (``fx12 ... fz4`` for the default
``kistler8``). ``file`` names the recording (defaults: ``calibration_001.csv``;
``trial_0001.csv`` and ``test_001.csv`` from an integer label, ``<label>.csv`` from a text
one, its characters other than letters, digits, ``-``, ``_`` and ``.`` percent-encoded, so that
different labels never share a file). In a recording struct every numeric vector as long as
``time_s`` is a column (unknown ones are kept); other unknown scalar or text fields of walking
and bench elements are kept as manifest extras. Files up to v7 are read with
:func:`scipy.io.loadmat`, v7.3 files (HDF5) with h5py. Errors name the MATLAB field, e.g.
``session.walking(3).fz1``.
"""

from __future__ import annotations

import math
import re
import urllib.parse
from collections.abc import Callable, Iterator
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
)
from anklelab.data._files import not_a_file
from anklelab.data._h5safe import H5_ERRORS, check_h5_file, damaged, open_h5
from anklelab.data._progress import Progress, ticker
from anklelab.data.session import (
    BENCH_COLUMNS,
    BenchTest,
    Recording,
    Session,
    WalkingTrial,
    label_text,
)
from anklelab.errors import SessionFormatError

__all__ = ["read_matlab"]

_SECTIONS = ("calibration", "walking", "bench")


# --- reading the file into plain Python values ----------------------------------------------------


def _decode(value: Any) -> str:
    return value.decode("ascii", "replace") if isinstance(value, bytes) else str(value)


def _h5_value(
    item: h5py.Group | h5py.Dataset, f: h5py.File, where: str, enclosing: frozenset[int]
) -> Any:
    """A MATLAB v7.3 object as the value :func:`scipy.io.loadmat` would give (simplify_cells).

    ``where`` names the value in messages (``session.walking(3)``); ``enclosing`` holds the
    addresses of the objects around it, so that a reference back to one of them (a cycle) is
    refused rather than followed forever.
    """
    address = h5py.h5o.get_info(item.id).addr
    if address in enclosing:
        raise SessionFormatError(
            f"{where}: refers back to a value that contains it (a reference cycle); expected a "
            "tree of values"
        )
    inside = enclosing | {address}

    def follow(ref: h5py.Reference, at: str) -> Any:
        if not ref:
            raise SessionFormatError(f"{at}: a null reference; expected a value")
        try:
            target = f[ref]
        except H5_ERRORS:
            raise SessionFormatError(
                f"{at}: a dangling reference (the object it names does not exist)"
            ) from None
        return _h5_value(target, f, at, inside)

    cls = _decode(item.attrs.get("MATLAB_class", b""))
    if isinstance(item, h5py.Group):
        order = item.attrs.get("MATLAB_fields")
        names = (
            [b"".join(np.asarray(field).ravel()).decode("ascii", "replace") for field in order]
            if order is not None
            else [k for k in item if not k.startswith("#")]
        )
        members = {name: item[name] for name in names if name in item}
        is_array = members and all(
            isinstance(m, h5py.Dataset)
            and m.dtype == h5py.ref_dtype
            and "MATLAB_class" not in m.attrs
            for m in members.values()
        )
        if not is_array:
            return {name: _h5_value(m, f, f"{where}.{name}", inside) for name, m in members.items()}
        refs = {name: m[()].ravel(order="F") for name, m in members.items()}
        count = min(map(len, refs.values()))
        elements = [
            {name: follow(r[i], f"{where}({i + 1}).{name}") for name, r in refs.items()}
            for i in range(count)
        ]
        return elements[0] if count == 1 else elements
    if np.asarray(item.attrs.get("MATLAB_empty", 0)).any():
        return "" if cls == "char" else np.empty(0)
    data = np.asarray(item[()]).T  # HDF5 stores MATLAB arrays transposed
    if cls == "char":
        try:
            return "".join(map(chr, data.ravel()))
        except (TypeError, ValueError, OverflowError):
            raise SessionFormatError(f"{where}: not valid character codes") from None
    if cls == "cell":
        cells = [follow(ref, f"{where}{{{i + 1}}}") for i, ref in enumerate(data.ravel())]
        return cells[0] if len(cells) == 1 else cells
    if cls == "logical":
        data = data.astype(bool)
    data = np.squeeze(data)
    return data.item() if data.ndim == 0 else data


def _load(path: Path, only: str | None = None) -> dict[str, Any]:
    """The top-level variables of a MAT file as plain values; with ``only``, just that one (no
    other variable is read).

    Raises
    ------
    SessionFormatError
        When the file cannot be read (a v7.3 file: any link, alias, oversized dataset, reference
        cycle or damage, see :func:`~anklelab.data._h5safe.check_h5_file`), or has no variable
        ``only`` (naming the variables it has).
    """
    if h5py.is_hdf5(str(path)):  # v7.3
        try:
            with open_h5(path, "a MATLAB v7.3 file") as f:
                check_h5_file(f, path)
                names = [k for k in f if not k.startswith("#")]
                _require(path, only, names)
                return {
                    k: _h5_value(f[k], f, f"{path}: {k}", frozenset())
                    for k in ([only] if only else names)
                }
        except SessionFormatError:
            raise
        except H5_ERRORS as exc:
            raise damaged(path, exc) from None
        except RecursionError:
            raise SessionFormatError(f"{path}: values nested too deeply") from None
    import scipy.io  # only for pre-v7.3 files; slow to import

    try:
        names = [name for name, _, _ in scipy.io.whosmat(str(path))]
        _require(path, only, names)
        return scipy.io.loadmat(str(path), simplify_cells=True, variable_names=only and [only])
    except SessionFormatError:
        raise
    except Exception as exc:  # scipy raises many types for a file that is not a MAT file
        raise SessionFormatError(
            f"{path}: cannot read as a MAT file ({excerpt(str(exc), 100, quote=False)})"
        ) from None


def _require(path: Path, name: str | None, names: list[str]) -> None:
    if name is not None and name not in names:
        found = ", ".join(excerpt(k, 40, quote=False) for k in names) or "none"
        hint = (
            "; a MATLAB file of another layout is read with 'anklelab import matlab FILE --map "
            "MAP.toml' (see the guide 'Lab data formats')"
            if name == "session"
            else ""
        )
        raise SessionFormatError(f"{path}: no variable {name!r} (found: {found}){hint}")


# --- building the session -----------------------------------------------------------------------


def _elements(value: Any, where: str) -> list[dict[str, Any]]:
    if isinstance(value, dict):
        return [value]
    if isinstance(value, list) and all(isinstance(v, dict) for v in value):
        return value
    if isinstance(value, np.ndarray) and value.size == 0:
        return []
    if (
        isinstance(value, np.ndarray)
        and value.dtype == object
        and all(isinstance(v, dict) for v in value.ravel())
    ):
        return list(value.ravel())
    raise SessionFormatError(f"{where}: expected a struct array, got {type(value).__name__}")


def _scalar(value: Any, where: str, kind: Callable[[Any], Any], expected: str) -> Any:
    array = np.asarray(value)
    if array.size == 1 and array.dtype.kind in "biuf":
        number = array.item()
        try:
            return kind(number)
        except ValueError:
            pass
    raise SessionFormatError(f"{where}: expected {expected}, got {excerpt(value)}")


def _label(value: Any, where: str) -> str:
    """A label: a char array, or an integer-valued number (its decimal text)."""
    if isinstance(value, str):
        return label_text(value, where)
    return str(_scalar(value, where, _integer, "a label (text or an integer)"))


def _integer(number: float) -> int:
    if not float(number).is_integer():
        raise ValueError
    return int(number)


def _default_name(label: str, prefix: str, digits: int) -> str:
    """The default file name of a recording, different for different labels.

    ``trial_0003.csv`` for an integer label written plainly (``3``); for any other (``03``,
    ``d060_1``) the label with every character but letters, digits, ``-``, ``_`` and ``.``
    percent-encoded (``bench A``: ``bench%20A.csv``), and so is a leading ``.`` (no hidden
    file) and the ``_`` of a label that reads like an integer's name (``trial_0003``).

    >>> [_default_name(x, "trial", 4) for x in ("7", "07", "trial_0007", "S03 T1", ".x")]
    ['trial_0007.csv', '07.csv', 'trial%5F0007.csv', 'S03%20T1.csv', '%2Ex.csv']
    """
    if label.isascii() and label.isdigit() and str(int(label)) == label:
        return f"{prefix}_{int(label):0{digits}d}.csv"
    name = urllib.parse.quote(label, safe="-_.")
    if name.startswith("."):
        name = "%2E" + name[1:]
    if re.fullmatch(rf"{prefix}_\d+", name):
        name = name.replace("_", "%5F", 1)
    return name + ".csv"


def _flag(number: float) -> bool:
    if number not in (0, 1):
        raise ValueError
    return bool(number)


def _delay(value: Any, where: str) -> float:
    if isinstance(value, np.ndarray) and value.size == 0:
        return math.nan
    return _scalar(value, where, float, "a number in ms (NaN or [] if unperturbed)")


def _text(value: Any, where: str) -> str:
    if not isinstance(value, str):
        raise SessionFormatError(f"{where}: expected text (a char array), got {excerpt(value)}")
    return value


def _split(
    element: dict[str, Any],
    where: str,
    required: tuple[str, ...],
    meta: tuple[str, ...],
    fs: float,
    nullable: tuple[str, ...] = (),
) -> tuple[Recording, dict[str, Any], dict[str, str]]:
    """Columns, known manifest fields and extra manifest fields of one struct element."""
    time = np.asarray(element.get("time_s", np.empty(0)))
    n = time.size
    columns, known, extra = {}, {}, {}
    for key, value in element.items():
        array = np.asarray(value)
        if key in meta or key == "file":
            known[key] = value
        elif (
            array.dtype.kind in "biuf"
            and array.ndim >= 1
            and array.size == n
            and (array.size == max(array.shape))
        ):
            columns[key] = array.ravel().astype(np.float64)
        elif key in required:
            raise SessionFormatError(
                f"{where}.{key}: expected a numeric vector as long as time_s ({n} samples), "
                f"got {type(value).__name__} of shape {array.shape}"
            )
        elif isinstance(value, str) or array.size == 1:
            extra[key] = str(value)
    for key in meta:
        if key not in known:
            raise SessionFormatError(f"{where}.{key}: field is missing")
    check_recording(where, columns, required, fs, nullable=nullable)
    return Recording("", columns), known, extra


def _name(known: dict[str, Any], where: str, default: str) -> str:
    return _text(known["file"], f"{where}.file") if "file" in known else default


def read_matlab(path: str | Path, *, progress: Progress | None = None) -> Session:
    """Read a session from a MATLAB ``.mat`` file (layout in the module docstring).

    ``progress``, if given, is called as ``progress(done, total)`` after each recording.

    Raises
    ------
    SessionFormatError
        Naming the file and the MATLAB field (``session.walking(3).delay_ms``).
    """
    path = Path(path)
    if problem := not_a_file(path):
        raise SessionFormatError(f"{path}: {problem}; expected a MATLAB .mat file")
    root = _load(path, "session")["session"]
    if not isinstance(root, dict):
        raise SessionFormatError(f"{path}: session: expected a scalar struct")
    meta = {k: v for k, v in root.items() if k not in _SECTIONS}
    info = info_from_mapping(meta, str(path), "session.")
    fs, nullable = info.sample_rate_hz, info.force_plate.nullable
    sections = {}
    for section in _SECTIONS:
        items = _elements(root.get(section, np.empty(0)), f"{path}: session.{section}")
        labels = [f"session.{section}({i + 1})" for i in range(len(items))]
        sections[section] = [
            (f"{path}: {label}", label, e) for label, e in zip(labels, items, strict=True)
        ]
    tick = ticker(progress, sum(map(len, sections.values())))

    def elements(section: str) -> Iterator[tuple[str, str, dict[str, Any]]]:
        """(location for messages, short label, struct) of each element, ticking progress."""
        for item in sections[section]:
            yield item
            tick()

    calibration = []
    for i, (where, _, element) in enumerate(elements("calibration")):
        rec, known, _ = _split(element, where, info.calibration_columns, (), fs, nullable)
        name = _name(known, where, f"calibration_{i + 1:03d}.csv")
        calibration.append(Recording(name, rec.columns))
    walking = []
    for where, label, element in elements("walking"):
        fields = ("trial", "perturbed", "direction", "delay_ms")
        rec, known, extra = _split(element, where, info.walking_columns, fields, fs, nullable)
        trial_id = _label(known["trial"], f"{where}.trial")
        name = _name(known, where, _default_name(trial_id, "trial", 4))
        trial = WalkingTrial(
            trial=trial_id,
            recording=Recording(name, rec.columns),
            perturbed=_scalar(known["perturbed"], f"{where}.perturbed", _flag, "0 or 1"),
            direction=_text(known["direction"], f"{where}.direction"),  # type: ignore[arg-type]
            delay_ms=_delay(known["delay_ms"], f"{where}.delay_ms"),
            extra=extra,
        )
        check_walking_row(where, trial.perturbed, trial.direction, trial.delay_ms)
        walking.append((trial, label))
    check_walking_trials(str(path), walking)
    bench = []
    for where, label, element in elements("bench"):
        rec, known, extra = _split(element, where, BENCH_COLUMNS, ("test", "distance_m"), fs)
        test_id = _label(known["test"], f"{where}.test")
        name = _name(known, where, _default_name(test_id, "test", 3))
        test = BenchTest(
            test=test_id,
            recording=Recording(name, rec.columns),
            distance_m=_scalar(known["distance_m"], f"{where}.distance_m", float, "a number"),
            extra=extra,
        )
        bench.append((test, label))
    check_bench_tests(str(path), bench)
    return Session(
        info=info,
        calibration=tuple(calibration),
        walking=tuple(t for t, _ in walking),
        bench=tuple(b for b, _ in bench),
        source=str(path),
    )
