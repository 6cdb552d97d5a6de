"""A person on the platform, the person guard, the safety limits a parameter file may set, and a
fault injected into every new mode: the current ends at 0 and the platform inside its limits."""

import math
import tomllib

import numpy as np
import pytest

from anklelab._params import parameters_from_mapping
from anklelab.control import VirtualEnvironment
from anklelab.control.person_guard import guard_constants, guard_update, new_guard_state
from anklelab.control.safety import Fault
from anklelab.errors import ParameterError
from anklelab.experiments.capstan import CapstanSetup, FaultInjection, simulate_closed_loop
from anklelab.experiments.capstan.config import Channel
from anklelab.platforms import load_platform, platform_file
from anklelab.platforms.capstan import CapstanParameters
from anklelab.sim.capstan.person import person_profile

P = load_platform("capstan")


def test_person_profiles_follow_the_human_ankle():
    human = load_platform("perturberator")
    stand = person_profile("standing", 4.0, 1000.0, P, human)
    assert stand.stiffness_nm_per_rad[0] == pytest.approx(3.2 * 75.0)
    assert stand.load_torque_nm[-1] < -5  # the forefoot pushes the front down
    walk = person_profile("walking", 4.0, 1000.0, P, human)
    assert 0.55 < walk.contact.mean() < 0.7 and np.all(
        walk.stiffness_nm_per_rad[walk.contact == 0] == 0
    )


def test_guard_limits_torque_and_jerk_and_stops_on_request():
    c = guard_constants(P, 1000.0, foot_inertia_kgm2=0.02)
    state = new_guard_state(c)
    current, clamped = guard_update(c, state, 100.0, 0.0, 0.0, 0.0, 0.0)  # 700 N·m asked
    torque = current * c.torque_per_amp - c.gravity_torque * math.sin(c.com_angle)
    assert clamped == 1.0 and torque == pytest.approx(min(c.torque_step, c.torque_limit))
    for _ in range(20):
        current, _ = guard_update(c, state, 100.0, 0.0, 0.0, 0.0, 0.0)
    torque = current * c.torque_per_amp - c.gravity_torque * math.sin(c.com_angle)
    assert torque == pytest.approx(c.torque_limit)
    for _ in range(c.stop_ticks + 2):
        current, _ = guard_update(c, state, 1.0, 0.0, 0.5, 0.0, 1.0)  # stop requested
    assert current == 0.0 and state[0] == 1.0


def test_a_person_falling_off_triggers_the_fall_safe_stop():
    setup = CapstanSetup(person="standing")
    n = 4000
    run = simulate_closed_loop(setup, n, fault=FaultInjection("person-falls", 2.0))
    tripped = np.flatnonzero(run["fault"] == Fault.FALL_STOP)
    assert tripped.size and 2000 <= tripped[0] <= 2300
    stop = tripped[0] + round(P.person_safety.stop_time_s * setup.fs) + 1
    assert np.all(run["current_command_a"][stop:] == 0.0)
    calm = simulate_closed_loop(setup, n)  # standing still is not a fall
    assert calm["fault"].max() == 0


def _hostile(**safety):
    data = tomllib.loads(platform_file("capstan").read_text())
    for key, value in safety.items():
        data["safety"][key]["value"] = value
    return data


@pytest.mark.parametrize(
    ("key", "value", "limit"),
    [
        ("angle_limit_rad", 1.5, "workspace.angle_limit_rad = 0.75049"),
        ("velocity_limit_rad_s", 1e9, "no-load speed"),
        ("current_trip_a", 1e9, "drive.current_limit_a = 6"),
        ("sensor_range_rad", 1e9, "vertical plate"),
    ],
)
def test_a_parameter_file_cannot_set_safety_limits_beyond_the_physical_ones(key, value, limit):
    with pytest.raises(ParameterError, match=rf"safety.{key}: .*{limit}"):
        parameters_from_mapping(CapstanParameters, _hostile(**{key: value}), origin="p.toml")


def test_fault_codes_have_meanings():
    for fault in Fault:
        assert fault.meaning and fault.name in fault.describe()


def _env():
    return VirtualEnvironment(stiffness_nm_per_rad=80.0, damping_nms_per_rad=4.0)


NEW_MODES = {
    "admittance": dict(mode="admittance", environment=_env()),
    "impedance with passivity control": dict(mode="impedance", environment=_env()),
    "feed-forward tracking": dict(
        reference=np.radians(10) * np.sin(np.pi * np.arange(3000) / 1000.0),
        reference_speed=np.radians(10) * np.pi * np.cos(np.pi * np.arange(3000) / 1000.0),
    ),
    "teleoperation": dict(
        mode="teleoperation",
        channel=Channel("wave", 0.2, 0.05),
        remote_ground=np.radians(5) * np.sin(np.arange(3000) / 1000.0),
    ),
}


@pytest.mark.parametrize("name", list(NEW_MODES))
@pytest.mark.parametrize("person", ["seated", "standing"])
@pytest.mark.parametrize("kind", ["encoder-nan", "encoder-jump", "current-nan"])
def test_a_sensor_fault_in_every_new_mode_leaves_zero_current_inside_the_limits(name, person, kind):
    setup = CapstanSetup.for_rendering(
        person=None if person == "seated" else person, passivity_control=True
    )
    value = 0.3 if kind == "encoder-jump" else 0.0
    voluntary = 2.0 * np.sin(2 * np.pi * 0.7 * np.arange(3000) / 1000.0)
    run = simulate_closed_loop(
        setup, 3000, voluntary=voluntary, fault=FaultInjection(kind, 1.0, value), **NEW_MODES[name]
    )
    tripped = np.flatnonzero(run["fault"] > 0)
    assert tripped.size and tripped[0] >= 1000
    assert run["current_command_a"][-1] == 0.0
    assert np.all(run["current_command_a"][-200:] == 0.0)
    assert np.max(np.abs(run["angle_rad"])) < P.workspace.angle_limit_rad
