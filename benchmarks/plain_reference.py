"""A plain reference analysis of a CSV session directory, as a whole process (the yardstick of
issue 10's "file to results" target).

It is what a lab would write from paper 000 without our fast path: every CSV file read with
``pandas.read_csv`` one after the other, then :func:`benchmarks.bench_walking.per_trial_loop`,
the analysis trial by trial with the paper's model and its 60 % subsample repetitions. It
prints the stiffness per condition and draws no figure::

    python -m benchmarks.plain_reference SESSION_DIR
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path


def read_directory(root: Path):
    """The session in ``root`` (DESIGN §4 layout), read file by file with pandas."""
    import pandas as pd

    from anklelab.data import Recording, Session, SessionInfo, WalkingTrial
    from anklelab.forceplate import PlateGeometry

    meta = tomllib.loads((root / "session.toml").read_text(encoding="utf-8"))
    # the paper's method takes the plate's channels as recorded (no delay_ms)
    plate = {k: v for k, v in meta["force_plate"].items() if k not in ("type", "delay_ms")}

    def recording(path: Path) -> Recording:
        frame = pd.read_csv(path)
        return Recording(path.name, {name: frame[name].to_numpy() for name in frame.columns})

    calibration = tuple(recording(p) for p in sorted((root / "calibration").glob("*.csv")))
    manifest = pd.read_csv(root / "walking" / "trials.csv")
    walking = tuple(
        WalkingTrial(
            trial=row.trial,
            recording=recording(root / "walking" / row.file),
            perturbed=bool(row.perturbed),
            direction=row.direction,
            delay_ms=float(row.delay_ms),
        )
        for row in manifest.itertuples()
    )
    info = SessionInfo(
        platform=meta["platform"],
        sample_rate_hz=meta["sample_rate_hz"],
        subject=meta.get("subject", ""),
        force_plate=PlateGeometry(**plate),
        **meta["geometry"],
    )
    return Session(info, calibration, walking, ())


def main(root: str) -> None:
    from anklelab.pipelines.walking import WalkingSettings
    from benchmarks.bench_walking import PAPER_SETTINGS, per_trial_loop

    stiffness = per_trial_loop(read_directory(Path(root)), WalkingSettings(**PAPER_SETTINGS))
    for key, value in stiffness.items():
        print(f"{key}: {value:.1f} N·m/rad")


if __name__ == "__main__":
    main(sys.argv[1])
