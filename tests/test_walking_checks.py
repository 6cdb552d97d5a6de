"""Plausibility checks of the walking analysis: a plate declared a quarter turn off, and an
implausibly low stiffness, are named (found by a new user's trial: 7 N·m/rad printed as fine)."""

from __future__ import annotations

import dataclasses
import re

import pytest

from anklelab.pipelines import WalkingSettings, analyze_walking
from anklelab.pipelines.walking.checks import plausibility, walking_direction
from anklelab.pipelines.walking.results import Estimate, TimingPoint
from tests.lab_twin import small_twin


@pytest.fixture(scope="module")
def twin():
    return small_twin(seed=3)


def _declared(session, anterior_axis):
    plate = session.info.force_plate.model_copy(update={"anterior_axis": anterior_axis})
    return dataclasses.replace(session, info=dataclasses.replace(session.info, force_plate=plate))


def test_the_declared_walking_direction_passes(twin):
    assert twin.info.force_plate.anterior_axis == "+x"
    assert walking_direction(twin) == []


@pytest.mark.filterwarnings("ignore::anklelab.errors.AnklelabWarning")
def test_a_plate_declared_a_quarter_turn_off_is_named(twin):
    """The walking direction is the plate's +x; declared +y, the COP of the loaded foot moves
    16 cm across the declared direction and 0.1 cm along it, and the stiffness reads -35 to
    +22 N·m/rad."""
    session = _declared(twin, "+y")
    (message,) = walking_direction(session)
    match = re.fullmatch(
        r"walking/: the centre of pressure of the loaded foot travels ([\d.]+) cm across the "
        r"declared walking direction \(anterior_axis = '\+y'\) and ([\d.]+) cm along it "
        r"\(medians of 10 unperturbed trials\): the walking direction is probably the plate's x "
        r"axis \(anterior_axis '\+x' or '-x'\), and every lever arm and stiffness is then wrong",
        message,
    )
    assert match and float(match[1]) > 10 * float(match[2])
    result = analyze_walking(session, WalkingSettings(bootstrap_reps=10, interval_reps=40))
    assert result.warnings[0] == message
    low = [w for w in result.warnings if "is below 20, implausible" in w]
    assert low and all(0 < float(w.split()[2]) < 20 for w in low)


def _point(stiffness):
    e = Estimate(stiffness, 1.0, (0.9 * stiffness, 1.1 * stiffness))
    return TimingPoint(100.0, "dorsi", 50, 200, 0.06, e, e, e, e, "constant", e, False)


@pytest.mark.parametrize(("stiffness", "flagged"), [(7.0, True), (19.9, True), (20.0, False)])
def test_a_stiffness_below_20_nm_per_rad_is_implausible(stiffness, flagged):
    messages = plausibility([_point(stiffness)], 0.04)
    assert any("below 20, implausible for an ankle loaded in stance" in m for m in messages) == (
        flagged
    )
