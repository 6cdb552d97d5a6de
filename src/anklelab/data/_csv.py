"""Numeric CSV recordings: pyarrow's parser for speed, the csv module to explain what is wrong.

A recording file is a header line naming the columns, then one row of numbers per sample.
:func:`parse_numeric` hands the bytes to pyarrow's C++ CSV reader (which releases the GIL, so
files parse in parallel threads). Only when pyarrow refuses the file is it read again row by row
with the :mod:`csv` module, which accepts exactly the same numbers (:data:`NUMBER`) and names
the first bad row, column and CSV line; files pyarrow cannot read for other reasons (a line
with only spaces) are parsed that way in full. Messages never quote more of a file than a short
escaped excerpt of one cell.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab.data._checks import check_columns
from anklelab.data._text import excerpt
from anklelab.errors import SessionFormatError

__all__ = ["NUMBER", "decode", "header", "parse_numeric"]

NUMBER = re.compile(
    r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)", re.ASCII | re.IGNORECASE
)
"""A number as a cell may hold it (surrounding spaces and quotes aside): what pyarrow and NumPy
accept, and not Python's extensions (``1_000``, non-ASCII digits)."""
_SPACE = " \t\r"


def decode(path: object, data: bytes, expected: str = "a CSV file") -> str:
    """``data`` as text (UTF-8, an optional byte-order mark dropped)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SessionFormatError(
            f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); expected {expected}"
        ) from None


def header(path: object, data: bytes, required: tuple[str, ...]) -> list[str]:
    """The column names on line 1, checked against ``required``."""
    first = decode(path, data.split(b"\n", 1)[0])
    if not first.strip():
        raise SessionFormatError(
            f"{path}: empty file or blank line 1; expected a header line naming the columns "
            f"{', '.join(required)}"
        )
    try:
        names = [name.strip() for name in next(csv.reader([first]))]
    except csv.Error as exc:
        raise SessionFormatError(f"{path}: header (line 1): {exc}; expected column names") from None
    if len(names) == 1 and any(sep in first for sep in ";\t"):
        raise SessionFormatError(
            f"{path}: header (line 1) {excerpt(first.strip())} is not comma-separated; expected "
            f"the columns {', '.join(required)} separated by commas"
        )
    if "" in names:
        raise SessionFormatError(
            f"{path}: column {names.index('') + 1} of the header (line 1) has no name; expected "
            "a name for every column"
        )
    check_columns(str(path), names, required, "header (line 1)")
    return names


def _data_lines(data: bytes) -> list[int]:
    """CSV line numbers (1-based) of the data rows: the non-blank lines after the header."""
    return [k + 1 for k, line in enumerate(data.split(b"\n")) if k > 0 and line.strip()]


def _values(column: Any) -> NDArray[np.float64]:
    """A pyarrow float64 array as NumPy, its nulls NaN: read from Arrow's buffers, because
    ``to_numpy`` imports pandas (0.2 s) to do it."""
    validity, values = column.buffers()
    n, offset = len(column), column.offset
    out = np.frombuffer(values, dtype=np.float64, count=n, offset=8 * offset)
    if not column.null_count:
        return out
    bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
    return np.where(bits[offset : offset + n].astype(bool), out, np.nan)


def _fast(
    data: bytes, names: list[str], nullable: tuple[str, ...], lines: int
) -> NDArray[np.float64] | None:
    """pyarrow's parse, as (columns, rows); ``None`` if pyarrow refuses the file or finds an
    empty cell outside the ``nullable`` columns.

    The text is parsed block by block straight into an array sized by its ``lines``, so the
    peak memory is the text (twice: Arrow reads its own copy), the array and one block. Empty
    cells read as NaN.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv

    out = np.empty((len(names), lines))
    rows = 0
    allow = [name in nullable for name in names]
    # The reader reads ahead on Arrow's I/O threads, which may drop their last reference to
    # the text after this returns: a buffer that Arrow owns (a copy) is freed without the GIL,
    # where one wrapping the Python bytes would take the GIL from that thread, and abort the
    # process if that happens while the interpreter shuts down (terminate called without an
    # active exception, seen about once in 150 runs that stop on an error).
    text = pa.allocate_buffer(len(data))
    pa.FixedSizeBufferWriter(text).write(data)
    try:
        with pacsv.open_csv(
            pa.BufferReader(text),
            read_options=pacsv.ReadOptions(skip_rows=1, column_names=names, use_threads=False),
            parse_options=pacsv.ParseOptions(newlines_in_values=False),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(names, pa.float64()),
                null_values=[""] if nullable else [],
                strings_can_be_null=False,
                quoted_strings_can_be_null=bool(nullable),
            ),
        ) as reader:
            for batch in reader:
                n = batch.num_rows
                for row, column, ok in zip(out, batch.columns, allow, strict=True):
                    if column.null_count and not ok:
                        return None  # the row-by-row parse names the empty cell
                    row[rows : rows + n] = _values(column)
                rows += n
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        return None
    return out[:, :rows]


