"""Nested metadata trees (``truth``, ``provenance``, extra ``session.toml`` tables).

A tree is a mapping of ``str`` to values of a small closed set, so that it can be stored the
same way in JSON, HDF5 and TOML and compared exactly:

- mappings (nested trees),
- ``None``, ``bool``, ``int``, ``float``, ``str`` (NumPy scalars become Python scalars),
- NumPy arrays of bool, integers or floats (stored as ``bool``, ``int64`` or ``float64``);
  lists and tuples of numbers become such arrays, 0-d arrays become scalars,
- sequences of strings (kept as a tuple of ``str``).

Keys are non-empty strings; no key or text may contain a NUL character (HDF5 cannot store
it) or a lone surrogate (it has no UTF-8 encoding).

:func:`canonical` converts a tree to this form (dates and times become ISO strings) and raises
``ValueError`` naming the key of anything else. JSON files keep arrays as (nested) lists and
non-finite floats as ``NaN``/``Infinity`` (Python's JSON dialect); HDF5 keeps mappings as
groups, arrays as datasets and everything else as attributes. Both are written with sorted keys
so that equal trees give identical bytes.
"""

from __future__ import annotations

import datetime as dt
import json
from collections.abc import Mapping, Sequence
from typing import Any

import h5py
import numpy as np

from anklelab.data._text import storable

__all__ = [
    "canonical",
    "create_group",
    "from_json",
    "h5_scalar",
    "insert_array",
    "link_name",
    "read_h5_tree",
    "split_arrays",
    "to_json",
    "tree_differences",
    "unlink_name",
    "write_h5_tree",
]

_DTYPES = {"b": np.bool_, "i": np.int64, "u": np.int64, "f": np.float64}


def canonical(tree: Mapping[str, Any], path: str = "") -> dict[str, Any]:
    """Return ``tree`` in canonical form (see the module docstring).

    Examples
    --------
    >>> canonical({"a": (1.0, 2.0), "b": {"c": np.int32(3)}, "d": ["x", "y"]})
    {'a': array([1., 2.]), 'b': {'c': 3}, 'd': ('x', 'y')}
    """
    if not isinstance(tree, Mapping):
        raise ValueError(f"{path or 'tree'}: expected a mapping, got {type(tree).__name__}")
    out = {}
    for key, value in tree.items():
        if not isinstance(key, str) or not key or not storable(key):
            raise ValueError(f"{path}{key!r}: keys must be non-empty UTF-8 strings without NUL")
        out[key] = _value(value, f"{path}{key}")
    return out


def _value(value: Any, path: str) -> Any:
    if isinstance(value, Mapping):
        return canonical(value, path + ".")
    if isinstance(value, str) and not storable(value):
        raise ValueError(f"{path}: text must be UTF-8 without NUL characters to be stored")
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value)
    if isinstance(value, dt.date | dt.time):
        return value.isoformat()
    if isinstance(value, np.ndarray | Sequence):
        if not isinstance(value, np.ndarray) and value and all(isinstance(v, str) for v in value):
            return tuple(_value(v, path) for v in value)
        try:
            array = np.asarray(value)
        except ValueError:
            raise ValueError(
                f"{path}: ragged nested sequence; expected a rectangular array"
            ) from None
        if array.dtype.kind in "US" and array.ndim == 1:
            return tuple(str(v) for v in array)
        if array.size == 0 and array.dtype.kind not in _DTYPES:
            array = array.astype(np.float64)
        if array.dtype.kind not in _DTYPES:
            raise ValueError(
                f"{path}: unsupported sequence of {array.dtype}; expected numbers or strings"
            )
        array = array.astype(_DTYPES[array.dtype.kind], copy=True)
        return array.item() if array.ndim == 0 else array
    raise ValueError(
        f"{path}: unsupported value of type {type(value).__name__}; expected a mapping, None, "
        "bool, int, float, str, a numeric array or a sequence of strings"
    )


def tree_differences(a: Any, b: Any, path: str = "") -> list[str]:
    """Describe every difference between two canonical trees (empty when equal).

    Arrays must match in dtype kind, shape and values (NaN equal to NaN).
    """
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        out = []
        for key in sorted(set(a) | set(b)):
            where = f"{path}.{key}" if path else key
            if key not in a or key not in b:
                out.append(f"{where}: only in {'second' if key in b else 'first'}")
            else:
                out += tree_differences(a[key], b[key], where)
        return out
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        same = (
            isinstance(a, np.ndarray)
            and isinstance(b, np.ndarray)
            and a.dtype.kind == b.dtype.kind
            and a.shape == b.shape
            and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
        )
        return [] if same else [f"{path}: arrays differ"]
    if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        return []
    if type(a) is not type(b) or a != b:
        return [f"{path}: {a!r} != {b!r}"]
    return []


# --- JSON ---------------------------------------------------------------------------------------


