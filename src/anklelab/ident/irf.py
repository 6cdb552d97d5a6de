"""Impulse-response (FIR) filters from input-output correlations, and the platform filters.

:class:`ImpulseResponse` estimates causal FIR filters from several parallel inputs to many
outputs, ``y_c[n] = sum_i sum_k h_ci[k] u_i[n-k]``, with the correlation method: the input
auto-correlations form a (block-)Toeplitz matrix that is solved once for every output channel
at the same time. Low-pass inputs make that matrix ill-conditioned; the pseudo-inverse variant
keeps only the eigenvector terms that earn their place by the minimum description length (MDL)
criterion (Westwick & Kearney, *Identification of Nonlinear Physiological Systems*, ch. 5).

:class:`PlatformFilters` applies it to paper 000's calibration (section 2.2): the motor angle,
low-pass filtered and differentiated, drives the eight force channels of the unloaded plate. The
paper uses the acceleration alone; a tilting plate also loads its sensors through gravity in
proportion to the angle, so both pathways are the default here: the angle through a static gain
(the gravity tilt) and the acceleration through a 100-lag filter (the plate's inertia, spread by
the resonance of the drivetrain that carries it).

SciPy's FFT and linear algebra are imported where they are used: the figure workers that draw
a fitted filter unpickle this module but never fit or apply one.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab._atomic import write_text_atomic
from anklelab._params import read_parameter_document
from anklelab._version import __version__
from anklelab.errors import ParameterError
from anklelab.forceplate import CHANNELS
from anklelab.ident._base import (
    Constraint,
    Estimator,
    distinct_subset,
    interval,
    none,
    one_of,
    sequence_of,
    validate_parameter,
)
from anklelab.signals import derivative, lowpass, vaf

__all__ = ["FILTERS_FORMAT", "INPUTS", "ImpulseResponse", "PlatformFilters"]

INPUTS = ("angle", "velocity", "acceleration")
"""Input pathways a :class:`PlatformFilters` can use (motor angle and its derivatives)."""
FILTERS_FORMAT = "anklelab-platform-filters/1"

Method = Literal["pinv", "toeplitz"]
Input = Literal["angle", "velocity", "acceleration"]


def _as_batch(x: ArrayLike, name: str) -> NDArray[np.float64]:
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None]
    if x.ndim < 2 or x.shape[-1] < 2:
        raise ParameterError(f"{name}: expected shape (..., n_signals, n_times), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ParameterError(f"{name}: contains NaN or infinite values")
    return x


def _centred(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each record minus its mean over time."""
    return x - x.mean(axis=-1, keepdims=True)


_POSITIVE_INT = interval(1, integer=True)
_METHOD = [one_of("pinv", "toeplitz")]


