"""Run a study into an output directory, resuming from the cells it already holds.

The directory holds ``study.json`` (the study, the anklelab version, the study file's SHA-256
and the cell keys), ``cells/KEY.json`` (one result per finished cell), the tables of
:mod:`anklelab.studies.tables` and ``figures/``. Running the same study into the same directory
again resumes it: finished cells are kept, the others run. A directory holding another study,
or other files, is refused unless ``force`` is set, which starts it afresh.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from anklelab._atomic import write_text_atomic
from anklelab._version import __version__
from anklelab.errors import ParameterError
from anklelab.studies.execute import ResultStore, Task, run_tasks
from anklelab.studies.spec import Study
from anklelab.studies.tables import cells_table, results_table, summary_table, write_table

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["StudyRun", "prepare_output", "run_study"]

MANIFEST = "study.json"
OWNED = (
    MANIFEST, "cells", "figures", "sessions", "design.json",
    *(f"{stem}.{ext}" for stem in ("results", "summary", "cells", "group", "pooled")
      for ext in ("csv", "parquet")),
)  # fmt: skip
"""What the study, design and batch commands write into their directory (and --force clears)."""


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


def prepare_output(out: Path, manifest: dict[str, Any], *, force: bool) -> None:
    """Make ``out`` ready for the run described by ``manifest``: new, resumable, or (``force``)
    emptied of a previous run's files."""
    path = out / MANIFEST
    if out.exists() and not out.is_dir():
        raise ParameterError(f"{out}: exists and is not a directory")
    if path.is_file():
        try:
            same = json.loads(path.read_text(encoding="utf-8")).get("cells") == manifest["cells"]
        except json.JSONDecodeError:
            same = False
        if not same and not force:
            raise ParameterError(
                f"{out}: holds the results of another run (its {MANIFEST} lists other cells); "
                f"give --force to start it afresh, or another --out"
            )
        if not same:
            _clear(out)
    elif out.exists() and any(out.iterdir()):
        if not force:
            raise ParameterError(
                f"{out}: exists and is not an output of this command; give --force to write "
                f"into it anyway (its other files are kept), or another --out"
            )
        _clear(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(manifest, indent=2, default=list))


def run_study(
    study: Study,
    out: Path,
    *,
    study_sha256: str | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 1,
    force: bool = False,
    figures: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> StudyRun:
    """Simulate and analyse every cell of ``study`` (on Dask) and write the tables to ``out``.

    Parameters
    ----------
    study : Study
    out : Path
        Output directory (resumed when it holds this study's cells).
    study_sha256 : str, optional
        SHA-256 of the study file, recorded in ``study.json``.
    scheduler, workers, retries, progress
        See :func:`anklelab.studies.execute.run_tasks`.
    force : bool
        Start afresh in a directory that holds other files or another study.
    figures : bool
        Draw ``figures/*.png``.
    """
    from anklelab.studies.cell import run_cell

    cells = study.cells()
    manifest = {
        "anklelab_version": __version__,
        "study": study.describe(),
        "study_sha256": study_sha256,
        "cells": [cell.key for cell in cells],
    }
    prepare_output(out, manifest, force=force)
    store = ResultStore(out / "cells")
    unique = {cell.key: cell for cell in cells}
    tasks = [Task(key, run_cell, (cell,)) for key, cell in unique.items()]
    run = run_tasks(
        tasks, store, scheduler=scheduler, workers=workers, retries=retries, progress=progress
    )
    varied = study.varied
    records = [
        ({"cell": c.key, "cell_index": c.index, "seed": c.seed} | c.variables, store.read(c.key))
        for c in cells
    ]
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


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _clear(out: Path) -> None:
    """Remove what a previous run of these commands wrote into ``out`` (nothing else)."""
    for name in OWNED:
        child = out / name
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child)
        elif child.exists() or child.is_symlink():
            child.unlink()
