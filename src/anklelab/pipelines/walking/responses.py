"""Perturbation responses of one condition: each trial minus the nominal stance, adjusted.

For every perturbed trial of a condition (``"dorsi/225"``) the window after its own detected
onset is cut, the mean unperturbed trial at the same times after heel contact is subtracted,
the angle and torque offsets are read ``offset_reference`` before the onset (before the
zero-phase low-pass has spread the perturbation backwards) and removed, and the trial's own
gait variation predicted from before the onset is subtracted (:mod:`.adjustment`). The
unperturbed trials cut at the condition's median onset give the same departures without a
perturbation: they train the adjustment, and their residuals carry the nominal's own sampling
error into the intervals.

A trial whose response departs from the others' median by more than ``outlier_mads`` robust
standard deviations at any sample (a glitch in one channel, a trial from another experiment)
would dominate the ensemble; it is dropped with a reason naming the trial. (A one-sample glitch
of 1e6 N is dropped earlier, by the stance: its vertical force rings far below zero.)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import cast

import numpy as np
from numpy.typing import NDArray

from anklelab.pipelines.walking.adjustment import (
    FEATURE_CHANNELS,
    fit_adjustment,
    pre_onset_features,
)
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import samples
from anklelab.signals import Trials

__all__ = ["RESPONSE", "Responses", "condition_responses", "outliers"]

RESPONSE = ("angle", "velocity", "acceleration", "torque", "time_angle", "plate_angle")
"""Channels of a response: rad, rad/s, rad/s², N·m; rad·s: the time since the onset times the
unfiltered angle, low-passed (the regressor of a stiffness that changes in time); and rad: the
plate's rotation (the reference of the angle's gain, :mod:`.gain`)."""
_CUT = (*RESPONSE, "torque_untwisted")  # cut from the stance: the responses, then the torque
# without the coupler's twist correction, which only its average leaves
_ANGLE, _TORQUE, _TIME_ANGLE = (RESPONSE.index(name) for name in ("angle", "torque", "time_angle"))
_OFFSETS = [_ANGLE, _TORQUE, _CUT.index("torque_untwisted"), _CUT.index("plate_angle")]
_SCREENED = [RESPONSE.index("angle"), RESPONSE.index("torque")]
_MAD_TO_SD = 1.4826
_MIN_SCREENED = 5  # the median and MAD of 5 still stand one wild trial in 5 (a 1e6 N glitch)


@dataclass(frozen=True)
class Responses:
    """The responses of one condition over the longest window.

    Attributes
    ----------
    perturbed : Trials
        One response per kept perturbed trial, channels :data:`RESPONSE`, time 0 at the onset;
        metadata ``trial``, ``onset_ms``, ``offset`` (onset, samples after heel contact).
    unperturbed : ndarray, shape (n_unperturbed, len(RESPONSE), n_window)
        The unperturbed trials' departures at the median onset, adjusted like the responses
        (mean zero): what the nominal's sampling error adds.
    nominal_dx : ndarray, shape (n_window,)
        Mean nominal lever arm over the perturbed trials' windows, m.
    twist_torque : ndarray, shape (n_window,)
        What the torque response loses without the coupler's twist correction (the kept
        perturbed trials' mean), N·m: how much the estimates lean on that correction.
    explained : float
        Fraction of the torque departures' variance the covariate adjustment removed (0: none).
    dropped : dict of int to str
        Stance-trial positions (``Trials.selection``) of perturbed trials dropped as outliers,
        with the reason.
    """

    perturbed: Trials
    unperturbed: NDArray[np.float64]
    nominal_dx: NDArray[np.float64]
    twist_torque: NDArray[np.float64]
    explained: float
    dropped: dict[int, str]


def _departures(
    stance: Trials,
    nominal: NDArray[np.float64],
    onset: NDArray[np.int64],
    reference: int,
    n_window: int,
) -> NDArray[np.float64]:
    """Each trial's channels ``_CUT`` minus the nominal, offsets removed.

    The stance's ``time_angle`` counts time from heel contact; the response's counts it from the
    onset, with the angle's offset ``c`` taken out like the angle's: ``L((t - t_on) (θ - c)) =
    L(t θ) - t_on L(θ) - c (t - t_on)`` (the zero-phase low-pass ``L`` keeps a straight line).
    """
    index = np.concatenate(
        [np.maximum(onset - reference, 0)[:, None], onset[:, None] + np.arange(n_window)], axis=1
    )
    picks = np.array([stance.ch_names.index(name) for name in _CUT])
    segment = stance.data[np.arange(len(index))[:, None, None], picks[:, None], index[:, None, :]]
    departure = segment - nominal[picks][:, index].transpose(1, 0, 2)
    since_onset = (index - onset[:, None]) / stance.fs
    angle = departure[:, _ANGLE]
    departure[:, _TIME_ANGLE] -= onset[:, None] / stance.fs * angle + angle[:, :1] * since_onset
    departure[:, _OFFSETS] -= departure[:, _OFFSETS, :1]
    return departure[..., 1:]


def outliers(data: NDArray[np.float64], limit: float) -> NDArray[np.bool_]:
    """Trials that depart from the trials' median by more than ``limit`` robust sd anywhere.

    The robust sd at each sample is 1.4826 × the median absolute deviation there, but never
    less than its median over time (where the trials happen to agree, as right after an offset
    is removed, a tiny spread must not turn ordinary departures into outliers).

    Parameters
    ----------
    data : ndarray, shape (n_trials, n_channels, n_times)
    limit : float
        In robust standard deviations.

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(30, 1, 50))
    >>> x[7, 0, 20] = 1e6
    >>> np.flatnonzero(outliers(x, 20.0)).tolist()
    [7]
    """
    if len(data) < _MIN_SCREENED:
        return np.zeros(len(data), dtype=bool)
    median = np.median(data, axis=0)
    spread = _MAD_TO_SD * np.median(np.abs(data - median), axis=0)
    typical = np.median(spread, axis=-1, keepdims=True)
    scale = np.maximum(spread, np.maximum(typical, np.finfo(float).tiny))
    # one flag per trial: ``any`` over the channel and time axes of a 3-D array is 1-D
    return cast("NDArray[np.bool_]", (np.abs(data - median) / scale > limit).any(axis=(1, 2)))


def condition_responses(
    stance: Trials, key: str, unperturbed: Trials, settings: WalkingSettings
) -> Responses:
    """The adjusted responses of condition ``key`` (see the module docstring).

    Parameters
    ----------
    stance : Trials
        Kept stance trials aligned at heel contact.
    key : str
        Condition, e.g. ``"dorsi/225"``.
    unperturbed : Trials
        The unperturbed stance trials (outliers already dropped).
    settings : WalkingSettings
        ``window_ms`` and sensitivity windows, ``offset_reference``, the adjustment and
        outlier settings.
    """
    group = stance[key]
    fs = stance.fs
    n_window = max(samples(w, fs) for w in settings.windows_ms())
    reference = round(settings.offset_reference() * fs / 1000.0)
    nominal = unperturbed.average()
    onset = group.metadata["offset"]
    cut = _departures(group, nominal, onset, reference, n_window)
    response, untwisted = cut[:, :-1], cut[:, -1]
    median_onset = np.full(len(unperturbed), int(np.median(onset)))
    baseline = _departures(unperturbed, nominal, median_onset, reference, n_window)[:, :-1]
    explained = 0.0
    if settings.covariate_adjustment:
        raw = [stance.ch_names.index(name) for name in FEATURE_CHANNELS]
        features = partial(
            pre_onset_features,
            span_ms=settings.adjustment_span_ms,
            guard_ms=settings.adjustment_guard_ms,
            n_bins=settings.adjustment_bins,
        )
        features_u = features(unperturbed.data[:, raw], nominal[raw], median_onset, fs)
        features_p = features(group.data[:, raw], nominal[raw], onset, fs)
        adjustment = fit_adjustment(features_u, baseline)
        response = response - adjustment.predict(features_p)
        baseline = baseline - adjustment.predict(features_u)
        explained = float(adjustment.explained[_TORQUE])
    wild = outliers(response[:, _SCREENED], settings.outlier_mads)
    dropped = {
        int(position): f"its response departs from the other {key} trials' median by more than "
        f"{settings.outlier_mads:g} robust sd (a glitch?) [trial {trial}]"
        for position, trial in zip(
            group.selection[wild], group.metadata["trial"][wild], strict=True
        )
    }
    dx = stance.ch_names.index("dx")
    index = onset[~wild, None] + np.arange(n_window)
    metadata = {name: group.metadata[name][~wild] for name in ("trial", "onset_ms", "offset")}
    return Responses(
        perturbed=Trials(response[~wild], fs, RESPONSE, metadata),
        unperturbed=baseline,
        nominal_dx=nominal[dx][index].mean(axis=0),
        twist_torque=(untwisted - cut[:, _TORQUE])[~wild].mean(axis=0),
        explained=explained,
        dropped=dropped,
    )
