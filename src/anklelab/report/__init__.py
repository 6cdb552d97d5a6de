"""Figures and the self-contained HTML report."""

from anklelab.report.comparisons import Comparison
from anklelab.report.demo import write_demo_report
from anklelab.report.figures_walking import save_walking_figures, walking_figures
from anklelab.report.html import Figure, Section, Table, figure_png, render_html, write_report
from anklelab.report.paper_values import PAPER_000, PAPER_001, PaperValue
from anklelab.report.sections import results_report

__all__ = [
    "PAPER_000",
    "PAPER_001",
    "Comparison",
    "Figure",
    "PaperValue",
    "Section",
    "Table",
    "figure_png",
    "render_html",
    "results_report",
    "save_walking_figures",
    "walking_figures",
    "write_demo_report",
    "write_report",
]
