"""Second-order joint impedance ``T = I θ'' + b θ' + k θ`` by linear least squares.

Paper 000 (section 2.4.2) fits this model to the averaged perturbation response over a 100 ms
window, for every bootstrap repetition, and checks 75 and 125 ms windows. Everything here is
vectorised: leading axes (repetitions, conditions) are solved at once, and the fits over
several window lengths starting at the same sample come from one cumulative sum of the
normal-equation terms.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import NotFittedError, ParameterError
from anklelab.signals import vaf

__all__ = ["ImpedanceFit", "ImpedanceModel", "fit_impedance"]


class ImpedanceFit(NamedTuple):
    """Least-squares impedance estimates; each field has the fit's leading shape.

    Attributes
    ----------
    stiffness : ndarray
        ``k``, N·m/rad.
    damping : ndarray
        ``b``, N·m·s/rad.
    inertia : ndarray
        ``I``, kg·m².
    vaf : ndarray
        Variance of the torque accounted for by the model over the window, %.
    """

    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    inertia: NDArray[np.float64]
    vaf: NDArray[np.float64]


def _check(kinematics: ArrayLike, torque: ArrayLike) -> tuple[NDArray, NDArray]:
    kin = np.asarray(kinematics, dtype=float)
    tq = np.asarray(torque, dtype=float)
    if kin.ndim < 2 or kin.shape[-2] != 3 or kin.shape[:-2] + kin.shape[-1:] != tq.shape:
        raise ParameterError(
            "kinematics, torque: expected shapes (..., 3, n_times) and (..., n_times), "
            f"got {kin.shape} and {tq.shape}"
        )
    return kin, tq


def fit_impedance(
    kinematics: ArrayLike, torque: ArrayLike, lengths: Sequence[int] | None = None
) -> ImpedanceFit:
    """Fit ``T = I θ'' + b θ' + k θ`` over windows that start at the first sample.

    Parameters
    ----------
    kinematics : array_like, shape (..., 3, n_times)
        ``(θ, θ', θ'')``: angle, rad; velocity, rad/s; acceleration, rad/s².
    torque : array_like, shape (..., n_times)
        Torque, N·m.
    lengths : sequence of int, optional
        Window lengths in samples (each <= n_times). Omitted: one window, the whole record.

    Returns
    -------
    ImpedanceFit
        Fields shaped ``(len(lengths), ...)``, or ``(...)`` when ``lengths`` is omitted.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(100) / 1000.0
    >>> th = 0.035 * np.clip(t / 0.075, 0, 1) + 0.001 * np.sin(90 * t)
    >>> kin = np.stack([th, np.gradient(th, t), np.gradient(np.gradient(th, t), t)])
    >>> fit = fit_impedance(kin, [1200.0, 2.0, 0.3] @ kin)
    >>> [round(float(v), 6) for v in fit[:3]]
    [1200.0, 2.0, 0.3]
    """
    kin, tq = _check(kinematics, torque)
    n_times = tq.shape[-1]
    single = lengths is None
    sizes = np.array([n_times] if single else lengths, dtype=int)
    if sizes.size == 0 or np.any((sizes < 3) | (sizes > n_times)):
        raise ParameterError(
            f"lengths: expected window lengths between 3 and {n_times} samples, got {lengths!r}"
        )
    x = np.moveaxis(kin, -2, -1)  # (..., n_times, 3)
    scale = np.sqrt((x[..., : sizes.max(), :] ** 2).mean(axis=-2, keepdims=True))
    scale = np.where(scale > 0, scale, 1.0)
    x = x / scale
    end = sizes - 1
    gram = np.cumsum(x[..., :, None] * x[..., None, :], axis=-3)[..., end, :, :]
    cross = np.cumsum(x * tq[..., None], axis=-2)[..., end, :]
    sum_x = np.cumsum(x, axis=-2)[..., end, :]
    sum_t = np.cumsum(tq, axis=-1)[..., end]
    sum_tt = np.cumsum(tq**2, axis=-1)[..., end]
    coef = np.linalg.solve(gram, cross[..., None])[..., 0]  # (..., n_windows, 3)
    res_ss = sum_tt - 2 * (coef * cross).sum(-1) + np.einsum("...i,...ij,...j", coef, gram, coef)
    res_mean = (sum_t - (coef * sum_x).sum(-1)) / sizes
    total = sum_tt / sizes - (sum_t / sizes) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        vaf_percent = 100.0 * (1.0 - (res_ss / sizes - res_mean**2) / total)
    coef = coef / scale
    fields = (coef[..., 0], coef[..., 1], coef[..., 2], vaf_percent)
    if single:
        return ImpedanceFit(*(f[..., 0] for f in fields))
    return ImpedanceFit(*(np.moveaxis(f, -1, 0) for f in fields))


class ImpedanceModel:
    """Estimator of ``T = I θ'' + b θ' + k θ`` (scikit-learn style).

    Attributes
    ----------
    stiffness_, damping_, inertia_ : ndarray
        Estimates with the leading shape of the data, N·m/rad, N·m·s/rad, kg·m².
    vaf_ : ndarray
        In-sample VAF, %.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(100) / 1000.0
    >>> th = 0.03 * np.sin(20 * t) + 0.01 * np.sin(70 * t)
    >>> kin = np.stack([th, np.gradient(th, t), np.gradient(np.gradient(th, t), t)])
    >>> model = ImpedanceModel().fit(kin, [900.0, 3.0, 0.25] @ kin)
    >>> round(float(model.stiffness_), 6), round(model.score(kin, [900.0, 3.0, 0.25] @ kin), 6)
    (900.0, 100.0)
    """

    def fit(self, kinematics: ArrayLike, torque: ArrayLike) -> ImpedanceModel:
        """Fit over the whole record.

        Parameters
        ----------
        kinematics : array_like, shape (..., 3, n_times)
            ``(θ, θ', θ'')`` in rad, rad/s, rad/s².
        torque : array_like, shape (..., n_times)
            Torque, N·m.
        """
        fit = fit_impedance(kinematics, torque)
        self.stiffness_, self.damping_, self.inertia_, self.vaf_ = fit
        return self

    def predict(self, kinematics: ArrayLike) -> NDArray[np.float64]:
        """Model torque, N·m, shape ``(..., n_times)``."""
        if not hasattr(self, "stiffness_"):
            raise NotFittedError(f"{type(self).__name__} is not fitted yet; call fit() first")
        kin = np.asarray(kinematics, dtype=float)
        coef = np.stack([self.stiffness_, self.damping_, self.inertia_], axis=-1)
        return np.einsum("...i,...it->...t", coef, kin)

    def score(self, kinematics: ArrayLike, torque: ArrayLike) -> float:
        """Mean VAF of :meth:`predict` against ``torque``, %."""
        return float(np.mean(vaf(torque, self.predict(kinematics))))
