"""The demonstration (``anklelab demo``): both papers' experiments on the digital twins.

An application built on every layer above it: :mod:`~anklelab.demo.run` runs the experiments
(simulate, identify, control, analyse), :mod:`~anklelab.demo.comparisons` lines up each paper's
numbers with anklelab's measurements and the twins' truth, and :mod:`~anklelab.demo.report`
writes the figures, ``summary.json`` and ``report.html``. Importing it loads the twins.
"""

from anklelab.demo.comparisons import (
    COLUMNS,
    Comparison,
    capstan_comparison,
    grouped,
    perturberator_comparison,
)
from anklelab.demo.report import write_demo_report
from anklelab.demo.run import (
    CHIRP,
    CHIRP_DEG,
    COMPENSATIONS,
    OBSERVER_TASKS,
    SETPOINTS_DEG,
    CapstanDemo,
    ChirpRun,
    DemoSettings,
    PerturberatorDemo,
    StepRun,
    run_capstan,
    run_perturberator,
)

__all__ = [
    "CHIRP",
    "CHIRP_DEG",
    "COLUMNS",
    "COMPENSATIONS",
    "OBSERVER_TASKS",
    "SETPOINTS_DEG",
    "CapstanDemo",
    "ChirpRun",
    "Comparison",
    "DemoSettings",
    "PerturberatorDemo",
    "StepRun",
    "capstan_comparison",
    "grouped",
    "perturberator_comparison",
    "run_capstan",
    "run_perturberator",
    "write_demo_report",
]
