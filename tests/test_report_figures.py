"""Every walking figure as a reader sees it: no overlapping texts, no legend over a panel, units
on every axis, no code names; the impedance figures' intervals, paper values and flags."""

import numpy as np
import pytest
from matplotlib.figure import Figure

from anklelab.report import figures_walking
from anklelab.report.figures_impedance import CI95, IMPEDANCE, SD95, impedance_figure, interval
from anklelab.report.summary import impedance_summary_table, notes, readable_name
from tests.figure_checks import problems


@pytest.fixture(scope="module")
def results():
    from anklelab.experiments import simulate_perturberator
    from anklelab.pipelines import WalkingSettings, analyze_walking

    session = simulate_perturberator(trials_per_point=8, n_unperturbed=16, n_calibration=2, seed=5)
    return analyze_walking(session, WalkingSettings(bootstrap_reps=10))


def test_the_checker_finds_what_a_reader_would():
    fig = Figure(figsize=(4, 3), layout="constrained")
    ax = fig.subplots()
    ax.plot(np.arange(10), np.arange(10), label="a long legend label right over the data")
    ax.legend(loc="center")
    ax.set_xlabel("cop_m")
    ax.set_ylabel("stiffness")
    ax.text(4.5, 4.5, "overlapping words")
    found = problems(fig)
    assert "axis label without a unit: 'cop_m'" in found
    assert "axis label without a unit: 'stiffness'" in found
    assert "code name 'cop_m' in 'cop_m'" in found
    assert any("overlap" in p and "'overlapping words'" in p for p in found), found
    assert "a legend covers the panel ''" in found  # a legend inside a panel, over its data
    fig = Figure(figsize=(4, 3), layout="constrained")
    fig.subplots().plot([0, 1])
    fig.legend(["line"], loc="center")
    assert "a legend covers the panel ''" in problems(fig)
    fig = Figure(figsize=(4, 3))  # no layout: the default margins cut a long y label
    ax = fig.subplots()
    ax.plot([0, 1e6])
    ax.set_ylabel("a force that needs a long label (N)", fontsize=30)
    assert "a text is cut by the figure's edge: 'a force that needs a long label (N)'" in problems(
        fig
    )
    fig = Figure(figsize=(6, 3), layout="constrained")  # a right panel of another quantity
    left, right = fig.subplots(1, 2, sharex=True)
    left.plot([0, 1], [0, 1])
    right.plot([0, 1], [0, 100])
    right.set_title("torque")
    right.label_outer()  # drops the right panel's own y scale
    assert problems(fig) == ["the panel 'torque' has no y scale"]


def test_every_walking_figure_is_legible(results):
    figures = figures_walking.walking_figures(results)
    assert list(figures) == [
        "impedance_summary",
        "filters",
        "stance_profiles",
        "model_fit",
        "impedance_vs_lever_arm",
    ]
    for name, fig in figures.items():
        assert problems(fig) == [], name
        width, height = fig.get_size_inches() * 100  # pixels in the report (100 dpi)
        assert width <= 1100 and height <= 700, (name, width, height)


def _with_delays(results, delays):
    """``results`` with every direction's first timing point copied to each of ``delays``
    (its stance trials relabelled to match)."""
    from dataclasses import replace

    from anklelab.signals import Trials

    stance = results.stance
    points, data = [], [stance["none"].data]
    conditions = [["none"] * len(stance["none"])]
    for first in {tp.direction: tp for tp in reversed(results.timing_points)}.values():
        for delay in delays:
            points.append(replace(first, delay_ms=float(delay)))
            data.append(stance[first.key].data)
            conditions.append([points[-1].key] * len(stance[first.key]))
    metadata = {"condition": np.concatenate(conditions)}
    trials = Trials(np.concatenate(data), stance.fs, stance.ch_names, metadata, tmin=stance.tmin)
    return replace(results, timing_points=points, stance=trials)


@pytest.mark.parametrize("variant", ["one condition missing", "six timing points", "one direction"])
def test_the_walking_figures_stay_legible_with_other_conditions(results, variant):
    """A condition that lost every trial leaves a gap in the grids, without taking a row's or a
    column's scale with it; more timing points wrap the legend and the titles."""
    from dataclasses import replace

    points = results.timing_points
    if variant == "six timing points":
        results = _with_delays(results, [100, 190, 280, 370, 460, 550])
    elif variant == "one direction":
        results = replace(results, timing_points=[tp for tp in points if tp.direction == "plantar"])
    for missing in range(len(points)) if variant == "one condition missing" else [None]:
        shown = results
        if missing is not None:
            shown = replace(results, timing_points=points[:missing] + points[missing + 1 :])
        for name in ("stance_profiles", "model_fit"):
            fig = figures_walking.walking_figure(shown, name)
            assert problems(fig) == [], (variant, missing, name)
            assert fig.get_size_inches()[1] * 100 <= 700


def test_stance_profiles_show_angles_in_degrees(results):
    fig = figures_walking.stance_figure(results)
    angle = fig.axes[0]
    assert angle.get_ylabel() == "ankle angle (deg)"
    # the perturbation is 0.035 rad, 2.0 deg: the perturbed mean departs by about that much
    unperturbed, perturbed = angle.lines[0].get_ydata(), angle.lines[1].get_ydata()
    assert 1.0 < np.max(np.abs(perturbed - unperturbed)) < 3.0


