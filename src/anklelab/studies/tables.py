"""A study's tables: the tidy per-session results, the per-cell summary and the run log.

- ``results`` (Parquet and CSV): one row per session (cell) x timing point x quantity, with the
  cell's varied settings and seed, truth, estimate, interval, error and coverage
  (:mod:`anklelab.studies.rows`). Rows are in cell order and hold nothing about how the study
  ran, so the file is the same, byte for byte, however and wherever it ran.
- ``summary``: per point of the grid or sample (its varied settings), timing point and
  quantity, over the seeds: bias, sd, RMSE (also in % of the truth), the median, 95th
  percentile and largest absolute error in %, the mean interval half-width in %, the
  coverage (fraction of intervals holding the truth), with the interval's kind, and the
  fraction of sessions whose estimate the analysis flagged as poorly determined.
  A failed cell is one row of ``results`` with ``status = "failed"`` and the error as
  ``failure``; the summary counts failed sessions per point (``n_failed``).
- ``cells.csv``: the run log, one row per cell: status, error, tries, simulate and analyse
  times. Times differ from run to run; they live here only.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from anklelab._atomic import write_bytes_atomic, write_text_atomic

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["cells_table", "results_table", "summary_table", "write_table"]


def results_table(
    records: Sequence[tuple[dict[str, Any], dict[str, Any]]], varied: Sequence[str]
) -> pd.DataFrame:
    """The tidy table from ``(identity, record)`` pairs in cell order.

    ``identity`` holds ``cell``, ``cell_index``, ``seed`` and the varied settings; ``record`` is
    what :func:`anklelab.studies.execute.attempt` returned for the cell.
    """
    import pandas as pd

    rows: list[dict[str, Any]] = []
    for identity, record in records:
        if record["ok"]:
            rows += [identity | row | {"status": "ok", "failure": ""} for row in record["rows"]]
        else:
            rows.append(identity | {"status": "failed", "failure": record["error"]})
    columns = ["cell", "cell_index", "seed", *varied]
    table = pd.DataFrame(rows)
    for name in (*columns, "status", "failure"):
        if name not in table:
            table[name] = None
    rest = [c for c in table.columns if c not in (*columns, "status", "failure")]
    return table[[*columns, *rest, "status", "failure"]].reset_index(drop=True)


def summary_table(results: pd.DataFrame, varied: Sequence[str]) -> pd.DataFrame:
    """Bias, sd, RMSE, error percentiles, half-width and coverage per point and timing point; a
    point whose every session failed is one row with ``n_sessions = 0`` and its ``n_failed``."""
    import pandas as pd

    keys = [*varied, "direction", "delay_ms", "quantity"]
    point = list(varied)
    ok = results[results["status"] == "ok"]
    failed = results[results["status"] == "failed"]
    if ok.empty and failed.empty:
        return pd.DataFrame(columns=[*keys, "n_sessions", "n_failed"])
    failures = _point_labels(failed, point).value_counts()
    out = []
    grouped = ok.assign(_point=_point_labels(ok, point)).groupby(
        ["_point", "direction", "delay_ms", "quantity"], sort=False
    )
    for (label, direction, delay, quantity), group in grouped:
        first = group.iloc[0]
        error = group["error"].to_numpy(float)
        truth = group["truth"].to_numpy(float)
        percent = group["error_percent"].to_numpy(float)
        covered = group["covered"].dropna()
        n_failed = int(failures.get(label, 0))
        out.append(
            {k: first[k] for k in point}
            | {
                "direction": direction,
                "delay_ms": delay,
                "quantity": quantity,
                "n_sessions": len(group),
                "n_failed": n_failed,
                "interval_kind": "/".join(sorted(set(group["interval_kind"]) - {""})),
                "truth_mean": _mean(truth),
                "estimate_mean": _mean(group["estimate"].to_numpy(float)),
                "bias": _mean(error),
                "bias_percent": _mean(percent),
                "sd": _sd(group["estimate"].to_numpy(float)),
                "sd_percent": _sd(percent),
                "rmse": float(np.sqrt(_mean(error**2))),
                "rmse_percent": float(np.sqrt(_mean(percent**2))),
                "abs_error_percent_median": _quantile(np.abs(percent), 0.5),
                "abs_error_percent_p95": _quantile(np.abs(percent), 0.95),
                "abs_error_percent_max": float(np.nanmax(np.abs(percent)))
                if np.isfinite(percent).any()
                else np.nan,
                "half_width_percent_mean": _mean(group["half_width_percent"].to_numpy(float)),
                "coverage": float(covered.astype(bool).mean()) if len(covered) else np.nan,
                "poorly_determined_fraction": _share(group["poorly_determined"]),
            }
        )
    # a point whose every session failed is a row of its own, not a gap
    lost = failed.assign(_point=_point_labels(failed, point)).drop_duplicates("_point")
    for _, first in lost[~lost["_point"].isin(_point_labels(ok, point))].iterrows():
        out.append(
            {k: first[k] for k in point}
            | {"n_sessions": 0, "n_failed": int(failures[first["_point"]])}
        )
    return pd.DataFrame(out, columns=None if out else [*keys, "n_sessions", "n_failed"])


def cells_table(
    records: Sequence[tuple[dict[str, Any], dict[str, Any]]], varied: Sequence[str]
) -> pd.DataFrame:
    """The run log: one row per cell (status, error, tries, times)."""
    import pandas as pd

    rows = [
        {k: identity.get(k) for k in ("cell", "cell_index", "seed", *varied)}
        | {
            "status": "ok" if record["ok"] else "failed",
            "error": record.get("error", ""),
            "attempts": record.get("attempts"),
            "simulate_s": record.get("simulate_s", record.get("read_s")),
            "analyze_s": record.get("analyze_s"),
        }
        for identity, record in records
    ]
    return pd.DataFrame(rows)


def write_table(table: pd.DataFrame, stem: Path, *, parquet: bool = True) -> list[Path]:
    """Write ``stem.csv`` (and ``stem.parquet``) atomically; returns the paths."""
    written = [write_text_atomic(stem.with_suffix(".csv"), table.to_csv(index=False))]
    if parquet:
        buffer = io.BytesIO()
        _plain(table).to_parquet(buffer, index=False)
        written.append(write_bytes_atomic(stem.with_suffix(".parquet"), buffer.getvalue()))
    return written


def _plain(table: pd.DataFrame) -> pd.DataFrame:
    """Parquet needs one type per column: columns mixing lists or None with text become text."""
    out = table.copy()
    for name in out.columns:
        if out[name].dtype == object:
            kinds = {type(v) for v in out[name] if v is not None}
            if len(kinds) > 1 or kinds & {list, tuple, dict}:
                out[name] = out[name].map(lambda v: None if v is None else str(v))
    return out


def _point_labels(table: pd.DataFrame, point: Sequence[str]) -> pd.Series:
    """A text label per row naming its point of the grid or sample."""
    import pandas as pd

    if not point or table.empty:
        return pd.Series([""] * len(table), index=table.index, dtype=object)
    return table[list(point)].map(repr).agg("|".join, axis=1)


def _share(flags: pd.Series) -> float:
    """Fraction of the set flags among the rows that carry one (NaN if none does)."""
    known = flags.dropna()
    return float(known.astype(bool).mean()) if len(known) else np.nan


def _mean(values: np.ndarray) -> float:
    return float(np.nanmean(values)) if np.isfinite(values).any() else np.nan


def _sd(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.std(finite, ddof=1)) if finite.size > 1 else np.nan


def _quantile(values: np.ndarray, q: float) -> float:
    finite = values[np.isfinite(values)]
    return float(np.quantile(finite, q)) if finite.size else np.nan
