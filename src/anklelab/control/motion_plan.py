"""Step/direction motion plan of the Perturberator's microcontroller (paper 000, section 2.1).

The microcontroller drives the servo with step pulses (20,000 steps per motor revolution, so one
step is ``2 pi / (20000 * 70)`` rad at the platform) and a direction line. Every update period
(2.5 kHz) it sets the pulse frequency so that the pulses emitted during the period bring the
step count to the planned position at the period's end, rounded to whole steps; the pulses
are evenly spaced over the period. The drive counts pulses, and its position loop samples the
count. So the position command is quantised in position (whole steps) and in time (pulse
instants, frequency changes only at updates), exactly as this scheme implies.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import ParameterError, SafetyLimitError
from anklelab.platforms.perturberator import PerturberatorParameters

__all__ = ["StepDirectionPlan"]


@dataclass(frozen=True)
class StepDirectionPlan:
    """Step/direction pulse generator.

    Attributes
    ----------
    step_rad : float
        Platform rotation per step pulse, rad.
    update_rate_hz : float
        Rate at which the pulse frequency is updated, Hz.
    angle_limit_rad : float
        Largest platform angle the plan may command, rad (larger plans are refused).

    Examples
    --------
    >>> plan = StepDirectionPlan(step_rad=0.01, update_rate_hz=2500.0, angle_limit_rad=1.0)
    >>> plan.reference(np.array([[0.0, 0.04, 0.04, 0.04]]), loop_rate_hz=10000.0, n_ticks=9)
    array([[0.  , 0.01, 0.02, 0.03, 0.04, 0.04, 0.04, 0.04, 0.04]])
    """

    step_rad: float
    update_rate_hz: float
    angle_limit_rad: float

    @classmethod
    def from_params(cls, params: PerturberatorParameters) -> StepDirectionPlan:
        """The plan of the parameter set (steps per motor revolution, gear ratio, update rate)."""
        steps = params.motion_plan.steps_per_motor_rev * params.transmission.ratio
        return cls(
            2 * np.pi / steps, params.motion_plan.update_rate_hz, params.hinge.angle_limit_rad
        )

    def update_times(self, duration_s: float) -> NDArray[np.float64]:
        """Update instants covering ``[0, duration_s]`` (one past the end), s."""
        return np.arange(int(np.ceil(duration_s * self.update_rate_hz)) + 2) / self.update_rate_hz

    def reference(
        self, planned_rad: NDArray[np.float64], loop_rate_hz: float, n_ticks: int
    ) -> NDArray[np.float64]:
        """Position command seen by the drive at each position-loop tick.

        Parameters
        ----------
        planned_rad : ndarray, shape (n_trials, n_updates)
            Planned platform angle at each update instant (:meth:`update_times`), rad.
        loop_rate_hz : float
            Rate at which the drive samples its step counter, Hz.
        n_ticks : int
            Number of ticks to return (the plan must cover them).

        Returns
        -------
        ndarray, shape (n_trials, n_ticks)
            Steps counted at each tick times the step size, rad.
        """
        planned = np.atleast_2d(np.asarray(planned_rad, dtype=float))
        if not np.isfinite(planned).all():
            raise SafetyLimitError("motion plan: planned angles must be finite (NaN/inf refused)")
        if np.any(np.abs(planned) > self.angle_limit_rad):
            raise SafetyLimitError(
                f"motion plan: |angle| up to {np.abs(planned).max():.4g} rad exceeds the "
                f"{self.angle_limit_rad} rad limit"
            )
        ratio = Fraction(self.update_rate_hz / loop_rate_hz).limit_denominator(1 << 20)
        ticks = np.arange(n_ticks, dtype=np.int64)
        k = ticks * ratio.numerator // ratio.denominator
        phase = (ticks * ratio.numerator % ratio.denominator) / ratio.denominator
        if k[-1] + 1 >= planned.shape[1]:
            raise ParameterError(
                f"planned_rad: {planned.shape[1]} updates do not cover {n_ticks} ticks at "
                f"{loop_rate_hz} Hz"
            )
        target = np.round(planned / self.step_rad).astype(np.int64)
        pulses = np.diff(target, axis=1)[:, k]
        counted = np.floor(phase * np.abs(pulses) + 1e-9).astype(np.int64)
        return (target[:, k] + np.sign(pulses) * counted) * self.step_rad
