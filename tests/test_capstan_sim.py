"""Capstan twin: friction sticks for real, spin-downs follow the exact solution, limits hold,
the transfer functions agree with the simulated plant."""

import math

import numpy as np
import pytest

from anklelab.platforms import load_platform
from anklelab.sim.capstan import (
    CapstanTwin,
    friction_array,
    friction_step,
    friction_torque,
    kinetic_friction,
    linear_platform,
    reference_to_angle,
    voltage_to_motor_speed,
)

P = load_platform("capstan")
TORQUE_PER_AMP_PINION = P.motor.torque_constant_nm_per_a * P.gearhead.ratio
FS = 1000.0


def pinion_run(torque_nm, *, params=P, w0=0.0, max_step_s=2e-4):
    """Uncoupled pinion driven by a pinion-torque profile (current = torque / (K_i r_g))."""
    twin = CapstanTwin(params, coupled=False, max_step_s=max_step_s)
    command = np.asarray(torque_nm, float) / TORQUE_PER_AMP_PINION
    start = twin.rest_state()
    start[0], start[2] = command[0], w0
    return twin.simulate(command, FS, state0=start)["pinion_speed_rad_s"]


def test_shaft_at_rest_stays_exactly_stuck_below_static_friction():
    w = pinion_run(np.full(2000, 0.95 * P.friction.static_friction_nm))
    assert np.all(w == 0.0)
    w = pinion_run(np.full(2000, -0.95 * P.friction.static_friction_nm))
    assert np.all(w == 0.0)


def test_shaft_breaks_away_above_static_friction():
    w = pinion_run(np.full(500, 1.05 * P.friction.static_friction_nm))
    assert w[-1] > 1.0


def test_coasting_shaft_stops_and_stays_stopped_under_small_torque():
    hold = 0.5 * P.friction.static_friction_nm
    w = pinion_run(np.full(3000, hold), w0=-30.0)
    stop = np.flatnonzero(w == 0.0)
    assert stop.size and np.all(w[stop[0] :] == 0.0)


def test_spin_down_follows_the_exact_solution():
    """J w' + b w = -Tc sign(w): w(t) = (w0 + Tc/b) exp(-b t / J) - Tc/b (cw).

    The implicit Euler step is first order: with 10 us steps it must be within 2e-5.
    """
    f = P.friction
    w0 = 60.0
    w = pinion_run(np.zeros(600), w0=w0, max_step_s=1e-5)
    t = np.arange(1, 601) / FS
    a, c = f.viscous_cw_nms_per_rad / f.inertia_kgm2, f.coulomb_cw_nm / f.viscous_cw_nms_per_rad
    exact = (w0 + c) * np.exp(-a * t) - c
    fast = exact > 12.0  # Stribeck term negligible (exp(-(12/3.2)^2) ~ 1e-6)
    np.testing.assert_allclose(w[fast], exact[fast], rtol=2e-5)
    # counter-clockwise uses the ccw coefficients
    w = pinion_run(np.zeros(600), w0=-w0, max_step_s=1e-5)
    a, c = f.viscous_ccw_nms_per_rad / f.inertia_kgm2, f.coulomb_ccw_nm / f.viscous_ccw_nms_per_rad
    exact = (-w0 - c) * np.exp(-a * t) + c
    fast = exact < -12.0
    np.testing.assert_allclose(w[fast], exact[fast], rtol=2e-5)


def test_implicit_friction_step_is_consistent_with_the_kinetic_law():
    law = friction_array(P.friction)
    j, h = P.friction.inertia_kgm2, 1e-4
    for w, torque in [(5.0, 0.0), (0.5, -0.2), (-2.0, 0.3), (40.0, 0.1), (-0.01, -0.5)]:
        w_new, friction = friction_step(w, torque, j, h, law)
        assert w_new != 0.0
        # the implicit equation is solved to 1e-9 rad/s: J * 1e-9 / h ~ 1e-8 N·m
        assert friction == pytest.approx(kinetic_friction(w_new, law), abs=1e-7)
        assert j * (w_new - w) / h == pytest.approx(torque - friction, rel=1e-12, abs=1e-15)


