"""Impulse-response estimation (correlation method, pseudo-inverse) and the platform filters."""

import json

import numpy as np
import pytest
from scipy.signal import freqz, lfilter

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
    est = ImpulseResponse(n_lags=30, method=method).fit(u, y)
    assert est.irf_.shape == irf.shape
    assert np.max(np.abs(est.irf_ - irf)) < 0.02 * np.max(np.abs(irf))
    assert est.score(u, y) > 99.0


def test_single_input_toeplitz_is_levinson_and_matches_least_squares():
    rng = np.random.default_rng(1)
    irf = _known_irf(n_out=4, n_in=1, n_lags=20)
    u = lfilter([1.0], [1.0, -0.8], rng.normal(size=5000))[None]  # coloured input
    y = _simulate(u, irf) + rng.normal(0, 0.1, (4, 5000))
    est = ImpulseResponse(n_lags=20, method="toeplitz").fit(u, y)
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
    est = ImpulseResponse(n_lags=15, method="toeplitz").fit(u, y)
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
    pinv = ImpulseResponse(n_lags=n_lags).fit(fit_u, fit_y)
    direct = ImpulseResponse(n_lags=n_lags, method="toeplitz").fit(fit_u, fit_y)
    assert 5 < pinv.order_ < n_lags
    assert pinv.score(test_u, test_y) >= direct.score(test_u, test_y) - 0.01
    assert pinv.score(test_u, test_y) > 98.0
    # the kept subspace carries all the filter's content in the input's band (after the start-up
    # transient, where the zero initial condition is a step the input never contains)
    error = pinv.predict(test_u) - _simulate(test_u, irf)
    assert np.max(np.abs(error[:, n_lags:])) < 0.01 * test_y.std()
    forced = ImpulseResponse(n_lags=n_lags, order=3).fit(fit_u, fit_y)
    assert forced.order_ == 3


def test_per_input_lengths_match_least_squares_on_the_shorter_design():
    """A 1-lag input (a static gain) beside a 20-lag one: the normal equations restricted to
    the fitted terms, and zeros beyond each input's own length."""
    rng = np.random.default_rng(5)
    u = lfilter([1.0], [1.0, -0.7], rng.normal(size=(2, 6000)), axis=-1)
    irf = _known_irf(n_out=3, n_in=2, n_lags=20)
    irf[:, 0, 1:] = 0.0
    y = _simulate(u, irf) + rng.normal(0, 0.1, (3, 6000))
    est = ImpulseResponse(n_lags=[1, 20], method="toeplitz").fit(u, y)
    assert est.irf_.shape == (3, 2, 20) and est.order_ == 21
    assert np.all(est.irf_[:, 0, 1:] == 0.0)
    uc, yc = u - u.mean(axis=1, keepdims=True), y - y.mean(axis=1, keepdims=True)
    lagged = [np.concatenate([np.zeros(k), uc[1, : uc.shape[1] - k]]) for k in range(20)]
    ols = np.linalg.lstsq(np.stack([uc[0], *lagged], axis=1), yc.T, rcond=None)[0].T
    assert np.allclose(est.irf_[:, 0, 0], ols[:, 0], atol=5e-3)
    assert np.allclose(est.irf_[:, 1], ols[:, 1:], atol=5e-3)
    assert np.allclose(est.irf_, irf, atol=0.05)
    with pytest.raises(ParameterError, match="one per input"):
        ImpulseResponse(n_lags=[1, 20, 5]).fit(u, y)
    with pytest.raises(ParameterError, match="n_lags"):
        ImpulseResponse(n_lags=[1, 0]).fit(u, y)


def test_not_fitted_and_bad_parameters():
    with pytest.raises(NotFittedError, match="ImpulseResponse"):
        ImpulseResponse().predict(np.zeros((1, 10)))
    with pytest.raises(ParameterError, match="method"):
        ImpulseResponse(method="fft").fit(np.ones((1, 10)), np.ones((1, 10)))
    with pytest.raises(ParameterError, match="constant"):
        ImpulseResponse(n_lags=5).fit(np.ones((1, 50)), np.ones((1, 50)))
    with pytest.raises(ParameterError, match="n_times must match"):
        ImpulseResponse(n_lags=5).fit(np.ones((1, 50)), np.ones((1, 40)))
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


