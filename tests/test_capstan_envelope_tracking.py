"""The display envelope (analytic against the twin) and tracking beyond the feedback bandwidth
(inverse-dynamics feed-forward, ZPETC)."""

import math

import numpy as np
import pytest

from anklelab.control.envelope import display_envelope
from anklelab.control.pid import design_critically_damped
from anklelab.control.tracking import closed_loop_model, zpetc_reference
from anklelab.experiments.capstan import CapstanSetup, chirp_tracking
from anklelab.experiments.capstan.envelope import check_envelope

P = CapstanSetup().params


def test_envelope_limits_are_the_analytic_bounds():
    env = display_envelope([0.1, 1.0, 10.0], P, design_critically_damped(P), 1000.0, user=P.user)
    assert env.amplitude_rad[0] == pytest.approx(P.safety.angle_limit_rad)
    assert env.limiting == ["workspace", "speed", "torque"]
    # speed limit: A w |F_v| = v_max at 1 Hz, the 100 Hz speed filter barely matters there
    assert env.bounds["speed"][1] == pytest.approx(3.0 / (2 * np.pi), rel=1e-3)


@pytest.mark.parametrize("frequency", [0.2, 3.0, 20.0])
def test_the_twin_renders_the_analytic_envelope_within_10_percent(frequency):
    check = check_envelope(CapstanSetup(feedforward=True), [frequency], iterations=5)
    assert abs(check.error_percent[0]) < 10.0, (check.simulated_rad, check.reasons)
    assert check.reasons[0]  # the first amplitude above it did reach a limit


def test_zpetc_inverts_the_loop_model():
    p = CapstanSetup().params
    model = closed_loop_model(p, design_critically_damped(p), 1000.0, feedforward=False)
    t = np.arange(4000) / 1000.0
    desired = 0.05 * np.sin(2 * np.pi * 4.0 * t) * np.clip(t, 0, 1) * np.clip(4 - t, 0, 1)
    reference = zpetc_reference(desired, model)
    from scipy.signal import lfilter

    followed = lfilter(model.num, model.den, reference)  # the model driven by the prefilter
    plain = lfilter(model.num, model.den, desired)  # ... and by the trajectory itself
    assert np.max(np.abs(followed - desired)) < 0.1 * np.max(np.abs(plain - desired))


def test_feedforward_more_than_doubles_the_1_degree_chirp_tracking_limit():
    kwargs = dict(amplitude_rad=math.radians(1.0), f0_hz=0.2, f1_hz=10.0, duration_s=20.0)
    _, pid = chirp_tracking(CapstanSetup(), **kwargs)
    _, ff = chirp_tracking(CapstanSetup(feedforward=True), **kwargs)
    assert 3.0 < pid.tracking_limit_hz < 5.0
    assert ff.tracking_limit_hz > 2 * pid.tracking_limit_hz  # inf: within to the sweep's end
    assert ff.rms_error_rad < 0.2 * pid.rms_error_rad


def test_the_5_degree_chirp_is_tracked_to_the_sweep_end_with_feedforward():
    _, pid = chirp_tracking(CapstanSetup())
    run, zpetc = chirp_tracking(CapstanSetup(feedforward=True), zpetc=True)
    assert pid.tracking_limit_hz < 5.0 and math.isinf(zpetc.tracking_limit_hz)
    assert zpetc.rms_error_rad < 0.05 * pid.rms_error_rad and run["fault"].max() == 0
