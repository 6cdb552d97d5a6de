"""A minimal TOML writer for ``session.toml`` (the standard library only reads TOML).

Writes canonical trees (see :mod:`anklelab.data._tree`): scalars, arrays and nested tables.
Floats use the shortest repr that round-trips exactly.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["dumps"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _scalar(value: Any, path: str) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, np.ndarray):
        return _array(value.tolist(), path)
    if isinstance(value, tuple):
        return _array(list(value), path)
    raise ValueError(f"{path}: {type(value).__name__} values cannot be written to TOML")


def _array(items: list[Any], path: str) -> str:
    return (
        "["
        + ", ".join(_array(v, path) if isinstance(v, list) else _scalar(v, path) for v in items)
        + "]"
    )


def _table(tree: Mapping[str, Any], prefix: tuple[str, ...], lines: list[str]) -> None:
    tables = []
    for key, value in tree.items():
        if isinstance(value, Mapping):
            tables.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_scalar(value, '.'.join((*prefix, key)))}")
    for key, value in tables:
        path = (*prefix, key)
        lines += ["", "[" + ".".join(_key(k) for k in path) + "]"]
        _table(value, path, lines)


def dumps(tree: Mapping[str, Any]) -> str:
    """TOML text for a canonical tree; ``tomllib.loads`` reads it back to an equal tree.

    Examples
    --------
    >>> print(dumps({"a": 1.5, "t": {"b": "x", "c": np.array([1, 2])}}), end="")
    a = 1.5
    <BLANKLINE>
    [t]
    b = "x"
    c = [1, 2]
    """
    lines: list[str] = []
    _table(tree, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"
