"""Legibility checks of a drawn matplotlib figure, as a reader would judge it.

:func:`problems` lists, in words, what would make a figure hard to read: texts that overlap
(titles, axis and tick labels, legends), a text cut by the figure's edge, a legend that covers
a panel, a panel whose axis has no scale (no tick labels of its own or of a panel sharing it),
an axis label without a unit, a code name (``cop_m``, ``snake_case``) in any text. The report
tests run it on every walking figure; the browser tests check how the page lays the figures out.
"""

from __future__ import annotations

import re
from itertools import combinations
from typing import Any

CODE_NAME = re.compile(r"\b[a-z]+_[a-z0-9_]+\b")
UNIT = re.compile(r"\([^()]+\)\s*$")


def _texts(fig: Any, renderer: Any) -> list[tuple[str, Any]]:
    """Every text drawn (titles, axis and tick labels, legends, figure texts) with its extent."""
    texts = [*fig.texts]
    for legend in fig.legends:
        texts += [legend.get_title(), *legend.get_texts()]
    for ax in (ax for ax in fig.axes if ax.get_visible()):
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label]
        texts += [ax.xaxis.offsetText, ax.yaxis.offsetText]  # "1e-5", "+1.3e3"
        texts += [*ax.texts]
        if ax.get_legend():
            texts += [ax.get_legend().get_title(), *ax.get_legend().get_texts()]
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis._update_ticks():  # the ticks inside the view, as drawn
                texts += [tick.label1, tick.label2]
    return [
        (str(t.get_text()), t.get_window_extent(renderer))
        for t in dict.fromkeys(texts)
        if t.get_visible() and str(t.get_text()).strip()
    ]


def _span(ax: Any, name: str) -> Any:
    """The grid columns (``name`` "x") or rows ("y") that ``ax`` spans (``None`` off a grid)."""
    spec = ax.get_subplotspec()
    return None if spec is None else (spec.colspan if name == "x" else spec.rowspan)


def _has_scale(ax: Any, name: str) -> bool:
    """Whether ``ax`` shows tick labels on its ``name`` ("x" or "y") axis."""
    axis = ax.xaxis if name == "x" else ax.yaxis
    return any(
        (tick.label1.get_visible() and tick.label1.get_text())
        or (tick.label2.get_visible() and tick.label2.get_text())
        for tick in axis._update_ticks()
    )


def problems(fig: Any) -> list[str]:
    """What makes ``fig`` hard to read (empty when nothing does)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()  # lays the figure out as it is saved
    renderer = canvas.get_renderer()
    found: list[str] = []
    texts = _texts(fig, renderer)
    for (a, box_a), (b, box_b) in combinations(texts, 2):
        if box_a.overlaps(box_b) and box_a.width > 0 and box_b.width > 0:
            inter = box_a.intersection(box_a, box_b)
            if inter is not None and inter.width > 1 and inter.height > 1:
                found.append(f"texts overlap: {a!r} and {b!r}")
    edge = fig.bbox
    for text, box in texts:
        if (
            box.x0 < edge.x0 - 1
            or box.y0 < edge.y0 - 1
            or box.x1 > edge.x1 + 1
            or box.y1 > edge.y1 + 1
        ):
            found.append(f"a text is cut by the figure's edge: {text!r}")
    panels = [ax for ax in fig.axes if ax.get_visible()]
    for ax in panels:
        for name, shared in (("x", ax.get_shared_x_axes()), ("y", ax.get_shared_y_axes())):
            scaled = [  # a panel in the same column (x) or row (y) that shows the scale
                other
                for other in shared.get_siblings(ax)
                if other in panels and _span(other, name) == _span(ax, name)
                if _has_scale(other, name)
            ]
            if not scaled:
                found.append(f"the panel {ax.get_title()!r} has no {name} scale")
    for legend in fig.legends + [ax.get_legend() for ax in panels if ax.get_legend()]:
        box = legend.get_window_extent(renderer)
        for ax in panels:
            if box.overlaps(ax.get_window_extent(renderer)):
                found.append(f"a legend covers the panel {ax.get_title()!r}")
    for ax in panels:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label and not UNIT.search(label):
                found.append(f"axis label without a unit: {label!r}")
    shared = getattr(fig, "_supxlabel", None)
    if shared is not None and shared.get_text() and not UNIT.search(shared.get_text()):
        found.append(f"axis label without a unit: {shared.get_text()!r}")
    for text, _ in texts:
        for name in CODE_NAME.findall(text):
            found.append(f"code name {name!r} in {text!r}")
    return sorted(set(found))
