"""Capstan experiments: set-points, chirp metrics, faults under closed loop, observer, rendering."""

import math

import numpy as np
import pytest
from scipy import signal

from anklelab.control import VirtualEnvironment
from anklelab.control.safety import Fault
from anklelab.experiments.capstan import (
    CapstanSetup,
    FaultInjection,
    chirp_metrics,
    chirp_reference,
    observer_trial,
    render,
    simulate_closed_loop,
    step_response,
)

SETUP = CapstanSetup()
P = SETUP.params


@pytest.mark.parametrize("degrees", [5.0, 10.0, 15.0])
def test_set_points_are_reached_within_300_ms(degrees):
    run, m = step_response(SETUP, math.radians(degrees), hold_s=1.0)
    assert m.settling_time_5_s < 0.3  # paper 001: every set-point reached within 300 ms
    assert m.overshoot_percent < 5.0
    assert abs(m.steady_state_error_rad) < math.radians(0.1)
    assert np.all(run["fault"] == 0)


def test_chirp_metrics_recover_a_known_linear_response():
    fs = 1000.0
    ref = chirp_reference(0.1, 0.2, 5.0, 10.0, fs)[0]
    ref = np.concatenate([ref, np.zeros(3000)])  # rest: the response rings down
    w0 = 2 * np.pi * 2.0  # critically damped pair at 2 Hz: -3 dB at 1.29 Hz, -45 deg at 0.83 Hz
    b, a = signal.bilinear([w0**2], [1, 2 * w0, w0**2], fs)
    m = chirp_metrics(ref, signal.lfilter(b, a, ref), fs, 0.2, 5.0, duration_s=10.0)
    assert m.bandwidth_3db_hz == pytest.approx(2.0 * math.sqrt(math.sqrt(2) - 1), rel=0.02)
    assert m.bandwidth_45deg_hz == pytest.approx(2.0 * math.tan(math.radians(22.5)), rel=0.02)
    x = m.frequency_hz / 2.0
    np.testing.assert_allclose(m.gain, 1 / (1 + x**2), rtol=0.03)


@pytest.mark.parametrize(
    ("kind", "value", "faults"),
    [
        ("encoder-nan", 0.0, {Fault.SENSOR_NAN}),
        ("current-nan", 0.0, {Fault.SENSOR_NAN}),
        ("encoder-stale", 0.0, {Fault.SENSOR_STALE}),
        ("encoder-jump", 1.0, {Fault.SENSOR_RANGE}),
        ("encoder-jump", 0.2, {Fault.POSITION, Fault.VELOCITY}),
        ("encoder-reversed", 0.0, {Fault.VELOCITY, Fault.POSITION}),
    ],
)
def test_injected_faults_trip_and_leave_the_platform_safe(kind, value, faults):
    n, onset = 3000, 0.5
    t = np.arange(n) / SETUP.fs
    ref = math.radians(20.0) * np.sin(np.pi * t)  # faults strike while the platform moves
    speed = math.radians(20.0) * np.pi * np.cos(np.pi * t)
    run = simulate_closed_loop(
        SETUP, n, reference=ref, reference_speed=speed, fault=FaultInjection(kind, onset, value)
    )
    tripped = np.flatnonzero(run["fault"] > 0)
    assert tripped.size and Fault(int(run["fault"][-1])) in faults
    k = tripped[0]
    assert k >= round(onset * SETUP.fs)
    assert k <= round(onset * SETUP.fs) + P.safety.max_stale_ticks + 300
    # a sensor fault may first look like a fall to the person guard, which brakes for at most
    # stop_time_s; from the monitor's own trip (or the end of that stop) the current is 0
    generic = np.flatnonzero((run["fault"] > 0) & (run["fault"] != Fault.FALL_STOP))
    stop_end = k + round(P.person_safety.stop_time_s * SETUP.fs) + 1
    zero_from = min(generic[0] if generic.size else stop_end, stop_end)
    assert np.all(run["current_command_a"][zero_from:] == 0.0)
    assert np.max(np.abs(run["angle_rad"])) < P.workspace.angle_limit_rad
    # the drive holds its *sensed* current to the limit; the true one is off by sensor noise
    assert np.max(np.abs(run["current_a"])) <= P.drive.current_limit_a + 5 * P.drive.current_noise_a


