"""Perturbation trajectories: ramp-and-hold moves and pseudorandom calibration sequences.

A ramp-and-hold perturbation starting at ``onset`` rises linearly by ``amplitude`` over
``ramp_s``, holds for ``hold_s`` and returns linearly to zero over ``return_s`` (paper 000:
0.035 rad, 75 ms ramp; 100 ms hold for calibration, 25 ms for walking). Signs are +1 for
dorsiflexion (toes up) and -1 for plantarflexion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError

__all__ = ["RampHold", "calibration_schedule"]


@dataclass(frozen=True)
class RampHold:
    """One ramp-and-hold-and-return move (amplitude rad, durations s).

    Examples
    --------
    >>> move = RampHold(0.035, ramp_s=0.075, hold_s=0.025, return_s=0.075)
    >>> move(np.array([0.0, 0.0375, 0.1, 0.1375, 0.2]), onset_s=0.0).round(5).tolist()
    [0.0, 0.0175, 0.035, 0.0175, 0.0]
    """

    amplitude_rad: float
    ramp_s: float
    hold_s: float
    return_s: float

    def __post_init__(self) -> None:
        if self.ramp_s <= 0 or self.return_s <= 0 or self.hold_s < 0:
            raise ParameterError(
                f"RampHold: ramp_s and return_s must be > 0 and hold_s >= 0; got {self}"
            )

    @property
    def duration_s(self) -> float:
        """From onset back to zero, s."""
        return self.ramp_s + self.hold_s + self.return_s

    def __call__(self, t: ArrayLike, onset_s: ArrayLike, sign: ArrayLike = 1.0) -> NDArray:
        """Position at times ``t`` for moves starting at ``onset_s`` (all broadcast), rad."""
        s = np.asarray(t, dtype=float) - np.asarray(onset_s, dtype=float)
        up = np.clip(s / self.ramp_s, 0.0, 1.0)
        down = np.clip((s - self.ramp_s - self.hold_s) / self.return_s, 0.0, 1.0)
        return np.asarray(sign, dtype=float) * self.amplitude_rad * (up - down)

    def sequence(self, t: ArrayLike, onsets_s: ArrayLike, signs: ArrayLike) -> NDArray:
        """Sum of moves at ``onsets_s`` with ``signs`` (1-D), evaluated at ``t`` (1-D), rad."""
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for onset, sign in zip(np.atleast_1d(onsets_s), np.atleast_1d(signs), strict=True):
            span = slice(*np.searchsorted(t, [onset, onset + self.duration_s + 1e-12]))
            out[span] += self(t[span], onset, sign)
        return out


def calibration_schedule(
    move: RampHold,
    n_perturbations: int,
    duration_s: float,
    max_gap_s: float,
    quiet_s: float,
    seed: int | np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Onsets (s) and signs of a pseudorandom calibration trial (paper 000, section 2.2).

    Directions are dorsi/plantar with equal probability; gaps between moves are uniform on
    ``[0, max_gap_s]``. When ``n_perturbations`` moves with such gaps do not fit between the
    leading and trailing ``quiet_s`` of a ``duration_s`` trial, all gaps are scaled down
    together (paper 000's ~40 moves, 0-2 s gaps and ~20 s trials cannot all hold at once);
    if even gapless moves do not fit, fewer moves are made. ``seed`` is an int or a
    numpy.random.Generator (which then continues its stream).

    Examples
    --------
    >>> move = RampHold(0.035, 0.075, 0.1, 0.075)
    >>> on, sg = calibration_schedule(move, 40, 20.0, 2.0, 0.5, seed=0)
    >>> len(on), bool(on[-1] + move.duration_s <= 19.5), set(sg.tolist()) <= {-1.0, 1.0}
    (40, True, True)
    """
    room = duration_s - 2 * quiet_s
    n = min(n_perturbations, int(room // move.duration_s))
    if n < 1:
        raise ParameterError(f"calibration: a {duration_s} s trial has no room for a perturbation")
    rng = np.random.default_rng(seed)
    gaps = rng.uniform(0.0, max_gap_s, n)
    free = room - n * move.duration_s
    if gaps.sum() > free:
        gaps *= free / gaps.sum()
    signs = rng.choice([-1.0, 1.0], n)
    onsets = quiet_s + np.cumsum(gaps) + np.arange(n) * move.duration_s
    return onsets, signs