class ImpulseResponse(Estimator):
    """Multi-input, multi-output causal FIR filters by the correlation method.

    Parameters
    ----------
    n_lags : int or sequence of int
        Filter length in samples (lags 0 .. n_lags-1): one for every input, or one per input.
        A pathway of length 1 is a static gain. Inputs that are filtered versions of each other
        (an angle and its acceleration) can trade content between equally long filters without
        changing the output, so such a split is undetermined; a short pathway beside a long one
        removes that freedom.
    method : {"pinv", "toeplitz"}
        ``"toeplitz"`` solves the normal equations directly (Levinson recursion for one input);
        ``"pinv"`` uses the eigen-decomposition of the correlation matrix and keeps the terms
        chosen by MDL, for ill-conditioned (low-pass) inputs.
    order : int, optional
        Number of eigenvector terms for ``"pinv"``; chosen by MDL when omitted.

    Attributes
    ----------
    irf_ : ndarray, shape (n_outputs, n_inputs, max(n_lags))
        Filter weights, output units per input unit per sample (zero beyond an input's own
        length).
    order_ : int
        Number of terms used (the sum of the filter lengths for ``"toeplitz"``).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> u = rng.normal(size=(2, 5000))
    >>> h = np.zeros((1, 2, 10)); h[0, 0, 2], h[0, 1, :3] = 1.0, [0.5, 0.25, 0.125]
    >>> est = ImpulseResponse(n_lags=10).fit(u, np.array([np.convolve(u[0], h[0, 0])[:5000]
    ...                                            + np.convolve(u[1], h[0, 1])[:5000]]))
    >>> bool(np.allclose(est.irf_, h, atol=0.02))
    True
    >>> y = 2.0 * u[:1] + np.convolve(u[1], h[0, 1])[:5000]   # a static gain on input 0
    >>> ImpulseResponse(n_lags=[1, 10]).fit(u, y).irf_[0, :, :4].round(2)
    array([[2.  , 0.  , 0.  , 0.  ],
           [0.5 , 0.25, 0.12, 0.  ]])
    """

    _parameter_constraints: ClassVar = {
        "n_lags": [_POSITIVE_INT, sequence_of(_POSITIVE_INT)],
        "method": _METHOD,
        "order": [_POSITIVE_INT, none()],
    }
    _fitted_attribute: ClassVar = "irf_"

    def __init__(
        self,
        *,
        n_lags: int | Sequence[int] = 100,
        method: Method = "pinv",
        order: int | None = None,
    ) -> None:
        self.n_lags = n_lags
        self.method = method
        self.order = order

    def _lags(self, n_inputs: int) -> tuple[int, ...]:
        """Validate the parameters; return the filter length of each input."""
        self._validate_params()
        if isinstance(self.n_lags, int | np.integer):
            return (int(self.n_lags),) * n_inputs
        validate_parameter("n_lags", self.n_lags, [sequence_of(_POSITIVE_INT, non_empty=True)])
        if len(self.n_lags) != n_inputs:
            raise ParameterError(
                f"n_lags: expected a positive integer or one per input ({n_inputs}), "
                f"got {self.n_lags!r}"
            )
        return tuple(int(n) for n in self.n_lags)

    def fit(self, u: ArrayLike, y: ArrayLike) -> ImpulseResponse:
        """Estimate the filters.

        Parameters
        ----------
        u : array_like, shape (..., n_inputs, n_times)
            Inputs. Leading axes are independent records (trials) pooled into one estimate.
        y : array_like, shape (..., n_outputs, n_times)
            Outputs, same leading axes and length as ``u``.

        Returns
        -------
        ImpulseResponse
            ``self``, fitted.
        """
        u, y = _as_batch(u, "u"), _as_batch(y, "y")
        lags = self._lags(u.shape[-2])
        if u.shape[:-2] != y.shape[:-2] or u.shape[-1] != y.shape[-1]:
            raise ParameterError(
                f"u, y: leading axes and n_times must match, got {u.shape} and {y.shape}"
            )
        n_in, n_out, n_lags = u.shape[-2], y.shape[-2], max(lags)
        u = _centred(u)
        y = _centred(y)
        scale = np.sqrt((u**2).mean(axis=(*range(u.ndim - 2), -1)))
        if np.any(scale == 0):
            raise ParameterError("u: an input is constant; it cannot drive a filter")
        uu, uy, n_total = _correlations(u / scale[:, None], y, n_lags)
        lag = np.arange(n_lags)
        blocks = uu[:, :, (lag[:, None] - lag[None, :]) % uu.shape[-1]]  # c_ij[a - b]
        used = (lag[None, :] < np.array(lags)[:, None]).ravel()  # (input, lag) terms fitted
        phi = blocks.transpose(0, 2, 1, 3).reshape(n_in * n_lags, n_in * n_lags)[used][:, used]
        rhs = uy[:, :, :n_lags].transpose(0, 2, 1).reshape(n_in * n_lags, n_out)[used]
        if self.method == "toeplitz":
            from scipy.linalg import solve, solve_toeplitz

            if n_in == 1:
                h = solve_toeplitz(uu[0, 0, :n_lags], rhs)
            else:
                h = solve(phi, rhs, assume_a="pos")
            self.order_ = int(used.sum())
        else:
            y_var = (y**2).sum(axis=(*range(y.ndim - 2), -1)) / n_total
            h, self.order_ = _pinv_mdl(phi, rhs, y_var, n_total, self.order)
        weights = np.zeros((n_in * n_lags, n_out))
        weights[used] = h
        self.irf_ = (weights.reshape(n_in, n_lags, n_out) / scale[:, None, None]).transpose(2, 0, 1)
        return self

    def predict(self, u: ArrayLike) -> NDArray[np.float64]:
        """Filter outputs for inputs ``u`` (zero initial conditions).

        Parameters
        ----------
        u : array_like, shape (..., n_inputs, n_times)

        Returns
        -------
        ndarray, shape (..., n_outputs, n_times)
        """
        self._check_fitted()
        return _filter(u, self.irf_)

    def score(self, u: ArrayLike, y: ArrayLike) -> float:
        """Mean over records of the VAF pooled over output channels, %."""
        return float(np.mean(vaf(_as_batch(y, "y"), self.predict(u), pool=-2)))


