"""JSON of results: JSON has no NaN."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["json_ready"]


def json_ready(node: Any) -> Any:
    """``node`` with its non-finite floats as ``None`` and NumPy floats as Python ones, through
    nested mappings, lists and tuples.

    >>> json_ready({"a": [1.0, float("nan")], "b": np.float64(2.5)})
    {'a': [1.0, None], 'b': 2.5}
    """
    if isinstance(node, dict):
        return {key: json_ready(value) for key, value in node.items()}
    if isinstance(node, list | tuple):
        return [json_ready(value) for value in node]
    if isinstance(node, float | np.floating) and not np.isfinite(node):
        return None
    if isinstance(node, np.floating):
        return float(node)
    return node
