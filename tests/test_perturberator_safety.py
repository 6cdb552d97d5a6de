"""Perturberator safety: injected faults trip the drive or the trigger, and the hinge stops.

Each drive fault must latch its code, brake as designed (controlled stop or dynamic brake and
holding brake) and leave the hinge within :func:`stopping_distance` of where it tripped; each bad
force reading must refuse the perturbation and flag the trial; the protocol names the trial.
"""

import numpy as np
import pytest

from anklelab.control.safety import Fault
from anklelab.control.trigger import reading_limits, screen_readings
from anklelab.errors import ParameterError, SafetyLimitError
from anklelab.experiments import TrialFault, simulate_perturberator
from anklelab.platforms import load_platform
from anklelab.sim import _kernels as K
from anklelab.sim.drivetrain import (
    DriveFault,
    EncoderFault,
    FootLoad,
    dynamic_brake_nms_per_rad,
    simulate_platform,
    stopping_distance,
)

FS = 8000.0  # record at the position-loop rate
P = load_platform("perturberator")
LIMIT = P.hinge.angle_limit_rad


def ramp(speed, n, top=1.0, accel_s=0.05, start_s=0.02):
    """A position command accelerating smoothly to ``speed`` (rad/s), capped at ``top`` (rad)."""
    t = np.arange(n) / FS
    return np.minimum(np.cumsum(speed * np.clip((t - start_s) / accel_s, 0, 1)) / FS, top)[None]


def foot_on_plate(n_samples, torque_nm, inertia_kgm2=0.3):
    """A foot flat on the plate pressing with a steady moment (1 kHz gait channels)."""
    channels = np.zeros((1, K.N_G, n_samples))
    channels[:, K.G_Z] = 700.0
    channels[:, K.G_TNOM] = torque_nm
    channels[:, K.G_K] = 1000.0
    channels[:, K.G_CONTACT] = 1.0
    scalars = np.zeros((1, K.N_FP))
    scalars[:, K.F_IF] = inertia_kgm2
    scalars[:, K.F_XA] = P.hinge.axis_anterior_m
    scalars[:, K.F_DZ] = P.geometry.ankle_height_m
    return FootLoad(channels, 1000.0, scalars)


def at_trip(run):
    """Sample index of the trip, motor speed there (rad/s) and the hinge angle there."""
    k = round(run.fault_s[0] * FS)
    return k, (run.motor_angle[0, k] - run.motor_angle[0, k - 1]) * FS, run.hinge_angle[0, k]


@pytest.mark.parametrize("speed", [0.3, 0.6, 0.9])
def test_position_trip_is_a_controlled_stop_within_the_stated_overtravel(speed):
    run = simulate_platform(P, ramp(speed, 12000), plate=False, record_fs=FS)
    assert run.fault.tolist() == [DriveFault.POSITION]
    k, w, trip = at_trip(run)
    assert w == pytest.approx(speed, rel=0.01)
    assert trip == pytest.approx(LIMIT, abs=2e-3)  # the encoder (motor) trips; the hinge lags
    hinge, motor = run.hinge_angle[0], run.motor_angle[0]
    over = hinge[k:].max() - trip
    assert 0 < over <= stopping_distance(P, w, DriveFault.POSITION)
    assert hinge.max() <= LIMIT + stopping_distance(P, 1.0, DriveFault.POSITION) < LIMIT + 0.006
    # then it holds: the velocity loop keeps the shaft near where it tripped, torque on
    assert abs(motor[-1] - motor[k]) < 1e-3
    assert np.ptp(hinge[-800:]) < 1e-6
    assert run.motor_torque[0, -1] == pytest.approx(P.hinge.gravity_stiffness_nm_per_rad * LIMIT,
                                                    rel=0.02)  # fmt: skip
    assert np.abs(run.motor_torque).max() <= P.transmission.peak_output_torque_nm + 1e-9