def _filter(u: ArrayLike, irf: NDArray[np.float64]) -> NDArray[np.float64]:
    """Causal FIR filtering of every record at once (FFT), zero initial conditions."""
    u = _as_batch(u, "u")
    if u.shape[-2] != irf.shape[1]:
        raise ParameterError(f"u: expected {irf.shape[1]} inputs, got {u.shape[-2]}")
    n = u.shape[-1]
    nfft = _fft_length(n + irf.shape[-1] - 1)
    spectrum = np.einsum("...if,oif->...of", np.fft.rfft(u, nfft), np.fft.rfft(irf, nfft))
    return np.fft.irfft(spectrum, nfft)[..., :n]


def _fft_length(n: int) -> int:
    """The smallest length >= ``n`` made of the factors 2, 3 and 5, at which NumPy's FFT is
    fastest (as ``scipy.fft.next_fast_len``, whose import costs every analysis 0.1 s: it
    imports ``scipy.special``). A power of two, up to twice as long, cost the analysis 3 %.

    Examples
    --------
    >>> _fft_length(1401), _fft_length(1500), _fft_length(1537)
    (1440, 1500, 1600)
    """
    best = 1 << (n - 1).bit_length()
    odd = 1  # 3^b 5^c
    while odd < best:
        factor = odd
        while factor < best:
            twos = (-(-n // factor) - 1).bit_length()  # the power of two that reaches n
            best = min(best, factor << twos)
            factor *= 3
        odd *= 5
    return best


def _correlations(
    u: NDArray[np.float64], y: NDArray[np.float64], n_lags: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Biased auto- and cross-correlations of all records, summed (FFT, no wrap-around).

    Returns ``uu[i, j, m] = sum_n u_i[n] u_j[n+m] / N`` (negative ``m`` at the end) and
    ``uy[i, c, k] = sum_n u_i[n] y_c[n+k] / N`` with ``N`` the total number of samples.
    """
    n = u.shape[-1]
    nfft = _fft_length(n + n_lags)
    fu = np.fft.rfft(u.reshape(-1, *u.shape[-2:]), nfft)
    fy = np.fft.rfft(y.reshape(-1, *y.shape[-2:]), nfft)
    cuu = np.einsum("rif,rjf->ijf", fu.conj(), fu)
    cuy = np.einsum("rif,rcf->icf", fu.conj(), fy)
    n_total = n * fu.shape[0]
    return np.fft.irfft(cuu, nfft) / n_total, np.fft.irfft(cuy, nfft) / n_total, n_total


def _pinv_mdl(
    phi: NDArray[np.float64],
    rhs: NDArray[np.float64],
    y_var: NDArray[np.float64],
    n_samples: int,
    order: int | None,
) -> tuple[NDArray[np.float64], int]:
    """Pseudo-inverse solution of ``phi @ h = rhs`` keeping the terms chosen by MDL.

    Each eigenvector term explains ``(v' rhs_c)^2 / lambda`` of output ``c``'s variance; terms
    are ranked by the variance they explain (each output normalised by its own variance, summed
    over outputs) and the number kept minimises ``R(m) * (1 + m ln N / N)``, ``R(m)`` being the
    unexplained normalised variance.
    """
    lam, vec = np.linalg.eigh(phi)
    usable = lam > lam[-1] * phi.shape[0] * np.finfo(float).eps
    lam, vec = lam[usable], vec[:, usable]
    coord = vec.T @ rhs
    gain = (coord**2 / lam[:, None] / np.where(y_var > 0, y_var, 1.0)).sum(axis=1)
    rank = np.argsort(gain)[::-1]
    if order is None:
        m = np.arange(1, rank.size + 1)
        residual = np.maximum(y_var.size - np.cumsum(gain[rank]), 0.0)
        order = int(m[np.argmin(residual * (1.0 + m * np.log(n_samples) / n_samples))])
    keep = rank[: min(int(order), rank.size)]
    return vec[:, keep] @ (coord[keep] / lam[keep, None]), keep.size


class PlatformFilters(Estimator):
    """The unloaded platform's force transients on every force channel, from the motor angle.

    The motor angle is low-pass filtered (zero-phase Butterworth) and differentiated by a local
    quadratic fit; the chosen pathways (angle, velocity, acceleration) feed one
    :class:`ImpulseResponse` whose outputs are the equally filtered force channels. Walking
    trials are corrected by subtracting :meth:`predict` from their filtered channels.

    Physically the unloaded plate's channels are ``A_c θ_h + B_c θ_h''`` (gravity tilt and
    inertia of the top plate, ``θ_h`` the hinge angle), and the hinge follows the motor through
    the drivetrain's compliance, a lightly damped resonance. Seen from the motor angle, the
    acceleration pathway therefore starts small, rings at that resonance and decays (paper 000,
    section 3.1), and the angle pathway is the static gain ``A_c``. The angle filter is 1 lag
    long by default: an angle filter as long as the acceleration filter can take over any part
    of the acceleration filter (the acceleration is a fixed 5-lag filter of the angle) without
    changing the prediction, so the split between the two pathways is undetermined and the
    fitted pathways are not the physical ones. On twin sessions both lengths predict held-out
    calibration trials equally well (pooled VAF 99.8 %) and give the same walking stiffness,
    while only the 1-lag angle pathway recovers the true gravity gains and in-band inertial
    response (see ``docs/guide/walking-analysis.md``).

    Parameters
    ----------
    inputs : sequence of {"angle", "velocity", "acceleration"}
        Input pathways. Paper 000 uses ``("acceleration",)``; the default adds the angle, through
        which gravity loads a tilting plate.
    n_lags : int
        Length of the velocity and acceleration filters, samples (paper 000: 100 at 1 kHz).
    angle_lags : int
        Length of the angle filter, samples; 1 (default) makes it a static gain. ``n_lags``
        reproduces the earlier default of equal lengths (an undetermined split).
    method : {"pinv", "toeplitz"}
        See :class:`ImpulseResponse`.
    cutoff_hz, filter_order : float, int
        Low-pass applied to the motor angle and the forces (paper 000: 20 Hz, 4th order).
    derivative_window : int
        Samples per local polynomial fit for the derivatives (paper 000: 5).
    channels : sequence of str
        Names of the force channels, in the order of the ``forces`` arrays.

    Attributes
    ----------
    irf_ : ndarray, shape (n_channels, n_inputs, max(lags))
        Filter weights: N per (rad, rad/s or rad/s²) per sample, zero beyond a pathway's length.
        With inputs low-passed at ``cutoff_hz``, neighbouring lags carry nearly the same input,
        and the last lag of a pathway stands in for the response beyond the filter's length:
        it jumps, and is not part of the decaying response (on the twin, zeroing it lowers the
        held-out VAF from 99.8 to 98.0 %; 150 or 300 lags move the jump to their own last lag
        and score 99.8 %).
    fs_ : float
        Sample rate the filters were fitted at, Hz.
    order_ : int
        Pseudo-inverse terms kept.
    rigid_gains_ : ndarray, shape (n_channels, 3)
        The same calibration fitted without memory: N per rad, per rad/s and per rad/s² of the
        low-passed angle and its two derivatives (least squares; the drivetrain's resonance is
        folded into them, so they are not the bare gravity and inertia). In the band the
        calibration excites they predict as the filters do; beyond it they grow as a rigid
        plate's forces do, where the filters, known only in that band, amplified a coupler
        twist with content near the cut-off (VAF −210 %). :meth:`predict_departure` uses them.
    """

    _parameter_constraints: ClassVar = {
        "inputs": [distinct_subset(INPUTS)],
        "n_lags": [_POSITIVE_INT],
        "angle_lags": [_POSITIVE_INT],
        "method": _METHOD,
        "cutoff_hz": [interval(0, closed="neither")],
        "filter_order": [_POSITIVE_INT],
        "derivative_window": [interval(3, integer=True)],
        "channels": [sequence_of(Constraint("a name", lambda v: isinstance(v, str)))],
    }
    _fitted_attribute: ClassVar = "irf_"

    def __init__(
        self,
        *,
        inputs: Sequence[Input] = ("angle", "acceleration"),
        n_lags: int = 100,
        angle_lags: int = 1,
        method: Method = "pinv",
        cutoff_hz: float = 20.0,
        filter_order: int = 4,
        derivative_window: int = 5,
        channels: Sequence[str] = CHANNELS,
    ) -> None:
        self.inputs = tuple(inputs)
        self.n_lags = n_lags
        self.angle_lags = angle_lags
        self.method = method
        self.cutoff_hz = cutoff_hz
        self.filter_order = filter_order
        self.derivative_window = derivative_window
        self.channels = tuple(channels)

    @property
    def lags(self) -> tuple[int, ...]:
        """Filter length of each input pathway, samples (``angle_lags`` or ``n_lags``)."""
        self._validate_params()
        return tuple(self.angle_lags if name == "angle" else self.n_lags for name in self.inputs)

    def input_signals(self, motor_angle: ArrayLike, fs: float) -> NDArray[np.float64]:
        """The filter inputs for a motor angle: shape ``(..., n_inputs, n_times)``."""
        self._validate_params()
        angle = lowpass(motor_angle, fs, self.cutoff_hz, order=self.filter_order)
        return self._kinematics(angle, fs, self.inputs)

    def fit(self, motor_angle: ArrayLike, forces: ArrayLike, *, fs: float) -> PlatformFilters:
        """Fit the filters on calibration data (nobody on the plate).

        Parameters
        ----------
        motor_angle : array_like, shape (..., n_times)
            Motor angle referred to the platform, rad (one or more records).
        forces : array_like, shape (..., n_channels, n_times)
            Force channels, N, unfiltered.
        fs : float
            Sample rate, Hz.

        Returns
        -------
        PlatformFilters
            ``self``, fitted.
        """
        forces = self._check_forces(forces)
        filtered = self._filtered(forces, fs)
        self._validate_params()
        angle = lowpass(motor_angle, fs, self.cutoff_hz, order=self.filter_order)
        every = self._kinematics(angle, fs)  # the filters' inputs are some of these
        est = ImpulseResponse(n_lags=self.lags, method=self.method)
        est.fit(every[..., [INPUTS.index(name) for name in self.inputs], :], filtered)
        self.irf_, self.order_, self.fs_ = est.irf_, est.order_, float(fs)
        kinematics = np.moveaxis(every, -2, 0).reshape(len(INPUTS), -1)
        outputs = np.moveaxis(filtered, -2, 0).reshape(len(self.channels), -1)
        gains = np.linalg.lstsq(kinematics.T, outputs.T, rcond=None)[0]
        self.rigid_gains_: NDArray[np.float64] = np.ascontiguousarray(gains.T, dtype=np.float64)
        return self

    def _kinematics(
        self, angle: NDArray[np.float64], fs: float, names: Sequence[str] = INPUTS
    ) -> NDArray[np.float64]:
        """The ``names`` of :data:`INPUTS` (a low-passed angle and its two derivatives) for
        ``angle``, shape ``(..., len(names), n_times)``; only those are computed."""
        window = self.derivative_window
        signals = {
            name: angle if order == 0 else derivative(angle, fs, window, deriv=order)
            for order, name in enumerate(INPUTS)
            if name in names
        }
        return np.stack([signals[name] for name in names], axis=-2)

    def _check_forces(self, forces: ArrayLike) -> NDArray[np.float64]:
        forces = _as_batch(forces, "forces")
        if forces.shape[-2] != len(self.channels):
            raise ParameterError(
                f"forces: expected {len(self.channels)} channels ({', '.join(self.channels)}) "
                f"on axis -2, got {forces.shape[-2]}"
            )
        return forces

    def _filtered(self, forces: NDArray[np.float64], fs: float) -> NDArray[np.float64]:
        return lowpass(forces, fs, self.cutoff_hz, order=self.filter_order)

    def predict(
        self, motor_angle: ArrayLike, *, combine: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """Platform force transients (low-pass domain), N.

        Parameters
        ----------
        motor_angle : array_like, shape (..., n_times)
            Motor angle relative to the platform's resting angle, rad (the angle pathway
            predicts no force at rest).
        combine : array_like, shape (n_combinations, n_channels), optional
            Predict these linear combinations of the channels instead of every channel (e.g.
            the sagittal resultants; cheaper when there are fewer combinations than channels).

        Returns
        -------
        ndarray, shape (..., n_channels or n_combinations, n_times)
        """
        self._check_fitted()
        angle = lowpass(motor_angle, self.fs_, self.cutoff_hz, order=self.filter_order)
        return self.predict_low_passed(angle, combine=combine)

    def predict_low_passed(
        self, angle: ArrayLike, *, combine: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """:meth:`predict` for a motor angle already low-passed as the filters' inputs are
        (``cutoff_hz``, ``filter_order``), N: a caller that needs the low-passed angle too
        filters it once."""
        self._check_fitted()
        irf = _combined(self.irf_, combine)
        inputs = self._kinematics(np.asarray(angle, dtype=float), self.fs_, self.inputs)
        return _filter(inputs, irf)

    def predict_departure(
        self, departure: ArrayLike, *, combine: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """The plate's own forces for a small ``departure`` of its angle from the motor's, N.

        Parameters
        ----------
        departure : array_like, shape (..., n_times)
            The plate's angle minus the motor's, rad, already low-passed at ``cutoff_hz``
            (it is not filtered again).
        combine : array_like, shape (n_combinations, n_channels), optional
            As in :meth:`predict`.

        Returns
        -------
        ndarray, shape (..., n_channels or n_combinations, n_times)
            From :attr:`rigid_gains_`.
        """
        self._check_fitted()
        gains = _combined(self.rigid_gains_, combine)
        kinematics = self._kinematics(np.asarray(departure, dtype=float), self.fs_)
        return np.einsum("ok,...kt->...ot", gains, kinematics)

    def vaf(
        self, motor_angle: ArrayLike, forces: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Held-out VAF per record, pooled over channels and per channel (DESIGN.md section 5).

        Parameters
        ----------
        motor_angle : array_like, shape (..., n_times)
        forces : array_like, shape (..., n_channels, n_times)
            Unfiltered channels; they are filtered as in :meth:`fit`.

        Returns
        -------
        pooled : ndarray, shape (...)
            ``100 * (1 - sum_c var(residual_c) / sum_c var(force_c))`` per record, %.
        by_channel : ndarray, shape (..., n_channels)
            Each channel's own VAF per record, %.
        """
        measured = self._filtered(self._check_forces(forces), self.fs_)
        predicted = self.predict(motor_angle)
        return vaf(measured, predicted, pool=-2), vaf(measured, predicted)

    def score(self, motor_angle: ArrayLike, forces: ArrayLike) -> float:
        """Mean over records of the pooled VAF, %."""
        return float(np.mean(self.vaf(motor_angle, forces)[0]))

    def to_dict(self, **extra: Any) -> dict[str, Any]:
        """JSON-ready description of the fitted filters (``extra`` keys are added)."""
        self._check_fitted()
        return {
            "format": FILTERS_FORMAT,
            "anklelab_version": __version__,
            "fs_hz": self.fs_,
            "inputs": list(self.inputs),
            "channels": list(self.channels),
            "n_lags": int(self.n_lags),
            "angle_lags": int(self.angle_lags),
            "method": self.method,
            "cutoff_hz": float(self.cutoff_hz),
            "filter_order": int(self.filter_order),
            "derivative_window": int(self.derivative_window),
            "order": int(self.order_),
            "irf": self.irf_.tolist(),
            "rigid_gains": self.rigid_gains_.tolist(),
            **extra,
        }

    def save(self, path: str | Path, **extra: Any) -> Path:
        """Write the filters to a JSON file atomically; ``extra`` keys are stored alongside."""
        return write_text_atomic(path, json.dumps(self.to_dict(**extra), indent=1))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, origin: str = "filters") -> PlatformFilters:
        """Rebuild fitted filters from :meth:`to_dict` output; errors name ``origin`` and key."""
        if data.get("format") != FILTERS_FORMAT:
            raise ParameterError(
                f"{origin}: format: expected {FILTERS_FORMAT!r}, got {data.get('format')!r:.40}"
            )
        _check_scalars(data, origin)
        try:
            filters = cls(
                inputs=data["inputs"],
                n_lags=data["n_lags"],
                # files written before per-pathway lengths used n_lags for the angle too
                angle_lags=data.get("angle_lags", data["n_lags"]),
                method=data["method"],
                cutoff_hz=data["cutoff_hz"],
                filter_order=data["filter_order"],
                derivative_window=data["derivative_window"],
                channels=data["channels"],
            )
            irf = np.asarray(data["irf"], dtype=float)
            fs, order = float(data["fs_hz"]), int(data["order"])
        except KeyError as exc:
            raise ParameterError(f"{origin}: required key {exc.args[0]!r} is missing") from None
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"{origin}: malformed value: {exc}") from None
        filters._validate_params()
        expected = (len(filters.channels), len(filters.inputs), max(filters.lags))
        if irf.shape != expected or not np.all(np.isfinite(irf)):
            raise ParameterError(
                f"{origin}: irf: expected finite values of shape {expected} "
                f"(channels, inputs, longest filter), got {irf.shape}"
            )
        filters.irf_, filters.fs_, filters.order_ = irf, fs, order
        filters.rigid_gains_ = _rigid_gains(data, filters, origin)
        return filters

    @classmethod
    def load(cls, path: str | Path) -> PlatformFilters:
        """Read filters written by :meth:`save`."""
        data = read_parameter_document(path, "json", what="filter file")
        return cls.from_dict(data, origin=str(path))


