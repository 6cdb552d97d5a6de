"""The disturbance observer at work: the user pushes while the platform holds or tracks, and the
estimate is scored against the twin's true interaction torque."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.sim.capstan import SimulationResult, voluntary_torque

__all__ = ["ObserverMetrics", "observer_metrics", "observer_trial"]


@dataclass(frozen=True)
class ObserverMetrics:
    """How well the disturbance observer tracked the true human (interaction) torque.

    Attributes
    ----------
    vaf_percent : float
        Variance accounted for, ``100 (1 - var(true - estimate) / var(true))``.
    delay_s : float
        Lag of the estimate maximising its cross-correlation with the truth.
    vaf_delay_compensated_percent : float
        VAF after shifting the estimate back by ``delay_s``.
    rms_error_nm : float
        RMS of ``true - estimate``.
    """

    vaf_percent: float
    delay_s: float
    vaf_delay_compensated_percent: float
    rms_error_nm: float


def _vaf(true: NDArray[np.float64], estimate: NDArray[np.float64]) -> float:
    return float(100.0 * (1.0 - np.var(true - estimate) / np.var(true)))


def observer_metrics(
    true: ArrayLike, estimate: ArrayLike, fs: float, *, max_delay_s: float = 0.2
) -> ObserverMetrics:
    """VAF, delay (cross-correlation peak) and error of a torque estimate against the truth."""
    y = np.asarray(true, dtype=float)
    e = np.asarray(estimate, dtype=float)
    max_lag = round(max_delay_s * fs)
    yc, ec = y - y.mean(), e - e.mean()
    lags = np.arange(0, max_lag + 1)
    corr = np.array([np.dot(yc[: yc.size - k], ec[k:]) for k in lags])
    lag = int(lags[np.argmax(corr)])
    return ObserverMetrics(
        vaf_percent=_vaf(y, e),
        delay_s=lag / fs,
        vaf_delay_compensated_percent=_vaf(y[: y.size - lag], e[lag:]),
        rms_error_nm=float(np.sqrt(np.mean((y - e) ** 2))),
    )


def observer_trial(
    setup: CapstanSetup,
    task: Literal["hold", "track"] = "hold",
    *,
    duration_s: float = 20.0,
    torque_rms_nm: float = 3.0,
    band_hz: tuple[float, float] = (0.1, 3.0),
    track_amplitude_rad: float = math.radians(10.0),
    settle_s: float = 1.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, ObserverMetrics]:
    """The user pushes with a random voluntary torque while the platform holds or tracks.

    ``hold``: the set-point is level. ``track``: the set-point is a smooth multisine
    (0.1-0.5 Hz, ``track_amplitude_rad`` peak). Metrics ignore the first ``settle_s``.
    ``seed`` (int or Generator) draws the voluntary torque, the tracked multisine and the
    current-sensor noise; the same seed gives the same run.
    """
    if task not in ("hold", "track"):
        raise ParameterError(f"task must be 'hold' or 'track'; got {task!r}")
    rng = np.random.default_rng(seed)
    n = round(duration_s * setup.fs)
    torque = voluntary_torque(duration_s, setup.fs, rms_nm=torque_rms_nm, band_hz=band_hz, seed=rng)
    reference = np.zeros(n)
    speed = np.zeros(n)
    if task == "track":
        reference = voluntary_torque(duration_s, setup.fs, band_hz=(0.1, 0.5), seed=rng)
        reference *= track_amplitude_rad / np.max(np.abs(reference))
        speed = np.gradient(reference, 1.0 / setup.fs)
    result = simulate_closed_loop(
        setup, n, reference=reference, reference_speed=speed, voluntary=torque, seed=rng
    )
    skip = round(settle_s * setup.fs)
    metrics = observer_metrics(
        result["interaction_torque_nm"][skip:], result["estimated_torque_nm"][skip:], setup.fs
    )
    return result, metrics
