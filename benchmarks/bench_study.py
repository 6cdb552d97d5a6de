"""Whole-process timings: study throughput on 1 and 2 workers, and the default session's
``anklelab simulate perturberator`` next to the code base before the twin was made faster.

Every figure is the wall time of a whole command as a user runs it (a fresh Python process:
imports, kernel loading from numba's cache, simulation, analysis, writing), repeated; the best
and the median of the repeats are printed.

- **Study throughput**: the same small study (4 sessions of 20 perturbed trials per timing
  point, 80 unperturbed, 2 calibration trials, 30 bootstrap repetitions) run by
  ``anklelab study`` with ``--workers 1`` and ``--workers 2``, from an empty output directory
  each time; sessions simulated and analysed per minute, and the scaling ratio.
- **Default session**: ``anklelab simulate perturberator --out S.h5`` (5 calibration, 800
  walking, 15 bench trials), ours against the commit before this work (``BASELINE_COMMIT``,
  extracted with ``git archive`` and run on the same interpreter and packages, with its own
  numba cache, warmed by one untimed run).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks._harness import Result

BASELINE_COMMIT = "8451f9c"
ROOT = Path(__file__).resolve().parents[1]
REPEAT = 3
STUDY = """
name = "throughput"
seeds = 4
[twin]
trials_per_point = 20
n_unperturbed = 80
n_calibration = 2
bench = false
[analysis]
bootstrap_reps = 30
"""
CLI = "from anklelab.cli import program; program()"  # the console script's entry point
BASELINE_CLI = "from anklelab.cli import run; run()"  # the baseline has no main()


def _timed(command: list[str], env: dict[str, str], before=None) -> float:
    if before is not None:
        before()
    start = time.perf_counter()
    subprocess.run(command, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)  # fmt: skip
    return time.perf_counter() - start


def _repeat(command: list[str], env: dict[str, str], before=None) -> list[float]:
    _timed(command, env, before)  # warm-up: numba's cache, the OS file cache
    return [_timed(command, env, before) for _ in range(REPEAT)]


def _say(label: str, times: list[float]) -> None:
    print(f"  {label}: best {min(times):.2f} s, median {statistics.median(times):.2f} s "
          f"over {len(times)} runs", file=sys.stderr)  # fmt: skip


def _study(tmp: Path, env: dict[str, str]) -> Result:
    study = tmp / "throughput.toml"
    study.write_text(STUDY, encoding="utf-8")
    out = tmp / "study-out"
    times = {}
    for workers in (1, 2):
        command = [sys.executable, "-c", CLI, "study", str(study), "--out", str(out),
                   "--workers", str(workers), "--no-figures"]  # fmt: skip
        times[workers] = _repeat(command, env, before=lambda: shutil.rmtree(out, True))
        rate = 4 / min(times[workers]) * 60
        _say(f"study, {workers} worker(s): {rate:.1f} sessions per minute", times[workers])
    return Result("study: 4 sessions, 2 workers (baseline 1)", min(times[2]), min(times[1]),
                  "the same study on 1 worker")  # fmt: skip


def _simulate(tmp: Path, env: dict[str, str]) -> Result | None:
    baseline = tmp / "baseline"
    baseline.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", BASELINE_COMMIT],
                             capture_output=True, check=False)  # fmt: skip
    if archive.returncode != 0:
        print(f"  (no git history with {BASELINE_COMMIT}: baseline skipped)", file=sys.stderr)
        return None
    subprocess.run(["tar", "-x", "-C", str(baseline)], input=archive.stdout, check=True)
    out = tmp / "session.h5"
    command = [sys.executable, "-c", CLI, "simulate", "perturberator", "--out", str(out)]

    def fresh() -> None:
        out.unlink(missing_ok=True)

    ours = _repeat(command, env, fresh)
    command[2] = BASELINE_CLI
    base_env = env | {"PYTHONPATH": str(baseline / "src"),
                      "NUMBA_CACHE_DIR": str(tmp / "numba-baseline")}  # fmt: skip
    theirs = _repeat(command, base_env, fresh)
    _say("simulate default session, ours", ours)
    _say(f"simulate default session, {BASELINE_COMMIT}", theirs)
    return Result("simulate: default session, whole process", min(ours), min(theirs),
                  f"commit {BASELINE_COMMIT} (before)")  # fmt: skip


def run() -> list[Result]:
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as tmp:
        results = [_study(Path(tmp), env)]
        simulate = _simulate(Path(tmp), env)
    return results + ([simulate] if simulate else [])


if __name__ == "__main__":
    from benchmarks._harness import report

    report(run())
