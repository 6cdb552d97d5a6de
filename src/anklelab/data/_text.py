"""Text checks and excerpts shared by the readers, the writers and their messages.

No message ever shows more of a file than a short escaped excerpt (:func:`excerpt`); text a
store must hold is :func:`storable` in all of them.
"""

from __future__ import annotations

__all__ = ["excerpt", "format_bytes", "plain_text", "storable"]


def excerpt(value: object, limit: int = 40, *, quote: bool = True) -> str:
    r"""A short, escaped excerpt of ``value`` for messages, so that no message ever shows more
    than ``limit`` characters of what a file holds.

    Text is shown as its ``repr`` (control characters escaped); anything else as its ``repr``
    too, cut to ``limit`` characters with the full length appended when longer.

    Examples
    --------
    >>> excerpt("abc")
    "'abc'"
    >>> excerpt("x" * 100, 8)
    "'xxxxxxxx…' (100 characters)"
    >>> excerpt("a\x00b", quote=False)
    'a\\x00b'
    """
    if isinstance(value, str):
        shown = repr(value[:limit])
        if len(value) > limit:
            shown = f"{shown[:-1]}…{shown[-1]} ({len(value)} characters)"
        return shown if quote else repr(value[:limit])[1:-1] + ("…" if len(value) > limit else "")
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "…"


def format_bytes(n: int) -> str:
    """``n`` bytes in binary units (``"1.5 GiB"``).

    >>> format_bytes(1536), format_bytes(3 * 2**30)
    ('1.5 KiB', '3 GiB')
    """
    value = float(n)
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            return f"{value:.3g} {unit}"
        value /= 1024
    raise AssertionError  # unreachable


def storable(text: str) -> bool:
    """Whether HDF5, JSON and TOML files can all hold ``text`` (UTF-8, no NUL)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate
        return False
    return "\x00" not in text


def plain_text(text: object) -> bool:
    """Non-empty text every store can hold, without surrounding spaces or line breaks."""
    return (
        isinstance(text, str)
        and bool(text)
        and text == text.strip()
        and "\n" not in text
        and storable(text)
    )
