"""Walking impedance analysis of the default twin session vs a per-trial-loop implementation.

The baseline is paper 000's analysis written the straightforward way: every walking trial
filtered, corrected and segmented on its own, the platform filters applied channel by channel
with ``np.convolve``, one ``np.linalg.lstsq`` for the all-trial average and one per bootstrap
repetition and window. Both run with the paper's model (constant stiffness, no covariate
adjustment, no outlier screen, the motor angle taken as the plate's) and must give the same
all-trial stiffness (checked); ours also fits the linear model and resamples for the intervals,
the baseline does not.
"""

from __future__ import annotations

import numpy as np

from anklelab.forceplate import CHANNELS, ankle_torque, resultants, sagittal_load
from anklelab.pipelines.walking import WalkingSettings, analyze_walking, fit_platform_filters
from anklelab.pipelines.walking.stance import _cop_at_contact
from anklelab.signals import (
    bootstrap_weights,
    heel_contact,
    kinematics,
    lowpass,
    perturbation_onset,
)
from benchmarks._harness import Result, compare


def _trial(trial, info, settings, filters):
    """One walking trial: (kinematics, torque, dx, onset offset) aligned at heel contact."""
    fs = info.sample_rate_hz
    rec = trial.recording
    n_base = round(settings.baseline_ms * fs / 1000.0)
    motor = rec["motor_angle"] - rec["motor_angle"][:n_base].mean()
    channels = rec.stack(CHANNELS)
    channels = channels - channels[:, :n_base].mean(axis=1, keepdims=True)
    hc = int(heel_contact(channels[4:].sum(axis=0), fs, settings.heel_contact_threshold_n))
    inputs = filters.input_signals(motor, fs)
    predicted = np.array(
        [
            sum(
                np.convolve(inputs[i], filters.irf_[c, i])[: motor.size] for i in range(len(inputs))
            )
            for c in range(len(CHANNELS))
        ]
    )
    forces = lowpass(channels, fs, settings.cutoff_hz, order=settings.filter_order) - predicted
    load = sagittal_load(resultants(forces, info.force_plate), info.force_plate.anterior_axis)
    raw = sagittal_load(resultants(channels, info.force_plate), info.force_plate.anterior_axis)
    cop_x = load.cop_x.copy()
    cop_x[hc] = _cop_at_contact(
        raw.grf_z[None],
        (raw.grf_z * np.nan_to_num(raw.cop_x))[None],
        np.array([hc]),
        settings.heel_contact_threshold_n,
        fs,
        settings.contact_cop_ms,
        settings.contact_cop_degree,
    )[0]
    torque, dx = ankle_torque(
        type(load)(load.grf_x, load.grf_z, cop_x),
        hc,
        heel_to_ankle_m=info.heel_to_ankle_m,
        ankle_height_m=info.ankle_height_m,
    )
    ankle = lowpass(rec["ankle_angle"], fs, settings.cutoff_hz, order=settings.filter_order)
    kin = kinematics(ankle - ankle[hc], fs, settings.derivative_window)
    onset = perturbation_onset(motor, start=hc, min_amplitude_rad=settings.onset_min_amplitude_rad)
    offset = round(float(onset.index)) - hc if trial.perturbed else 0
    return np.vstack([kin, torque, dx])[:, hc:], offset


PAPER_SETTINGS = {
    "stiffness_model": "constant",
    "inertia_model": "point",
    "angle_gain": "measured",
    "covariate_adjustment": False,
    "outlier_mads": 1e9,
    "interval_reps": 100,
    "transmission_stiffness_nm_per_rad": 0.0,
    "force_delay_ms": 0.0,
}
"""Paper 000's model, which the loop below implements: constant stiffness, each point's own
inertia, the ankle angle as measured, no covariate adjustment, no outlier screen, the motor angle
taken as the plate's, the plate's channels taken as recorded (paper 000's DAQ has no anti-alias
filter to take out)."""


def per_trial_loop(session, settings):
    """The analysis trial by trial and repetition by repetition; stiffness by condition."""
    filters, *_ = fit_platform_filters(session, settings)
    fs = session.info.sample_rate_hz
    trials = [_trial(t, session.info, settings, filters) for t in session.walking]
    span = min(x.shape[1] for x, _ in trials)
    none = [
        x[:, :span] for (x, _), t in zip(trials, session.walking, strict=True) if not t.perturbed
    ]
    nominal = sum(none) / len(none)
    rng = np.random.default_rng(settings.seed)
    lengths = [round(w * fs / 1000.0) for w in settings.windows_ms()]
    ref = round(settings.offset_reference() * fs / 1000.0)
    keys = sorted(
        {(t.direction, t.delay_ms) for t in session.walking if t.perturbed},
        key=lambda k: (("dorsi", "plantar").index(k[0]), k[1]),
    )
    stiffness = {}
    for direction, delay in keys:
        responses = []
        for (x, offset), t in zip(trials, session.walking, strict=True):
            if t.perturbed and (t.direction, t.delay_ms) == (direction, delay):
                r0 = max(offset - ref, 0)
                window = slice(offset, offset + max(lengths))
                response = x[:4, window] - nominal[:4, window]
                response[[0, 3]] -= (x[[0, 3], r0] - nominal[[0, 3], r0])[:, None]
                responses.append(response)
        n = lengths[0]
        weights = bootstrap_weights(len(responses), settings.bootstrap_reps, 0.6, random_state=rng)
        for w in weights:
            average = sum(wi * r for wi, r in zip(w, responses, strict=True) if wi)
            for m in lengths:
                np.linalg.lstsq(average[:3, :m].T, average[3, :m], rcond=None)
        average = sum(responses) / len(responses)
        coef = np.linalg.lstsq(average[:3, :n].T, average[3, :n], rcond=None)[0]
        stiffness[f"{direction}/{delay:g}"] = float(coef[0])
    return stiffness


def _session():
    from anklelab.experiments import simulate_perturberator

    return simulate_perturberator(seed=0)


def run() -> list[Result]:
    session = _session()
    settings = WalkingSettings(**PAPER_SETTINGS)
    ours = analyze_walking(session, settings)
    theirs = per_trial_loop(session, settings)
    for tp in ours.timing_points:
        assert np.isclose(tp.stiffness.mean, theirs[tp.key], rtol=1e-6), tp.key
    n = len(session.walking)
    return [
        compare(
            f"walking analysis: {n} trials, {len(ours.timing_points)} conditions",
            lambda: analyze_walking(session, settings),
            lambda: per_trial_loop(session, settings),
            "per-trial / per-repetition loops",
            repeat=3,
        )
    ]