def _combined(weights: NDArray[np.float64], combine: ArrayLike | None) -> NDArray[np.float64]:
    """Per-channel ``weights`` (channels first), or their linear combinations ``combine``
    (shape ``(n_combinations, n_channels)``)."""
    if combine is None:
        return weights
    return np.einsum("mc,c...->m...", np.asarray(combine, dtype=float), weights)


def _rigid_gains(
    data: Mapping[str, Any], filters: PlatformFilters, origin: str
) -> NDArray[np.float64]:
    """The memoryless gains of a filter file; a file written before them had none, and its
    filters' weights summed over their lags (each pathway's low-frequency gain) stand in."""
    if "rigid_gains" not in data:
        summed = filters.irf_.sum(axis=-1)
        gains = np.zeros((len(filters.channels), len(INPUTS)))
        gains[:, [INPUTS.index(name) for name in filters.inputs]] = summed
        return gains
    try:
        gains = np.asarray(data["rigid_gains"], dtype=float)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"{origin}: rigid_gains: malformed value: {exc}") from None
    expected = (len(filters.channels), len(INPUTS))
    if gains.shape != expected or not np.all(np.isfinite(gains)):
        raise ParameterError(
            f"{origin}: rigid_gains: expected finite values of shape {expected} "
            f"(channels; angle, velocity, acceleration), got {gains.shape}"
        )
    return gains


def _check_scalars(data: Mapping[str, Any], origin: str) -> None:
    """The scalar settings of a filter file: positive integers, a positive finite rate and
    cutoff, a known method (a file edited by hand must fail here, not deep in the analysis)."""
    for key in ("n_lags", "angle_lags", "filter_order", "derivative_window", "order"):
        value = data.get(key, 1)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ParameterError(f"{origin}: {key}: expected a positive integer, got {value!r:.40}")
    for key in ("cutoff_hz", "fs_hz"):
        value = data.get(key, 1.0)
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not 0 < value < math.inf
        ):
            raise ParameterError(
                f"{origin}: {key}: expected a positive finite number, got {value!r:.40}"
            )
    if data.get("method", "pinv") not in get_args(Method):
        raise ParameterError(
            f"{origin}: method: expected one of {', '.join(get_args(Method))}, "
            f"got {data.get('method')!r:.40}"
        )