def test_friction_law_values():
    f = P.friction
    assert friction_torque(1e-9, f) == pytest.approx(f.static_friction_nm)
    assert friction_torque(-1e-9, f) == pytest.approx(-f.static_friction_nm)
    big = 100.0
    cw = f.coulomb_cw_nm + f.viscous_cw_nms_per_rad * big
    assert friction_torque(big, f) == pytest.approx(cw)
    assert friction_torque(-big, f) == pytest.approx(
        -f.coulomb_ccw_nm - f.viscous_ccw_nms_per_rad * big
    )


def test_rest_state_holds_still_on_the_coupled_platform():
    twin = CapstanTwin(P, P.user)
    for angle in (-0.3, 0.0, 0.2):
        x0 = twin.rest_state(angle)
        run = twin.simulate(np.full(500, x0[0]), FS, angle0=angle)
        assert np.max(np.abs(run["angle_rad"] - angle)) < 1e-6


def test_current_and_voltage_limits_hold():
    twin = CapstanTwin(P)
    run = twin.simulate(np.full(1500, 50.0), FS)  # far above the drive's limit
    assert np.max(np.abs(run["current_a"])) <= P.drive.current_limit_a * (1 + 1e-9)
    assert np.max(np.abs(run["voltage_v"])) <= P.drive.supply_voltage_v * (1 + 1e-9)
    # the platform runs into its end stop, which holds it close to the workspace limit
    assert np.max(run["angle_rad"]) < P.workspace.angle_limit_rad + math.radians(5)


def test_uncoupled_top_speed_is_set_by_the_supply_voltage():
    twin = CapstanTwin(P, coupled=False)
    run = twin.simulate(np.full(3000, 5.0), FS)
    no_load = P.drive.supply_voltage_v / P.motor.back_emf_constant_v_s_per_rad / P.gearhead.ratio
    top = run["pinion_speed_rad_s"][-1]
    assert 0.9 * no_load < top < no_load


def test_frictionless_rigid_response_matches_the_linear_model():
    """Zero friction: platform speed under a current step follows 1/(J s + b) with J, b lumped."""
    params = P.replace(
        {
            "friction.coulomb_cw_nm": 0.0,
            "friction.coulomb_ccw_nm": 0.0,
            "friction.static_friction_nm": 0.0,
            "friction.viscous_ccw_nms_per_rad": 6.312e-4,
            "platform.mass_kg": 1e-6,
        }
    )
    lin = linear_platform(params)
    twin = CapstanTwin(params)
    current = 0.5
    run = twin.simulate(np.full(400, current), FS)
    t = np.arange(1, 401) / FS
    torque = current * lin.torque_per_amp_nm_per_a
    rate = lin.damping_nms_per_rad / lin.inertia_kgm2
    expected = torque / lin.damping_nms_per_rad * (1 - np.exp(-rate * t))
    late = t > 0.1  # after the cable mode has rung down
    np.testing.assert_allclose(run["speed_rad_s"][late], expected[late], rtol=0.01)


def test_transfer_functions():
    m = P.motor
    g1 = voltage_to_motor_speed(P)
    # the motor's own mechanical time constant (Table 1: 3.05 ms) when only the rotor turns
    rotor = P.replace(
        {
            "friction.inertia_kgm2": m.rotor_inertia_kgm2 * P.gearhead.ratio**2,
            "platform.inertia_kgm2": 1e-12,
            "friction.viscous_cw_nms_per_rad": 0.0,
            "friction.viscous_ccw_nms_per_rad": 0.0,
        }
    )
    den = voltage_to_motor_speed(rotor).den[0][0]
    assert den[0] / den[1] == pytest.approx(m.mechanical_time_constant_s, rel=0.01)
    assert float(g1.dcgain()) == pytest.approx(1 / m.back_emf_constant_v_s_per_rad, rel=0.05)
    g8 = reference_to_angle(P, kp=200.0, kd=17.0, ki=900.0)
    assert float(g8.dcgain()) == pytest.approx(1.0)
    assert np.all(np.real(g8.poles()) < 0)
