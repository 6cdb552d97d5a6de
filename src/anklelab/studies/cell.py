"""One study cell, run inside a worker: simulate a session, analyse it, return result rows.

:func:`run_cell` is a pure function of the cell (its settings and seed): the session is made
and analysed where the function runs, and only the rows (plain numbers and text) travel back.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any

import numpy as np

from anklelab.data.session import Session
from anklelab.studies.rows import timing_point_rows
from anklelab.studies.spec import Cell, TwinSettings

__all__ = ["run_cell", "simulate_cell"]

_NOISE_KEYS = (
    "force_plate.noise_n",
    "force_plate.drift_n_per_s",
    "goniometer.precision_small_rad",
    "goniometer.precision_full_scale_rad",
    "bench.load_cell_noise_n",
)


def simulate_cell(cell: Cell, *, threads: int | None = 1) -> Session:
    """The session of a cell (the twin, or a randomised twin's draw, with the cell's settings).

    ``threads`` is how many threads the simulation uses: 1 in a study, whose workers are the
    parallelism.
    """
    from anklelab.errors import AnklelabWarning
    from anklelab.experiments import draw_twin, simulate_perturberator
    from anklelab.platforms import load_platform
    from anklelab.platforms.perturberator import PerturberatorParameters

    twin = TwinSettings().replace(cell.twin)
    base = (
        load_platform("perturberator")
        if cell.base is None
        else PerturberatorParameters.model_validate(cell.base)
    )
    options: dict[str, Any] = dict(
        n_calibration=twin.n_calibration,
        bench=twin.bench,
        artefacts=twin.artefacts,
        time_courses=False,
        threads=threads,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AnklelabWarning)
        if twin.randomised == "none":
            params = base.replace(_noise(base, twin.noise_scale) | _truth_window(cell))
            per_point = twin.trials_per_point or params.walking.trials_per_point
            return simulate_perturberator(
                params, seed=cell.seed, foot=twin.foot, trials_per_point=per_point,
                n_unperturbed=_unperturbed(twin, per_point), **options,
            )  # fmt: skip
        # the randomised twin's own sequence (simulate_randomised), with the cell's overrides
        rng = np.random.default_rng(cell.seed)
        draw = draw_twin(
            rng,
            kind=twin.randomised,
            noise_scale=twin.noise_scale if "noise_scale" in cell.twin else None,
            trials_per_point=twin.trials_per_point,
            params=base,
        )
        unperturbed = _unperturbed(twin, draw.trials_per_point) or draw.n_unperturbed
        draw = dataclasses.replace(draw, n_unperturbed=unperturbed)  # as simulated
        session = simulate_perturberator(
            draw.params.replace(_truth_window(cell)), seed=rng, foot=draw.foot,
            trials_per_point=draw.trials_per_point, n_unperturbed=draw.n_unperturbed, **options,
        )  # fmt: skip
        truth = dict(session.truth or {}) | {"draw": draw.describe()}
        return Session(
            session.info, session.calibration, session.walking, session.bench, truth,
            session.provenance,
        )  # fmt: skip


def run_cell(cell: Cell, *, threads: int | None = 1) -> dict[str, Any]:
    """Simulate and analyse one cell.

    Returns
    -------
    dict
        ``rows``: one per timing point and quantity (see
        :func:`anklelab.studies.rows.timing_point_rows`); ``simulate_s`` and ``analyze_s``:
        wall times, s (kept apart from the rows, which must not depend on how the study ran).
    """
    from anklelab.errors import AnklelabWarning
    from anklelab.pipelines.walking import WalkingSettings, analyze_walking

    start = time.perf_counter()
    session = simulate_cell(cell, threads=threads)
    simulated = time.perf_counter()
    settings = WalkingSettings().replace(cell.analysis)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AnklelabWarning)
        results = analyze_walking(session, settings)
    document = results.to_dict(session=f"cell {cell.key}")
    truth = session.truth or {}
    rows = timing_point_rows(document, truth["reference"])
    if truth.get("draw"):
        draw = {f"draw.{k}": v for k, v in truth["draw"].items()}
        rows = [draw | row for row in rows]
    return {
        "rows": rows,
        "simulate_s": simulated - start,
        "analyze_s": time.perf_counter() - simulated,
    }


def _truth_window(cell: Cell) -> dict[str, Any]:
    """The cell's parameter overrides, with the twin's truth taken over the analysis's window:
    ``walking.window_ms`` (the shipped or the base parameter set's) is the analysis's
    ``window_ms`` unless the cell sets it. The window changes only the truth, not what is
    simulated; a stiffness that changes within the window has a different θ²-weighted average
    over 75 or 125 ms than over 100."""
    from anklelab.pipelines.walking import WalkingSettings

    if "walking.window_ms" in cell.params:
        return cell.params
    window = WalkingSettings().replace(cell.analysis).window_ms
    return cell.params | {"walking.window_ms": window}


def _unperturbed(twin: TwinSettings, per_point: int) -> int | None:
    """Unperturbed trials the settings ask for (None: the default)."""
    if twin.unperturbed_per_point is not None:
        return max(1, round(twin.unperturbed_per_point * per_point))
    return twin.n_unperturbed


def _noise(base: Any, scale: float) -> dict[str, float]:
    """Every noise source of ``base`` times ``scale`` (nothing when the scale is 1)."""
    if scale == 1.0:
        return {}
    out = {}
    for dotted in _NOISE_KEYS:
        section, key = dotted.split(".")
        out[dotted] = getattr(getattr(base, section), key) * scale
    return out
