"""Session I/O: reading an ~800-trial CSV session directory, and the native HDF5 store.

The session is synthetic (noise at full float precision, the worst case for text parsing):
5 calibration, 800 walking and 5 bench recordings of 1200 samples at 1 kHz, written to a
temporary directory once.
"""

from __future__ import annotations

import csv
import tempfile
from pathlib import Path

import numpy as np

from anklelab.data import diff_sessions, read_directory, read_hdf5, save_session
from anklelab.data._synthetic import random_session
from benchmarks._harness import Result, compare


def _per_row_csv(root: Path) -> dict[str, dict[str, np.ndarray]]:
    """Baseline: the csv module, one float() per cell, then columns to arrays."""
    out = {}
    files = sorted((root / "calibration").glob("*.csv"))
    for folder, manifest in (("walking", "trials.csv"), ("bench", "tests.csv")):
        with open(root / folder / manifest, newline="") as f:
            files += [root / folder / row["file"] for row in csv.DictReader(f)]
    for path in files:
        with open(path, newline="") as f:
            reader = csv.reader(f)
            names = next(reader)
            rows = [[float(cell) for cell in row] for row in reader]
        out[str(path)] = dict(zip(names, np.array(rows).T, strict=True))
    return out


def run() -> list[Result]:
    session = random_session(
        n_calibration=5, n_walking=800, n_bench=5, n_samples=1200, truth=True, seed=0
    )
    with tempfile.TemporaryDirectory() as tmp:
        root = save_session(session, Path(tmp) / "session", format="dir")
        h5 = save_session(session, Path(tmp) / "session.h5")
        assert diff_sessions(read_directory(root), session) == []
        assert diff_sessions(read_hdf5(h5), session) == []
        n = len(session.calibration) + len(session.walking) + len(session.bench)
        return [
            compare(
                f"read CSV session dir ({n} files x 1200 rows)",
                lambda: read_directory(root),
                lambda: _per_row_csv(root),
                "csv module, float() per cell (no checks)",
                repeat=1,
            ),
            compare(
                f"read native HDF5 session ({n} recordings)",
                lambda: read_hdf5(h5),
                lambda: read_directory(root),
                "our CSV directory reader",
                repeat=1,
            ),
            compare(
                f"write native HDF5 session ({n} recordings)",
                lambda: save_session(session, Path(tmp) / "w.h5"),
                lambda: save_session(session, Path(tmp) / "w", format="dir"),
                "our CSV directory writer",
                repeat=1,
            ),
        ]


if __name__ == "__main__":
    from benchmarks._harness import report

    report(run())
