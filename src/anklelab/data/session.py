"""In-memory session: what one experiment recorded, as DESIGN.md section 4 lays it out.

A :class:`Session` holds the session metadata (``session.toml``), the calibration recordings
(platform moving, nobody on it), the walking trials with their manifest rows, the bench tests,
an optional ``truth`` tree (simulated sessions: what the twin used) and provenance. Recordings
keep every column they were given: required ones are checked, unknown ones are carried along.
Readers and writers for the CSV session directory and the native HDF5 store live beside this
module and all produce or consume this one object.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from anklelab.data._text import excerpt, plain_text
from anklelab.errors import SessionFormatError
from anklelab.forceplate import CHANNELS, ForcePlate

__all__ = [
    "BENCH_COLUMNS",
    "BENCH_MANIFEST_COLUMNS",
    "CALIBRATION_COLUMNS",
    "DIRECTIONS",
    "SESSION_FORMAT",
    "WALKING_COLUMNS",
    "WALKING_MANIFEST_COLUMNS",
    "BenchTest",
    "Recording",
    "Session",
    "SessionInfo",
    "WalkingTrial",
    "label_text",
]

SESSION_FORMAT = "anklelab-session/1"
CALIBRATION_COLUMNS = ("time_s", "motor_angle", *CHANNELS)
"""Required calibration columns with the default ``kistler8`` plate (see
:attr:`SessionInfo.calibration_columns` for any plate type)."""
WALKING_COLUMNS = ("time_s", "motor_angle", "ankle_angle", *CHANNELS)
"""Required walking columns with the default ``kistler8`` plate (see
:attr:`SessionInfo.walking_columns`)."""
BENCH_COLUMNS = ("time_s", "displacement_m", "force_n")
WALKING_MANIFEST_COLUMNS = ("trial", "file", "perturbed", "direction", "delay_ms")
BENCH_MANIFEST_COLUMNS = ("test", "file", "distance_m")
DIRECTIONS = ("dorsi", "plantar", "none")
Direction = Literal["dorsi", "plantar", "none"]


def label_text(value: object, where: str = "label") -> str:
    """A trial or bench-test label as text: any non-empty text without surrounding spaces,
    line breaks or NUL characters; an integer becomes its decimal text (``12`` -> ``"12"``).

    Raises
    ------
    SessionFormatError
        Naming ``where`` when ``value`` is neither.

    Examples
    --------
    >>> label_text(12), label_text("d060_1")
    ('12', 'd060_1')
    """
    if isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_):
        return str(int(value))
    if plain_text(value):
        return value  # type: ignore[return-value]
    raise SessionFormatError(
        f"{where}: got {excerpt(value)}; expected a label (non-empty text without surrounding "
        "spaces, line breaks or NUL characters, or an integer)"
    )


@dataclass(frozen=True)
class SessionInfo:
    """The contents of ``session.toml``.

    Attributes
    ----------
    platform : str
        Name of a parameter set under ``anklelab/platforms``.
    sample_rate_hz : float
        Sampling rate of every recording, Hz.
    subject : str
        Subject or specimen label.
    force_plate : PlateGeometry, SixAxisPlate or GrfCopPlate
        The force plate: its type (which channels the recordings hold), geometry and mounting.
    ankle_height_m : float
        Height ``dz`` of the ankle centre above the plate surface, m.
    heel_to_ankle_m : float
        Anterior distance from the heel-contact COP to the ankle centre, m.
    extra : mapping
        Any other tables or keys of ``session.toml``, kept as read.
    force_delay_ms : float
        How much later the plate's channels are recorded than the angles, ms
        (``[force_plate] delay_ms``, default 0): the group delay of an analog low-pass that only
        the force channels pass, such as the plate amplifier's anti-alias filter.
    """

    platform: str
    sample_rate_hz: float
    subject: str
    force_plate: ForcePlate
    ankle_height_m: float
    heel_to_ankle_m: float
    extra: Mapping[str, Any] = field(default_factory=dict)
    force_delay_ms: float = 0.0

    @property
    def calibration_columns(self) -> tuple[str, ...]:
        """Required columns of a calibration recording with this session's plate."""
        return ("time_s", "motor_angle", *self.force_plate.channels)

    @property
    def walking_columns(self) -> tuple[str, ...]:
        """Required columns of a walking recording with this session's plate."""
        return ("time_s", "motor_angle", "ankle_angle", *self.force_plate.channels)


