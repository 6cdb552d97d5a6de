"""Opening HDF5 files (anklelab stores, MATLAB v7.3 files) without trusting them.

Before anything is read, :func:`check_h5_file` walks every link of the file once and refuses:

- soft links and external links (a dangling link, a link into another file), user-defined links;
- an object reached through more than one hard link (an alias, or a cycle back to an ancestor);
- datasets whose raw data lives outside the file (external storage, virtual datasets);
- datasets declaring more data than the file holds for them (an unallocated or truncated
  dataset would otherwise be read as gigabytes of fill values), or more than
  :data:`MAX_SESSION_BYTES` in total.

Messages name the file and the HDF5 path; they never show stored or linked data (link targets
are shown as a short escaped excerpt).
"""

from __future__ import annotations

from pathlib import Path

import h5py

from anklelab.data._text import excerpt, format_bytes
from anklelab.errors import SessionFormatError

__all__ = ["H5_ERRORS", "MAX_SESSION_BYTES", "check_h5_file", "damaged", "open_h5"]

MAX_SESSION_BYTES = 32 * 2**30
"""Most data (bytes, as read into memory) that one session file may declare."""
_DEFLATE_MAX_RATIO = 1100
"""zlib never compresses more than about 1032:1; a larger ratio means unallocated data."""


H5_ERRORS = (OSError, KeyError, RuntimeError, ValueError, TypeError, SystemError)
"""What h5py raises for a damaged file (HDF5's errors surface as any of these)."""


def damaged(path: object, exc: BaseException) -> BaseException:
    """The error for a file HDF5 cannot read (``exc`` as raised by h5py); or, when ``exc`` was
    caused by an interruption (Ctrl-C, or a signal the program turns into an exception that is
    not an :class:`Exception`), which h5py reports as a ``SystemError``, that interruption."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if not isinstance(cause, Exception):
            return cause
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return SessionFormatError(
        f"{path}: damaged HDF5 file, cannot be read ({type(exc).__name__}: "
        f"{excerpt(str(exc), 100, quote=False)})"
    )


def open_h5(path: Path, what: str) -> h5py.File:
    """Open ``path`` read-only; a file HDF5 cannot open is one clear error (``what`` names the
    expected kind, e.g. ``"an anklelab HDF5 session"``)."""
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        reason = str(exc).split("(", 1)[-1].rstrip(")") if "(" in str(exc) else str(exc)
        raise SessionFormatError(
            f"{path}: cannot open as {what}: the file is truncated or damaged "
            f"({excerpt(reason, 80, quote=False)})"
        ) from None


def _link_text(value: object) -> str:
    if isinstance(value, tuple):
        return " in ".join(_link_text(v) for v in reversed(value))
    text = value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
    return excerpt(text, 200)


def _dataset_problem(dataset: h5py.h5d.DatasetID) -> tuple[str, int]:
    """(problem or "", declared bytes) of one dataset."""
    plist = dataset.get_create_plist()
    if plist.get_layout() == h5py.h5d.VIRTUAL:
        return "is a virtual dataset (its data lives in other files); expected data stored here", 0
    if plist.get_external_count():
        return "stores its data in external files; expected data stored in this file", 0
    space = dataset.get_space()
    count = space.get_simple_extent_npoints() if space.get_simple_extent_type() else 0
    declared = count * dataset.get_type().get_size()
    stored = dataset.get_storage_size()
    filters = {plist.get_filter(i)[0] for i in range(plist.get_nfilters())}
    bound = stored * (_DEFLATE_MAX_RATIO if h5py.h5z.FILTER_DEFLATE in filters else 1)
    if (
        plist.get_layout() != h5py.h5d.COMPACT
        and declared > bound
        and filters
        <= {
            h5py.h5z.FILTER_DEFLATE,
            h5py.h5z.FILTER_SHUFFLE,
            h5py.h5z.FILTER_FLETCHER32,
        }
    ):
        return (
            f"declares {count} values ({format_bytes(declared)}) but the file holds only "
            f"{format_bytes(stored)} for them (truncated, or never written)",
            declared,
        )
    return "", declared


def check_h5_file(f: h5py.File, origin: str | Path) -> None:
    """Refuse anything in ``f`` that could read outside it or allocate beyond it.

    Parameters
    ----------
    f : h5py.File
        An open file.
    origin : str or Path
        The file name used in messages.

    Raises
    ------
    SessionFormatError
        Naming the file, the HDF5 path and the problem.
    """
    seen = {h5py.h5o.get_info(f.id).addr: "/"}
    total = 0
    problem: list[str] = []

    def visit(name: bytes, info: h5py.h5l.LinkInfo) -> int | None:
        try:
            check(name, info)
        except H5_ERRORS as exc:  # HDF5 cannot read this object: report it, stop visiting
            error = damaged(origin, exc)
            if not isinstance(error, SessionFormatError):
                raise error from None
            problem.append(str(error))
        return 1 if problem else None

    def check(name: bytes, info: h5py.h5l.LinkInfo) -> None:
        nonlocal total
        where = f"{origin}:/{excerpt(name.decode('utf-8', 'replace'), 200, quote=False)}"
        if info.type == h5py.h5l.TYPE_SOFT:
            target = _link_text(f.id.links.get_val(name))
            problem.append(
                f"{where}: is a soft link (to {target}); links are not followed, expected the "
                "data stored in place"
            )
        elif info.type == h5py.h5l.TYPE_EXTERNAL:
            target = _link_text(f.id.links.get_val(name))
            problem.append(
                f"{where}: is an external link (to {target}); expected data stored in this file, "
                "links to other files are not followed"
            )
        elif info.type != h5py.h5l.TYPE_HARD:
            problem.append(f"{where}: is a user-defined link; expected data stored in place")
        elif info.u in seen:
            problem.append(
                f"{where}: is the same object as {seen[info.u]} (a hard-link alias or cycle); "
                "expected every group and dataset stored once"
            )
        else:
            seen[info.u] = "/" + name.decode("utf-8", "replace")
            obj = h5py.h5o.open(f.id, name)
            if isinstance(obj, h5py.h5d.DatasetID):
                message, declared = _dataset_problem(obj)
                total += declared
                if message:
                    problem.append(f"{where}: {message}")
                elif total > MAX_SESSION_BYTES:
                    problem.append(
                        f"{where}: the datasets read so far declare {format_bytes(total)}, more "
                        f"than the limit of {format_bytes(MAX_SESSION_BYTES)} for one session"
                    )

    f.id.links.visit(visit, info=True)
    if problem:
        raise SessionFormatError(problem[0])
