"""Stance and feet: heel contact, COP progression, stiffness laws, variability."""

import numpy as np
import pytest

from anklelab.platforms import load_platform
from anklelab.sim.foot import bench_law, foot_load, foot_model
from anklelab.sim.gait import heel_contact_times, sample_gait, stance_signals

FS = 1000.0


@pytest.fixture(scope="module")
def params():
    return load_platform("perturberator")


@pytest.fixture(scope="module")
def stance(params):
    trials = sample_gait(params.gait, 40, np.random.default_rng(3))
    time = np.arange(round(params.gait.trial_duration_s * FS)) / FS
    return trials, time, stance_signals(trials, params.gait, time)


def test_heel_contact_is_the_25_newton_crossing(params, stance):
    trials, _, _ = stance
    hc = heel_contact_times(trials, params.gait, 25.0)
    at = stance_signals(trials, params.gait, hc)
    assert np.allclose(np.diag(at.grf_z), 25.0, atol=1e-6)
    assert np.all(hc > trials.contact_s) and np.all(hc - trials.contact_s < trials.loading_s)
    with pytest.raises(ValueError, match="does not reach"):
        heel_contact_times(trials, params.gait, 1e5)


def test_cop_stays_at_the_heel_until_after_heel_contact(params, stance):
    trials, time, sig = stance
    hc = heel_contact_times(trials, params.gait, 25.0)
    for i in range(len(trials)):
        first = np.searchsorted(time, hc[i])
        assert sig.progression[i, first] == 0.0
        assert sig.progression[i, first + 80] > 0.03  # heel rocker after loading


def test_stance_forces_have_the_expected_shape(params, stance):
    sig = stance[2]
    weight = params.gait.body_mass_kg * 9.81
    assert sig.grf_z.max() / weight == pytest.approx(1.1, abs=0.1)
    u = sig.fraction
    assert np.all(sig.grf_x[u < 0.4] <= 0) and np.all(sig.grf_x[u > 0.6] >= 0)  # brake, propel
    assert np.all(sig.grf_z[~sig.contact] == 0)
    assert np.all(
        np.diff(np.where(sig.contact, sig.progression, 0), axis=1)[sig.contact[:, 1:]] >= -1e-12
    )


def test_variability_switch(params):
    fixed = sample_gait(params.gait, 5, np.random.default_rng(0), variability=False)
    assert np.all(fixed.stance_s == params.gait.stance_s) and np.all(fixed.placement_m == 0)
    varied = sample_gait(params.gait, 200, np.random.default_rng(0))
    assert varied.stance_s.std() / params.gait.stance_s == pytest.approx(0.02, rel=0.2)
    with pytest.raises(ValueError, match="trial_duration_s"):
        sample_gait(params.gait.replace({"trial_duration_s": 0.5}), 3, np.random.default_rng(0))


def test_prosthetic_stiffness_follows_the_bench_law(params):
    d = np.array([0.06, 0.085, 0.11, 0.135])
    assert bench_law(params, d) == pytest.approx([1300.0, 1137.5, 975.0, 812.5])
    assert bench_law(params, np.array([5.0]))[0] == pytest.approx(0.05 * 975.0)  # floored


def test_human_stiffness_rises_through_stance(params):
    human = foot_model("human", params)
    t = np.array([0.15, 0.275, 0.4, 0.525])
    k = human.stiffness(np.zeros(4), t) / params.gait.body_mass_kg
    assert k == pytest.approx([1.5, 3.2, 4.9, 6.5])
    assert human.inertia_kgm2 == params.human.inertia_kgm2
    with pytest.raises(ValueError, match="foot"):
        foot_model("robot", params)


@pytest.mark.parametrize("kind", ["prosthetic", "human"])
def test_foot_is_coupled_only_while_flat(params, stance, kind):
    trials, time, sig = stance
    hc = heel_contact_times(trials, params.gait, 25.0)
    load, nominal = foot_load(foot_model(kind, params), trials, sig, hc, time)
    flat = load.channels[:, 7] > 0
    u = sig.fraction[flat]
    assert u.min() >= params.gait.foot_flat_fraction and u.max() <= params.gait.heel_off_fraction
    assert np.all(nominal.stiffness_nm_per_rad[~flat] == 0)
    dz = params.geometry.ankle_height_m
    lever = np.nan_to_num(nominal.lever_arm_m)
    assert np.allclose(nominal.torque_nm, sig.grf_z * lever + sig.grf_x * dz * sig.contact)
    assert np.isfinite(nominal.angle_rad).all()
