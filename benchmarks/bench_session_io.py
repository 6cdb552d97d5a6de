"""Session I/O as users run it: whole ``anklelab`` processes on the paper-size twin session.

Each row times a complete command (interpreter start, imports, reading, writing, printing) and
its peak memory, as the best of a few runs, next to the same command of anklelab before the
fast path (main at :data:`BASELINE_COMMIT`, extracted with ``git archive`` and run by the same
interpreter). Each version reads its own HDF5 store: the baseline the one-dataset-per-column
``anklelab-h5/1`` file its ``import`` writes, ours the ``anklelab-h5/2`` file ours writes.
``import`` + ``analyze``, and ``analyze`` straight from the directory (one command), are also
timed against the plain reference analysis of the same CSV directory
(:mod:`benchmarks.plain_reference`: pandas file by file, the per-trial loop of paper 000's
model, no figures), as a whole process.

The session is the twin's paper-size experiment (``simulate_perturberator(seed=0)``: 5
calibration, 800 walking and 15 bench recordings, truth time courses included). ``--scale 4``
tiles its walking trials to 3 200, to check that peak memory stays within 3x the data::

    python -m benchmarks.bench_session_io --scale 4
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import os
import resource
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

from anklelab.data import save_session
from anklelab.data.session import Session
from benchmarks._harness import Result

BASELINE_COMMIT = "806a6be7b435b1d367d28680770a4b2a14c644b6"
"""main just before the fast path (HDF5 layout, pyarrow CSV, lazy imports) was merged."""
REPEAT = 3
# the child reports its own peak resident memory (VmHWM: this program's, reset by exec, unlike
# ru_maxrss, which keeps the parent's size at the fork)
PEAK = (
    "import atexit, os, re\n"
    "def peak():\n"
    "    status = open('/proc/self/status').read()\n"
    "    os.write(2, ('\\nPEAK_KIB ' + re.search(r'VmHWM:\\s+(\\d+)', status)[1]).encode())\n"
    "atexit.register(peak)\n"
)
CLI = PEAK + "from anklelab.cli import {entry}\n{entry}()\n"
"""The command as a program (``program``, the console script's entry point; the baseline has only
``run``), reporting its peak memory from an exit handler."""
PLAIN = PEAK + "import sys\nfrom benchmarks.plain_reference import main\nmain(sys.argv[1])\n"
"""The plain reference analysis (:mod:`benchmarks.plain_reference`), reporting its peak memory."""


def _baseline_src(tmp: Path) -> Path | None:
    """The baseline's ``src`` directory, or ``None`` outside a git checkout holding it."""
    root = Path(__file__).resolve().parents[1]
    try:
        archive = subprocess.run(
            ["git", "-C", str(root), "archive", BASELINE_COMMIT, "src"],
            capture_output=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(tmp / "baseline", filter="data")
    return tmp / "baseline" / "src"


def _reap_orphans() -> None:
    """Adopt the command's orphaned descendants (Linux): a fork server outlives the command by
    a moment, and its workers' CPU time counts only once this process has waited for them."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):
        pass


def _wait_for_orphans() -> None:
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return


def _run(
    argv: list[str], src: Path | None, clean: Path | None = None, code: str | None = None
) -> tuple[float, ...]:
    """Wall time (s), CPU time (user + system, s, of the process and everything it started)
    and peak RSS (MiB) of one ``anklelab`` process (``src`` on PYTHONPATH selects the
    baseline; ``code``, another program); ``clean`` is removed first."""
    if clean is not None:
        shutil.rmtree(clean, ignore_errors=True)
    _reap_orphans()
    env = dict(os.environ) | ({"PYTHONPATH": str(src)} if src else {})
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryFile() as errors:
        start = time.perf_counter()
        status = subprocess.run(
            [sys.executable, "-c", code or CLI.format(entry="run" if src else "program"), *argv],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=errors,
        ).returncode
        wall = time.perf_counter() - start
        errors.seek(0)
        text = errors.read().decode(errors="replace")
    _wait_for_orphans()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if status:
        raise RuntimeError(f"{' '.join(argv)} failed: {text[-2000:]}")
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall, cpu, int(text.rsplit("PEAK_KIB ", 1)[1]) / 1024


def _best(
    argv: list[str], src: Path | None, clean: Path | None = None, code: str | None = None
) -> tuple[float, ...]:
    """Best wall time, best CPU time and largest peak memory of :data:`REPEAT` runs."""
    runs = [_run(argv, src, clean, code) for _ in range(REPEAT)]
    return tuple(f(r[k] for r in runs) for k, f in enumerate((min, min, max)))


def _tiled(session: Session, copies: int) -> Session:
    """``session`` with its walking trials (and their truth rows) repeated ``copies`` times."""
    n = len(session.walking)
    walking = tuple(
        dataclasses.replace(
            t,
            trial=str(int(t.trial) + k * 100_000),  # the baseline reads only integer labels
            recording=dataclasses.replace(t.recording, name=f"c{k}_{t.recording.name}"),
        )
        for k in range(copies)
        for t in session.walking
    )

    def tile(tree):
        return {
            key: tile(v)
            if isinstance(v, dict)
            else (np.concatenate([v] * copies) if isinstance(v, np.ndarray) and len(v) == n else v)
            for key, v in tree.items()
        }

    truth = dict(session.truth or {})
    for key in ("time_courses", "trials"):
        if key in truth:
            truth[key] = tile(truth[key])
    return dataclasses.replace(session, walking=walking, truth=truth)


def _numbers_mib(session: Session) -> float:
    """MiB of numbers the session holds (recordings and truth arrays, as float64)."""
    recordings = [*session.calibration, *(t.recording for t in session.walking)]
    recordings += [b.recording for b in session.bench]
    total = sum(v.nbytes for r in recordings for v in r.columns.values())

    def arrays(tree):
        return sum(
            arrays(v) if isinstance(v, dict) else (v.nbytes if isinstance(v, np.ndarray) else 0)
            for v in tree.values()
        )

    return (total + arrays(session.truth or {})) / 2**20


def run(scale: int = 1) -> list[Result]:
    from anklelab.experiments import simulate_perturberator

    session = simulate_perturberator(seed=0)
    if scale > 1:
        session = _tiled(session, scale)
    data_mib = _numbers_mib(session)
    n = len(session.walking)
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        directory = save_session(session, tmp / "session", format="dir")
        del session
        baseline = _baseline_src(tmp)
        if baseline is None:
            print("bench_session_io: no git checkout with the baseline commit; skipped")
            return []
        versions = {"ours": None, "baseline": baseline}
        h5 = {v: tmp / f"{v}.h5" for v in versions}
        rows: dict[str, dict[str, tuple[float, float]]] = {}
        for v, src in versions.items():
            out = tmp / f"{v}-results"
            rows.setdefault("import", {})[v] = _best(
                ["import", str(directory), "--out", str(h5[v]), "--force"], src
            )
            rows.setdefault("read h5", {})[v] = _best(["session", "info", str(h5[v])], src)
            rows.setdefault("read dir", {})[v] = _best(["session", "info", str(directory)], src)
            rows.setdefault("analyze", {})[v] = _best(
                ["analyze", str(h5[v]), "--out", str(out)], src, clean=out
            )
            rows.setdefault("analyze dir", {})[v] = _best(
                ["analyze", str(directory), "--out", str(out)], src, clean=out
            )
        plain = _best([str(directory)], None, code=PLAIN) if scale == 1 else None
    label = f"{n} walking trials, {data_mib:.0f} MiB of numbers"
    what = f"anklelab at {BASELINE_COMMIT[:7]} (before the fast path)"
    titles = {
        "read h5": "session info S.h5 (read the HDF5 store)",
        "read dir": "session info DIR (read the CSV directory)",
        "import": "import DIR --out S.h5",
        "analyze": "analyze S.h5 (figures included)",
        "analyze dir": "analyze DIR (figures included: one command from the CSV directory)",
    }
    results = []
    for index, kind in ((0, "wall"), (1, "CPU")):
        for key, title in titles.items():
            ours, base = rows[key]["ours"][index], rows[key]["baseline"][index]
            results.append(Result(f"{title}, {kind}, {label}", ours, base, what))
        both = [sum(rows[k][v][index] for k in ("import", "analyze")) for v in ("ours", "baseline")]
        results.append(Result(f"import + analyze of the CSV directory, {kind}", *both, what))
        if plain is not None:
            for title, ours in (
                ("import + analyze of the CSV directory", both[0]),
                ("analyze DIR", rows["analyze dir"]["ours"][index]),
            ):
                results.append(
                    Result(
                        f"{title}, {kind}",
                        ours,
                        plain[index],
                        "plain reference: pandas per file, per-trial loop, no figures",
                    )
                )
    for key in ("read h5", "read dir", "import", "analyze", "analyze dir"):
        ours, base = rows[key]["ours"][2], rows[key]["baseline"][2]
        name = f"peak memory: {titles[key].split(' (')[0]} ({ours / data_mib:.1f}x the data)"
        results.append(Result(name, ours, base, what, unit="MiB"))
    return results


if __name__ == "__main__":
    from benchmarks._harness import report

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scale", type=int, default=1, help="tile the walking trials")
    report(run(parser.parse_args().scale))
