"""Content hashes: SHA-256 over stored *values*, so equal content gives equal hashes however a
file lays it out.

The encoding is unambiguous: every value is written as a one-byte type tag followed by
length-prefixed bytes, mappings in sorted key order. Arrays contribute their dtype, shape and
little-endian bytes (read by :mod:`hashlib` straight from the array's memory, without a copy).

>>> sha256_tree({"a": 1.0, "b": ("x", "y")})[:12]
'76fd81343af2'
>>> sha256_tree({"b": ("x", "y"), "a": 1.0}) == sha256_tree({"a": 1.0, "b": ("x", "y")})
True
"""

from __future__ import annotations

import hashlib
import struct
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["sha256_tree", "update", "update_array_header"]


def _length(n: int) -> bytes:
    return struct.pack("<Q", n)


def _text(digest: Any, text: str) -> None:
    data = text.encode("utf-8")
    digest.update(_length(len(data)))
    digest.update(data)


def update(digest: Any, value: Any) -> None:
    """Feed one value to ``digest`` (a :mod:`hashlib` object).

    Values are those of canonical trees (:mod:`anklelab.data._tree`): mappings with string
    keys, ``None``, ``bool``, ``int``, ``float``, ``str``, tuples of ``str`` and NumPy arrays.
    """
    if isinstance(value, Mapping):
        digest.update(b"{" + _length(len(value)))
        for key in sorted(value):
            _text(digest, key)
            update(digest, value[key])
    elif value is None:
        digest.update(b"N")
    elif isinstance(value, bool | np.bool_):
        digest.update(b"T" if value else b"F")
    elif isinstance(value, int | np.integer):
        digest.update(b"i")
        _text(digest, str(int(value)))
    elif isinstance(value, float | np.floating):
        digest.update(b"f" + struct.pack("<d", float(value)))
    elif isinstance(value, str):
        digest.update(b"s")
        _text(digest, value)
    elif isinstance(value, tuple):
        digest.update(b"t" + _length(len(value)))
        for item in value:
            _text(digest, item)
    elif isinstance(value, np.ndarray):
        array = np.ascontiguousarray(value, dtype=value.dtype.newbyteorder("<"))
        update_array_header(digest, array.dtype, array.shape)
        digest.update(array.reshape(-1).data.cast("B"))
    else:
        raise TypeError(f"cannot hash a value of type {type(value).__name__}")


def update_array_header(digest: Any, dtype: np.dtype, shape: tuple[int, ...]) -> None:
    """Feed the header of an array value; its little-endian bytes in C order must follow (in
    pieces if need be: a 2-D array may be fed row by row)."""
    digest.update(b"a")
    _text(digest, np.dtype(dtype).newbyteorder("<").str)
    digest.update(_length(len(shape)) + b"".join(_length(n) for n in shape))


def sha256_tree(tree: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of a tree of values (see :func:`update`)."""
    digest = hashlib.sha256()
    update(digest, tree)
    return digest.hexdigest()