def _slow(
    path: object, data: bytes, names: list[str], nullable: tuple[str, ...]
) -> tuple[NDArray[np.float64], list[int]]:
    """Row-by-row parse with :mod:`csv`: the values as (columns, rows) and each row's line, or
    the first problem as a :class:`SessionFormatError`. Empty cells of ``nullable`` columns
    read as NaN."""
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        raise SessionFormatError(
            f"{path}: line {line} holds a NUL byte (binary data, or a file padded with zeros); "
            "expected comma-separated numbers"
        )
    reader = csv.reader(io.StringIO(decode(path, data)))
    rows, lines = [], []
    try:
        next(reader)
        for fields in reader:
            if not any(field.strip(_SPACE) for field in fields):
                continue
            line = reader.line_num
            if len(fields) != len(names):
                raise SessionFormatError(
                    f"{path}: line {line} has {len(fields)} fields; expected {len(names)} like the "
                    "header (line 1)"
                )
            values = []
            for name, field in zip(names, fields, strict=True):
                cell = field.strip(_SPACE)
                if not cell and name in nullable:
                    values.append(math.nan)
                    continue
                if not NUMBER.fullmatch(cell):
                    got = "an empty cell" if not cell else excerpt(field)
                    empty = " or an empty cell" if name in nullable else ""
                    raise SessionFormatError(
                        f"{path}: column {name!r}, line {line}: {got}; expected a number{empty}"
                    )
                values.append(float(cell))
            rows.append(values)
            lines.append(line)
    except csv.Error as exc:
        raise SessionFormatError(
            f"{path}: line {max(reader.line_num, 1)}: {exc}; expected comma-separated numbers"
        ) from None
    return np.array(rows, dtype=np.float64).reshape(-1, len(names)).T.copy(), lines


def parse_numeric(
    path: object, data: bytes, names: list[str], nullable: tuple[str, ...] = ()
) -> tuple[NDArray[np.float64], Callable[[int], str]]:
    """The numbers below the header of ``data``, one row per column, and a function naming the
    CSV line of a data row (0-based) for messages. Empty cells of the ``nullable`` columns
    (e.g. a ``grf_cop`` plate's COP) read as NaN; anywhere else they are an error.

    Raises
    ------
    SessionFormatError
        Naming the file, the CSV line and the column of the first cell that is not a number, or
        a row whose field count differs from the header's.
    """
    n_lines = data.count(b"\n") + (not data.endswith(b"\n"))
    values = _fast(data, names, nullable, n_lines)
    # pyarrow skips blank lines: a row for every line after the header means there were none
    # (one count of the text, where two searches for blank lines took 0.37 ms a file)
    if values is not None and values.shape[1] == n_lines - 1:

        def line(i: int) -> str:  # row i is on line i + 2 (the text is let go)
            return f"line {i + 2}"

    elif values is not None:
        lines: list[int] | None = None

        def line(i: int) -> str:
            nonlocal lines
            lines = lines or _data_lines(data)
            return f"line {lines[i]}"

    else:
        values, found = _slow(path, data, names, nullable)

        def line(i: int) -> str:
            return f"line {found[i]}"

    if not values.shape[1]:
        raise SessionFormatError(f"{path}: no data rows after the header; expected samples")
    return values, line
