"""Generic safety monitor: every check trips, the fault latches, requests are clamped."""

import math

import pytest

from anklelab.control.safety import Fault, SafetyLimits, SafetyMonitor
from anklelab.errors import ParameterError

LIMITS = SafetyLimits(
    position_min=-0.7,
    position_max=0.7,
    velocity_max=3.0,
    output_max=6.0,
    output_trip=8.0,
    sensor_min=-1.5,
    sensor_max=1.5,
    max_stale_ticks=2,
)
GOOD = {"position": 0.1, "velocity": 0.5, "measured_output": 1.0, "request": 2.0}


def run(monitor, n=1, start=0, **changes):
    values = {**GOOD, **changes}
    out = None
    for k in range(n):
        out = monitor.check(
            values["position"],
            values["velocity"],
            counter=start + k,
            measured_output=values["measured_output"],
            request=values["request"],
        )
    return out


def test_healthy_requests_pass_and_are_clamped():
    m = SafetyMonitor(LIMITS)
    assert run(m) == 2.0
    assert run(m, start=1, request=-50.0) == -6.0
    assert m.fault is Fault.NONE


@pytest.mark.parametrize(
    ("changes", "fault"),
    [
        ({"position": math.nan}, Fault.SENSOR_NAN),
        ({"velocity": math.inf}, Fault.SENSOR_NAN),
        ({"measured_output": math.nan}, Fault.SENSOR_NAN),
        ({"position": 2.0}, Fault.SENSOR_RANGE),
        ({"position": 0.71}, Fault.POSITION),
        ({"position": -0.71}, Fault.POSITION),
        ({"velocity": -3.1}, Fault.VELOCITY),
        ({"measured_output": 8.5}, Fault.OUTPUT),
        ({"request": math.nan}, Fault.COMMAND_NAN),
    ],
)
def test_each_check_trips_and_latches(changes, fault):
    m = SafetyMonitor(LIMITS)
    assert run(m, n=3) == 2.0
    assert run(m, start=3, **changes) == 0.0
    assert m.fault is fault
    # healthy readings afterwards do not clear a latched fault
    assert run(m, n=5, start=10) == 0.0 and m.fault is fault
    m.reset()
    assert run(m, start=20) == 2.0 and m.fault is Fault.NONE


def test_stale_counter_trips_after_max_stale_ticks():
    m = SafetyMonitor(LIMITS)
    outputs = [m.check(0.1, 0.0, counter=7, measured_output=0.0, request=1.0) for _ in range(4)]
    assert outputs == [1.0, 1.0, 1.0, 0.0]  # 2 repeats tolerated, the 3rd trips
    assert m.fault is Fault.SENSOR_STALE


def test_custom_safe_output():
    limits = LIMITS.replace({"safe_output": -0.5})
    m = SafetyMonitor(limits)
    assert run(m, position=math.nan) == -0.5


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"position_min": 0.8}, "position_min must be < position_max"),
        ({"sensor_max": 0.5}, "sensor range must contain"),
        ({"safe_output": 7.0}, "safe_output"),
        ({"velocity_max": 0.0}, "velocity_max: Input should be greater than 0"),
    ],
)
def test_invalid_limits_are_rejected(changes, message):
    with pytest.raises(ParameterError, match=message):
        LIMITS.replace(changes)
