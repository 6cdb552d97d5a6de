"""Studies at scale: Monte Carlo validation and experiment design on the twin, and batches of
recorded sessions, run on Dask (a local scheduler, a local cluster or a running cluster).

- :func:`load_study` / :func:`run_study`: a grid or seeded random sample over twin settings,
  analysis settings and seeds; tidy results, a summary per cell, figures.
- :func:`design_trials`: trials per timing point for a target stiffness interval and power.
- :func:`run_batch`: many recorded sessions analysed with one settings file; a group table.

Nothing here imports the twin until a cell runs, so analysing recorded data never loads the
simulator or numba.
"""

from anklelab.studies.batch import BatchRun, run_batch
from anklelab.studies.design import Design, design_trials
from anklelab.studies.execute import (
    LOCAL_CLUSTER,
    ResultStore,
    Task,
    attempt,
    checkpoint_for,
    run_tasks,
)
from anklelab.studies.rows import interval, timing_point_rows
from anklelab.studies.spec import Cell, Study, TwinSettings, load_study, study_from_mapping
from anklelab.studies.study import StudyRun, run_study

__all__ = [
    "LOCAL_CLUSTER",
    "BatchRun",
    "Cell",
    "Design",
    "ResultStore",
    "Study",
    "StudyRun",
    "Task",
    "TwinSettings",
    "attempt",
    "checkpoint_for",
    "design_trials",
    "interval",
    "load_study",
    "run_batch",
    "run_study",
    "run_tasks",
    "study_from_mapping",
    "timing_point_rows",
]
