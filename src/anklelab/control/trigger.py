"""Heel-contact trigger and delay counter of the Perturberator's microcontroller.

Each motion-plan update (2.5 kHz) the microcontroller compares its reading of the vertical
force with the 25 N threshold; from the first update above it, a counter of update periods
runs to the intended delay, and the perturbation's motion plan starts at that update (paper
000, section 2.4.1). Two imperfections make the onset jitter relative to the true heel contact:
the reading carries a trial-to-trial offset (so the effective threshold varies and the delay
depends on the loading rate), and the counter's period is off by a small trial-to-trial
fraction (so the error grows with the delay). Both are parameters (``[trigger]``).

Bad force data must never fire a perturbation: before comparing a reading, the microcontroller
passes it through the generic safety monitor (:mod:`anklelab.control.safety`), with the reading
as the monitored value (:func:`reading_limits`). A non-finite reading (``SENSOR_NAN``), one
beyond ``±force_limit_n`` (``SENSOR_RANGE``: a saturated or broken channel) or more than
``max_dropped_updates`` updates in a row without a new sample (``SENSOR_STALE``) latches a
fault; from then on the trial is refused (:func:`screen_readings`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.control.safety import SafetyLimits, new_safety_state, safety_update
from anklelab.errors import EventNotFoundError

__all__ = ["onset_updates", "reading_limits", "screen_readings", "trigger_updates"]


def trigger_updates(
    force_n: NDArray[np.float64], threshold_n: float, offset_n: NDArray[np.float64]
) -> NDArray[np.int64]:
    """First update index at which ``force + offset`` reaches the threshold, per trial.

    Parameters
    ----------
    force_n : ndarray, shape (n_trials, n_updates)
        Vertical force at the update instants, N.
    threshold_n : float
        Trigger threshold, N.
    offset_n : ndarray, shape (n_trials,)
        Offset of the microcontroller's reading, N.

    Examples
    --------
    >>> trigger_updates(np.array([[0.0, 10, 20, 30, 40]]), 25.0, np.array([6.0])).tolist()
    [2]
    """
    above = force_n + offset_n[:, None] >= threshold_n
    if not above.any(axis=1).all():
        bad = int(np.flatnonzero(~above.any(axis=1))[0])
        raise EventNotFoundError(f"trigger: trial {bad} never reaches {threshold_n} N")
    return np.argmax(above, axis=1)


def onset_updates(
    trigger: NDArray[np.int64],
    delay_s: NDArray[np.float64],
    update_rate_hz: float,
    counter_error: NDArray[np.float64],
) -> NDArray[np.int64]:
    """Update index at which the perturbation starts: trigger plus the counted delay.

    Examples
    --------
    >>> onset_updates(np.array([10]), np.array([0.1]), 2500.0, np.array([0.0])).tolist()
    [260]
    """
    return trigger + np.round(delay_s * (1 + counter_error) * update_rate_hz).astype(np.int64)


def reading_limits(force_limit_n: float, max_dropped_updates: int) -> SafetyLimits:
    """The safety monitor's limits for the trigger's force reading.

    The reading is the monitored value, valid within ``±force_limit_n`` (N); ``counter`` is the
    ADC's sample counter, which may stay unchanged for ``max_dropped_updates`` updates. The
    trigger drives nothing, so the speed and output checks are off.

    Examples
    --------
    >>> reading_limits(3000.0, 1).sensor_max
    3000.0
    """
    return SafetyLimits(
        position_min=-force_limit_n,
        position_max=force_limit_n,
        sensor_min=-force_limit_n,
        sensor_max=force_limit_n,
        velocity_max=math.inf,
        output_max=math.inf,
        output_trip=math.inf,
        max_stale_ticks=max_dropped_updates,
    )


def screen_readings(
    reading_n: NDArray[np.float64], counter: NDArray[np.float64], limits: SafetyLimits
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pass each trial's readings, update by update, through the generic safety monitor.

    Parameters
    ----------
    reading_n : ndarray, shape (n_trials, n_updates)
        The microcontroller's force reading at each update, N.
    counter : ndarray, shape (n_trials, n_updates)
        The ADC's sample counter read with it (unchanged: no new sample).
    limits : SafetyLimits
        From :func:`reading_limits`.

    Returns
    -------
    fault : ndarray of int, shape (n_trials,)
        Latched :class:`anklelab.control.safety.Fault` code (0: none).
    update : ndarray of int, shape (n_trials,)
        Update at which it latched (``n_updates`` if it did not).

    Examples
    --------
    >>> r = np.array([[0.0, 10.0, np.nan, 30.0], [0.0, 10.0, 20.0, 30.0]])
    >>> fault, at = screen_readings(r, np.tile(np.arange(4.0), (2, 1)), reading_limits(3e3, 1))
    >>> fault.tolist(), at.tolist()
    ([1, 0], [2, 4])
    """
    out = _screen(
        limits.to_array(),
        np.ascontiguousarray(reading_n, dtype=float),
        np.ascontiguousarray(counter, dtype=float),
    )
    return out[:, 0], out[:, 1]


@njit(cache=True)
def _screen(limits, reading, counter):  # type: ignore[no-untyped-def]
    n_trials, n = reading.shape
    out = np.zeros((n_trials, 2), dtype=np.int64)
    for i in range(n_trials):
        state = new_safety_state()
        out[i, 1] = n
        for k in range(n):
            safety_update(limits, state, reading[i, k], 0.0, counter[i, k], 0.0, 0.0)
            if state[0] != 0.0:
                out[i, 0] = int(state[0])
                out[i, 1] = k
                break
    return out
