"""Derivatives by a local 2nd-order polynomial fit (paper 000, section 2.4.2).

A least-squares polynomial fitted to ``window`` samples centred on each time point and
differentiated there is exactly a Savitzky-Golay filter, so the work is one FIR per derivative.
SciPy's signal package is imported on first use (see :mod:`anklelab.signals.filters`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError

__all__ = ["derivative", "kinematics"]


def _check_window(window: int, polyorder: int) -> None:
    if int(window) != window or window % 2 == 0 or window <= polyorder:
        raise ParameterError(
            f"window: expected an odd number of samples greater than polyorder={polyorder}, "
            f"got {window!r}"
        )


def derivative(
    x: ArrayLike,
    fs: float,
    window: int = 5,
    *,
    deriv: int = 1,
    polyorder: int = 2,
    axis: int = -1,
) -> NDArray[np.float64]:
    """Time derivative of a sampled signal from a local polynomial fit.

    Parameters
    ----------
    x : array_like
        Signals, any shape, time along ``axis``.
    fs : float
        Sample rate, Hz.
    window : int
        Number of samples in each local fit (odd; paper 000 uses the point and the four
        surrounding it, 5).
    deriv : int
        Order of the derivative (0 returns the smoothed signal).
    polyorder : int
        Degree of the local polynomial (2 in paper 000).
    axis : int
        Time axis.

    Returns
    -------
    ndarray
        The ``deriv``-th derivative in units of ``x`` per s**deriv; near the ends the polynomial
        fitted to the first/last ``window`` samples is used.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(50) / 100.0
    >>> bool(np.allclose(derivative(3.0 * t**2, 100.0, deriv=2), 6.0))
    True
    """
    from scipy.signal import savgol_filter

    _check_window(window, polyorder)
    return savgol_filter(
        x, int(window), polyorder, deriv=deriv, delta=1.0 / fs, axis=axis, mode="interp"
    )


def kinematics(
    x: ArrayLike, fs: float, window: int = 5, *, polyorder: int = 2, axis: int = -1
) -> NDArray[np.float64]:
    """An angle with its first two derivatives, stacked just before the time axis.

    Parameters
    ----------
    x : array_like, shape (..., n_times)
        Angle, rad (time along ``axis``).
    fs : float
        Sample rate, Hz.
    window : int
        Samples per local polynomial fit (see :func:`derivative`).
    polyorder : int
        Degree of the local polynomial.
    axis : int
        Time axis of ``x``.

    Returns
    -------
    ndarray, shape (..., 3, n_times)
        ``(θ, θ', θ'')`` in rad, rad/s and rad/s²; ``θ`` is returned unsmoothed.
    """
    x = np.moveaxis(np.asarray(x, dtype=float), axis, -1)
    velocity = derivative(x, fs, window, deriv=1, polyorder=polyorder)
    acceleration = derivative(x, fs, window, deriv=2, polyorder=polyorder)
    return np.stack([x, velocity, acceleration], axis=-2)
