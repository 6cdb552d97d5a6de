"""Many recorded sessions analysed with one settings file: per-session results and a group table.

Each session (a directory, ``.h5`` or ``.mat`` file) is read and analysed inside a Dask worker
(:mod:`anklelab.studies.execute`); only its ``results.json`` document travels back. The output
directory holds, per session, ``sessions/NAME/results.json`` and ``results.csv`` (as
``anklelab analyze`` writes them), and:

- ``group.parquet`` / ``group.csv``: one row per session, timing point and quantity (subject,
  session, its SHA-256, stiffness model, estimate, sd, 95 % interval and its kind,
  ``poorly_determined``, warnings); a session that could not be analysed is one row with
  ``status = "failed"`` and the reason as ``failure``;
- ``pooled.parquet`` / ``pooled.csv``: per timing point and quantity, the mean over subjects of
  each subject's mean (over their sessions), the sd across subjects and a 95 % interval
  (Student's t; none with one subject), and ``poorly_determined`` when that interval is, as in
  ``results.json``, or any session's estimate is (with two subjects the half-width is 6.35
  times the difference of their means: it often spans zero);
- ``figures/``: stiffness against timing point per subject, and pooled.

Nothing here imports the twin or numba. On a cluster, the workers must see the session files
at the same paths as this machine (a shared file system): each is sent by its absolute path.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from anklelab._atomic import write_text_atomic
from anklelab._version import __version__, code_fingerprint
from anklelab.errors import ParameterError
from anklelab.studies.execute import ResultStore, Task, run_tasks
from anklelab.studies.rows import timing_point_rows
from anklelab.studies.tables import write_table

if TYPE_CHECKING:
    import pandas as pd

    from anklelab.pipelines.walking import WalkingSettings

__all__ = ["BatchRun", "analyse_session_file", "pooled_table", "run_batch", "session_names"]


@dataclass(frozen=True)
class BatchRun:
    """What :func:`run_batch` produced.

    ``names``: the output name of each session path; ``failed``: the error of each session
    (by name) that could not be analysed; ``inputs``: the SHA-256 of each analysed session
    (by path).
    """

    group: pd.DataFrame
    pooled: pd.DataFrame
    names: dict[str, str]
    failed: dict[str, str]
    resumed: int
    ran: int
    inputs: dict[str, str]


def analyse_session_file(path: str, settings: WalkingSettings) -> dict[str, Any]:
    """Read and analyse one session (in a worker); its results document and CSV rows."""
    import warnings

    from anklelab.data import input_name, load_session_hashed
    from anklelab.errors import AnklelabWarning
    from anklelab.pipelines.walking import analyze_walking

    start = time.perf_counter()
    session, sha256 = load_session_hashed(path)
    read = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AnklelabWarning)
        results = analyze_walking(session, settings)
    document = results.to_dict(
        session=input_name(path), session_sha256=sha256, subject=session.info.subject
    )
    return {
        "subject": session.info.subject,
        "document": document,
        "table": results.table(),
        "read_s": read - start,
        "analyze_s": time.perf_counter() - read,
    }


def session_names(paths: Sequence[str | os.PathLike[str]]) -> list[str]:
    """Output names: each session's file or directory stem, with as many parent directories as
    it takes to tell apart sessions of the same name (``S01-session1``, ``S02-session1``).

    Examples
    --------
    >>> session_names([Path("S01/day1.h5"), Path("S02/day1.h5"), Path("S03/x")])
    ['S01-day1', 'S02-day1', 'x']

    A session given twice, however its path is spelled, is refused, naming both as given.
    """
    real = [os.path.realpath(p) for p in paths]
    for i, target in enumerate(real):
        if target in real[:i]:
            first = paths[real.index(target)]
            raise ParameterError(f"SESSIONS: {paths[i]} is {first} given again")
    plain = [Path(os.path.normpath(p)) for p in paths]  # no '.' or 'a/..' in the names
    parts = [p.with_suffix("").parts if p.suffix else p.parts for p in plain]
    depth = [1] * len(parts)
    while True:
        names = ["-".join(p[-d:]) for p, d in zip(parts, depth, strict=True)]
        clashes = {n for n in names if names.count(n) > 1}
        grow = [i for i, n in enumerate(names) if n in clashes and depth[i] < len(parts[i])]
        if not grow:
            if clashes:
                raise ParameterError(f"SESSIONS: {sorted(clashes)[0]!r} is given more than once")
            return names
        for i in grow:
            depth[i] += 1


def run_batch(
    paths: Sequence[str | os.PathLike[str]],
    out: Path,
    *,
    settings: WalkingSettings,
    store: Path | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    retries: int = 0,
    figures: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> BatchRun:
    """Analyse every session in ``paths`` with ``settings`` and write the group tables to ``out``.

    ``store`` is where each analysed session's result is kept as it arrives (default
    ``out/cells``; see :func:`anklelab.studies.run_study`): a session already there (the same
    path, size, modification time and settings) is not analysed again. ``scheduler``,
    ``workers``, ``retries`` and ``progress`` are those of
    :func:`anklelab.studies.execute.run_tasks`.
    """
    if not paths:
        raise ParameterError("SESSIONS: give at least one session")
    names = session_names(paths)  # the paths as given, for its messages
    files = [Path(p) for p in paths]
    for path in files:
        if not path.exists():
            raise ParameterError(f"{path}: session not found")
    config = settings.model_dump(mode="json")
    keys = [_key(path, config) for path in files]
    results = ResultStore(
        out / "cells" if store is None else store, fields=("subject", "document", "table")
    )
    # absolute paths: a cluster's workers have working directories of their own
    tasks = list(
        {
            k: Task(k, analyse_session_file, (os.path.abspath(p), settings))
            for k, p in zip(keys, files, strict=True)
        }.values()
    )
    run = run_tasks(
        tasks, results, scheduler=scheduler, workers=workers, retries=retries, progress=progress
    )
    results.copy_into(list(dict.fromkeys(keys)), out / "cells")
    rows: list[dict[str, Any]] = []
    failed, hashes = {}, {}
    for path, name, key in zip(files, names, keys, strict=True):
        record = results.read(key)
        if not record["ok"]:
            failed[name] = record["error"]
            rows.append({"session": name, "status": "failed", "failure": record["error"]})
            continue
        document = record["document"]
        hashes[str(path)] = document["session_sha256"]
        folder = out / "sessions" / name
        write_text_atomic(folder / "results.json", json.dumps(document, indent=2))
        write_table(_frame(record["table"]), folder / "results", parquet=False)
        identity = {
            "subject": record["subject"],
            "session": name,
            "session_sha256": document["session_sha256"],
        }
        for row in timing_point_rows(document, {}):
            kept = {k: v for k, v in row.items() if k not in _TRUTH}
            rows.append(identity | kept | {"status": "ok", "failure": ""})
    group = _frame(rows)
    pooled = pooled_table(group)
    write_table(group, out / "group")
    write_table(pooled, out / "pooled")
    if figures and not pooled.empty:
        from anklelab.studies.figures import group_figures

        group_figures(group[group["status"] == "ok"], pooled, out / "figures")
    named = dict(zip((str(p) for p in files), names, strict=True))
    return BatchRun(group, pooled, named, failed, int(run["resumed"]), int(run["ran"]), hashes)


_TRUTH = ("truth", "error", "error_percent", "covered")


def pooled_table(group: pd.DataFrame) -> pd.DataFrame:
    """Per direction, timing point and quantity: mean over subjects of each subject's mean,
    sd across subjects, a 95 % interval (Student's t) and whether it is poorly determined (the
    interval by :attr:`~anklelab.pipelines.walking.results.Estimate.poorly_determined`, or any
    session's estimate)."""
    import pandas as pd

    from anklelab._student_t import t_quantile
    from anklelab.pipelines.walking.results import Estimate

    ok = group[group["status"] == "ok"] if "status" in group else group
    if ok.empty or "quantity" not in ok:
        return pd.DataFrame(columns=["direction", "delay_ms", "quantity", "n_subjects"])
    keys = ["direction", "delay_ms", "quantity"]
    by_subject = ok.groupby([*keys, "subject"], sort=True)
    per_subject = by_subject["estimate"].agg(["mean", "size"])
    per_subject["flagged"] = by_subject["poorly_determined"].agg(
        lambda f: bool(f.astype(bool).any())
    )
    out = []
    for (direction, delay, quantity), part in per_subject.groupby(level=keys, sort=True):
        means = part["mean"].to_numpy(float)
        n = len(means)
        sd = float(np.std(means, ddof=1)) if n > 1 else np.nan
        half = float(t_quantile(n - 1, 0.975) * sd / np.sqrt(n)) if n > 1 else np.nan
        mean = float(np.mean(means))
        pooled = Estimate(mean, sd, (mean - half, mean + half))
        out.append(
            {"direction": direction, "delay_ms": delay, "quantity": quantity, "n_subjects": n,
             "n_sessions": int(part["size"].sum()), "mean": mean, "sd_between_subjects": sd,
             "ci95_low": mean - half, "ci95_high": mean + half,
             "poorly_determined": pooled.poorly_determined or bool(part["flagged"].any())}
        )  # fmt: skip
    return pd.DataFrame(out)


def _frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    import pandas as pd

    return pd.DataFrame(rows)


def _key(path: Path, settings: dict[str, Any]) -> str:
    """Names a session's result: its path, size and modification time, the settings and the
    anklelab version and code."""
    stat = path.stat()
    text = json.dumps(
        [
            str(path.resolve()),
            stat.st_size,
            stat.st_mtime_ns,
            settings,
            __version__,
            code_fingerprint(),
        ],
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]
