"""Plausibility checks of the walking analysis: a plate declared a quarter turn off, an
implausibly low stiffness (a new user's trial printed 7 N·m/rad as fine) and a bench value
extrapolated beyond the tested distances are named."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from anklelab.ident.bench import BenchStiffness
from anklelab.pipelines import WalkingResults, WalkingSettings, analyze_walking
from anklelab.pipelines.walking.checks import (
    extrapolated_bench,
    plausibility,
    walking_direction,
)
from anklelab.pipelines.walking.results import Estimate, TimingPoint
from anklelab.report.summary import impedance_summary_table
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
    16 cm across the declared direction and 0.1 cm along it (the stiffness reads -35 to +22
    N·m/rad)."""
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
    assert result.warnings[0] == message  # first, before what follows from it


def _point(stiffness, upper=None):
    upper = 1.1 * stiffness if upper is None else upper
    e = Estimate(stiffness, 1.0, (0.9 * stiffness, upper))
    return TimingPoint(100.0, "dorsi", 50, 200, 0.06, e, e, e, e, "constant", e, False)


@pytest.mark.parametrize(
    ("stiffness", "upper", "flagged"),
    [(7.0, 9.0, True), (19.9, 19.95, True), (19.0, 25.0, False), (20.0, 22.0, False)],
)
def test_a_stiffness_whose_interval_lies_below_20_nm_per_rad_is_implausible(
    stiffness, upper, flagged
):
    messages = plausibility([_point(stiffness, upper)], 0.04)
    implausible = any("below 20, implausible for an ankle loaded in stance" in m for m in messages)
    assert implausible == flagged


def test_a_lever_arm_beyond_the_bench_distances_is_extrapolated_and_named():
    """The clean-room stiff prosthetic foot of seed 100 read lever arms of 2.3 and 4.2 cm where
    the bench tested 6.2 to 10.6 cm: its walking-minus-bench errors came from the bench line
    extended. 0.5 mm short of the tested range is no extrapolation."""
    bench = [BenchStiffness(0.062, 1400.0, 1.0, 5), BenchStiffness(0.106, 1000.0, 1.0, 5)]
    points = [
        dataclasses.replace(_point(1500.0), delay_ms=d, direction=direction, cop_m=cop)
        for d, direction, cop in (
            (100.0, "dorsi", 0.023),
            (225.0, "dorsi", 0.0615),
            (225.0, "plantar", 0.02),
            (475.0, "dorsi", 0.12),
        )
    ]
    (message,) = extrapolated_bench(points, bench)
    assert message.startswith(
        "validation: the lever arms of dorsi/100 (2.3 cm), dorsi/475 (12.0 cm) lie more than 5 mm "
        "outside the bench tests' actuator distances (6.2 to 10.6 cm)"
    )
    results = WalkingResults(WalkingSettings(), {}, points, bench)
    flags = {row["delay_ms"]: row["bench_extrapolated"] for row in results.validation()}
    assert flags == {100.0: True, 225.0: False, 475.0: True}
    table = impedance_summary_table(results)
    column = list(table.columns).index("bench stiffness (N·m/rad)")
    marked = [row[column].endswith(" (line extended)") for row in table.rows]
    assert marked == [True, False, True, True]  # the report marks them, plantarflexion too
    assert extrapolated_bench(points[1:3], bench) == [] == extrapolated_bench(points, [])


@pytest.mark.parametrize(
    ("gain", "flagged"),
    [(1.0, False), (0.55, False), (1.45, False), (0.45, True), (57.3, True), (-1.0, True),
     (float("nan"), False)],
)  # fmt: skip
def test_an_ankle_angle_that_does_not_follow_the_plate_is_implausible(gain, flagged):
    messages = plausibility([dataclasses.replace(_point(1200.0), angle_gain=gain)], 0.04)
    named = [m for m in messages if "times the plate's rotation" in m]
    assert bool(named) == flagged
    if flagged:
        assert named[0].startswith(f"dorsi/100: the ankle angle moves {gain:.2f} times")


@pytest.mark.filterwarnings("ignore::anklelab.errors.AnklelabWarning")
def test_an_ankle_angle_recorded_in_degrees_is_named(twin):
    """The goniometer's column in degrees: every point's angle moves about 57 times the plate's
    (this small session's gains scatter by some percent)."""
    from anklelab.data import Recording, WalkingTrial

    walking = tuple(
        WalkingTrial(
            t.trial,
            Recording(
                t.recording.name,
                dict(t.recording.columns) | {"ankle_angle": np.degrees(t.recording["ankle_angle"])},
            ),
            t.perturbed,
            t.direction,
            t.delay_ms,
        )
        for t in twin.walking
    )
    session = dataclasses.replace(twin, walking=walking)
    result = analyze_walking(session, WalkingSettings(bootstrap_reps=10, interval_reps=40))
    named = [w for w in result.warnings if "times the plate's rotation" in w]
    assert len(named) == len(result.timing_points)
    gains = [float(re.search(r"moves ([\d.]+) times", w)[1]) for w in named]
    assert all(50 < gain < 66 for gain in gains)
