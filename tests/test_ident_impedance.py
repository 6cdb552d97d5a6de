"""Second-order impedance by least squares, vectorised over repetitions and windows."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from anklelab.errors import NotFittedError, ParameterError
from anklelab.ident import ImpedanceModel, fit_impedance, impedance_torque
from anklelab.signals import kinematics, lowpass

FS = 1000.0
K, B, INERTIA = 1200.0, 2.5, 0.3


def _ramp(n=125, onset=0.0, amplitude=0.035):
    t = np.arange(n) / FS
    return amplitude * np.clip((t - onset) / 0.075, 0, 1)


def _smooth_ramp(n=160):
    """A ramp through a 40 Hz critically damped low-pass, solved accurately (smooth derivatives)."""
    w = 2 * np.pi * 40.0

    def rhs(t, s):
        target = 0.035 * min(max(t / 0.075, 0.0), 1.0)
        return [s[1], w * w * (target - s[0]) - 2 * w * s[1]]

    t = np.arange(n) / FS
    sol = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=1e-4)
    return sol.y[0]


def test_recovers_k_b_i_from_a_smooth_perturbation_with_quadratic_fit_derivatives():
    theta = _smooth_ramp()
    kin = kinematics(theta, FS, 5)
    torque = K * theta + B * kin[1] + INERTIA * kin[2]
    fit = fit_impedance(kin[:, :100], torque[:100])
    assert fit.stiffness == pytest.approx(K, rel=1e-9)
    assert fit.damping == pytest.approx(B, rel=1e-7)
    assert fit.inertia == pytest.approx(INERTIA, rel=1e-7)
    assert fit.vaf == pytest.approx(100.0)


def test_windows_and_repetitions_in_one_call_match_separate_fits():
    rng = np.random.default_rng(0)
    theta = _smooth_ramp()[None] * rng.uniform(0.8, 1.2, (7, 1))
    kin = kinematics(theta, FS, 5)
    torque = K * kin[:, 0] + B * kin[:, 1] + INERTIA * kin[:, 2] + rng.normal(0, 0.3, theta.shape)
    fits = fit_impedance(kin, torque, lengths=[100, 75, 125])
    assert fits.stiffness.shape == (3, 7)
    for w, n in enumerate([100, 75, 125]):
        for r in (0, 6):
            x = kin[r, :, :n].T
            coef, *_ = np.linalg.lstsq(x, torque[r, :n], rcond=None)
            assert np.allclose([fits.stiffness[w, r], fits.damping[w, r], fits.inertia[w, r]], coef)
            res = torque[r, :n] - x @ coef
            assert fits.vaf[w, r] == pytest.approx(100 * (1 - res.var() / torque[r, :n].var()))


def test_estimator_interface():
    theta = _smooth_ramp()[:100]
    kin = kinematics(theta, FS)
    torque = K * kin[0] + B * kin[1] + INERTIA * kin[2]
    with pytest.raises(NotFittedError, match="ImpedanceModel"):
        ImpedanceModel().predict(kin)
    model = ImpedanceModel().fit(kin, torque)
    assert model.stiffness_ == pytest.approx(K) and model.inertia_ == pytest.approx(INERTIA)
    assert np.allclose(model.predict(kin), torque)
    assert model.score(kin, torque) == pytest.approx(100.0)
    with pytest.raises(ParameterError, match="kinematics, torque"):
        fit_impedance(kin[:2], torque)
    with pytest.raises(ParameterError, match="lengths"):
        fit_impedance(kin, torque, lengths=[200])


# --- stiffness changing linearly within the window ----------------------------------------------

K0, K1 = 300.0, 1000.0  # N·m/rad at the θ²-weighted time and N·m/rad/s: a human-like rise


def _rising(n=100):
    """Smooth ramp, its quadratic-fit derivatives and the torque of a linearly rising stiffness,
    with ``t_c`` the θ²-weighted mean time of the first ``n`` samples."""
    theta = _smooth_ramp()
    kin = kinematics(theta, FS, 5)
    t = np.arange(theta.size) / FS
    centre = (theta[:n] ** 2 @ t[:n]) / (theta[:n] @ theta[:n])
    torque = (K0 + K1 * (t - centre)) * theta + B * kin[1] + INERTIA * kin[2]
    return kin, torque, t, centre


def test_linear_stiffness_model_recovers_k0_at_the_weighted_time_slope_damping_and_inertia():
    kin, torque, _, _ = _rising()
    fit = fit_impedance(kin[:, :100], torque[:100], stiffness_model="linear", fs=FS)
    assert fit.stiffness == pytest.approx(K0, rel=1e-9)
    assert fit.stiffness_slope == pytest.approx(K1, rel=1e-9)
    assert fit.damping == pytest.approx(B, rel=1e-7)
    assert fit.inertia == pytest.approx(INERTIA, rel=1e-7)
    assert fit.vaf == pytest.approx(100.0)


def test_constant_model_bias_is_the_omitted_variable_bias_of_the_slope_term():
    """Least squares with the term ``z = k1 (t - t_c) θ`` left out: the estimates move by
    ``k1 (XᵀX)⁻¹ Xᵀ z``. ``t_c`` makes ``z`` orthogonal to θ, so the bias enters only through the
    ramp's velocity and acceleration (which come early in the window, where ``t < t_c``): the
    damping absorbs part of the rise and the stiffness comes out above its θ²-weighted value."""
    kin, torque, t, centre = _rising()
    x = kin[:, :100].T
    z = (t[:100] - centre) * kin[0, :100]
    assert x[:, 0] @ z == pytest.approx(0.0, abs=1e-12)
    bias = K1 * np.linalg.lstsq(x, z, rcond=None)[0]
    fit = fit_impedance(kin[:, :100], torque[:100])
    assert [fit.stiffness, fit.damping, fit.inertia] == pytest.approx(
        [K0 + bias[0], B + bias[1], INERTIA + bias[2]], rel=1e-9
    )
    assert bias[0] > 0.05 * K0 and bias[1] < -0.5 * B  # the pattern seen on the walking twin
    assert fit.stiffness_slope == 0.0


def test_linear_model_over_windows_and_repetitions_matches_separate_fits():
    rng = np.random.default_rng(1)
    kin0, torque0, t, _ = _rising()
    gain = rng.uniform(0.8, 1.2, (5, 1))
    kin = kin0[None] * gain[:, None]
    torque = torque0 * gain + rng.normal(0, 0.05, (5, torque0.size))
    fits = fit_impedance(kin, torque, lengths=[100, 75, 125], stiffness_model="linear", fs=FS)
    assert fits.stiffness.shape == fits.stiffness_slope.shape == (3, 5)
    for w, n in enumerate([100, 75, 125]):
        for r in (0, 4):
            theta = kin[r, 0, :n]
            centre = (theta**2 @ t[:n]) / (theta @ theta)
            x = np.column_stack([theta, kin[r, 1, :n], kin[r, 2, :n], (t[:n] - centre) * theta])
            coef, *_ = np.linalg.lstsq(x, torque[r, :n], rcond=None)
            got = [fits.stiffness, fits.damping, fits.inertia, fits.stiffness_slope]
            assert np.allclose([g[w, r] for g in got], coef, rtol=1e-8)
            res = torque[r, :n] - x @ coef
            assert fits.vaf[w, r] == pytest.approx(100 * (1 - res.var() / torque[r, :n].var()))


def test_low_passed_data_need_the_low_passed_product_of_time_and_the_raw_angle():
    """``L(k(t) θ) ≠ k(t) L(θ)``: after paper 000's 20 Hz low-pass the slope's regressor must be
    ``L(t θ)`` of the unfiltered angle; ``t L(θ)`` reads the damping high and the stiffness low."""
    pad = np.zeros(300)  # the window sits far from the record's ends (the filter's edges)
    theta = np.concatenate([pad, _smooth_ramp(), np.full(300, _smooth_ramp()[-1])])
    kin_raw = kinematics(theta, FS, 5)
    t = (np.arange(theta.size) - pad.size) / FS  # time from the window's start
    torque = (K0 + K1 * t) * theta + B * kin_raw[1] + INERTIA * kin_raw[2]
    theta_f, torque_f = lowpass(theta, FS, 20.0), lowpass(torque, FS, 20.0)
    window = slice(pad.size, pad.size + 100)
    kin = kinematics(theta_f, FS, 5)[:, window]
    product = lowpass(t * theta, FS, 20.0)[window]
    weight = theta_f[window] ** 2
    expected = K0 + K1 * (weight @ t[window]) / weight.sum()  # θ²-weighted, as filtered
    fit = fit_impedance(kin, torque_f[window], stiffness_model="linear", fs=FS, time_angle=product)
    assert [fit.stiffness, fit.stiffness_slope, fit.damping, fit.inertia] == pytest.approx(
        [expected, K1, B, INERTIA], rel=1e-9
    )
    assert np.allclose(
        impedance_torque(fit, kin, FS, time_angle=product), torque_f[window], atol=1e-9
    )
    model = ImpedanceModel(stiffness_model="linear").fit(
        kin, torque_f[window], fs=FS, time_angle=product
    )
    assert model.score(kin, torque_f[window], time_angle=product) == pytest.approx(100.0)
    plain = fit_impedance(kin, torque_f[window], stiffness_model="linear", fs=FS)
    assert plain.damping > 1.03 * B and plain.stiffness < 0.997 * expected
    with pytest.raises(ParameterError, match="time_angle"):
        fit_impedance(kin, torque_f[window], stiffness_model="linear", fs=FS, time_angle=t)


def test_linear_model_estimator_and_model_torque():
    kin, torque, _, _ = _rising()
    model = ImpedanceModel(stiffness_model="linear").fit(kin[:, :100], torque[:100], fs=FS)
    assert model.stiffness_slope_ == pytest.approx(K1)
    assert np.allclose(model.predict(kin[:, :100]), torque[:100])
    assert model.score(kin[:, :100], torque[:100]) == pytest.approx(100.0)
    fit = fit_impedance(kin[:, :100], torque[:100], stiffness_model="linear", fs=FS)
    assert np.allclose(impedance_torque(fit, kin[:, :100], FS), torque[:100])
    with pytest.raises(ParameterError, match="fs"):
        impedance_torque(fit, kin[:, :100])
    with pytest.raises(ParameterError, match="fs"):
        ImpedanceModel(stiffness_model="linear").fit(kin[:, :100], torque[:100])
    with pytest.raises(ParameterError, match="stiffness_model"):
        fit_impedance(kin, torque, stiffness_model="quadratic")  # type: ignore[arg-type]


def test_a_shared_inertia_is_the_joint_fit_of_records_with_their_own_stiffness_and_damping():
    """Records that share one inertia: the sums of their terms give the least-squares inertia of
    the joint fit (each its own k, b; here also k₁), a fit around a given inertia equals the
    free fit when given the free fit's own, and the shared inertia is the better determined
    (whether the stiffnesses gain depends on the noise: see the walking pipeline's test)."""
    from anklelab.ident import inertia_terms

    rng = np.random.default_rng(3)
    n_records, n = 8, 125
    theta = _smooth_ramp(n)[None] * rng.uniform(0.7, 1.3, (n_records, 1))
    kin = kinematics(theta, FS, 5)
    k = rng.uniform(300.0, 1500.0, n_records)
    b = rng.uniform(1.0, 6.0, n_records)
    torque = k[:, None] * kin[:, 0] + b[:, None] * kin[:, 1] + INERTIA * kin[:, 2]
    noisy = torque + rng.normal(0.0, 0.4, torque.shape)
    for model in ("constant", "linear"):
        options = {"stiffness_model": model, "fs": FS}
        free = fit_impedance(kin, noisy, [100, 75, 125], **options)
        terms = inertia_terms(kin, noisy, [100, 75, 125], **options)
        assert terms.numerator.shape == terms.denominator.shape == (3, n_records)
        assert np.allclose(terms.numerator / terms.denominator, free.inertia)
        again = fit_impedance(kin, noisy, [100, 75, 125], inertia=free.inertia, **options)
        assert all(np.allclose(a, f) for a, f in zip(again, free, strict=True))
        shared = terms.numerator.sum(axis=1) / terms.denominator.sum(axis=1)
        # the joint least squares, written out: per record [θ, θ' (, t θ)], one θ'' column
        x = [kin[r, :2, :100].T for r in range(n_records)]
        if model == "linear":
            x = [np.column_stack([xr, np.arange(100) / FS * kin[r, 0, :100]]) for r, xr in
                 enumerate(x)]  # fmt: skip
        width = x[0].shape[1]
        joint = np.zeros((n_records * 100, n_records * width + 1))
        for r in range(n_records):
            joint[r * 100 : (r + 1) * 100, r * width : (r + 1) * width] = x[r]
            joint[r * 100 : (r + 1) * 100, -1] = kin[r, 2, :100]
        coef, *_ = np.linalg.lstsq(joint, noisy[:, :100].ravel(), rcond=None)
        assert shared[0] == pytest.approx(coef[-1], rel=1e-9)
        around = fit_impedance(kin, noisy, [100, 75, 125], inertia=shared[:, None], **options)
        assert np.all(around.inertia == shared[:, None])
        assert abs(shared[0] - INERTIA) < np.abs(free.inertia[0] - INERTIA).mean()
    exact = inertia_terms(kin, torque, stiffness_model="constant")
    assert exact.numerator.sum() / exact.denominator.sum() == pytest.approx(INERTIA, rel=1e-9)


def test_a_known_inertia_of_the_wrong_shape_is_named_and_the_fit_owns_its_arrays():
    theta = _smooth_ramp()
    kin = kinematics(theta, FS, 5)
    torque = K * theta + B * kin[1] + INERTIA * kin[2]
    fit = fit_impedance(kin, torque, lengths=[100, 75], inertia=[INERTIA, INERTIA])
    assert fit.inertia.flags.writeable and fit.inertia.shape == (2,)
    assert fit.stiffness == pytest.approx([K, K], rel=1e-6)
    with pytest.raises(ParameterError, match=r"inertia: expected the fields' shape \(2,\)"):
        fit_impedance(kin, torque, lengths=[100, 75], inertia=[0.1, 0.2, 0.3])
