"""Covariate adjustment: remove each trial's own gait variation, predicted from before the onset.

Every perturbed trial's response is its stance minus the mean unperturbed stance. What that
difference holds besides the perturbation is the trial's own departure from the average stride
(a slower loading, a longer stance, a COP that rolls faster), which at paper 000's first timing
point is as large as the perturbation torque of a soft ankle. Much of it is predictable from the
trial's own signals *before* the onset, which the perturbation cannot have touched: the
unperturbed trials show how a departure before the onset continues into the window.

So, per condition, the unperturbed trials (cut at the condition's median onset) teach a ridge
regression from pre-onset features — bin means of the raw (unfiltered) torque, vertical force
and ankle angle, as departures from the unperturbed mean, over the last ``span_ms`` before the
onset (ending ``guard_ms`` before it) — to the departure over the window; the prediction is
subtracted from every perturbed trial. This is regression adjustment in a randomised experiment
(ANCOVA; Lin 2013, Ann. Appl. Stat. 7:295): perturbations are assigned at random, so the
features of perturbed and unperturbed trials share one distribution and the adjustment changes
the expected response by nothing; it only removes variance. The ridge penalty is chosen by
generalised cross-validation on the unperturbed trials; a penalty of infinity (no adjustment) is
among the candidates, so a session whose strides are not predictable is left as it was.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["Adjustment", "fit_adjustment", "pre_onset_features"]

FEATURE_CHANNELS = ("torque_raw", "grf_z_raw", "angle_raw")
"""Raw stance channels the features are taken from."""
_RANK_TOLERANCE = 1e-6  # feature directions weaker than this (relative) carry no information
_PENALTIES = (1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3, np.inf)  # relative to the number of trials


@dataclass(frozen=True)
class Adjustment:
    """A fitted covariate adjustment, one ridge regression per response channel.

    Attributes
    ----------
    coef : ndarray, shape (n_channels, n_features, n_times)
        Maps standardised features to each channel's predicted departure.
    scale : ndarray, shape (n_features,)
        Feature standard deviations (features are divided by them).
    bounds : ndarray, shape (2, n_features)
        The smallest and largest feature values of the unperturbed trials: features are clipped
        to them, so the regression is never extrapolated.
    penalty : ndarray, shape (n_channels,)
        Chosen ridge penalty per trial, per channel (``inf``: that channel is not adjusted).
    explained : ndarray, shape (n_channels,)
        Fraction of each channel's departure variance the adjustment removes, by generalised
        cross-validation on the unperturbed trials.
    """

    coef: NDArray[np.float64]
    scale: NDArray[np.float64]
    bounds: NDArray[np.float64]
    penalty: NDArray[np.float64]
    explained: NDArray[np.float64]

    def predict(self, features: NDArray[np.float64]) -> NDArray[np.float64]:
        """Predicted departures, shape ``(n_trials, n_channels, n_times)``."""
        clipped = np.clip(features, self.bounds[0], self.bounds[1])
        return np.einsum("nf,cft->nct", clipped / self.scale, self.coef)


def pre_onset_features(
    raw: NDArray[np.float64],
    nominal: NDArray[np.float64],
    onset: NDArray[np.int64],
    fs: float,
    *,
    span_ms: float,
    guard_ms: float,
    n_bins: int,
) -> NDArray[np.float64]:
    """Bin means of each trial's departure from the nominal before its onset.

    Parameters
    ----------
    raw : ndarray, shape (n_trials, n_channels, n_times)
        Raw stance channels aligned at heel contact.
    nominal : ndarray, shape (n_channels, n_times)
        Their mean over the unperturbed trials.
    onset : ndarray of int, shape (n_trials,)
        Onset of each trial, samples after heel contact.
    fs : float
        Sample rate, Hz.
    span_ms, guard_ms : float
        The features cover ``[onset - span, onset - guard)`` (not before heel contact), ms.
    n_bins : int
        Equal bins over that span.

    Returns
    -------
    ndarray, shape (n_trials, n_channels * n_bins)
    """
    guard = max(1, round(guard_ms * fs / 1000.0))
    first = np.maximum(onset - round(span_ms * fs / 1000.0), 0)
    last = np.maximum(onset - guard, first + n_bins)
    edges = first[:, None] + ((last - first)[:, None] * np.arange(n_bins + 1)) // n_bins
    departure = raw - nominal
    total = np.concatenate([np.zeros((*departure.shape[:2], 1)), departure.cumsum(-1)], -1)
    sums = np.take_along_axis(
        total, np.broadcast_to(edges[:, None, :], (*raw.shape[:2], n_bins + 1)), -1
    )
    means = np.diff(sums, axis=-1) / np.maximum(np.diff(edges, axis=-1), 1)[:, None, :]
    return means.reshape(len(raw), -1)


def fit_adjustment(features: NDArray[np.float64], targets: NDArray[np.float64]) -> Adjustment:
    """Ridge regressions of each channel's departures on the features, penalties by GCV.

    Parameters
    ----------
    features : ndarray, shape (n_trials, n_features)
        Pre-onset features of the unperturbed trials (departures: mean about zero).
    targets : ndarray, shape (n_trials, n_channels, n_times)
        Their departures over the window.

    Returns
    -------
    Adjustment

    Examples
    --------
    Targets that are a linear function of the features plus noise are mostly explained:

    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(300, 4))
    >>> y = np.einsum("nf,fct->nct", x, rng.normal(size=(4, 2, 50)))
    >>> fit = fit_adjustment(x, y + 0.3 * rng.normal(size=y.shape))
    >>> bool(fit.explained.min() > 0.9), fit.predict(x[:2]).shape
    (True, (2, 2, 50))
    """
    n = len(features)
    scale = features.std(axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    u, s, vt = np.linalg.svd(features / scale, full_matrices=False)
    keep = s > _RANK_TOLERANCE * np.sqrt(n)  # standardised features: s ~ sqrt(n) when informative
    u, s, vt = u[:, keep], s[keep], vt[keep]
    uty = np.einsum("nk,nct->ckt", u, targets)  # (n_channels, n_directions, n_times)
    total = (targets**2).sum(axis=(0, 2))
    projected = (uty**2).sum(axis=2)  # (n_channels, n_directions)
    penalties = np.array(_PENALTIES)
    finite = np.isfinite(penalties)[:, None]
    shrink = np.where(finite, s**2 / (s**2 + np.where(finite, penalties[:, None], 1.0) * n), 0.0)
    residual = total[None, :] - (
        (2 * shrink - shrink**2) @ projected.T
    )  # (n_penalties, n_channels)
    gcv = residual / n / (1 - shrink.sum(axis=1, keepdims=True) / n) ** 2
    best = np.where(total > 0, gcv.argmin(axis=0), len(penalties) - 1)  # nothing to explain
    chosen = shrink[best]  # (n_channels, n_directions)
    coef = np.einsum("fk,ck,ckt->cft", vt.T, chosen / s, uty)
    with np.errstate(invalid="ignore", divide="ignore"):
        explained = np.clip(1.0 - gcv[best, np.arange(len(best))] * n / total, 0.0, 1.0)
    bounds = np.stack([features.min(axis=0), features.max(axis=0)])
    return Adjustment(coef, scale, bounds, penalties[best], np.nan_to_num(explained))
