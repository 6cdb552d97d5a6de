"""Impedance of one timing point and direction from the stance trials, with bootstrap.

Every perturbed trial of the condition is cut at its own detected onset; the mean unperturbed
trial, cut at the same time after heel contact, is subtracted; angle and torque offsets are read
``offset_reference`` before the onset (before the low-pass has spread the perturbation backwards
in time); bootstrap averages of random subsets of the trials are fitted with
``T = I θ'' + b θ' + k θ`` over the analysis and sensitivity windows.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.ident.impedance import ImpedanceFit, fit_impedance, impedance_torque
from anklelab.pipelines.walking.results import TimingPoint, sd
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import samples
from anklelab.signals import Trials

__all__ = ["DIRECTIONS", "condition_order", "timing_point"]

DIRECTIONS = ("dorsi", "plantar")
KINEMATICS = ("angle", "velocity", "acceleration")
RESPONSE = (*KINEMATICS, "torque")
_SLOPE_WARNING_FRACTION = 0.2  # stiffness change over the window / stiffness: warn above
_SLOPE_WARNING_SDS = 3.0  # ... if the slope also exceeds this many bootstrap sd


def condition_order(stance: Trials) -> list[str]:
    """The perturbed conditions (``"dorsi/225"``), dorsiflexion first, by timing point."""
    keys = [c for c in stance.conditions() if c != "none"]
    delay = dict(zip(stance.metadata["condition"], stance.metadata["delay_ms"], strict=True))
    return sorted(keys, key=lambda c: (DIRECTIONS.index(c.split("/")[0]), delay[c]))


def timing_point(
    stance: Trials,
    key: str,
    unperturbed: NDArray[np.float64],
    n_unperturbed: int,
    settings: WalkingSettings,
    seed: int | np.random.Generator,
) -> TimingPoint:
    """Bootstrap impedance of one condition (``"dorsi/225"``) from the stance trials.

    ``unperturbed`` is the mean unperturbed stance trial, shape (n_channels, n_times), channels
    as ``stance.ch_names``; ``seed`` draws the bootstrap subsets (a Generator continues its
    stream).
    """
    group = stance[key]
    fs = stance.fs
    windows = settings.windows_ms()
    lengths = [samples(w, fs) for w in windows]
    onset = group.metadata["offset"]
    reference = np.maximum(onset - round(settings.offset_reference() * fs / 1000.0), 0)
    index = np.concatenate([reference[:, None], onset[:, None] + np.arange(max(lengths))], axis=1)
    segment = np.take_along_axis(group.data, index[:, None, :], axis=-1)
    nominal = unperturbed[:, index].transpose(1, 0, 2)
    picks = [stance.ch_names.index(name) for name in RESPONSE]
    difference = segment[:, picks] - nominal[:, picks]
    offsets = [RESPONSE.index("angle"), RESPONSE.index("torque")]
    difference[:, offsets] -= difference[:, offsets, :1]
    response = Trials(difference[..., 1:], fs, RESPONSE)
    boot = response.bootstrap(
        settings.bootstrap_reps,
        settings.bootstrap_fraction,
        random_state=np.random.default_rng(seed),
    )
    kin, torque = boot.get_data(KINEMATICS), boot.get_data("torque")
    fit = fit_impedance(
        kin, torque, lengths=lengths, stiffness_model=settings.stiffness_model, fs=fs
    )
    n = lengths[0]
    analysis = ImpedanceFit(*(field[0] for field in fit))
    angle = response.get_data("angle")[:, :n].mean(axis=0)
    weight = angle**2
    dx = nominal[:, stance.ch_names.index("dx"), 1 : n + 1].mean(axis=0)
    return TimingPoint(
        delay_ms=float(group.metadata["delay_ms"][0]),
        direction=key.split("/")[0],
        n_perturbed=len(group),
        n_unperturbed=n_unperturbed,
        cop_m=float(weight @ dx / weight.sum()),
        stiffness=analysis.stiffness,
        damping=analysis.damping,
        inertia=analysis.inertia,
        vaf=analysis.vaf,
        stiffness_slope=analysis.stiffness_slope,
        window_stiffness={
            f"{w:g}": float(np.mean(k)) for w, k in zip(windows[1:], fit.stiffness[1:], strict=True)
        },
        onset_ms=group.metadata["onset_ms"],
        time_s=np.arange(n) / fs,
        angle=boot.get_data("angle")[:, :n],
        torque=torque[:, :n],
        model_torque=impedance_torque(analysis, kin[..., :n], fs),
        warnings=(
            ()
            if settings.stiffness_model == "linear"
            else _slope_warning(key, analysis.stiffness, kin[..., :n], torque[:, :n], fs)
        ),
    )


def _slope_warning(
    key: str,
    stiffness: NDArray[np.float64],
    kinematics: NDArray[np.float64],
    torque: NDArray[np.float64],
    fs: float,
) -> tuple[str, ...]:
    """A warning when a constant-stiffness estimate hides a stiffness that changes in its window.

    The linear stiffness model (:func:`~anklelab.ident.impedance.fit_impedance`,
    ``stiffness_model="linear"``) is fitted to the same bootstrap averages as a diagnostic. A
    warning is returned when the change it finds over the window, ``|k₁| × window``, exceeds
    ``_SLOPE_WARNING_FRACTION`` (20 %) of the constant model's stiffness and ``|k₁|``
    exceeds ``_SLOPE_WARNING_SDS`` (3) bootstrap sd (a slope that noise alone could produce is
    not reported).

    Parameters
    ----------
    key : str
        Condition named in the message (``"dorsi/225"``).
    stiffness : ndarray, shape (n_reps,)
        Bootstrap stiffness of the constant model, N·m/rad.
    kinematics : ndarray, shape (n_reps, 3, n_window)
        Bootstrap ``(θ, θ', θ'')`` over the analysis window, rad, rad/s, rad/s².
    torque : ndarray, shape (n_reps, n_window)
        Bootstrap torque over the window, N·m.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    tuple of str
        The warning, or nothing.
    """
    slope = fit_impedance(kinematics, torque, stiffness_model="linear", fs=fs).stiffness_slope
    mean, window_s, k = float(np.mean(slope)), torque.shape[-1] / fs, float(np.mean(stiffness))
    change = abs(mean) * window_s
    if change <= _SLOPE_WARNING_FRACTION * abs(k) or abs(mean) <= _SLOPE_WARNING_SDS * sd(slope):
        return ()
    return (
        f"{key}: the stiffness changes within the {window_s * 1000:g} ms window: the linear "
        f"model finds {mean:+.0f} ± {sd(slope):.0f} N·m/rad/s, {change / abs(k):.0%} of the "
        f"constant model's {k:.0f} N·m/rad over the window; a constant stiffness lets damping "
        'and inertia absorb the change and biases it: consider stiffness_model = "linear"',
    )
