"""A self-contained HTML report: sections of text, tables and figures embedded as PNG data URIs.

The page needs no network and no JavaScript, so it opens anywhere (e-mail, an offline lab PC).
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from anklelab._atomic import write_text_atomic

__all__ = [
    "PNG_SIGNATURE",
    "Figure",
    "Section",
    "Table",
    "figure_png",
    "render_html",
    "write_report",
]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
"""The eight bytes every PNG file starts with."""


@dataclass(frozen=True)
class Figure:
    """A figure as PNG bytes with a caption.

    Raises
    ------
    ValueError
        ``png`` does not start with the PNG signature (only images are embedded).
    """

    title: str
    png: bytes
    caption: str = ""

    def __post_init__(self) -> None:
        if not self.png.startswith(PNG_SIGNATURE):
            raise ValueError(f"figure {self.title!r}: not PNG data")


@dataclass(frozen=True)
class Table:
    """A table of already-formatted cells (numbers are formatted with ``{:.4g}``)."""

    title: str
    columns: Sequence[str]
    rows: Sequence[Sequence[Any]]


@dataclass(frozen=True)
class Section:
    """One titled part of the report."""

    title: str
    text: str = ""
    tables: Sequence[Table] = field(default_factory=tuple)
    figures: Sequence[Figure] = field(default_factory=tuple)


def figure_png(fig: Any, *, dpi: int = 110) -> bytes:
    """Render a matplotlib figure to PNG bytes and close it."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return buffer.getvalue()


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape(str(value))


def _table(table: Table) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in table.columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>" for row in table.rows
    )
    return (
        f"<h3>{html.escape(table.title)}</h3>"
        f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
    )


def _figure(figure: Figure) -> str:
    data = base64.b64encode(figure.png).decode("ascii")
    caption = html.escape(figure.caption or figure.title)
    return (
        f'<figure><img alt="{html.escape(figure.title)}" src="data:image/png;base64,{data}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


def _paragraphs(text: str) -> str:
    return "".join(f"<p>{html.escape(p.strip())}</p>" for p in text.split("\n\n") if p.strip())


_STYLE = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h1{border-bottom:2px solid #444}h2{margin-top:2em;border-bottom:1px solid #bbb}
table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #ccc;padding:3px 8px}
th{background:#f0f0f0}td{text-align:right}td:first-child{text-align:left}
figure{display:inline-block;margin:0.5em;vertical-align:top}img{max-width:100%;height:auto}
figcaption{font-size:0.9em;color:#555}.meta{font-size:0.85em;color:#555}
"""


def render_html(title: str, sections: Iterable[Section], metadata: Mapping[str, Any]) -> str:
    """The report as one HTML string.

    Parameters
    ----------
    title : str
        Page title.
    sections : iterable of Section
        Report body, in order.
    metadata : mapping
        Shown at the top (anklelab version, inputs and their hashes, settings).

    Examples
    --------
    >>> page = render_html("R", [Section("S", "hello", [Table("T", ["a"], [[1.5]])])], {"v": 1})
    >>> "<td>1.5</td>" in page and "<h2>S</h2>" in page
    True
    """
    meta = "".join(
        f"<li><b>{html.escape(str(k))}</b>: {html.escape(str(v))}</li>" for k, v in metadata.items()
    )
    body = "".join(
        f"<section><h2>{html.escape(s.title)}</h2>{_paragraphs(s.text)}"
        + "".join(_table(t) for t in s.tables)
        + "".join(_figure(f) for f in s.figures)
        + "</section>"
        for s in sections
    )
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
        f'<body><h1>{html.escape(title)}</h1><ul class="meta">{meta}</ul>{body}</body></html>'
    )


def write_report(
    path: str | Path,
    title: str,
    sections: Iterable[Section],
    metadata: Mapping[str, Any],
    *,
    overwrite: bool = True,
) -> Path:
    """Write the report to ``path`` atomically and return the path.

    With ``overwrite`` false an existing ``path`` raises ``FileExistsError``.
    """
    return write_text_atomic(path, render_html(title, sections, metadata), overwrite=overwrite)
