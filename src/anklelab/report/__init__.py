"""Figures and the self-contained HTML report."""

from anklelab.report.figures_walking import save_walking_figures, walking_figures
from anklelab.report.html import Figure, Section, Table, figure_png, render_html, write_report

__all__ = [
    "Figure",
    "Section",
    "Table",
    "figure_png",
    "render_html",
    "save_walking_figures",
    "walking_figures",
    "write_report",
]