def test_reference_beyond_the_software_limit_trips_before_the_end_stop():
    n = 3000
    run = simulate_closed_loop(SETUP, n, reference=np.full(n, math.radians(60.0)))
    assert Fault(int(run["fault"][-1])) in {Fault.POSITION, Fault.VELOCITY}
    assert np.max(run["angle_rad"]) < P.workspace.angle_limit_rad


@pytest.mark.parametrize("task", ["hold", "track"])
def test_observer_estimates_the_human_torque(task):
    run, m = observer_trial(SETUP, task, duration_s=10.0, seed=2)
    assert np.all(run["fault"] == 0)
    assert m.vaf_percent > 85.0
    assert 0.005 < m.delay_s < 0.04  # a 20 Hz critically damped Q delays by ~16 ms


def test_impedance_rendering_gives_the_virtual_stiffness():
    env = VirtualEnvironment(stiffness_nm_per_rad=100.0, damping_nms_per_rad=5.0)
    run, m = render(SETUP, env, mode="impedance", duration_s=30.0, seed=3)
    assert np.all(run["fault"] == 0)
    assert abs(m.stiffness_error_percent) < 15.0
    # the foot also feels the device's own inertia (pinion referred plus platform)
    assert m.inertia_kgm2 == pytest.approx(0.3733, rel=0.2)


def test_admittance_rendering_hides_the_device_inertia():
    env = VirtualEnvironment(stiffness_nm_per_rad=50.0, damping_nms_per_rad=5.0, inertia_kgm2=0.1)
    run, m = render(CapstanSetup.for_rendering(), env, mode="admittance", duration_s=30.0, seed=3)
    assert np.all(run["fault"] == 0)
    assert abs(m.stiffness_error_percent) < 10.0 and abs(m.damping_error_percent) < 10.0
    assert m.inertia_kgm2 == pytest.approx(0.1, rel=0.2)  # well below the device's 0.37 kg m^2


SHORT_RUNS = {
    "observer_trial": lambda seed: observer_trial(
        SETUP, "track", duration_s=2.0, settle_s=0.5, seed=seed
    ),
    "render": lambda seed: render(
        SETUP,
        VirtualEnvironment(stiffness_nm_per_rad=50.0, damping_nms_per_rad=5.0),
        duration_s=2.0,
        seed=seed,
    ),
}


def _same_run(a, b):
    return a.signals.keys() == b.signals.keys() and all(
        np.array_equal(a[name], b[name], equal_nan=True) for name in a.signals
    )


@pytest.mark.parametrize("name", list(SHORT_RUNS))
def test_seed_is_an_int_or_a_generator(name):
    run = SHORT_RUNS[name]
    by_int, metrics = run(4)
    by_generator, generator_metrics = run(np.random.default_rng(4))
    assert _same_run(by_int, by_generator) and repr(metrics) == repr(generator_metrics)
    assert _same_run(by_int, run(4)[0])  # same seed, same run
    assert not _same_run(by_int, run(5)[0])
    shared = np.random.default_rng(4)  # a generator passed twice continues its stream
    assert _same_run(by_int, run(shared)[0]) and not _same_run(by_int, run(shared)[0])


def test_bad_arguments():
    with pytest.raises(ValueError, match="fault kind"):
        FaultInjection("gremlins", 0.1)
    with pytest.raises(ValueError, match="needs an environment"):
        simulate_closed_loop(SETUP, 10, mode="admittance")
    with pytest.raises(ValueError, match=r"reference must have shape \(10,\)"):
        simulate_closed_loop(SETUP, 10, reference=np.zeros(5))
