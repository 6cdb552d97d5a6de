"""Goodness of fit: variance accounted for (VAF).

On the ground floor (it imports nothing of anklelab), so that every layer, the twins' experiments
included, scores fits with the same function; :mod:`anklelab.signals` re-exports it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["vaf"]


def vaf(
    y: ArrayLike, y_hat: ArrayLike, *, axis: int = -1, pool: int | None = None
) -> NDArray[np.float64]:
    """Variance accounted for, percent: ``100 * (1 - var(y - y_hat) / var(y))``.

    Parameters
    ----------
    y, y_hat : array_like
        Measured and predicted signals of the same shape.
    axis : int
        Time axis; variances are taken along it (each signal's mean removed).
    pool : int, optional
        An axis (e.g. channels) whose variances are summed before the ratio: DESIGN.md
        section 5's pooled VAF, ``1 - total residual variance / total variance``.

    Returns
    -------
    ndarray
        VAF, %, with ``axis`` (and ``pool``) reduced; 100 is a perfect fit, it can be negative.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.array([[1.0, 2.0, 3.0, 4.0], [4.0, 1.0, 3.0, 2.0]])
    >>> vaf(y, y).tolist()
    [100.0, 100.0]
    >>> float(vaf(y, y * [[1.0], [0.0]], pool=0))
    50.0
    """
    y = np.asarray(y, dtype=float)
    residual = np.var(y - np.asarray(y_hat, dtype=float), axis=axis, keepdims=True)
    total = np.var(y, axis=axis, keepdims=True)
    axes: tuple[int, ...] = (axis,)
    if pool is not None:
        residual = residual.sum(axis=pool, keepdims=True)
        total = total.sum(axis=pool, keepdims=True)
        axes = (axis, pool)
    with np.errstate(invalid="ignore", divide="ignore"):  # a constant signal has no VAF (NaN)
        return np.squeeze(100.0 * (1.0 - residual / total), axis=axes)
