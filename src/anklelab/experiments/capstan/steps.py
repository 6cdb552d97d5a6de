"""Set-point steps on the capstan twin and their figures of merit (paper 001, Fig. 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.sim.capstan import SimulationResult

__all__ = ["StepMetrics", "step_metrics", "step_response"]


@dataclass(frozen=True)
class StepMetrics:
    """Set-point response figures (platform angle as the encoder measures it).

    Attributes
    ----------
    amplitude_rad : float
        Step size.
    rise_time_s : float
        10 % to 90 % of the step.
    settling_time_s : float
        Last entry into the ±2 % band (inf if never settled).
    settling_time_5_s : float
        Same with a ±5 % band.
    overshoot_percent : float
        Peak beyond the set-point, % of the step (0 if none).
    steady_state_error_rad : float
        Mean of ``set-point - angle`` over the last 20 % of the record.
    """

    amplitude_rad: float
    rise_time_s: float
    settling_time_s: float
    settling_time_5_s: float
    overshoot_percent: float
    steady_state_error_rad: float


def _first_crossing(t: NDArray[np.float64], y: NDArray[np.float64], level: float) -> float:
    above = np.flatnonzero(y >= level)
    return float(t[above[0]]) if above.size else math.inf


def _settling(t: NDArray[np.float64], err: NDArray[np.float64], band: float) -> float:
    outside = np.flatnonzero(np.abs(err) > band)
    if outside.size == 0:
        return 0.0
    if outside[-1] == len(t) - 1:
        return math.inf
    return float(t[outside[-1] + 1])


def step_metrics(
    angle: ArrayLike, fs: float, amplitude_rad: float, *, start_s: float = 0.0
) -> StepMetrics:
    """Rise, settling, overshoot and steady-state error of a step from 0 to ``amplitude_rad``.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(1000) / fs
    >>> y = 0.1 * (1 - (1 + 20 * t) * np.exp(-20 * t))          # critically damped, w0 = 20
    >>> m = step_metrics(y, fs, 0.1)
    >>> round(m.rise_time_s, 3), round(m.settling_time_s, 3), m.overshoot_percent
    (0.168, 0.292, 0.0)
    """
    y = np.asarray(angle, dtype=float)
    t = np.arange(y.size) / fs - start_s
    keep = t >= 0
    t, y = t[keep], y[keep] / amplitude_rad
    err = 1.0 - y
    tail = max(1, y.size // 5)
    return StepMetrics(
        amplitude_rad=amplitude_rad,
        rise_time_s=_first_crossing(t, y, 0.9) - _first_crossing(t, y, 0.1),
        settling_time_s=_settling(t, err, 0.02),
        settling_time_5_s=_settling(t, err, 0.05),
        overshoot_percent=float(max(0.0, (y.max() - 1.0) * 100.0)),
        steady_state_error_rad=float(np.mean(err[-tail:]) * amplitude_rad),
    )


def step_response(
    setup: CapstanSetup,
    amplitude_rad: float,
    *,
    hold_s: float = 1.5,
    pre_s: float = 0.2,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, StepMetrics]:
    """Step the set-point from 0 to ``amplitude_rad`` after ``pre_s`` and hold ``hold_s``."""
    n = round((pre_s + hold_s) * setup.fs)
    reference = np.where(np.arange(n) >= round(pre_s * setup.fs), amplitude_rad, 0.0)
    result = simulate_closed_loop(setup, n, reference=reference, seed=seed)
    metrics = step_metrics(result["measured_angle_rad"], setup.fs, amplitude_rad, start_s=pre_s)
    return result, metrics