def _jsonable(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return list(value)
    return value


def to_json(tree: Mapping[str, Any]) -> str:
    """Serialise a tree as JSON text (sorted keys, arrays as lists, shortest float repr)."""
    return json.dumps(_jsonable(canonical(tree)), sort_keys=True, separators=(",", ":")) + "\n"


def _from_json_value(value: Any, path: str) -> Any:
    if isinstance(value, dict):
        return {k: _from_json_value(v, f"{path}.{k}") for k, v in value.items()}
    if isinstance(value, list):
        return _value(value, path)
    return value


def from_json(text: str) -> dict[str, Any]:
    """Parse JSON text written by :func:`to_json` back into a canonical tree.

    Raises ``ValueError`` (``json.JSONDecodeError`` for bad syntax) with the offending key.
    """
    data = json.loads(text)
    if not isinstance(data, dict):
        raise ValueError("expected a JSON object at the top level")
    return {k: _from_json_value(v, k) for k, v in data.items()}


def split_arrays(
    tree: Mapping[str, Any], min_values: int
) -> tuple[dict[str, Any], dict[tuple[str, ...], np.ndarray]]:
    """``tree`` (canonical) without its arrays of at least ``min_values`` values, and those
    arrays by their key path, in sorted key order.

    JSON text is a slow container for large arrays (a float takes ~18 characters, and Python
    parses 30-50 MB/s); the session directory keeps such arrays in ``.npy`` files beside it.

    Examples
    --------
    >>> small, large = split_arrays({"a": np.zeros(3), "b": {"c": np.ones(5)}}, 4)
    >>> small, {key: array.size for key, array in large.items()}
    ({'a': array([0., 0., 0.]), 'b': {}}, {('b', 'c'): 5})
    """
    arrays: dict[tuple[str, ...], np.ndarray] = {}

    def kept(node: Mapping[str, Any], path: tuple[str, ...]) -> dict[str, Any]:
        out = {}
        for key in sorted(node):
            value = node[key]
            if isinstance(value, Mapping):
                out[key] = kept(value, (*path, key))
            elif isinstance(value, np.ndarray) and value.size >= min_values:
                arrays[(*path, key)] = value
            else:
                out[key] = value
        return out

    return kept(canonical(tree), ()), arrays


def insert_array(tree: dict[str, Any], path: Sequence[str], value: Any) -> None:
    """Put ``value`` (canonicalised) at the key ``path`` of ``tree``, creating mappings on the
    way; ``ValueError`` naming the path if a value is there already or a key on the way holds
    something other than a mapping."""
    node = tree
    for depth, key in enumerate(path[:-1]):
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            raise ValueError(f"{'.'.join(path[: depth + 1])}: holds a value, not a mapping")
    if path[-1] in node:
        raise ValueError(f"{'.'.join(path)}: given twice")
    node[path[-1]] = _value(value, ".".join(path))


# --- HDF5 ---------------------------------------------------------------------------------------


def link_name(name: str) -> str:
    """An HDF5 link name for ``name`` (``%`` and ``/`` percent-escaped; ``.`` as ``%2E``)."""
    escaped = name.replace("%", "%25").replace("/", "%2F")
    return "%2E" if escaped == "." else escaped


def unlink_name(link: str) -> str:
    """Inverse of :func:`link_name`."""
    return link.replace("%2F", "/").replace("%2E", ".").replace("%25", "%")


def create_group(parent: h5py.Group, name: str) -> h5py.Group:
    """A child group that remembers the creation order of its members."""
    return parent.create_group(link_name(name), track_order=True)


def write_h5_tree(group: h5py.Group, tree: Mapping[str, Any]) -> dict[str, Any]:
    """Store a tree in ``group``: sub-trees as groups, arrays as datasets, the rest as attributes.

    Keys are written in sorted order and no timestamps are stored, so equal trees give
    identical bytes. Returns the canonical form of ``tree`` that was written (made once: a
    session's truth holds hundreds of MiB of arrays).
    """
    written = canonical(tree)
    _write_canonical(group, written)
    return written


def _write_canonical(group: h5py.Group, tree: Mapping[str, Any]) -> None:
    for key, value in sorted(tree.items()):
        if isinstance(value, dict):
            _write_canonical(create_group(group, key), value)
        elif isinstance(value, np.ndarray):
            group.create_dataset(link_name(key), data=value, track_times=False)
        elif value is None:
            group.attrs[key] = h5py.Empty("f8")
        elif isinstance(value, tuple):
            group.attrs.create(key, data=list(value), dtype=h5py.string_dtype())
        elif isinstance(value, bool):
            group.attrs[key] = np.bool_(value)
        elif isinstance(value, int):
            group.attrs[key] = np.int64(value)
        else:
            group.attrs[key] = value


def h5_scalar(value: Any) -> Any:
    """An HDF5 attribute value as a canonical tree value."""
    if isinstance(value, h5py.Empty):
        return None
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OSU":
            return tuple(v.decode("utf-8") if isinstance(v, bytes) else str(v) for v in value)
        return _value(value, "")
    return _value(value, "")


def read_h5_tree(group: h5py.Group) -> dict[str, Any]:
    """Read a tree written by :func:`write_h5_tree`."""
    tree = {key: h5_scalar(value) for key, value in group.attrs.items()}
    for link, item in group.items():
        key = unlink_name(link)
        if isinstance(item, h5py.Group):
            tree[key] = read_h5_tree(item)
        else:
            tree[key] = _value(item[()], key)
    return tree
