"""Figures and the self-contained HTML report.

Importing this package does not import matplotlib: each figure function imports it (Agg
backend) when it draws.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "chirp_tracking_figure": "figures_capstan",
    "envelope_figure": "figures_capstan",
    "friction_figures": "figures_capstan",
    "observer_figure": "figures_capstan",
    "render_figure": "figures_capstan",
    "scene_figure": "figures_capstan",
    "step_figure": "figures_capstan",
    "teleop_figure": "figures_capstan",
    "zwidth_figure": "figures_capstan",
    "impedance_figure": "figures_impedance",
    "filters_figure": "figures_walking",
    "model_fit_figure": "figures_walking",
    "save_walking_figures": "figures_walking",
    "stance_figure": "figures_walking",
    "submit_filters_figure": "figures_walking",
    "walking_figure": "figures_walking",
    "walking_figures": "figures_walking",
    "WALKING_FIGURES": "figures_walking",
    "FigureRenderer": "render",
    "PendingFigures": "render",
    "Figure": "html",
    "Section": "html",
    "Table": "html",
    "figure_png": "html",
    "render_html": "html",
    "write_report": "html",
    "PAPER_000": "paper_values",
    "PAPER_001": "paper_values",
    "PaperValue": "paper_values",
    "results_report": "sections",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
