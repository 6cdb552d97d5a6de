"""Shape-preserving piecewise cubic (PCHIP) interpolation in NumPy.

The gait's COP path and the human ankle's angle pattern are PCHIP curves through a few knots.
``scipy.interpolate`` would cost a simulation most of a second of imports for these few lines;
this is the same interpolant (Fritsch–Carlson monotone slopes with the weighted harmonic mean
of paper-standard PCHIP, the three-point end formula), checked against SciPy in the tests.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["pchip"]


def pchip(x: ArrayLike, y: ArrayLike, at: ArrayLike) -> NDArray[np.float64]:
    """The PCHIP interpolant through ``(x, y)`` (``x`` increasing) at ``at``; NaN outside ``x``.

    Examples
    --------
    >>> pchip([0.0, 1.0, 2.0], [0.0, 1.0, 1.0], [0.5, 1.5, 3.0]).round(4).tolist()
    [0.6875, 1.0, nan]
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    t = np.asarray(at, dtype=float)
    h = np.diff(x)
    m = np.diff(y) / h
    d = np.zeros_like(y)
    if len(x) == 2:
        d[:] = m[0]
    else:
        w1 = 2 * h[1:] + h[:-1]
        w2 = h[1:] + 2 * h[:-1]
        same = (np.sign(m[1:]) * np.sign(m[:-1])) > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            inner = (w1 + w2) / (w1 / m[:-1] + w2 / m[1:])
        d[1:-1] = np.where(same, inner, 0.0)
        d[0] = _end_slope(h[0], h[1], m[0], m[1])
        d[-1] = _end_slope(h[-1], h[-2], m[-1], m[-2])
    k = np.clip(np.searchsorted(x, t, side="right") - 1, 0, len(x) - 2)
    s = (t - x[k]) / h[k]
    h00 = (1 + 2 * s) * (1 - s) ** 2
    h10 = s * (1 - s) ** 2
    h01 = s * s * (3 - 2 * s)
    h11 = s * s * (s - 1)
    value = h00 * y[k] + h10 * h[k] * d[k] + h01 * y[k + 1] + h11 * h[k] * d[k + 1]
    return np.where((t >= x[0]) & (t <= x[-1]), value, np.nan)


def _end_slope(h0: float, h1: float, m0: float, m1: float) -> float:
    """One-sided three-point slope at an end, kept shape-preserving."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if np.sign(d) != np.sign(m0):
        return 0.0
    if np.sign(m0) != np.sign(m1) and abs(d) > abs(3 * m0):
        return 3 * m0
    return float(d)
