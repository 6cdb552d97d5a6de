"""Impulse-response estimation (correlation method, pseudo-inverse) and the platform filters."""

import json

import numpy as np
import pytest
from scipy.signal import lfilter

from anklelab.errors import NotFittedError, ParameterError
from anklelab.forceplate import CHANNELS
from anklelab.ident import ImpulseResponse, PlatformFilters
from anklelab.signals import lowpass

FS = 1000.0


def _simulate(u, irf):
    """y_c = sum_i h_ci * u_i, causal, zero initial conditions (the definition, by lfilter)."""
    return np.stack(
        [
            sum(lfilter(irf[c, i], [1.0], u[..., i, :]) for i in range(irf.shape[1]))
            for c in range(irf.shape[0])
        ],
        axis=-2,
    )


def _known_irf(n_out=3, n_in=2, n_lags=30):
    k = np.arange(n_lags)
    irf = np.empty((n_out, n_in, n_lags))
    for c in range(n_out):
        for i in range(n_in):
            irf[c, i] = (c + 1) * (-1) ** i * np.exp(-k / (5 + 3 * i)) * np.cos(0.3 * (c + 1) * k)
    return irf


@pytest.mark.parametrize("method", ["toeplitz", "pinv"])
def test_recovers_known_multi_input_filters_from_white_inputs(method):
    rng = np.random.default_rng(0)
    irf = _known_irf()
    u = rng.normal(size=(2, 20000))
    y = _simulate(u, irf) + rng.normal(0, 0.05, (3, 20000))
    est = ImpulseResponse(30, method=method).fit(u, y)
    assert est.irf_.shape == irf.shape
    assert np.max(np.abs(est.irf_ - irf)) < 0.02 * np.max(np.abs(irf))
    assert est.score(u, y) > 99.0


def test_single_input_toeplitz_is_levinson_and_matches_least_squares():
    rng = np.random.default_rng(1)
    irf = _known_irf(n_out=4, n_in=1, n_lags=20)
    u = lfilter([1.0], [1.0, -0.8], rng.normal(size=5000))[None]  # coloured input
    y = _simulate(u, irf) + rng.normal(0, 0.1, (4, 5000))
    est = ImpulseResponse(20, method="toeplitz").fit(u, y)
    # reference: ordinary least squares on the lagged (Hankel) data matrix, demeaned
    uc, yc = u[0] - u[0].mean(), y - y.mean(axis=1, keepdims=True)
    lagged = np.stack([np.concatenate([np.zeros(k), uc[: uc.size - k]]) for k in range(20)], axis=1)
    ols = np.linalg.lstsq(lagged, yc.T, rcond=None)[0].T
    assert np.allclose(est.irf_[:, 0], ols, atol=5e-3)


def test_records_are_pooled():
    rng = np.random.default_rng(2)
    irf = _known_irf(n_out=2, n_in=1, n_lags=15)
    u = rng.normal(size=(4, 1, 3000))
    y = _simulate(u, irf)
    est = ImpulseResponse(15, method="toeplitz").fit(u, y)
    assert np.allclose(est.irf_, irf, atol=0.02)
    assert est.predict(u).shape == (4, 2, 3000)


def test_pinv_selects_an_order_for_a_low_pass_input_and_beats_the_direct_solution():
    """A 20 Hz low-passed input leaves most correlation eigenvalues at noise level."""
    rng = np.random.default_rng(3)
    n_lags = 100
    k = np.arange(n_lags)
    irf = (np.exp(-k / 8.0) * np.sin(2 * np.pi * 0.06 * k))[None, None]
    fit_u, test_u = (lowpass(rng.normal(size=(1, 20000)), FS, 20.0) for _ in range(2))
    noise = lambda: rng.normal(0, 0.02, (1, 20000))  # noqa: E731
    fit_y, test_y = _simulate(fit_u, irf) + noise(), _simulate(test_u, irf) + noise()
    pinv = ImpulseResponse(n_lags).fit(fit_u, fit_y)
    direct = ImpulseResponse(n_lags, method="toeplitz").fit(fit_u, fit_y)
    assert 5 < pinv.order_ < n_lags
    assert pinv.score(test_u, test_y) >= direct.score(test_u, test_y) - 0.01
    assert pinv.score(test_u, test_y) > 98.0
    # the kept subspace carries all the filter's content in the input's band (after the start-up
    # transient, where the zero initial condition is a step the input never contains)
    error = pinv.predict(test_u) - _simulate(test_u, irf)
    assert np.max(np.abs(error[:, n_lags:])) < 0.01 * test_y.std()
    forced = ImpulseResponse(n_lags, order=3).fit(fit_u, fit_y)
    assert forced.order_ == 3


