"""Derivatives by a local 2nd-order polynomial fit (paper 000, section 2.4.2).

A least-squares polynomial fitted to ``window`` samples centred on each time point and
differentiated there is exactly a Savitzky-Golay filter, so the work is one FIR per derivative.
Its weights are a few lines of least squares, computed here rather than by ``scipy.signal``,
whose import would cost the analysis 1-1.7 s of start-up (see :mod:`anklelab.iir`).
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
    _check_window(window, polyorder)
    window = int(window)
    x = np.moveaxis(np.asarray(x, dtype=float), axis, -1)
    if x.shape[-1] < window:
        raise ParameterError(
            f"x: {x.shape[-1]} samples along axis {axis}; a derivative over window={window} "
            "samples needs at least that many"
        )
    weights = _fit_weights(window, polyorder, deriv) * fs**deriv
    half = window // 2
    n = x.shape[-1]
    out = np.zeros_like(x)
    for k, weight in enumerate(weights[half]):  # the centred fit: an FIR of `window` taps
        out[..., half : n - half] += weight * x[..., k : n - window + 1 + k]
    out[..., :half] = x[..., :window] @ weights[:half].T  # the first window's polynomial
    out[..., n - half :] = x[..., -window:] @ weights[half + 1 :].T  # the last one's
    return np.moveaxis(out, -1, axis)


def _fit_weights(window: int, polyorder: int, deriv: int) -> NDArray[np.float64]:
    """``W[i] @ x[:window]``: the ``deriv``-th derivative at sample ``i`` (per sample**deriv) of
    the degree-``polyorder`` polynomial fitted to ``window`` samples by least squares."""
    t = np.arange(window) - window // 2
    powers = np.arange(polyorder + 1)
    coefficients = np.linalg.pinv(t[:, None] ** powers)  # (polyorder + 1, window)
    falling = np.array([np.prod(np.arange(p - deriv + 1, p + 1)) for p in powers], dtype=float)
    at = np.where(powers >= deriv, t[:, None] ** np.maximum(powers - deriv, 0), 0.0) * falling
    return at @ coefficients


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