def _results(stiffness_ci95=(np.nan, np.nan), flag_last_stiffness=False, warnings=()):
    """Two dorsiflexion conditions; damping's interval spans zero at both (poorly determined)."""
    from anklelab.ident.bench import BenchStiffness
    from anklelab.pipelines.walking import TimingPoint, WalkingResults, WalkingSettings
    from anklelab.pipelines.walking.results import Estimate

    def point(delay_ms, cop_m, ci95):
        return TimingPoint(
            delay_ms,
            "dorsi",
            10,
            20,
            cop_m,
            Estimate(1200.0, 10.0, ci95),
            Estimate(2.0, 0.4, (-0.5, 4.5)),
            Estimate(0.3, 0.01),
            Estimate(99.0, 0.1),
            "constant",
            Estimate(0.0, 0.0),
            False,
            stiffness_change_verdict="undetermined" if delay_ms == 100.0 else None,
            warnings=(f"dorsi/{delay_ms:g}: a point's doubt",) if delay_ms == 475.0 else (),
        )

    last = (300.0, 2100.0) if flag_last_stiffness else stiffness_ci95
    return WalkingResults(
        settings=WalkingSettings(),
        platform_filters={},
        timing_points=[point(100.0, 0.06, stiffness_ci95), point(475.0, 0.105, last)],
        bench=[BenchStiffness(0.06, 1300.0, 0.99, 5), BenchStiffness(0.11, 975.0, 0.99, 5)],
        warnings=warnings,
    )


def test_intervals_are_the_ci95_when_given_else_labelled_sd():
    stiffness = IMPEDANCE[0]
    with_ci = _results((1180.0, 1230.0))
    e = interval(with_ci.timing_points[0], stiffness)
    assert (e.low, e.high, e.kind) == (1180.0, 1230.0, CI95)
    e = interval(_results().timing_points[0], stiffness)  # an older file: no intervals
    assert (e.low, e.high, e.kind) == (1180.4, 1219.6, SD95)
    table = impedance_summary_table(with_ci)
    assert table.rows[0][3] == "1200\N{NO-BREAK SPACE}[1180,\N{NO-BREAK SPACE}1230]"
    assert table.rows[0][4].endswith("[-0.50,\N{NO-BREAK SPACE}4.50] (poorly determined)")
    assert table.rows[1][-2:] == ["1008", "+19.1"]  # 1300 - 325 * 4.5 / 5 at 10.5 cm; error
    # the model, with the change diagnostic's verdict (none in an older file)
    assert [row[-3] for row in table.rows] == ["constant: change undetermined", "constant"]
    assert "*" in impedance_summary_table(_results()).rows[0][3]  # mean ± 1.96 sd, marked


def test_intervals_read_back_from_results_json_are_the_same():
    from anklelab.pipelines.walking import WalkingResults

    results = _results((1180.0, 1230.0), flag_last_stiffness=True)
    again = WalkingResults.from_dict(results.to_dict(session="s"))
    assert impedance_summary_table(again).rows == impedance_summary_table(results).rows
    assert notes(again) == notes(results)


def test_an_interval_beside_its_estimate_is_drawn_as_given():
    """A resampling interval need not contain the estimate (1200 below [1210, 1260])."""
    fig = impedance_figure(_results((1210.0, 1260.0)))
    bars = [c for c in fig.axes[0].collections if len(c.get_segments())]
    assert [list(b.get_segments()[0][:, 1]) for b in bars[:2]] == [[1210.0, 1260.0]] * 2
    assert problems(fig) == []


def test_the_key_figure_draws_flags_hollow_and_the_paper():
    results = _results((1180.0, 1230.0), flag_last_stiffness=True, warnings=("implausible x",))
    fig = impedance_figure(results)
    stiffness, damping, _ = fig.axes
    drawn = [line for line in stiffness.lines if line.get_marker() == "o" and len(line.get_xdata())]
    face = [line.get_markerfacecolor() for line in drawn]
    assert face == ["tab:blue", "white"]  # the 475 ms stiffness is poorly determined
    assert all(
        line.get_markerfacecolor() == "white" for line in damping.lines if line.get_marker() == "o"
    )  # damping is poorly determined at both points
    stars = [line for line in stiffness.lines if line.get_marker() == "*"]
    assert [list(s.get_ydata()) for s in stars] == [[1277.0, 860.0]]  # paper 000's range ends
    legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert "poorly determined" in legend and "paper 000" in legend and "bench" in legend
    assert problems(fig) == []
    assert notes(results) == [
        "implausible x",
        "dorsi/475: a point's doubt",
        "Poorly determined (the 95 % interval spans zero or is wider than ±50 % of the "
        "estimate; drawn hollow, not to be read as precise numbers): stiffness at dorsi/475; "
        "damping at all 2 conditions.",
    ]


@pytest.mark.parametrize("x", ["timing", "lever_arm"])
def test_paper_000_is_drawn_beside_a_session_with_bench_tests_only(x):
    """Paper 000's values are its prosthetic foot's on its testing machine: beside a session
    without bench tests (a human ankle) they are no reference."""
    import dataclasses

    without = dataclasses.replace(_results((1180.0, 1230.0)), bench=[])
    for results, drawn in ((_results((1180.0, 1230.0)), True), (without, False)):
        fig = impedance_figure(results, x=x)
        legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
        assert ("paper 000" in legend) == drawn
        assert problems(fig) == []


def test_settings_read_as_words_with_units():
    assert readable_name("cutoff_hz") == "low-pass cut-off (Hz)"
    assert readable_name("new_window_ms") == "new window (ms)"
