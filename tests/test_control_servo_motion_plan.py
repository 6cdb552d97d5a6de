"""What the drive is commanded: step/direction quantisation, perturbation shapes, the trigger."""

import numpy as np
import pytest

from anklelab.control.motion_plan import StepDirectionPlan
from anklelab.control.perturbation import RampHold, calibration_schedule
from anklelab.control.trigger import onset_updates, trigger_updates
from anklelab.errors import EventNotFoundError, SafetyLimitError
from anklelab.platforms import load_platform

LOOP_HZ = 8000.0


@pytest.fixture(scope="module")
def plan():
    return StepDirectionPlan.from_params(load_platform("perturberator"))


def test_step_size_is_20000_steps_per_motor_revolution_through_70_to_1(plan):
    assert plan.step_rad == pytest.approx(2 * np.pi / 20000 / 70)
    assert plan.update_rate_hz == 2500.0


def test_reference_is_whole_steps_reaching_each_update_target(plan):
    move = RampHold(0.035, ramp_s=0.075, hold_s=0.025, return_s=0.075)
    times = plan.update_times(0.3)
    planned = move(times, 0.0123)[None]
    n_ticks = int(0.3 * LOOP_HZ)
    ref = plan.reference(planned, LOOP_HZ, n_ticks)[0]
    steps = ref / plan.step_rad
    assert np.allclose(steps, np.round(steps), atol=1e-6)  # quantised in position
    # at ticks that coincide with an update instant the count equals the rounded plan there
    ticks = np.arange(n_ticks)
    on_update = ticks % 16 == 0  # 8000/2500 = 3.2: every 16th tick is the 5th update
    k = ticks[on_update] * 5 // 16
    assert np.array_equal(np.round(steps[on_update]), np.round(planned[0, k] / plan.step_rad))
    # between updates the count moves monotonically towards the next target (time quantised)
    assert np.all(np.diff(steps[: int(0.08 * LOOP_HZ)]) >= -1e-9)
    # the command lags the plan by at most one update period of motion
    t = ticks / LOOP_HZ
    speed = 0.035 / 0.075
    assert np.abs(ref - move(t, 0.0123)).max() <= speed / plan.update_rate_hz + plan.step_rad


def test_pulses_are_spread_evenly_within_an_update():
    plan = StepDirectionPlan(step_rad=1.0, update_rate_hz=1.0, angle_limit_rad=100.0)
    ref = plan.reference(np.array([[0.0, 8.0, 8.0]]), loop_rate_hz=4.0, n_ticks=8)
    assert ref.tolist() == [[0.0, 2.0, 4.0, 6.0, 8.0, 8.0, 8.0, 8.0]]
    back = plan.reference(np.array([[0.0, -3.0, -3.0]]), loop_rate_hz=3.0, n_ticks=4)
    assert back.tolist() == [[0.0, -1.0, -2.0, -3.0]]


def test_motion_plan_refuses_unsafe_or_invalid_commands(plan):
    times = plan.update_times(0.01)
    with pytest.raises(SafetyLimitError, match="limit"):
        plan.reference(np.full((1, times.size), 0.5), LOOP_HZ, 40)
    bad = np.zeros((1, times.size))
    bad[0, 3] = np.nan
    with pytest.raises(SafetyLimitError, match="finite"):
        plan.reference(bad, LOOP_HZ, 40)
    with pytest.raises(ValueError, match="do not cover"):
        plan.reference(np.zeros((1, 3)), LOOP_HZ, 40)


def test_ramp_hold_shape_and_validation():
    move = RampHold(0.035, ramp_s=0.075, hold_s=0.1, return_s=0.075)
    t = np.linspace(0, 0.4, 4001)
    x = move(t, 0.1, -1.0)
    assert x.min() == pytest.approx(-0.035) and x.max() == 0.0
    assert np.all(x[t < 0.1] == 0)
    assert np.allclose(x[t > 0.1 + move.duration_s], 0.0, atol=1e-15)
    assert np.allclose(x[(t >= 0.175) & (t <= 0.275)], -0.035)
    with pytest.raises(ValueError, match="ramp_s"):
        RampHold(0.035, ramp_s=0.0, hold_s=0.1, return_s=0.075)


def test_calibration_schedule_fits_the_trial_with_random_directions():
    move = RampHold(0.035, 0.075, 0.1, 0.075)
    rng = np.random.default_rng(5)
    onsets, signs = calibration_schedule(move, 40, 20.0, 2.0, 0.5, rng)
    assert len(onsets) == 40
    assert onsets[0] >= 0.5 and onsets[-1] + move.duration_s <= 19.5 + 1e-9
    assert np.all(np.diff(onsets) >= move.duration_s - 1e-12)  # moves never overlap
    assert 10 < (signs > 0).sum() < 30
    # with room to spare, gaps keep their 0-2 s distribution
    roomy, _ = calibration_schedule(move, 5, 60.0, 2.0, 0.5, np.random.default_rng(1))
    gaps = np.diff(roomy) - move.duration_s
    assert gaps.max() <= 2.0 and len(roomy) == 5
    with pytest.raises(ValueError, match="no room"):
        calibration_schedule(move, 5, 1.0, 2.0, 0.5, rng)


def test_trigger_and_delay_counter():
    force = np.array([[0.0, 5.0, 15.0, 25.0, 40.0], [0.0, 30.0, 60.0, 90.0, 120.0]])
    assert trigger_updates(force, 25.0, np.zeros(2)).tolist() == [3, 1]
    assert trigger_updates(force, 25.0, np.array([11.0, -10.0])).tolist() == [2, 2]
    with pytest.raises(EventNotFoundError, match="never reaches"):
        trigger_updates(force, 500.0, np.zeros(2))
    onset = onset_updates(np.array([3, 3]), np.array([0.1, 0.1]), 2500.0, np.array([0.0, 0.02]))
    assert onset.tolist() == [253, 258]  # 250 update periods, 2 % more with a slow counter