@pytest.mark.parametrize(
    ("kind", "code"),
    [
        (EncoderFault.NAN, DriveFault.ENCODER),
        (EncoderFault.STALE, DriveFault.ENCODER_STALE),
        (EncoderFault.JUMP, DriveFault.VELOCITY),  # a 1 mrad jump reads as 16 rad/s
    ],
)
def test_feedback_faults_brake_dynamically_then_the_holding_brake_locks(kind, code):
    fault_s = 0.1  # mid-way up a 0.035 rad move at 0.5 rad/s
    run = simulate_platform(
        P, ramp(0.5, 8000, top=0.035), plate=False, record_fs=FS,
        encoder_fault_s=np.array([fault_s]), encoder_fault=kind, encoder_jump_rad=1e-3,
    )  # fmt: skip
    assert run.fault.tolist() == [code]
    timeout = P.servo.encoder_timeout_samples if code == DriveFault.ENCODER_STALE else 0
    assert run.fault_s[0] == pytest.approx(fault_s + timeout / P.servo.velocity_loop_rate_hz)
    k, w, trip = at_trip(run)
    assert w == pytest.approx(0.5, rel=0.02)
    motor, torque = run.motor_angle[0], run.motor_torque[0]
    locked = k + round(P.motor.brake_engage_s * FS) + 1
    # dynamic brake: torque opposes the motor speed in proportion (no feedback used)
    speed = np.gradient(motor, 1 / FS)
    seg = slice(k + 8, locked - 1)
    slope = -np.sum(torque[seg] * speed[seg]) / np.sum(speed[seg] ** 2)
    assert slope == pytest.approx(dynamic_brake_nms_per_rad(P), rel=0.05)
    # holding brake: the shaft stays put and the output is off
    assert np.ptp(motor[locked:]) == 0.0
    assert np.abs(torque[locked + 40 :]).max() < 1e-6
    travel = np.abs(run.hinge_angle[0, k:] - trip).max()
    assert 0 < travel <= stopping_distance(P, w, code)


def test_a_runaway_command_trips_overspeed_and_stops_within_the_bound():
    run = simulate_platform(P, ramp(3.0, 8000), plate=False, record_fs=FS)
    assert run.fault.tolist() == [DriveFault.VELOCITY]
    k, w, trip = at_trip(run)
    limit = P.servo.velocity_limit_rad_per_s
    assert limit < w < 1.05 * limit  # tripped as soon as it got there
    assert np.abs(run.hinge_angle[0, k:] - trip).max() <= stopping_distance(
        P, w, DriveFault.VELOCITY
    )
    assert np.ptp(run.hinge_angle[0, -800:]) < 1e-5


@pytest.mark.parametrize("moment_nm", [100.0, -100.0])
def test_the_holding_brake_holds_a_foot_pressing_on_the_plate(moment_nm):
    """A dynamic brake alone yields to a steady load; the holding brake stops it."""
    load = foot_on_plate(2000, moment_nm)
    kw = dict(load=load, plate=False, record_fs=FS, encoder_fault_s=np.array([0.1]))
    run = simulate_platform(P, ramp(0.5, 12000, top=0.035), **kw)
    late = simulate_platform(P.replace({"motor.brake_engage_s": 1.0}), ramp(0.5, 12000, top=0.035),
                             **kw)  # fmt: skip
    k, w, trip = at_trip(run)
    bound = stopping_distance(P, w, DriveFault.ENCODER, load_nm=moment_nm, load_inertia_kgm2=0.3)
    assert np.abs(run.hinge_angle[0, k:] - trip).max() <= bound
    assert np.ptp(run.hinge_angle[0, -800:]) < 1e-5  # at rest, held
    assert np.abs(late.hinge_angle[0, k:] - trip).max() > 3 * bound  # yields without it


def test_a_loaded_position_trip_holds_the_load_without_creep():
    run = simulate_platform(P, ramp(0.5, 12000), load=foot_on_plate(2000, 100.0), plate=False,
                            record_fs=FS)  # fmt: skip
    assert run.fault.tolist() == [DriveFault.POSITION]
    k, w, trip = at_trip(run)
    bound = stopping_distance(P, w, DriveFault.POSITION, load_nm=100.0, load_inertia_kgm2=0.3)
    assert np.abs(run.hinge_angle[0, k:] - trip).max() <= bound
    assert np.ptp(run.hinge_angle[0, -800:]) < 1e-5


def test_a_command_jump_is_a_following_error_and_the_platform_stays_put():
    run = simulate_platform(P, np.full((1, 4000), 0.1), plate=False, record_fs=FS)
    assert run.fault.tolist() == [DriveFault.FOLLOWING_ERROR] and run.fault_s[0] == 0.0
    assert np.abs(run.hinge_angle).max() < 1e-6
    fine = simulate_platform(P, np.full((1, 400), 1e-3), plate=False)
    assert fine.fault.tolist() == [DriveFault.NONE] and np.isnan(fine.fault_s[0])


