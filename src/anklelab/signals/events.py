"""Event detection from the data: heel contact and the true perturbation onset.

Both detectors work on a batch of trials at once (time last) and never loop over samples.
Neither trusts the manifest: heel contact comes from the vertical force, the onset from the
motor angle leaving its resting value (DESIGN.md section 4).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError

__all__ = ["NOT_FOUND", "Onsets", "heel_contact", "perturbation_onset"]

NOT_FOUND = -1
"""Index returned by :func:`heel_contact` for a trial without an event."""


class Onsets(NamedTuple):
    """Detected perturbation onsets.

    Attributes
    ----------
    index : ndarray of float
        Onset as a fractional sample index (NaN where no perturbation was found).
    amplitude : ndarray of float
        Signed peak excursion of the angle after ``start``, rad (positive: dorsiflexion).
    """

    # a field named ``index`` shadows ``tuple.index``, which mypy reports as an incompatible
    # override; the field is public API (``onsets.index``), so it keeps its name
    index: NDArray[np.float64]  # type: ignore[assignment]
    amplitude: NDArray[np.float64]


def heel_contact(
    fz: ArrayLike, fs: float, threshold_n: float = 25.0, *, hold_ms: float = 5.0, axis: int = -1
) -> NDArray[np.int64]:
    """First sample at which the vertical force rises above a threshold and stays there.

    Parameters
    ----------
    fz : array_like, shape (..., n_times)
        Vertical ground reaction force (zeroed with nobody on the plate), N.
    fs : float
        Sample rate, Hz.
    threshold_n : float
        Contact threshold, N (paper 000: 25 N).
    hold_ms : float
        The force must stay at or above the threshold for this long, ms, so a single noise
        spike is not taken for a contact.
    axis : int
        Time axis.

    Returns
    -------
    ndarray of int
        Sample index of heel contact per trial; :data:`NOT_FOUND` (-1) where there is none.

    Examples
    --------
    >>> import numpy as np
    >>> fz = np.array([[0, 30, 0, 0, 26, 40, 60, 80, 90], [0, 1, 2, 1, 0, 1, 2, 1, 0.0]])
    >>> heel_contact(fz, 1000.0, hold_ms=3.0).tolist()
    [4, -1]
    """
    if threshold_n <= 0:
        raise ParameterError(f"threshold_n: expected > 0 N, got {threshold_n!r}")
    if hold_ms < 0:
        raise ParameterError(f"hold_ms: expected >= 0 ms, got {hold_ms!r}")
    above = np.moveaxis(np.asarray(fz, dtype=float), axis, -1) >= threshold_n
    hold = max(1, round(hold_ms * fs / 1000.0))
    counts = np.concatenate(
        [np.zeros((*above.shape[:-1], 1), dtype=np.int64), np.cumsum(above, axis=-1)], axis=-1
    )
    n = above.shape[-1]
    stop = np.minimum(np.arange(n) + hold, n)
    sustained = (counts[..., stop] - counts[..., :n]) == hold
    return np.where(sustained.any(axis=-1), sustained.argmax(axis=-1), NOT_FOUND)


def perturbation_onset(
    angle: ArrayLike,
    *,
    start: ArrayLike = 0,
    min_amplitude_rad: float = 0.005,
    levels: tuple[float, float] = (0.1, 0.5),
    axis: int = -1,
) -> Onsets:
    """True onset of a ramp perturbation: where the angle leaves its resting value.

    The excursion is the largest departure of ``angle`` from 0 after ``start``. The rising edge
    between the last sample below ``levels[0]`` of it and the first sample above ``levels[1]``
    is fitted with a straight line (least squares), and the onset is where that line crosses
    0. This is insensitive to sensor noise and quantisation near rest and gives sub-sample
    resolution.

    Parameters
    ----------
    angle : array_like, shape (..., n_times)
        Motor (platform) angle relative to its resting value, rad.
    start : int or array_like of int
        First sample searched, per trial (e.g. heel contact).
    min_amplitude_rad : float
        Smallest excursion that counts as a perturbation, rad; below it the onset is NaN.
    levels : (float, float)
        Fractions of the excursion bounding the fitted part of the rising edge.
    axis : int
        Time axis.

    Returns
    -------
    Onsets
        Fractional onset index (NaN where none) and signed excursion per trial.

    Examples
    --------
    A 0.035 rad ramp over 75 samples starting at sample 40.3:

    >>> import numpy as np
    >>> n = np.arange(300.0)
    >>> ramp = 0.035 * np.clip((n - 40.3) / 75.0, 0.0, 1.0)
    >>> onset = perturbation_onset(np.round(ramp, 4))  # 1e-4 rad quantisation
    >>> round(float(onset.index), 1), round(float(onset.amplitude), 4)
    (40.3, 0.035)
    """
    lo, hi = levels
    if not 0 < lo < hi <= 1:
        raise ParameterError(f"levels: expected 0 < low < high <= 1, got {levels!r}")
    if min_amplitude_rad <= 0:
        raise ParameterError(f"min_amplitude_rad: expected > 0 rad, got {min_amplitude_rad!r}")
    d = np.moveaxis(np.asarray(angle, dtype=float), axis, -1)
    n = np.arange(d.shape[-1], dtype=float)
    begin = np.asarray(start)[..., None]
    after = n >= begin
    size = np.where(after, np.abs(d), 0.0)
    amplitude = np.take_along_axis(d, size.argmax(axis=-1)[..., None], axis=-1)[..., 0]
    peak = np.abs(amplitude)[..., None]
    first_high = np.argmax(after & (size >= hi * peak), axis=-1)[..., None]
    low = after & (size < lo * peak) & (n < first_high)
    last_low = np.where(
        low.any(axis=-1), n.size - 1 - np.argmax(low[..., ::-1], axis=-1), begin[..., 0]
    )
    span = (n >= last_low[..., None]) & (n <= first_high)
    count = span.sum(axis=-1)
    sum_n, sum_d = (span * n).sum(axis=-1), (span * d).sum(axis=-1)
    sum_nn, sum_nd = (span * n * n).sum(axis=-1), (span * n * d).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = (count * sum_nd - sum_n * sum_d) / (count * sum_nn - sum_n**2)
        index = (slope * sum_n - sum_d) / (count * slope)
    found = (np.abs(amplitude) >= min_amplitude_rad) & np.isfinite(index)
    return Onsets(np.where(found, index, np.nan), amplitude)
