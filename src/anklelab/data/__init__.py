"""Sessions: the in-memory model, the CSV session directory and the native HDF5 store."""

from anklelab.data.session import (
    BENCH_COLUMNS,
    CALIBRATION_COLUMNS,
    DIRECTIONS,
    SESSION_FORMAT,
    WALKING_COLUMNS,
    BenchTest,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
)

__all__ = [
    "BENCH_COLUMNS",
    "CALIBRATION_COLUMNS",
    "DIRECTIONS",
    "SESSION_FORMAT",
    "WALKING_COLUMNS",
    "BenchTest",
    "Recording",
    "Session",
    "SessionInfo",
    "WalkingTrial",
]
