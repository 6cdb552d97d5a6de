"""Read a C3D file with ezc3d into plain values: run in a worker process (see ``_isolated``).

A standalone script: it imports only NumPy and ezc3d (not anklelab), so a worker starts in a
fifth of a second, and it reports bad input by raising ``ValueError``. Before ezc3d sees a file,
:func:`check_structure` rejects those whose header or block layout it would trip over.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np

BLOCK = 512


def check_structure(path: Path, raw: bytes) -> None:
    """Reject files whose header or block layout ezc3d would trip over (crash or endless read):
    a wrong signature, a parameter or data section outside the file, truncated data."""
    if len(raw) < BLOCK:
        raise ValueError(f"{path}: {len(raw)} bytes; a C3D file starts with a 512-byte header")
    if raw[1] != 0x50:
        raise ValueError(f"{path}: not a C3D file (header byte 2 is {raw[1]}, not 80)")
    start = (raw[0] - 1) * BLOCK
    if raw[0] < 1 or start + 4 > len(raw):
        raise ValueError(
            f"{path}: the header puts the parameter section at block {raw[0]}, outside the file"
        )
    blocks, processor = raw[start + 2], raw[start + 3]
    if processor not in (84, 85, 86):
        raise ValueError(
            f"{path}: unknown processor type {processor} in the parameter section (expected 84, "
            "85 or 86); the file is corrupt"
        )
    if blocks < 1 or start + blocks * BLOCK > len(raw):
        raise ValueError(
            f"{path}: truncated: the parameter section needs {blocks} blocks of 512 bytes from "
            f"byte {start}, the file has {len(raw)} bytes"
        )
    order = ">" if processor == 86 else "<"
    points, analogs, first, last = struct.unpack(order + "4H", raw[2:10])
    data_block = struct.unpack(order + "H", raw[16:18])[0]
    # the scale factor's sign says float (negative) or integer data: its sign bit is the top bit
    # of the last byte (Intel), of the second (DEC) or of the first (MIPS)
    sign_byte = {84: raw[15], 85: raw[13], 86: raw[12]}[processor]
    size = 4 if sign_byte & 0x80 else 2
    frames = max(0, last - first + 1)
    needed = (data_block - 1) * BLOCK + frames * (4 * points + analogs) * size
    if data_block < 1 or needed > len(raw):
        raise ValueError(
            f"{path}: truncated: the header announces {frames} frames of {points} points and "
            f"{analogs} analog values ({needed} bytes), the file has {len(raw)} bytes"
        )


def _plain(value: Any) -> Any:
    if isinstance(value, list):
        return [str(v).strip() for v in value]
    return np.asarray(value)


def load(path: Path) -> dict[str, Any]:
    """The file's rates, first analog sample, analog data and parameters as plain values."""
    import ezc3d

    check_structure(path, Path(path).read_bytes())
    try:
        c3d = ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d raises OSError, RuntimeError, ValueError...
        raise ValueError(f"{path}: cannot read as C3D ({exc})") from None
    header = c3d["header"]["analogs"]
    parameters = {
        group: {k: _plain(v["value"]) for k, v in values.items() if k != "__METADATA__"}
        for group, values in c3d["parameters"].items()
    }
    return {
        "analog_rate_hz": float(header["frame_rate"]),
        "point_rate_hz": float(c3d["header"]["points"]["frame_rate"]),
        "first_analog": int(header["first_frame"]),
        "analogs": np.ascontiguousarray(c3d["data"]["analogs"][0], dtype=np.float64),
        "parameters": parameters,
    }
