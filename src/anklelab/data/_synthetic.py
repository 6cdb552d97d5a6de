"""Random but well-formed sessions, for tests and benchmarks of the readers and writers.

The numbers are noise with the right shapes and sampling, not physics; use the digital twin
(:mod:`anklelab.experiments`) for sessions whose signals mean something.
"""

from __future__ import annotations

import numpy as np

from anklelab.data.session import (
    BENCH_COLUMNS,
    CALIBRATION_COLUMNS,
    WALKING_COLUMNS,
    BenchTest,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
)
from anklelab.forceplate import PlateGeometry

__all__ = ["random_session"]


def _recording(
    name: str, columns: tuple[str, ...], n: int, fs: float, rng: np.random.Generator
) -> Recording:
    data = {"time_s": np.arange(n) / fs}
    data |= {c: rng.normal(0.0, 100.0, n) for c in columns if c != "time_s"}
    return Recording(name, data)


def random_session(
    *,
    n_calibration: int = 2,
    n_walking: int = 6,
    n_bench: int = 2,
    n_samples: int = 50,
    fs: float = 1000.0,
    truth: bool = True,
    seed: int | np.random.Generator = 0,
) -> Session:
    """A valid session filled with noise.

    Walking trials cycle through unperturbed, dorsi 100 ms and plantar 225 ms; one extra
    manifest column (``note``) and, in the first walking trial, one extra data column
    (``emg``) exercise the "unknown columns are kept" rules.

    Examples
    --------
    >>> s = random_session(n_walking=3, seed=1)
    >>> [t.direction for t in s.walking]
    ['none', 'dorsi', 'plantar']
    """
    rng = np.random.default_rng(seed)
    info = SessionInfo(
        platform="perturberator",
        sample_rate_hz=fs,
        subject="S01",
        force_plate=PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045),
        ankle_height_m=0.08,
        heel_to_ankle_m=0.04,
        extra={"notes": {"operator": "synthetic"}},
    )
    calibration = tuple(
        _recording(f"cal_{i + 1:02d}.csv", CALIBRATION_COLUMNS, n_samples, fs, rng)
        for i in range(n_calibration)
    )
    kinds = [(False, "none", np.nan), (True, "dorsi", 100.0), (True, "plantar", 225.0)]
    walking = []
    for i in range(n_walking):
        perturbed, direction, delay = kinds[i % 3]
        rec = _recording(f"trial_{i + 1:04d}.csv", WALKING_COLUMNS, n_samples, fs, rng)
        if i == 0:
            rec = Recording(rec.name, dict(rec.columns) | {"emg": rng.normal(size=n_samples)})
        walking.append(
            WalkingTrial(i + 1, rec, perturbed, direction, delay, {"note": f"step {i}"})  # type: ignore[arg-type]
        )
    bench = tuple(
        BenchTest(
            i + 1,
            _recording(f"bench_{i + 1:02d}.csv", BENCH_COLUMNS, n_samples, fs, rng),
            0.06 + 0.01 * i,
        )
        for i in range(n_bench)
    )
    tree = {
        "parameters": {"foot": {"stiffness_nm_per_rad": 1200.0, "pair": (1.0, 2.0)}},
        "trials": {
            "onset_s": np.array(
                [np.nan if not p else 0.2 for p, _, _ in (kinds[i % 3] for i in range(n_walking))]
            ),
            "heel_contact_s": np.full(n_walking, 0.1),
        },
        "labels": ("a", "b"),
        "count": 3,
        "flag": True,
        "nothing": None,
    }
    return Session(
        info=info,
        calibration=calibration,
        walking=tuple(walking),
        bench=bench,
        truth=tree if truth else None,
        provenance={"created_by": "random_session", "seed": 0, "settings": {"n": n_walking}},
    )