def test_the_trigger_monitor_flags_nan_saturated_and_dropped_readings():
    n = 12
    reading = np.tile(np.linspace(0.0, 600.0, n), (5, 1))
    counter = np.tile(np.arange(n, dtype=float), (5, 1))
    reading[1, 4:] = np.nan
    reading[2, 6:] = 20000.0  # stuck at an amplifier's rail
    counter[3, 5:7] = counter[3, 4]  # two samples dropped in a row
    counter[4, 5] = counter[4, 4]  # one dropped sample is tolerated
    fault, at = screen_readings(reading, counter, reading_limits(P.trigger.force_limit_n, 1))
    assert fault.tolist() == [0, Fault.SENSOR_NAN, Fault.SENSOR_RANGE, Fault.SENSOR_STALE, 0]
    assert at.tolist() == [n, 4, 6, 6, n]


@pytest.fixture(scope="module")
def session_kw():
    return dict(trials_per_point=1, n_unperturbed=1, n_calibration=0, bench=False, seed=4)


@pytest.fixture(scope="module")
def healthy(session_kw):
    return simulate_perturberator(**session_kw)


def first_perturbed(session):
    onsets = session.truth["trials"]["onset_s"]
    i = int(np.flatnonzero(np.isfinite(onsets))[0])
    return i, session.truth["trials"]["heel_contact_s"][i], onsets[i]


@pytest.mark.parametrize(
    ("kind", "value", "fault"),
    [
        ("force-nan", 0.0, Fault.SENSOR_NAN),
        ("force-saturated", 2e4, Fault.SENSOR_RANGE),
        ("force-dropped", 0.0, Fault.SENSOR_STALE),
    ],
)
def test_bad_force_data_refuses_the_perturbation_and_flags_the_trial(
    healthy, session_kw, kind, value, fault
):
    i, contact, _ = first_perturbed(healthy)
    session = simulate_perturberator(
        fault=TrialFault(kind, i + 1, contact + 0.02, value), **session_kw
    )
    trial = session.walking[i]
    assert not trial.perturbed and trial.direction == "none" and np.isnan(trial.delay_ms)
    assert fault.name in trial.extra["note"] and "intended: " in trial.extra["note"]
    assert np.isnan(session.truth["trials"]["onset_s"][i])
    assert np.abs(trial.recording["motor_angle"]).max() < 1e-3  # the platform stayed level
    assert np.abs(healthy.walking[i].recording["motor_angle"]).max() > 0.03
    for j, (a, b) in enumerate(zip(healthy.walking, session.walking, strict=True)):
        if j != i:  # every other trial is untouched, byte for byte
            assert a.extra == b.extra == {}
            for column in a.recording.columns:
                np.testing.assert_array_equal(a.recording[column], b.recording[column])


def test_a_force_fault_after_the_onset_does_not_stop_a_running_perturbation(healthy, session_kw):
    i, _, onset = first_perturbed(healthy)
    session = simulate_perturberator(fault=TrialFault("force-nan", i + 1, onset + 0.01),
                                     **session_kw)  # fmt: skip
    assert session.walking[i].perturbed and session.walking[i].extra == {}
    np.testing.assert_array_equal(
        session.walking[i].recording["motor_angle"], healthy.walking[i].recording["motor_angle"]
    )


@pytest.mark.parametrize(
    ("kind", "value", "name"),
    [
        ("encoder-nan", 0.0, "ENCODER"),
        ("encoder-stale", 0.0, "ENCODER_STALE"),
        ("encoder-jump", 1e-3, "VELOCITY"),
    ],
)
def test_an_encoder_fault_stops_the_protocol_naming_the_trial(
    healthy, session_kw, kind, value, name
):
    i, _, onset = first_perturbed(healthy)
    with pytest.raises(
        SafetyLimitError, match=rf"walking trial {i + 1}: the drive tripped \({name}\)"
    ):
        simulate_perturberator(fault=TrialFault(kind, i + 1, onset + 0.03, value), **session_kw)


def test_fault_injections_are_validated(session_kw):
    with pytest.raises(ParameterError, match="fault kind must be one of"):
        TrialFault("encoder-melted", 1, 0.1)
    with pytest.raises(ParameterError, match="force-saturated: give its size"):
        TrialFault("force-saturated", 1, 0.1)
    with pytest.raises(ParameterError, match=r"fault.trial: expected 1 ... 5, got 9"):
        simulate_perturberator(fault=TrialFault("force-nan", 9, 0.1), **session_kw)