def _mode(f_hz=60.0, zeta=0.1):
    """Unit-gain second-order resonance (bilinear): the ``(b, a)`` of a lightly damped mode."""
    w, c = 2 * np.pi * f_hz, 2 * FS
    a0, a1, a2 = (
        c * c + 2 * zeta * w * c + w * w,
        2 * w * w - 2 * c * c,
        c * c - 2 * zeta * w * c + w * w,
    )
    return np.array([1, 2, 1]) * w * w / a0, np.array([1, a1 / a0, a2 / a0])


def _plate(angle, inertial, gravity, rng, noise=0.3):
    """Forces of an unloaded plate: acceleration through a lightly damped 60 Hz mode + gravity."""
    acc = np.gradient(np.gradient(angle, 1 / FS), 1 / FS)
    ring = lfilter(*_mode(), acc)
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
    acc_only = PlatformFilters(inputs=("acceleration",)).fit(angles[0], forces[0], fs=FS)
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


def test_platform_filters_predict_a_low_passed_angle_as_the_raw_one(calibration):
    """predict_low_passed takes the angle low-passed as the filters' inputs are, and gives
    predict's forces exactly (combined channels too)."""
    angles, forces = calibration
    filters = PlatformFilters().fit(angles[0], forces[0], fs=FS)
    combine = np.eye(8)[:3]
    low = lowpass(angles[1], FS, filters.cutoff_hz, order=filters.filter_order)
    np.testing.assert_array_equal(filters.predict_low_passed(low), filters.predict(angles[1]))
    np.testing.assert_array_equal(
        filters.predict_low_passed(low, combine=combine),
        filters.predict(angles[1], combine=combine),
    )


def _band_response(irf, f_hz):
    """Frequency response of FIR weights (..., n_lags) at ``f_hz``."""
    return np.array([freqz(h, 1, worN=f_hz, fs=FS)[1] for h in irf.reshape(-1, irf.shape[-1])])


def test_platform_filters_recover_the_physical_pathways(calibration):
    """Static gain on the angle + a decaying 60 Hz resonance on the acceleration, both seen
    through the 20 Hz low-pass: with a 1-lag angle pathway (the default) each pathway is the
    true one within the band the data carry (1-15 Hz: acceleration within 1 % of the largest
    inertial gain, angle within 2 % of the largest gravity gain). With an angle filter as long
    as the acceleration's (the earlier default) the prediction is as good, but the angle pathway
    takes over part of the acceleration's: the split is not determined by the data."""
    angles, forces = calibration
    f = np.linspace(1.0, 15.0, 15)
    true_acc = INERTIAL[:, None] * freqz(*_mode(), worN=f, fs=FS)[1]
    static = PlatformFilters().fit(angles[0], forces[0], fs=FS)
    assert static.lags == (1, 100) and np.all(static.irf_[:, 0, 1:] == 0.0)
    assert np.allclose(static.irf_[:, 0, 0], GRAVITY, atol=0.02 * GRAVITY.max())
    acc = _band_response(static.irf_[:, 1], f)
    assert np.max(np.abs(acc - true_acc)) < 0.01 * np.abs(INERTIAL).max()
    assert np.allclose(static.irf_[:, 1].sum(axis=1), INERTIAL, atol=0.01 * INERTIAL.max())

    equal = PlatformFilters(angle_lags=100).fit(angles[0], forces[0], fs=FS)
    assert equal.lags == (100, 100)
    held_out = np.stack(angles[1:]), np.stack(forces[1:])
    assert abs(equal.score(*held_out) - static.score(*held_out)) < 0.05
    angle = _band_response(equal.irf_[:, 0], f)
    assert np.max(np.abs(angle - GRAVITY[:, None])) > 0.5 * GRAVITY.max()
    acc = _band_response(equal.irf_[:, 1], f)
    assert np.max(np.abs(acc - true_acc)) > 0.01 * np.abs(INERTIAL).max()


