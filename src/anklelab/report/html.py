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
    """A table of already-formatted cells (numbers are formatted with ``{:.4g}``).

    Cells are right-aligned (numbers), the first column and the ``text_columns`` (indices of
    columns holding sentences) left-aligned.
    """

    title: str
    columns: Sequence[str]
    rows: Sequence[Sequence[Any]]
    text_columns: Sequence[int] = ()


@dataclass(frozen=True)
class Section:
    """One titled part of the report.

    Attributes
    ----------
    title, text : str
        Heading and paragraphs (separated by blank lines).
    tables, figures : sequence
        Shown in this order after the text (figures first with ``figures_first``).
    notes : sequence of str
        Points a reader must see before the numbers (warnings), shown as a list after the text.
    details : sequence of Table
        Reference tables folded away under their titles (an HTML ``<details>``: no script).
    figures_first : bool
        Figures before tables (a summary whose figure is the point).
    """

    title: str
    text: str = ""
    tables: Sequence[Table] = field(default_factory=tuple)
    figures: Sequence[Figure] = field(default_factory=tuple)
    notes: Sequence[str] = field(default_factory=tuple)
    details: Sequence[Table] = field(default_factory=tuple)
    figures_first: bool = False


def figure_png(fig: Any, *, dpi: int = 100) -> bytes:
    """Render a matplotlib figure to PNG bytes (at ``dpi``, which the figure keeps).

    The figure is laid out already (by its layout engine, or by fixed margins,
    :mod:`anklelab.report._panels`): it is saved at its own size, so a figure 11 inches wide
    fills the report's 1100-pixel column at 100 dpi without rescaling.
    It is drawn once, by its Agg canvas: ``savefig`` would draw it twice (once to run the
    layout), for the same bytes, 10-25 % slower. The PNG is compressed at zlib's fastest level:
    on the five walking figures of a paper-size session that took their rendering from 0.56 to
    0.46 s for files 2 % larger (567 against 557 kB).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig.set_dpi(dpi)
    buffer = io.BytesIO()
    FigureCanvasAgg(fig).print_png(buffer, pil_kwargs={"compress_level": 1})
    return buffer.getvalue()


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape(str(value))


def _table(table: Table, *, heading: bool = True) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in table.columns)
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="text">{_cell(v)}</td>'
            if k in table.text_columns
            else f"<td>{_cell(v)}</td>"
            for k, v in enumerate(row)
        )
        + "</tr>"
        for row in table.rows
    )
    title = f"<h3>{html.escape(table.title)}</h3>" if heading else ""
    return f"{title}<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _details(table: Table) -> str:
    return (
        f"<details><summary>{html.escape(table.title)}</summary>"
        f"{_table(table, heading=False)}</details>"
    )


def _section(s: Section) -> str:
    tables = "".join(_table(t) for t in s.tables)
    figures = "".join(_figure(f) for f in s.figures)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in s.notes)
    return (
        f"<section><h2>{html.escape(s.title)}</h2>{_paragraphs(s.text)}"
        + (f'<ul class="notes">{notes}</ul>' if notes else "")
        + (figures + tables if s.figures_first else tables + figures)
        + "".join(_details(t) for t in s.details)
        + "</section>"
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
body{font-family:system-ui,sans-serif;max-width:1100px;margin:1.5em auto;padding:0 1em;color:#222}
h1{border-bottom:2px solid #444;margin-bottom:0.4em}
h2{margin-top:1.6em;border-bottom:1px solid #bbb}
table{border-collapse:collapse;margin:0.5em 0 1.2em}td,th{border:1px solid #ccc;padding:2px 8px}
th{background:#f0f0f0}td{text-align:right}td:first-child,td.text{text-align:left}
figure{display:inline-block;margin:0.5em 0;vertical-align:top;max-width:100%}
img{max-width:100%;height:auto}figcaption{font-size:0.9em;color:#555;max-width:1100px}
.meta table{font-size:0.8em;color:#444;margin:0}.meta td{text-align:left;overflow-wrap:anywhere}
details{margin:0.3em 0 1em}summary{cursor:pointer;color:#333}
ul.notes{background:#fff6e0;border-left:4px solid #e0a000;padding:0.4em 1em 0.4em 2em}
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
        Shown under the title as a two-column table (what was analysed, when, by which
        anklelab version).

    Examples
    --------
    >>> page = render_html("R", [Section("S", "hello", [Table("T", ["a"], [[1.5]])])], {"v": 1})
    >>> "<td>1.5</td>" in page and "<h2>S</h2>" in page and "<th>v</th>" in page
    True
    """
    meta = _table(Table("", list(map(str, metadata)), [list(metadata.values())]), heading=False)
    body = "".join(_section(s) for s in sections)
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
        f'<body><h1>{html.escape(title)}</h1><div class="meta">{meta}</div>{body}</body></html>'
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
