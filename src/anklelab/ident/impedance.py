"""Second-order joint impedance ``T = I θ'' + b θ' + k θ`` by linear least squares.

Paper 000 (section 2.4.2) fits this model to the averaged perturbation response over a 100 ms
window, for every bootstrap repetition, and checks 75 and 125 ms windows. Everything here is
vectorised: leading axes (repetitions, conditions) are solved at once, and the fits over
several window lengths starting at the same sample come from one cumulative sum of the
normal-equation terms.

**Stiffness that changes within the window.** With ``stiffness="linear"`` the model is
``T = I θ'' + b θ' + (k + k₁ (t - t_c)) θ``, the simplest time-varying impedance in the sense
of the ensemble time-varying identification literature (MacNeil, Kearney & Hunter 1992, IEEE
TBME; applied to the walking ankle by Rouse et al. 2014 and Lee & Hogan 2015, IEEE TNSRE):
the window is short, so the stiffness is expanded to first order in time. ``t_c`` is the
θ²-weighted mean time of the window, ``Σ t θ² / Σ θ²``, which makes ``Σ θ² (t - t_c) = 0``:
``k`` is then exactly the θ²-weighted mean stiffness over the window (DESIGN.md section 5)
whenever the stiffness is linear in time. A constant-``k`` fit measures that value only if the
omitted term ``k₁ (t - t_c) θ`` is uncorrelated with ``θ'`` and ``θ''``; it is not for a
ramp-and-hold perturbation (its velocity comes early in the window, where ``t < t_c``), so a
rising stiffness is absorbed partly by the damping and inertia and biases ``k``. The model is
fitted as ``(k - k₁ t_c) θ + k₁ t θ`` (regressors ``θ, θ', θ'', t θ``, one cumulative sum as
above) and ``k`` recovered with the window's own ``t_c``.

**Low-passed data.** A low-pass ``L`` does not commute with a stiffness that changes in time:
``L(k(t) θ) ≠ k(t) L(θ)``. Where the torque and the angle were low-passed (paper 000's 20 Hz),
the regressor of ``k₁`` must be ``L(t θ)``, the product of time and the *unfiltered* angle passed
through the same low-pass (``time_angle``); then ``L(T) = I L(θ)'' + b L(θ)' + k L(θ) + k₁ L(t θ)``
holds exactly. The product of the filtered angle, ``t L(θ)``, instead reads the damping high:
for a stiffness rising linearly by 43 % per 150 ms under a 75 ms ramp-and-hold, low-passed at
20 Hz, by 4 % (stiffness −0.4 %, inertia −1.4 %); with ``L(t θ)`` the fit is exact.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError
from anklelab.ident._base import Estimator, one_of
from anklelab.signals import vaf

__all__ = [
    "ImpedanceFit",
    "ImpedanceModel",
    "InertiaTerms",
    "StiffnessModel",
    "fit_impedance",
    "impedance_torque",
    "inertia_terms",
]

StiffnessModel = Literal["constant", "linear"]
"""How the stiffness may change within the window: ``k`` or ``k + k₁ (t - t_c)``."""


class ImpedanceFit(NamedTuple):
    """Least-squares impedance estimates; each field has the fit's leading shape.

    Attributes
    ----------
    stiffness : ndarray
        ``k``, N·m/rad: with the linear stiffness model its θ²-weighted mean over the window.
    damping : ndarray
        ``b``, N·m·s/rad.
    inertia : ndarray
        ``I``, kg·m².
    vaf : ndarray
        Variance of the torque accounted for by the model over the window, %.
    stiffness_slope : ndarray
        ``k₁``, N·m/rad/s (0 with the constant stiffness model).
    """

    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    inertia: NDArray[np.float64]
    vaf: NDArray[np.float64]
    stiffness_slope: NDArray[np.float64]


def _check(kinematics: ArrayLike, torque: ArrayLike) -> tuple[NDArray, NDArray]:
    kin = np.asarray(kinematics, dtype=float)
    tq = np.asarray(torque, dtype=float)
    if kin.ndim < 2 or kin.shape[-2] != 3 or kin.shape[:-2] + kin.shape[-1:] != tq.shape:
        raise ParameterError(
            "kinematics, torque: expected shapes (..., 3, n_times) and (..., n_times), "
            f"got {kin.shape} and {tq.shape}"
        )
    return kin, tq


def _sample_rate(fs: float | None) -> float:
    if fs is None or not fs > 0:
        raise ParameterError(
            f"fs: the linear stiffness model needs the sample rate (Hz, > 0), got {fs!r}"
        )
    return float(fs)


def _window_sums(values: NDArray[np.float64], sizes: NDArray[np.int64], axis: int) -> NDArray:
    """Sums of ``values`` over the first ``size`` samples along ``axis``, for each of ``sizes``
    (that axis becomes the windows' axis): the segments between the sorted sizes are summed
    once, then accumulated."""
    bounds = np.unique(sizes)
    upto = values[(Ellipsis, slice(0, bounds[-1])) + (slice(None),) * (-1 - axis)]
    segments = np.add.reduceat(upto, np.concatenate([[0], bounds[:-1]]), axis=axis)
    return np.take(np.cumsum(segments, axis=axis), np.searchsorted(bounds, sizes), axis=axis)


def _check_product(time_angle: ArrayLike, torque: NDArray[np.float64]) -> NDArray[np.float64]:
    product = np.asarray(time_angle, dtype=float)
    if product.shape != torque.shape:
        raise ParameterError(
            f"time_angle: expected the torque's shape {torque.shape}, got {product.shape}"
        )
    return product


def _check_model(stiffness_model: str) -> bool:
    """True for the linear stiffness model."""
    if stiffness_model not in ("constant", "linear"):
        raise ParameterError(
            f"stiffness_model: expected 'constant' or 'linear', got {stiffness_model!r}"
        )
    return stiffness_model == "linear"


def fit_impedance(
    kinematics: ArrayLike,
    torque: ArrayLike,
    lengths: Sequence[int] | None = None,
    *,
    stiffness_model: StiffnessModel = "constant",
    fs: float | None = None,
    time_angle: ArrayLike | None = None,
    inertia: ArrayLike | None = None,
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
    stiffness_model : {"constant", "linear"}
        ``"linear"``: the stiffness is ``k + k₁ (t - t_c)`` within each window, ``t_c`` the
        window's θ²-weighted mean time (see the module docstring); ``k`` is the stiffness at
        ``t_c`` and ``k₁`` is returned as ``stiffness_slope``.
    fs : float, optional
        Sample rate, Hz (the time axis of the linear stiffness model; needed only by it).
    time_angle : array_like, shape (..., n_times), optional
        The linear model's regressor of ``k₁``: time from the first sample, s, times the
        unfiltered angle, rad, low-passed as the torque and ``θ`` were (see the module
        docstring). Omitted: ``t θ`` from the ``θ`` given, right for unfiltered data.
    inertia : array_like, optional
        A known inertia, kg·m², shaped like the fields or broadcastable to them (one value per
        window and record: ``(n_windows, ...)``; a value per window alone is
        ``(n_windows, 1, ...)`` with leading axes): only the stiffness, damping and slope are
        fitted, to ``T - I θ''``, and the fit's ``inertia`` is this one (for an inertia shared
        by several records, see :func:`inertia_terms`).

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

    A stiffness rising at 2000 N·m/rad/s; ``k`` is its θ²-weighted mean over the window:

    >>> k_t = 1200.0 + 2000.0 * (t - 0.05)
    >>> fit = fit_impedance(kin, k_t * th + [0, 2.0, 0.3] @ kin, stiffness_model="linear",
    ...                     fs=1000.0)
    >>> round(float(fit.stiffness), 6) == round(float(k_t @ th**2 / (th @ th)), 6)
    True
    >>> round(float(fit.stiffness_slope), 6), round(float(fit.damping), 6)
    (2000.0, 2.0)

    With the inertia known, the rest is fitted around it:

    >>> fit = fit_impedance(kin, [1200.0, 2.0, 0.3] @ kin, inertia=0.3)
    >>> [round(float(v), 6) for v in fit[:3]]
    [1200.0, 2.0, 0.3]
    """
    terms = _NormalTerms.of(kinematics, torque, lengths, stiffness_model, fs, time_angle)
    gram, cross, sizes = terms.gram, terms.cross, terms.sizes
    if inertia is None:
        coef = np.linalg.solve(gram, cross[..., None])[..., 0]
    else:  # in the scaled regressors' units; the others solved for T - I θ''
        given = terms.from_fields(np.asarray(inertia, dtype=float))
        known = given * terms.scale[..., _INERTIA]
        rest = terms.others
        shifted = cross[..., rest] - known[..., None] * gram[..., rest, _INERTIA]
        solved = np.linalg.solve(gram[..., rest, :][..., rest], shifted[..., None])[..., 0]
        coef = np.insert(solved, _INERTIA, known, axis=-1)
    res_ss = terms.sum_tt - 2 * (coef * cross).sum(-1)
    res_ss = res_ss + np.einsum("...i,...ij,...j", coef, gram, coef)
    res_mean = (terms.sum_t - (coef * terms.sum_x).sum(-1)) / sizes
    total = terms.sum_tt / sizes - (terms.sum_t / sizes) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        vaf_percent = 100.0 * (1.0 - (res_ss / sizes - res_mean**2) / total)
    coef = coef / terms.scale
    stiffness, slope = coef[..., 0], np.zeros_like(coef[..., 0])
    if terms.centre is not None:
        # (k - k1 t_c) θ + k1 t θ: the θ coefficient is moved to t_c = Σ t θ² / Σ θ²
        slope = coef[..., 3]
        stiffness = stiffness + slope * terms.centre
    fitted_inertia = coef[..., _INERTIA] if inertia is None else np.array(given)  # as given
    fields = (stiffness, coef[..., 1], fitted_inertia, vaf_percent, slope)
    return ImpedanceFit(*(terms.to_fields(f) for f in fields))


class InertiaTerms(NamedTuple):
    """One record's share of the least-squares inertia of a joint fit, in which several records
    share one inertia and each keeps its own stiffness and damping (and slope).

    With ``z`` the record's θ'' less its projection on the other regressors (``θ``, ``θ'``, and
    ``t θ`` with the linear model), ``numerator = Σ z T`` (N·m·rad/s²) and ``denominator =
    Σ z²`` ((rad/s²)²): ``numerator / denominator`` is the record's own inertia, and the sums of
    both over the records give the shared one (kg·m²), to pass to :func:`fit_impedance`.
    """

    numerator: NDArray[np.float64]
    denominator: NDArray[np.float64]


def inertia_terms(
    kinematics: ArrayLike,
    torque: ArrayLike,
    lengths: Sequence[int] | None = None,
    *,
    stiffness_model: StiffnessModel = "constant",
    fs: float | None = None,
    time_angle: ArrayLike | None = None,
) -> InertiaTerms:
    """Each record's :class:`InertiaTerms` (arguments as :func:`fit_impedance`; the terms are
    shaped like its fields).

    Examples
    --------
    Two records of one inertia (0.3 kg·m²) with different stiffness and damping:

    >>> import numpy as np
    >>> t = np.arange(100) / 1000.0
    >>> th = 0.035 * np.clip(t / 0.075, 0, 1) + 0.001 * np.sin(90 * t)
    >>> kin = np.stack([th, np.gradient(th, t), np.gradient(np.gradient(th, t), t)])
    >>> both = np.stack([kin, kin])
    >>> torque = np.stack([[1200.0, 2.0, 0.3] @ kin, [800.0, 5.0, 0.3] @ kin])
    >>> terms = inertia_terms(both, torque)
    >>> shared = terms.numerator.sum() / terms.denominator.sum()
    >>> round(float(shared), 6)
    0.3
    >>> [round(float(k), 6) for k in fit_impedance(both, torque, inertia=shared).stiffness]
    [1200.0, 800.0]
    """
    terms = _NormalTerms.of(kinematics, torque, lengths, stiffness_model, fs, time_angle)
    rest = terms.others
    inner = terms.gram[..., rest, :][..., rest]
    mixed = terms.gram[..., rest, _INERTIA]  # θ'' against the others
    solved = np.linalg.solve(inner, np.stack([mixed, terms.cross[..., rest]], axis=-1))
    numerator = terms.cross[..., _INERTIA] - (mixed * solved[..., 1]).sum(-1)
    denominator = terms.gram[..., _INERTIA, _INERTIA] - (mixed * solved[..., 0]).sum(-1)
    scale = terms.scale[..., _INERTIA]  # from the scaled regressor back to rad/s²
    return InertiaTerms(terms.to_fields(numerator * scale), terms.to_fields(denominator * scale**2))


_INERTIA = 2
"""Column of θ'' among the regressors."""


class _NormalTerms(NamedTuple):
    """The normal-equation sums of each window (leading axes, then the windows' axis), over the
    regressors ``θ, θ', θ''`` (and ``t θ``), each divided by its root mean square ``scale``."""

    gram: NDArray[np.float64]
    cross: NDArray[np.float64]
    sum_x: NDArray[np.float64]
    sum_t: NDArray[np.float64]
    sum_tt: NDArray[np.float64]
    scale: NDArray[np.float64]
    sizes: NDArray[np.int64]
    centre: NDArray[np.float64] | None
    """The linear model's ``t_c`` of each window (None with the constant model), s."""
    single: bool
    """No window lengths were given: the fields drop the windows' axis."""

    @classmethod
    def of(
        cls,
        kinematics: ArrayLike,
        torque: ArrayLike,
        lengths: Sequence[int] | None,
        stiffness_model: str,
        fs: float | None,
        time_angle: ArrayLike | None,
    ) -> _NormalTerms:
        kin, tq = _check(kinematics, torque)
        linear = _check_model(stiffness_model)
        n_times = tq.shape[-1]
        sizes = np.array([n_times] if lengths is None else lengths, dtype=int)
        if sizes.size == 0 or np.any((sizes < 3 + linear) | (sizes > n_times)):
            raise ParameterError(
                f"lengths: expected window lengths between {3 + linear} and {n_times} "
                f"samples, got {lengths!r}"
            )
        x = np.moveaxis(kin, -2, -1)  # (..., n_times, 3)
        centre = None
        if linear:
            time = np.arange(n_times) / _sample_rate(fs)
            product = (
                time * kin[..., 0, :] if time_angle is None else _check_product(time_angle, tq)
            )
            x = np.concatenate([x, product[..., None]], axis=-1)  # (..., n_times, 4)
            weight = kin[..., 0, :] ** 2
            centre = _window_sums(weight * time, sizes, -1) / _window_sums(weight, sizes, -1)
        scale = np.sqrt((x[..., : sizes.max(), :] ** 2).mean(axis=-2, keepdims=True))
        scale = np.where(scale > 0, scale, 1.0)
        x = x / scale
        return cls(
            gram=_window_sums(x[..., :, None] * x[..., None, :], sizes, axis=-3),
            cross=_window_sums(x * tq[..., None], sizes, axis=-2),
            sum_x=_window_sums(x, sizes, axis=-2),
            sum_t=_window_sums(tq, sizes, axis=-1),
            sum_tt=_window_sums(tq**2, sizes, axis=-1),
            scale=scale,
            sizes=sizes,
            centre=centre,
            single=lengths is None,
        )

    @property
    def others(self) -> list[int]:
        """Columns of every regressor but θ''."""
        return [i for i in range(self.gram.shape[-1]) if i != _INERTIA]

    def to_fields(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(..., n_windows)`` values as a fit's field: ``(n_windows, ...)``, or ``(...)`` when
        no window lengths were given."""
        return values[..., 0] if self.single else np.moveaxis(values, -1, 0)

    def from_fields(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """Field-shaped values (or values that broadcast to the fields) as ``(..., n_windows)``."""
        leading = self.sum_t.shape  # (..., n_windows)
        fields = leading[:-1] if self.single else (leading[-1], *leading[:-1])
        try:
            shaped = np.broadcast_to(values, fields)
        except ValueError:
            raise ParameterError(
                f"inertia: expected the fields' shape {fields} or one that broadcasts to it, got "
                f"{np.shape(values)}"
            ) from None
        return shaped[..., None] if self.single else np.moveaxis(shaped, 0, -1)


def impedance_torque(
    fit: ImpedanceFit,
    kinematics: ArrayLike,
    fs: float | None = None,
    *,
    time_angle: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Model torque of a fit, N·m, shape ``(..., n_times)``.

    Parameters
    ----------
    fit : ImpedanceFit
        One window's estimates, shaped like the leading axes of ``kinematics`` (or
        broadcastable to them).
    kinematics : array_like, shape (..., 3, n_times)
        ``(θ, θ', θ'')`` over the window the fit describes, rad, rad/s, rad/s².
    fs : float, optional
        Sample rate, Hz; needed when the fit has a stiffness slope (its ``t_c`` is the
        θ²-weighted mean time of these kinematics).
    time_angle : array_like, shape (..., n_times), optional
        The slope's regressor, as given to :func:`fit_impedance` (default ``t θ``).
    """
    kin = np.asarray(kinematics, dtype=float)
    theta = kin[..., 0, :]
    slope = np.asarray(fit.stiffness_slope, dtype=float)[..., None]
    model = np.asarray(fit.stiffness, dtype=float)[..., None] * theta
    if np.any(slope != 0):
        t = np.arange(theta.shape[-1]) / _sample_rate(fs)
        weight = theta**2
        centre = (weight @ t)[..., None] / weight.sum(axis=-1, keepdims=True)
        product = t * theta if time_angle is None else np.asarray(time_angle, dtype=float)
        model = model + slope * (product - centre * theta)
    damping = np.asarray(fit.damping, dtype=float)[..., None]
    inertia = np.asarray(fit.inertia, dtype=float)[..., None]
    return model + damping * kin[..., 1, :] + inertia * kin[..., 2, :]


class ImpedanceModel(Estimator):
    """Estimator of ``T = I θ'' + b θ' + k θ`` (scikit-learn style).

    Parameters
    ----------
    stiffness_model : {"constant", "linear"}
        Constant stiffness, or ``k + k₁ (t - t_c)`` (see :func:`fit_impedance`).

    Attributes
    ----------
    stiffness_, damping_, inertia_ : ndarray
        Estimates with the leading shape of the data, N·m/rad, N·m·s/rad, kg·m².
    stiffness_slope_ : ndarray
        ``k₁``, N·m/rad/s (0 for the constant model).
    vaf_ : ndarray
        In-sample VAF, %.
    fs_ : float or None
        Sample rate given to :meth:`fit`, Hz.

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

    _parameter_constraints: ClassVar = {"stiffness_model": [one_of("constant", "linear")]}
    _fitted_attribute: ClassVar = "stiffness_"

    def __init__(self, *, stiffness_model: StiffnessModel = "constant") -> None:
        self.stiffness_model = stiffness_model

    def fit(
        self,
        kinematics: ArrayLike,
        torque: ArrayLike,
        *,
        fs: float | None = None,
        time_angle: ArrayLike | None = None,
    ) -> ImpedanceModel:
        """Fit over the whole record.

        Parameters
        ----------
        kinematics : array_like, shape (..., 3, n_times)
            ``(θ, θ', θ'')`` in rad, rad/s, rad/s².
        torque : array_like, shape (..., n_times)
            Torque, N·m.
        fs : float, optional
            Sample rate, Hz (needed by the linear stiffness model).
        time_angle : array_like, shape (..., n_times), optional
            The linear model's slope regressor for low-passed data (:func:`fit_impedance`).
        """
        self._validate_params()
        fit = fit_impedance(
            kinematics, torque, stiffness_model=self.stiffness_model, fs=fs, time_angle=time_angle
        )
        self.stiffness_, self.damping_, self.inertia_, self.vaf_, self.stiffness_slope_ = fit
        self.fs_ = fs
        return self

    def predict(
        self, kinematics: ArrayLike, *, time_angle: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """Model torque, N·m, shape ``(..., n_times)`` (``time_angle`` as in :meth:`fit`)."""
        self._check_fitted()
        fit = ImpedanceFit(
            self.stiffness_, self.damping_, self.inertia_, self.vaf_, self.stiffness_slope_
        )
        return impedance_torque(fit, kinematics, self.fs_, time_angle=time_angle)

    def score(
        self, kinematics: ArrayLike, torque: ArrayLike, *, time_angle: ArrayLike | None = None
    ) -> float:
        """Mean VAF of :meth:`predict` against ``torque``, %."""
        return float(np.mean(vaf(torque, self.predict(kinematics, time_angle=time_angle))))