def test_platform_filters_save_and_load_round_trip(calibration, tmp_path):
    angles, forces = calibration
    filters = PlatformFilters(inputs=("angle", "velocity", "acceleration"), n_lags=50).fit(
        angles[0], forces[0], fs=FS
    )
    path = filters.save(tmp_path / "filters.json", calibration_vaf_percent=[99.0])
    loaded = PlatformFilters.load(path)
    assert loaded.inputs == ("angle", "velocity", "acceleration") and loaded.n_lags == 50
    assert loaded.channels == CHANNELS and loaded.fs_ == FS
    assert np.array_equal(loaded.predict(angles[1]), filters.predict(angles[1]))
    assert np.array_equal(loaded.rigid_gains_, filters.rigid_gains_)
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
        PlatformFilters(inputs=("jerk",)).fit(np.zeros(100), np.zeros((8, 100)), fs=FS)
    with pytest.raises(ParameterError, match="angle_lags"):
        PlatformFilters(angle_lags=0).fit(np.zeros(100), np.zeros((8, 100)), fs=FS)


def test_platform_filters_file_written_before_per_pathway_lengths_still_loads(calibration):
    """Files without ``angle_lags`` were fitted with every pathway ``n_lags`` long."""
    angles, forces = calibration
    filters = PlatformFilters(n_lags=40, angle_lags=40).fit(angles[0], forces[0], fs=FS)
    old = filters.to_dict()
    del old["angle_lags"]
    loaded = PlatformFilters.from_dict(old)
    assert loaded.lags == (40, 40)
    assert np.array_equal(loaded.predict(angles[1]), filters.predict(angles[1]))
    new = PlatformFilters.from_dict(
        PlatformFilters(n_lags=40).fit(angles[0], forces[0], fs=FS).to_dict()
    )
    assert new.lags == (1, 40) and new.irf_.shape == (8, 2, 40)


def test_rigid_gains_reproduce_the_filters_in_band_without_their_memory(calibration):
    """The memoryless fit of the same calibration predicts what a slow departure of the plate
    from the motor adds to its forces as the filters do, within 4 % (the drivetrain's 60 Hz
    mode is folded into its three gains, so they are not the bare gravity and inertia)."""
    angles, forces = calibration
    filters = PlatformFilters().fit(angles[0], forces[0], fs=FS)
    assert filters.rigid_gains_.shape == (8, 3)
    t = np.arange(2000) / FS
    departure = 1e-3 * np.sin(2 * np.pi * 3.0 * t)
    predicted = filters.predict_departure(departure)
    inner = slice(300, -300)  # the filters start from rest; the derivative fits are one-sided
    reference = filters.predict(departure)[:, inner]
    assert np.allclose(predicted[:, inner], reference, atol=0.04 * np.abs(reference).max())
    combine = np.ones((1, 8))
    assert np.allclose(filters.predict_departure(departure, combine=combine), predicted.sum(0))


def test_a_filter_file_without_rigid_gains_takes_the_filters_summed_gains(calibration, tmp_path):
    """Files written before the rigid gains: each pathway's low-frequency gain (its weights
    summed) stands in, with no velocity gain when the filters have no velocity pathway."""
    angles, forces = calibration
    filters = PlatformFilters().fit(angles[0], forces[0], fs=FS)
    old = filters.to_dict()
    del old["rigid_gains"]
    gains = PlatformFilters.from_dict(old).rigid_gains_
    assert np.allclose(gains[:, 0], filters.irf_[:, 0].sum(axis=1), rtol=1e-12)
    assert np.array_equal(gains[:, 1], np.zeros(8))
    assert np.allclose(gains[:, 2], filters.irf_[:, 1].sum(axis=1), rtol=1e-12)
    # they predict a slow departure as the fitted gains do, within 5 % of its largest force
    departure = 1e-3 * np.sin(2 * np.pi * 3.0 * np.arange(2000) / FS)
    fitted = filters.predict_departure(departure)[:, 300:-300]
    standing_in = PlatformFilters.from_dict(old).predict_departure(departure)[:, 300:-300]
    assert np.allclose(standing_in, fitted, atol=0.05 * np.abs(fitted).max())
    path = tmp_path / "f.json"
    for bad in ([[1.0, 2.0]], [[float("nan")] * 3] * 8):
        path.write_text(json.dumps(filters.to_dict() | {"rigid_gains": bad}))
        with pytest.raises(ParameterError, match="rigid_gains: expected finite values of shape"):
            PlatformFilters.load(path)


def test_fft_lengths_are_scipys_fast_lengths():
    from scipy.fft import next_fast_len

    from anklelab.ident.irf import _fft_length

    lengths = [*range(1, 3000), 4097, 15_001, 65_537]
    assert [_fft_length(n) for n in lengths] == [next_fast_len(n, real=True) for n in lengths]