@dataclass(frozen=True)
class Recording:
    """One recorded file: named columns of equal length, ``time_s`` among them.

    Attributes
    ----------
    name : str
        File name inside its session folder (``"trial_0001.csv"``).
    columns : mapping of str to ndarray
        Each column as a 1-D float array, in file order; unknown columns are kept.
    """

    name: str
    columns: Mapping[str, NDArray[np.float64]]

    def __getitem__(self, column: str) -> NDArray[np.float64]:
        return self.columns[column]

    @property
    def time_s(self) -> NDArray[np.float64]:
        """Sample times, s."""
        return self.columns["time_s"]

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.time_s)

    def stack(self, names: tuple[str, ...] = CHANNELS) -> NDArray[np.float64]:
        """Columns ``names`` stacked as ``(len(names), n_samples)``."""
        return np.stack([self.columns[name] for name in names])


@dataclass(frozen=True)
class WalkingTrial:
    """A walking recording with its row of ``walking/trials.csv``.

    ``trial`` is the trial's label: any non-empty text unique within the session (an integer is
    stored as its decimal text). ``delay_ms`` is the intended timing point after heel contact
    (NaN when unperturbed); the real heel contact and perturbation onset are detected from the
    data, never taken from here.
    ``extra`` holds any further manifest columns of this row, as the strings read.
    """

    trial: str
    recording: Recording
    perturbed: bool
    direction: Direction
    delay_ms: float
    extra: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if isinstance(self.trial, int | np.integer):
            object.__setattr__(self, "trial", label_text(self.trial))


@dataclass(frozen=True)
class BenchTest:
    """A testing-machine recording with its row of ``bench/tests.csv``.

    ``test`` is the test's label (text, like a trial's); ``distance_m`` is the actuator's
    distance along the foot, m; ``extra`` holds any further manifest columns of this row, as the
    strings read.
    """

    test: str
    recording: Recording
    distance_m: float
    extra: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if isinstance(self.test, int | np.integer):
            object.__setattr__(self, "test", label_text(self.test))


@dataclass(frozen=True)
class Session:
    """One experiment: metadata, calibration, walking and bench recordings, truth, provenance.

    Attributes
    ----------
    info : SessionInfo
        Session metadata.
    calibration : tuple of Recording
        Platform-only trials (nobody on the plate).
    walking : tuple of WalkingTrial
        Walking trials in manifest order.
    bench : tuple of BenchTest
        Testing-machine tests.
    truth : mapping or None
        Simulated sessions only: nested mapping of str to arrays, numbers, strings or mappings
        (the twin's parameters, true time courses and reference values).
    provenance : mapping
        ``anklelab_version``, ``settings``, ``source_sha256`` and the like.
    source : str
        Where the session was read from, as the user named it (``"s"``, ``"s.h5"``), for
        messages that name its files (``f"{session.source}/walking/trials.csv"``); empty for a
        session built in memory. Not part of the session's content (equality and
        :func:`~anklelab.data.diff_sessions` ignore it).
    """

    info: SessionInfo
    calibration: tuple[Recording, ...] = ()
    walking: tuple[WalkingTrial, ...] = ()
    bench: tuple[BenchTest, ...] = ()
    truth: Mapping[str, Any] | None = None
    provenance: Mapping[str, Any] = field(default_factory=dict)
    source: str = field(default="", compare=False)
