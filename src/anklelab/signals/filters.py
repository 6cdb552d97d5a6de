"""Zero-phase low-pass filtering (paper 000, section 2.4.2: bidirectional Butterworth)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError
from anklelab.iir import butterworth_sos, edge_padding, sosfiltfilt

__all__ = ["lowpass", "lowpass_min_samples"]

_design = lru_cache(maxsize=32)(butterworth_sos)
"""The Butterworth design, once per (order, cut-off, rate): an analysis filters many times."""


def _check(fs: float, cutoff_hz: float, order: int) -> NDArray[np.float64]:
    if not 0 < cutoff_hz < fs / 2:
        raise ParameterError(
            f"cutoff_hz: expected 0 < cutoff_hz < fs/2 = {fs / 2:g} Hz, got {cutoff_hz!r}"
        )
    if int(order) != order or order < 1:
        raise ParameterError(f"order: expected a positive integer, got {order!r}")
    return _design(int(order), float(cutoff_hz), float(fs))


def lowpass_min_samples(fs: float, cutoff_hz: float = 20.0, *, order: int = 4) -> int:
    """Shortest signal :func:`lowpass` can filter: one more than its edge padding, samples.

    The forward-backward filter extends each end of the signal by an odd reflection of
    ``padlen = 3 (order + 1)`` samples (SciPy's default for a Butterworth design), so the
    signal must be longer than that.

    Parameters
    ----------
    fs, cutoff_hz, order
        As in :func:`lowpass`.

    Returns
    -------
    int
        Minimum number of samples along the time axis.

    Examples
    --------
    >>> lowpass_min_samples(1000.0, 20.0, order=4)
    16
    """
    return edge_padding(_check(fs, cutoff_hz, order)) + 1


def lowpass(
    x: ArrayLike, fs: float, cutoff_hz: float = 20.0, *, order: int = 4, axis: int = -1
) -> NDArray[np.float64]:
    """Zero-phase Butterworth low-pass: the filter run forwards then backwards.

    Parameters
    ----------
    x : array_like
        Signals, any shape; filtered along ``axis`` (all other axes in one call).
    fs : float
        Sample rate, Hz.
    cutoff_hz : float
        -3 dB frequency of the single-pass Butterworth design, Hz (0 < cutoff < fs/2).
    order : int
        Order of the Butterworth design (applied twice, so the magnitude is squared and the
        phase is zero).
    axis : int
        Time axis.

    Returns
    -------
    ndarray
        Filtered signals, same shape as ``x``.

    Raises
    ------
    ParameterError
        If ``x`` has no more samples along ``axis`` than the edge padding (see
        :func:`lowpass_min_samples`).

    Examples
    --------
    A constant passes unchanged and a 200 Hz tone is removed:

    >>> import numpy as np
    >>> t = np.arange(1000) / 1000.0
    >>> y = lowpass(1.0 + np.sin(2 * np.pi * 200 * t), 1000.0, 20.0)
    >>> bool(np.allclose(y[100:-100], 1.0, atol=1e-3))
    True
    """
    return sosfiltfilt(_check(fs, cutoff_hz, order), x, axis=axis)
