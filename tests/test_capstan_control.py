"""Capstan control pieces: gain design, PID kernel vs wrapper, anti-windup, observer, haptics."""

import math

import numpy as np
import pytest

from anklelab.control import (
    DisturbanceObserver,
    PositionController,
    TerrainProfile,
    VirtualEnvironment,
    admittance_update,
    design_critically_damped,
)
from anklelab.control.haptics import new_admittance_state
from anklelab.experiments.capstan import CapstanSetup, simulate_closed_loop
from anklelab.platforms import load_platform
from anklelab.sim.capstan import linear_platform, reference_to_angle

P = load_platform("capstan")


@pytest.mark.parametrize("settling", [0.15, 0.2, 0.3])
def test_pd_design_places_a_double_pole(settling):
    g = design_critically_damped(P, settling_time_s=settling, integral_fraction=0.0)
    poles = reference_to_angle(P, g.kp_nm_per_rad, g.kd_nms_per_rad).poles()
    np.testing.assert_allclose(poles, [-5.83 / settling] * 2, rtol=1e-3)


def test_design_with_user_accounts_for_the_ankle():
    g = design_critically_damped(P, integral_fraction=0.0, with_user=True)
    poles = reference_to_angle(P, g.kp_nm_per_rad, g.kd_nms_per_rad, user=P.user).poles()
    np.testing.assert_allclose(poles, [-5.83 / 0.2] * 2, rtol=1e-3)
    with pytest.raises(ValueError, match="too slow"):
        design_critically_damped(P, settling_time_s=20.0, with_user=True)


def test_python_controller_reproduces_the_compiled_loop():
    setup = CapstanSetup(friction_compensation=0.5, guard=False)  # the PID alone
    n = 600
    ref = np.where(np.arange(n) > 50, math.radians(10), 0.0)
    run = simulate_closed_loop(setup, n, reference=ref, seed=3)
    ctrl = PositionController(P, setup.resolved_gains(), fs=setup.fs, friction_compensation=0.5)
    ctrl.reset(run["measured_angle_rad"][0])
    replay = [ctrl.step(r, 0.0, a) for r, a in zip(ref, run["measured_angle_rad"], strict=True)]
    limit = P.drive.current_limit_a
    np.testing.assert_allclose(np.clip(replay, -limit, limit), run["current_command_a"], atol=1e-12)


def test_integral_accumulates_at_most_the_error_limit_per_tick():
    g = design_critically_damped(P, integral_error_limit_rad=0.01)
    ctrl = PositionController(P, g, fs=1000.0, gravity_compensation=False)
    for _ in range(100):
        ctrl.step(0.5, 0.0, 0.0)  # error 0.5 rad, 50x the limit
    assert ctrl.state[0] == pytest.approx(100 * 0.01 / 1000.0)


def test_observer_matches_the_q_filtered_truth_on_an_exact_model():
    """Angle and current generated from the observer's own model: the estimate is Q T_h."""
    fs, cutoff = 1000.0, 20.0
    dob = DisturbanceObserver(P, fs, cutoff_hz=cutoff)
    c = dob.constants
    t = np.arange(20000) / fs
    for f in (0.5, 2.0, 5.0):
        dob.reset()
        w = 2 * np.pi * f
        theta = 0.05 * np.sin(w * t)
        wp = c.capstan_ratio * 0.05 * w * np.cos(w * t)
        tc = np.where(wp > 0, c.coulomb_cw, c.coulomb_ccw)
        b = np.where(wp > 0, c.viscous_cw, c.viscous_ccw)
        sign = np.clip(wp / c.smoothing_speed, -1.0, 1.0)
        friction = c.capstan_ratio * (tc * sign + b * wp)
        human = np.cos(w * t)
        motor = (
            c.inertia * -(w**2) * theta
            + friction
            + c.gravity_torque * np.sin(theta + c.com_angle)
            - human
        )
        current = motor / c.torque_per_amp
        est = np.array([dob.update(a, i) for a, i in zip(theta, current, strict=True)])
        late = t > 5
        phasor = 2 * np.mean(est[late] * np.exp(-1j * w * t[late]))
        q = 1 / (1 + 1j * w / (2 * np.pi * cutoff)) ** 2
        assert abs(phasor - q) < 0.03


def test_observer_rejects_a_cutoff_above_nyquist():
    with pytest.raises(ValueError, match="cutoff_hz"):
        DisturbanceObserver(P, 100.0, cutoff_hz=60.0)


def test_admittance_settles_at_the_static_deflection():
    env = VirtualEnvironment(stiffness_nm_per_rad=50.0, damping_nms_per_rad=10.0, inertia_kgm2=0.2)
    state = new_admittance_state()
    compiled = env.constants()
    for _ in range(5000):
        offset, speed, _ = admittance_update(compiled, state, 2.0, 50.0, 10.0, 0.1, 1e-3)
    assert offset == pytest.approx(2.0 / 50.0, rel=1e-6) and abs(speed) < 1e-9
    for _ in range(5000):  # a huge torque is held at the environment's angle limit
        admittance_update(compiled, state, 500.0, 50.0, 10.0, 0.1, 1e-3)
    assert state[0] + 0.1 == pytest.approx(env.angle_limit_rad) and state[1] == 0.0
    # infinite stiffness: rigid ground, no deflection
    assert admittance_update(compiled, state, 5.0, math.inf, 10.0, 0.1, 1e-3) == (0.0, 0.0, 0.0)


def test_admittance_lag_compensation_passes_the_deflection_through_one_over_q():
    """With lag (2/w0, 1/w0^2) the offset is d + (2/w0) d' + d''/w0^2 of the virtual d."""
    env = VirtualEnvironment(stiffness_nm_per_rad=50.0, damping_nms_per_rad=5.0)
    w0 = 2 * math.pi * 20.0
    plain, lagged = env.constants(), env.constants(lag=(2 / w0, 1 / w0**2))
    a, b = new_admittance_state(), new_admittance_state()
    for k in range(300):
        torque = math.sin(2 * math.pi * 2.0 * k * 1e-3)
        d_before = a.copy()
        admittance_update(plain, a, torque, 50.0, 5.0, 0.0, 1e-3)
        offset, _, acceleration = admittance_update(lagged, b, torque, 50.0, 5.0, 0.0, 1e-3)
    expected = d_before[0] + 2 / w0 * d_before[1] + acceleration / w0**2
    assert offset == pytest.approx(expected, rel=1e-12)


def test_terrain_profile():
    terrain = TerrainProfile.hills(10.0, seed=4)
    slope = terrain.slope_angle(np.linspace(0, 10, 101))
    assert np.all(np.abs(slope) < math.radians(25)) and np.ptp(slope) > math.radians(5)
    eq = terrain.equilibrium(5.0, 100.0, speed_m_s=1.2)
    assert eq.shape == (500,)
    with pytest.raises(ValueError, match="strictly increasing"):
        TerrainProfile(np.array([0.0, 0.0, 1.0]), np.zeros(3))


def test_linear_platform_lumps_user():
    bare, loaded = linear_platform(P), linear_platform(P, P.user)
    assert loaded.inertia_kgm2 - bare.inertia_kgm2 == pytest.approx(P.user.foot_inertia_kgm2)
    assert loaded.stiffness_nm_per_rad == P.user.ankle_stiffness_nm_per_rad
