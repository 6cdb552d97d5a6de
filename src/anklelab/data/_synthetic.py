"""Random but well-formed sessions, for tests and benchmarks of the readers and writers.

The numbers are noise with the right shapes and sampling, not physics; use the digital twin
(:mod:`anklelab.experiments`) for sessions whose signals mean something.
"""

from __future__ import annotations

import numpy as np

from anklelab.data.session import (
    BENCH_COLUMNS,
    BenchTest,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
)
from anklelab.forceplate import ForcePlate, GrfCopPlate, PlateGeometry

__all__ = ["random_session"]

_PLATES: dict[str, ForcePlate] = {
    "kistler8": PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045),
    "grf_cop": GrfCopPlate(anterior_axis="-y", plate_centre_m=(0.4, 2.0)),
}


def _recording(
    name: str,
    columns: tuple[str, ...],
    n: int,
    fs: float,
    rng: np.random.Generator,
    nullable: tuple[str, ...] = (),
) -> Recording:
    """Noise in every column; a ``nullable`` column is empty (NaN) in its first fifth."""
    data = {"time_s": np.arange(n) / fs}
    data |= {c: rng.normal(0.0, 100.0, n) for c in columns if c != "time_s"}
    for c in nullable:
        data[c][: n // 5] = np.nan
    return Recording(name, data)


def random_session(
    *,
    n_calibration: int = 2,
    n_walking: int = 6,
    n_bench: int = 2,
    n_samples: int = 50,
    fs: float = 1000.0,
    truth: bool = True,
    plate: str = "kistler8",
    text_labels: bool = False,
    seed: int | np.random.Generator = 0,
) -> Session:
    """A valid session filled with noise.

    Walking trials cycle through unperturbed, dorsi 100 ms and plantar 225 ms; one extra
    manifest column (``note``) and, in the first walking trial, one extra data column
    (``emg``) exercise the "unknown columns are kept" rules. ``plate`` is ``"kistler8"`` or
    ``"grf_cop"`` (whose COP columns are empty, NaN, in the first fifth of each recording);
    ``text_labels`` labels trials ``"S01 d3"`` and tests ``"b2"`` instead of ``1, 2, ...``.

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
        force_plate=_PLATES[plate],
        ankle_height_m=0.08,
        heel_to_ankle_m=0.04,
        extra={"notes": {"operator": "synthetic"}},
    )
    nullable = info.force_plate.nullable
    calibration = tuple(
        _recording(f"cal_{i + 1:02d}.csv", info.calibration_columns, n_samples, fs, rng, nullable)
        for i in range(n_calibration)
    )
    kinds = [(False, "none", np.nan), (True, "dorsi", 100.0), (True, "plantar", 225.0)]
    walking = []
    for i in range(n_walking):
        perturbed, direction, delay = kinds[i % 3]
        name = f"trial_{i + 1:04d}.csv"
        rec = _recording(name, info.walking_columns, n_samples, fs, rng, nullable)
        if i == 0:
            rec = Recording(rec.name, dict(rec.columns) | {"emg": rng.normal(size=n_samples)})
        walking.append(
            WalkingTrial(
                f"S01 d{i + 1}" if text_labels else i + 1,  # type: ignore[arg-type]
                rec,
                perturbed,
                direction,  # type: ignore[arg-type]
                delay,
                {"note": f"step {i}"},
            )
        )
    bench = tuple(
        BenchTest(
            f"b{i + 1}" if text_labels else i + 1,  # type: ignore[arg-type]
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
