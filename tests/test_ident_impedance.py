"""Second-order impedance by least squares, vectorised over repetitions and windows."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from anklelab.errors import NotFittedError, ParameterError
from anklelab.ident import ImpedanceModel, fit_impedance
from anklelab.signals import kinematics

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
