"""Heel-contact trigger and delay counter of the Perturberator's microcontroller.

Each motion-plan update (2.5 kHz) the microcontroller compares its reading of the vertical
force with the 25 N threshold; from the first update above it, a counter of update periods
runs to the intended delay, and the perturbation's motion plan starts at that update (paper
000, section 2.4.1). Two imperfections make the onset jitter relative to the true heel contact:
the reading carries a trial-to-trial offset (so the effective threshold varies and the delay
depends on the loading rate), and the counter's period is off by a small trial-to-trial
fraction (so the error grows with the delay). Both are parameters (``[trigger]``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import EventNotFoundError

__all__ = ["onset_updates", "trigger_updates"]


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
