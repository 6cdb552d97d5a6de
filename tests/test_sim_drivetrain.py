"""The servo-driven hinge: convergence in the integration step, static loads, limits, faults."""

import numpy as np
import pytest

from anklelab.errors import SafetyLimitError
from anklelab.experiments import simulate_perturberator
from anklelab.platforms import load_platform
from anklelab.sim import _kernels as K
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.drivetrain import DriveFault, FootLoad, platform_constants, simulate_platform


@pytest.fixture(scope="module")
def params():
    return load_platform("perturberator")


def constant_load(params, n_samples, torque_nm, vertical_n=700.0):
    """The plate carrying a steady load: a vertical force with a moment about the ankle."""
    channels = np.zeros((1, K.N_G, n_samples))
    channels[:, K.G_Z] = vertical_n
    channels[:, K.G_TNOM] = torque_nm
    scalars = np.zeros((1, K.N_FP))
    scalars[:, K.F_IF] = 0.3
    scalars[:, K.F_XA] = params.hinge.axis_anterior_m
    scalars[:, K.F_DZ] = params.geometry.ankle_height_m
    return FootLoad(channels, 1000.0, scalars)


def test_halving_the_integration_step_changes_recordings_by_under_half_a_percent():
    art = Artefacts(noise=False, drift=False, quantisation=False)
    kw = dict(trials_per_point=1, n_unperturbed=1, n_calibration=1, bench=False, seed=2)
    coarse = simulate_perturberator(artefacts=art, substeps=1, **kw)
    fine = simulate_perturberator(artefacts=art, substeps=2, **kw)
    pairs = [(a.recording, b.recording) for a, b in zip(coarse.walking, fine.walking, strict=True)]
    pairs += list(zip(coarse.calibration, fine.calibration, strict=True))
    worst = 0.0
    for a, b in pairs:
        for column in a.columns:
            scale = np.abs(a[column]).max()
            if scale > 0:
                worst = max(worst, np.abs(a[column] - b[column]).max() / scale)
    assert 0 < worst < 0.005


def test_a_steady_load_winds_up_the_coupler_while_the_servo_holds_the_motor(params):
    n = 1500
    run = simulate_platform(
        params, np.zeros((1, n * 8)), load=constant_load(params, n, 50.0), plate=False
    )
    pc = platform_constants(params, hinge_height_m=params.geometry.ankle_height_m)
    expected = -50.0 / (
        pc[K.K_S] + pc[K.K_G]
    )  # dorsiflexing moment on the foot tilts the plate down
    assert run.hinge_angle[0, -10] == pytest.approx(expected, rel=0.01)
    assert abs(run.motor_angle[0, -10]) < 1e-3 * abs(expected)  # integral action removes the error
    assert run.ankle_torque[0, -10] == pytest.approx(50.0)
    assert run.motor_torque[0, -10] == pytest.approx(50.0, rel=0.01)


def test_output_torque_never_exceeds_the_peak_rating(params):
    # a raw step (no motion plan) whose velocity command stays under the overspeed limit
    size = 0.9 * params.servo.velocity_limit_rad_per_s / params.servo.position_gain_per_s
    run = simulate_platform(params, np.full((1, 4000), size), plate=False, record_fs=8000.0)
    peak = params.transmission.peak_output_torque_nm
    assert run.fault.tolist() == [DriveFault.NONE]
    assert np.abs(run.motor_torque).max() <= peak + 1e-9
    assert np.isclose(np.abs(run.motor_torque).max(), peak, rtol=1e-3)  # it does saturate
    assert run.motor_angle[0, -1] == pytest.approx(size, abs=1e-6)


def test_encoder_quantisation_follows_the_artefact_switch(params):
    ref = np.full((1, 800), 1e-3)
    on = simulate_platform(params, ref, plate=False, record_loop=True, record_fs=8000.0)
    off = simulate_platform(
        params, ref, plate=False, record_loop=True, record_fs=8000.0,
        artefacts=Artefacts(quantisation=False),
    )  # fmt: skip
    q = params.servo.encoder_resolution_rad / params.transmission.ratio
    counts = on.loop["encoder"][0] / q
    assert np.allclose(counts, np.round(counts), atol=1e-6)
    assert not np.allclose(off.loop["encoder"][0] / q, np.round(off.loop["encoder"][0] / q))


