"""The experiment's schedule: which walking trial gets which perturbation, and the motion plans.

Paper 000 §2.4.1: each timing point gets ``trials_per_point`` perturbed trials, each dorsi or
plantar with equal probability, interleaved in random order with the unperturbed trials. §2.2:
calibration trials are ramp-and-hold moves in random directions separated by random pauses.
A motion plan is piecewise linear in time (the ramps of the step/direction command).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import ProtocolConfig

__all__ = ["WalkingPlan", "calibration_plan", "ramp_hold_ramp", "walking_plan"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class WalkingPlan:
    """The walking trials in recording order.

    Attributes
    ----------
    sign : ndarray of float, shape (n_trials,)
        +1 dorsiflexion, -1 plantarflexion, 0 unperturbed.
    point : ndarray of int, shape (n_trials,)
        Index into ``timing_points_ms`` (-1 when unperturbed).
    delay_ms : ndarray of float, shape (n_trials,)
        Intended delay after heel contact, ms (NaN when unperturbed).
    """

    sign: Array
    point: NDArray[np.int64]
    delay_ms: Array

    @property
    def n_trials(self) -> int:
        """Number of walking trials."""
        return len(self.sign)

    @property
    def perturbed(self) -> NDArray[np.bool_]:
        """Which trials are perturbed."""
        return self.sign != 0


def walking_plan(protocol: ProtocolConfig, rng: np.random.Generator) -> WalkingPlan:
    """Draw the conditions of every walking trial and shuffle their order."""
    n_points = len(protocol.timing_points_ms)
    point = np.concatenate(
        [
            np.repeat(np.arange(n_points), protocol.trials_per_point),
            -np.ones(protocol.n_unperturbed, int),
        ]
    )
    sign = np.where(point >= 0, rng.choice([-1.0, 1.0], size=len(point)), 0.0)
    order = rng.permutation(len(point))
    point, sign = point[order], sign[order]
    delays = np.asarray(protocol.timing_points_ms, dtype=float)
    delay_ms = np.where(point >= 0, delays[np.maximum(point, 0)], np.nan)
    return WalkingPlan(sign=sign, point=point, delay_ms=delay_ms)


def ramp_hold_ramp(
    t: Array, onset_s: Array | float, sign: Array | float, protocol: ProtocolConfig, hold_s: float
) -> Array:
    """Motion plan of ramp-hold-ramp moves: up in ``ramp_s``, hold, back in ``ramp_s``, rad.

    ``t``, ``onset_s`` and ``sign`` broadcast against each other (e.g. times along the last
    axis, one onset per trial in a column).
    """
    ramp = protocol.ramp_s
    rise = np.clip((t - onset_s) / ramp, 0.0, 1.0)
    fall = np.clip((t - onset_s - ramp - hold_s) / ramp, 0.0, 1.0)
    return sign * protocol.amplitude_rad * (rise - fall)


def calibration_plan(
    protocol: ProtocolConfig, rng: np.random.Generator
) -> list[tuple[Array, Array]]:
    """Onsets (s) and signs (+1 dorsi, -1 plantar) of each calibration trial's moves.

    Moves start after ``calibration_rest_s`` of rest and follow each other with pauses drawn
    uniformly from ``calibration_gap_s`` until the next one would end within the final rest.
    """
    plans = []
    move = 2 * protocol.ramp_s + protocol.calibration_hold_s
    end = protocol.calibration_duration_s - protocol.calibration_rest_s
    for _ in range(protocol.n_calibration):
        onsets = []
        onset = protocol.calibration_rest_s
        while onset + move <= end:
            onsets.append(onset)
            onset += move + rng.uniform(*protocol.calibration_gap_s)
        signs = rng.choice([-1.0, 1.0], size=len(onsets))
        plans.append((np.asarray(onsets), signs))
    return plans
