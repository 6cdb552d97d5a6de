"""A grid of panels placed by margins in inches: the figure is drawn once, not measured first.

Matplotlib's constrained layout measures every title, label and tick label of every panel
twice (its two passes) before the figure is drawn, and the draw measures them again. On the
walking figures that was 0.15-0.4 s of each figure's 0.5-0.95 s. The report's figures have a
fixed size and fixed fonts, so their margins can be fixed too: :class:`Margins` holds room for
the widest labels they carry (tick labels of up to six characters, such as ``-20000``,
beside an axis label).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Margins", "panel_grid", "set_title", "set_top_margin"]

LINE_IN = 0.2
"""Height of one line of text at the report's default font size (10 pt, with spacing), inches."""
SMALL_LINE_IN = 0.17
"""Height of one line of a small-font legend entry, inches."""


@dataclass(frozen=True)
class Margins:
    """Room around and between the panels of a figure, inches.

    The defaults hold, on the left of each panel, its y tick labels and y label (``left``,
    ``between_columns``); above it, a one-line title (``top``, ``between_rows`` with the
    tick labels of the panel above); below the bottom row, x tick labels and an x label.
    """

    left: float = 1.0
    right: float = 0.15
    top: float = 0.35
    bottom: float = 0.55
    between_columns: float = 1.0
    between_rows: float = 0.8


def panel_grid(
    rows: int, cols: int, width: float, height: float, margins: Margins = Margins(), **kw: Any
) -> tuple[Figure, Any]:
    """A ``width`` × ``height`` inch figure and its ``rows`` × ``cols`` panels (a 2-D array).

    Parameters
    ----------
    rows, cols : int
        The grid.
    width, height : float
        The figure's size, inches (100 dpi in the report).
    margins : Margins
        Room around and between the panels, inches.
    **kw
        Passed to :meth:`matplotlib.figure.Figure.subplots` (``sharex``, ``sharey``).

    Raises
    ------
    ValueError
        If the margins leave the panels no room.

    Examples
    --------
    >>> fig, axes = panel_grid(2, 3, 11.0, 6.0)
    >>> axes.shape, round(float(axes[0, 0].get_position().x0) * 11.0, 2)
    ((2, 3), 1.0)
    """
    from matplotlib.figure import Figure

    m = margins
    panel_width = (width - m.left - m.right - (cols - 1) * m.between_columns) / cols
    panel_height = (height - m.top - m.bottom - (rows - 1) * m.between_rows) / rows
    if panel_width <= 0 or panel_height <= 0:
        raise ValueError(
            f"margins: {m} leave no room for {rows} x {cols} panels in {width} x {height} in"
        )
    grid = {
        "left": m.left / width,
        "right": 1.0 - m.right / width,
        "bottom": m.bottom / height,
        "top": 1.0 - m.top / height,
        "wspace": m.between_columns / panel_width,
        "hspace": m.between_rows / panel_height,
    }
    fig = Figure(figsize=(width, height))
    axes = fig.subplots(rows, cols, squeeze=False, gridspec_kw=grid, **kw)
    for ax in axes.flat:  # no "+1.3e3" over a panel: it would meet the title (see set_title)
        ax.ticklabel_format(useOffset=False)
    return fig, axes


def set_top_margin(axes: Any, inches: float) -> None:
    """Move the top of the grid of ``axes`` (from :func:`panel_grid`) ``inches`` below the
    figure's top edge: room for a figure legend whose size is known only once drawn into."""
    flat = list(np.ravel(axes))
    fig = flat[0].get_figure()
    flat[0].get_gridspec().update(top=1.0 - inches / fig.get_figheight())
    for ax in flat:
        ax.set_position(ax.get_subplotspec().get_position(fig))


def set_title(ax: Any, text: str, **kw: Any) -> None:
    """Title a panel at a fixed height above it.

    Left to place itself, a title measures its panel's axes at every draw, to rise above tick
    labels on top, which these panels never have, and above an axis' offset or power of ten
    (``1e-5``): that was a fifth of the walking figures' drawing time. :func:`panel_grid` turns
    the offset off; a power of ten appears only for values below 1e-5 or above 1e6 in the
    panel's units, where it would touch a wide title.
    """
    ax.set_title(text, y=1.0, **kw)
