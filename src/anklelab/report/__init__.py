"""Figures and the self-contained HTML report.

Importing this package does not import matplotlib: each figure function imports it (Agg
backend) when it draws.
"""

from anklelab.report.figures_capstan import (
    chirp_tracking_figure,
    envelope_figure,
    friction_figures,
    observer_figure,
    render_figure,
    scene_figure,
    step_figure,
    teleop_figure,
    zwidth_figure,
)
from anklelab.report.figures_impedance import impedance_figure
from anklelab.report.figures_walking import (
    filters_figure,
    model_fit_figure,
    save_walking_figures,
    stance_figure,
    walking_figures,
)
from anklelab.report.html import Figure, Section, Table, figure_png, render_html, write_report
from anklelab.report.paper_values import PAPER_000, PAPER_001, PaperValue
from anklelab.report.sections import results_report

__all__ = [
    "PAPER_000",
    "PAPER_001",
    "Figure",
    "PaperValue",
    "Section",
    "Table",
    "chirp_tracking_figure",
    "envelope_figure",
    "figure_png",
    "filters_figure",
    "friction_figures",
    "impedance_figure",
    "model_fit_figure",
    "observer_figure",
    "render_figure",
    "render_html",
    "results_report",
    "save_walking_figures",
    "scene_figure",
    "stance_figure",
    "step_figure",
    "teleop_figure",
    "walking_figures",
    "write_report",
    "zwidth_figure",
]