def test_the_drive_refuses_non_finite_commands(params):
    ref = np.zeros((1, 80))
    ref[0, 10] = np.inf
    with pytest.raises(SafetyLimitError, match="non-finite"):
        simulate_platform(params, ref)
    with pytest.raises(ValueError, match="substeps"):
        simulate_platform(params, np.zeros((1, 80)), substeps=0)
    with pytest.raises(ValueError, match="record_fs"):
        simulate_platform(params, np.zeros((1, 80)), record_fs=3000.0)


def test_misaligned_hinge_rotates_the_ankle_more_than_the_plate(params):
    shifted = params.replace({"geometry.misalignment_vertical_m": 0.045})
    n = 600
    load = constant_load(shifted, n, 0.0)
    load.channels[:, K.G_CONTACT] = 1.0
    load.channels[:, K.G_K] = 1000.0
    load.scalars[:, K.F_MIS] = 0.045 / shifted.geometry.shank_length_m
    ref = np.zeros((1, n * 8))
    ref[0, 2400:] = 0.01
    run = simulate_platform(shifted, ref, load=load, plate=False)
    gain = run.ankle_angle[0, -10] / run.hinge_angle[0, -10]
    assert gain == pytest.approx(1 + 0.045 / 0.45, rel=1e-6)


def test_a_drive_fault_stops_the_protocol():
    strict = load_platform("perturberator").replace({"servo.following_error_limit_rad": 1e-4})
    with pytest.raises(SafetyLimitError, match=r"walking trial \d+: the drive tripped"):
        simulate_perturberator(strict, trials_per_point=1, n_unperturbed=0, n_calibration=0)


def test_a_compliant_shell_shares_the_rotation_with_the_ankle(params):
    n = 1500
    load = constant_load(params, n, 0.0)
    load.channels[:, K.G_CONTACT] = 1.0
    load.channels[:, K.G_K] = 1000.0
    load.scalars[:, K.F_KSH] = 10000.0
    load.scalars[:, K.F_BSH] = 100.0  # well damped, so it settles within the run
    ref = np.zeros((1, n * 8))
    ref[0, 2400:] = 0.01
    run = simulate_platform(params, ref, load=load, plate=False)
    hinge, ankle = run.hinge_angle[0, -10], run.ankle_angle[0, -10]
    assert ankle == pytest.approx(hinge * 10000.0 / 11000.0, rel=1e-3)  # springs in series
    assert run.ankle_torque[0, -10] == pytest.approx(1000.0 * ankle, rel=1e-3)


def test_the_steps_at_rest_before_a_load_are_skipped_without_changing_a_bit(params):
    """A trial starts where something first moves it; from step 0 (a resume from the rest
    state, which skips nothing) every output is the same to the last bit (with the plate's
    filters on; with both off, Fx and Fy at rest would read -0.0 instead of +0.0)."""
    from anklelab.sim.drivetrain import _steps_at_rest

    n = 1100
    load = constant_load(params, n, 30.0)
    load.channels[:, :, :300] = 0.0  # the foot lands at 0.3 s
    ticks = n * 8
    reference = np.zeros((1, ticks))
    reference[0, 5000:] = 0.01  # and the plate moves at 0.625 s
    steps_per_sample = 2 * params.servo.position_loop_rate_hz / load.fs
    start = _steps_at_rest(
        reference, np.zeros((1, 0)), load.channels.transpose(0, 2, 1), 1 / steps_per_sample,
        np.array([2 * ticks]),
    )  # fmt: skip
    assert 0.29 * 16000 < start[0] < 0.3 * 16000
    undefined = load.channels.transpose(0, 2, 1).copy()
    undefined[0, 10, K.G_K] = np.nan  # a stiffness that is not a number moves nothing only if
    at = _steps_at_rest(  # it is simulated (NaN times zero is NaN): no skip past it
        reference, np.zeros((1, 0)), undefined, 1 / steps_per_sample, np.array([2 * ticks])
    )
    assert at[0] < 10 * steps_per_sample
    skipped = simulate_platform(params, reference, load=load)
    everything = simulate_platform(
        params, reference, load=load, resume=(np.zeros(1, dtype=np.int64), np.zeros((1, K.N_SNAP)))
    )
    for name in ("motor_angle", "hinge_angle", "ankle_angle", "ankle_torque", "motor_torque"):
        assert getattr(skipped, name).tobytes() == getattr(everything, name).tobytes(), name
    assert skipped.wrench.tobytes() == everything.wrench.tobytes()
    assert np.abs(skipped.wrench[0, 2, 400:]).max() > 100  # the load reached the plate
