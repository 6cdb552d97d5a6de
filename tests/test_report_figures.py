"""Every walking figure as a reader sees it: no overlapping texts, no legend over a panel, units
on every axis, no code names; the impedance figures' intervals, paper values and flags."""

import numpy as np
import pytest
from matplotlib.figure import Figure

from anklelab.report import figures_walking
from anklelab.report.figures_impedance import CI95, SD95, estimate, impedance_figure
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


def test_stance_profiles_show_angles_in_degrees(results):
    fig = figures_walking.stance_figure(results)
    angle = fig.axes[0]
    assert angle.get_ylabel() == "ankle angle (deg)"
    # the perturbation is 0.035 rad, 2.0 deg: the perturbed mean departs by about that much
    unperturbed, perturbed = angle.lines[0].get_ydata(), angle.lines[1].get_ydata()
    assert 1.0 < np.max(np.abs(perturbed - unperturbed)) < 3.0


def _document(**stiffness):
    point = {
        "delay_ms": 100.0,
        "direction": "dorsi",
        "cop_m": 0.06,
        "stiffness_nm_per_rad": {"mean": 1200.0, "sd": 10.0, **stiffness},
        "damping_nms_per_rad": {"mean": 2.0, "sd": 0.4, "poorly_determined": True},
        "inertia_kgm2": {"mean": 0.3, "sd": 0.01},
        "vaf_percent": {"mean": 99.0, "sd": 0.1},
    }
    return {
        "timing_points": [point, {**point, "delay_ms": 475.0, "cop_m": 0.105}],
        "bench": [
            {"distance_m": 0.06, "stiffness_nm_per_rad": 1300.0, "r2": 0.99},
            {"distance_m": 0.11, "stiffness_nm_per_rad": 975.0, "r2": 0.99},
        ],
    }


def test_intervals_are_the_ci95_when_given_else_labelled_sd():
    with_ci = _document(ci95=[1180.0, 1230.0])
    e = estimate(with_ci["timing_points"][0], "stiffness_nm_per_rad")
    assert (e.low, e.high, e.kind) == (1180.0, 1230.0, CI95)
    e = estimate(_document()["timing_points"][0], "stiffness_nm_per_rad")
    assert (e.low, e.high, e.kind) == (1180.4, 1219.6, SD95)
    for bad in ([1, "x"], "wide", [1.0]):  # malformed ci95: falls back, labelled so
        assert (
            estimate(_document(ci95=bad)["timing_points"][0], "stiffness_nm_per_rad").kind == SD95
        )
    table = impedance_summary_table(with_ci)
    assert table.rows[0][3] == "1200\N{NO-BREAK SPACE}[1180,\N{NO-BREAK SPACE}1230]"
    assert table.rows[0][4].endswith("* (poorly determined)")
    assert table.rows[1][-2:] == ["1008", "+19.1"]  # 1300 - 325 * 4.5 / 5 at 10.5 cm; error


def test_the_key_figure_draws_flags_hollow_and_the_paper():
    document = _document(ci95=[1180.0, 1230.0])
    document["timing_points"][1]["flags"] = ["stiffness_nm_per_rad"]
    fig = impedance_figure(document)
    stiffness, damping, _ = fig.axes
    drawn = [line for line in stiffness.lines if line.get_marker() == "o" and len(line.get_xdata())]
    face = [line.get_markerfacecolor() for line in drawn]
    assert face == ["tab:blue", "white"]  # the 475 ms stiffness is flagged
    assert all(
        line.get_markerfacecolor() == "white" for line in damping.lines if line.get_marker() == "o"
    )  # damping is flagged at both points
    stars = [line for line in stiffness.lines if line.get_marker() == "*"]
    assert [list(s.get_ydata()) for s in stars] == [[1277.0, 860.0]]  # paper 000's range ends
    legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert "poorly determined" in legend and "paper 000" in legend and "bench" in legend
    assert problems(fig) == []
    assert [n for n in notes(document)] == [
        "dorsi 100 ms: damping poorly determined (drawn hollow)",
        "dorsi 475 ms: stiffness, damping poorly determined (drawn hollow)",
    ]


def test_settings_read_as_words_with_units():
    assert readable_name("cutoff_hz") == "low-pass cut-off (Hz)"
    assert readable_name("new_window_ms") == "new window (ms)"