def test_not_fitted_and_bad_parameters():
    with pytest.raises(NotFittedError, match="ImpulseResponse"):
        ImpulseResponse().predict(np.zeros((1, 10)))
    with pytest.raises(ParameterError, match="method"):
        ImpulseResponse(method="fft").fit(np.ones((1, 10)), np.ones((1, 10)))
    with pytest.raises(ParameterError, match="constant"):
        ImpulseResponse(5).fit(np.ones((1, 50)), np.ones((1, 50)))
    with pytest.raises(ParameterError, match="n_times must match"):
        ImpulseResponse(5).fit(np.ones((1, 50)), np.ones((1, 40)))
    with pytest.raises(NotFittedError, match="PlatformFilters"):
        PlatformFilters().predict(np.zeros(100))


def _ramps(rng, n=20000, amplitude=0.035):
    """Calibration-like motor angle: random-direction ramp-and-hold-and-back, random gaps."""
    x, t = np.zeros(n), 300
    ramp = np.arange(1, 76) / 75
    while t < n - 500:
        s = amplitude * rng.choice([-1.0, 1.0])
        seg = s * np.concatenate([ramp, np.ones(100), 1 - ramp])
        x[t : t + seg.size] = seg
        t += seg.size + int(rng.integers(0, 2000))
    return x


def _plate(angle, inertial, gravity, rng, noise=0.3):
    """Forces of an unloaded plate: acceleration through a lightly damped 60 Hz mode + gravity."""
    acc = np.gradient(np.gradient(angle, 1 / FS), 1 / FS)
    w, z, dt = 2 * np.pi * 60.0, 0.1, 1 / FS
    c = 2 / dt
    a0, a1, a2 = c * c + 2 * z * w * c + w * w, 2 * w * w - 2 * c * c, c * c - 2 * z * w * c + w * w
    ring = lfilter(np.array([1, 2, 1]) * w * w / a0, [1, a1 / a0, a2 / a0], acc)
    return (
        inertial[:, None] * ring + gravity[:, None] * angle + rng.normal(0, noise, (8, angle.size))
    )


INERTIAL = np.array([1.0, 1.0, 0.2, -0.2, 3.0, 3.0, -3.0, -3.0])  # N per rad/s^2
GRAVITY = np.array([60.0, 60.0, 0.0, 0.0, 8.0, -8.0, -8.0, 8.0])  # N per rad


@pytest.fixture(scope="module")
def calibration():
    rng = np.random.default_rng(4)
    angles = [_ramps(rng) for _ in range(3)]
    return angles, [_plate(a, INERTIAL, GRAVITY, rng) for a in angles]


def test_platform_filters_angle_pathway_captures_gravity(calibration):
    angles, forces = calibration
    both = PlatformFilters().fit(angles[0], forces[0], fs=FS)
    acc_only = PlatformFilters(("acceleration",)).fit(angles[0], forces[0], fs=FS)
    pooled, by_channel = both.vaf(np.stack(angles[1:]), np.stack(forces[1:]))
    assert pooled.shape == (2,) and by_channel.shape == (2, 8)
    assert np.all(pooled > 97.0)
    # static load of a held tilt: the angle pathway's DC gain is the gravity term
    assert np.allclose(both.irf_[:, 0].sum(axis=1), GRAVITY, atol=0.05 * GRAVITY.max())
    # during a hold the acceleration-only filters miss the gravity load
    hold = np.full(400, 0.035)
    hold[:75] = np.arange(75) / 75 * 0.035
    truth = GRAVITY * 0.035
    assert np.allclose(both.predict(hold)[:, -1], truth, atol=0.05 * truth.max())
    assert np.max(np.abs(acc_only.predict(hold)[:, -1] - truth)) > 0.2 * truth.max()


def test_platform_filters_save_and_load_round_trip(calibration, tmp_path):
    angles, forces = calibration
    filters = PlatformFilters(("angle", "velocity", "acceleration"), n_lags=50).fit(
        angles[0], forces[0], fs=FS
    )
    path = filters.save(tmp_path / "filters.json", calibration_vaf_percent=[99.0])
    loaded = PlatformFilters.load(path)
    assert loaded.inputs == ("angle", "velocity", "acceleration") and loaded.n_lags == 50
    assert loaded.channels == CHANNELS and loaded.fs_ == FS
    assert np.array_equal(loaded.predict(angles[1]), filters.predict(angles[1]))
    assert json.loads(path.read_text())["calibration_vaf_percent"] == [99.0]
    assert not list(tmp_path.glob(".*tmp"))


def test_platform_filters_bad_file_names_the_key(tmp_path):
    path = tmp_path / "f.json"
    path.write_text(json.dumps({"format": "anklelab-platform-filters/1", "inputs": ["angle"]}))
    with pytest.raises(ParameterError, match="'n_lags' is missing"):
        PlatformFilters.load(path)
    path.write_text("{")
    with pytest.raises(ParameterError, match="not valid JSON"):
        PlatformFilters.load(path)
    with pytest.raises(ParameterError, match="not found"):
        PlatformFilters.load(tmp_path / "missing.json")
    with pytest.raises(ParameterError, match="inputs"):
        PlatformFilters(("jerk",)).fit(np.zeros(100), np.zeros((8, 100)), fs=FS)
