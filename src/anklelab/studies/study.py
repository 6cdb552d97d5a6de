"""Run a study into an output directory, resuming from the cells already finished.

The directory receives ``cells/KEY.json`` (one result per cell), the tables of
:mod:`anklelab.studies.tables` and ``figures/``. Each finished cell is written at once to a
result store (by default ``DIR/cells``; the ``study`` command keeps it beside its output until
the run completes, :func:`anklelab.studies.execute.checkpoint_for`), so a run that was stopped
resumes from the cells it finished: a cell's key is a hash of what it computes, so a stored
result is only ever reused for the same computation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from anklelab.studies.execute import ResultStore, Task, run_tasks
from anklelab.studies.spec import Study
from anklelab.studies.tables import cells_table, results_table, summary_table, write_table

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["StudyRun", "run_study"]


@dataclass(frozen=True)
class StudyRun:
    """What :func:`run_study` produced: the tables and how the run went."""

    results: pd.DataFrame
    summary: pd.DataFrame
    cells: pd.DataFrame
    resumed: int
    ran: int
    wall_s: float

    @property
    def failed(self) -> pd.DataFrame:
        """The cells that failed (every try), with their errors."""
        return self.cells[self.cells["status"] == "failed"]


def run_study(
    study: Study,
    out: Path,
    *,
    store: Path | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 1,
    figures: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> StudyRun:
    """Simulate and analyse every cell of ``study`` (on Dask) and write the tables to ``out``.

    Parameters
    ----------
    study : Study
    out : Path
        Output directory (created if missing; its files of the same names are replaced).
    store : Path, optional
        Where each finished cell is kept as it arrives (default ``out/cells``); cells found
        there are not run again. The cells of this study are copied to ``out/cells`` when it
        lies elsewhere.
    scheduler, workers, retries, progress
        See :func:`anklelab.studies.execute.run_tasks`.
    figures : bool
        Draw ``figures/*.png``.
    """
    from anklelab.studies.cell import run_cell

    cells = study.cells()
    results_store = ResultStore(out / "cells" if store is None else store, fields=("rows",))
    tasks = [Task(cell.key, run_cell, (cell,)) for cell in cells]  # distinct: Study.points
    run = run_tasks(
        tasks, results_store, scheduler=scheduler, workers=workers, retries=retries,
        progress=progress,
    )  # fmt: skip
    results_store.copy_into([cell.key for cell in cells], out / "cells")
    varied = study.varied
    records = [
        ({"cell": c.key, "cell_index": c.index, "seed": c.seed} | c.variables,
         results_store.read(c.key))
        for c in cells
    ]  # fmt: skip
    results = results_table(records, varied)
    summary = summary_table(results, varied)
    log = cells_table(records, varied)
    write_table(results, out / "results")
    write_table(summary, out / "summary")
    write_table(log, out / "cells", parquet=False)
    if figures:
        from anklelab.studies.figures import study_figures

        study_figures(summary, varied, out / "figures", title=study.name)
    return StudyRun(results, summary, log, int(run["resumed"]), int(run["ran"]), run["wall_s"])
