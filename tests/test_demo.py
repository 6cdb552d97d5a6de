"""``anklelab demo --quick``: outputs, values against the twins' truth, the report in a browser."""

import json

import pytest
from typer.testing import CliRunner

from anklelab import __version__
from anklelab.cli import app
from anklelab.data import load_session
from anklelab.demo import COMPENSATIONS, OBSERVER_TASKS, SETPOINTS_DEG, DemoSettings
from anklelab.report.sections import FRICTION_FIGURES, WALKING_FIGURES
from tests.browser import view

# Bode + walking figures; set-point and chirp figures per compensation; observer; friction fits.
N_FIGURES = 1 + len(WALKING_FIGURES) + 2 * len(COMPENSATIONS) + len(OBSERVER_TASKS)
N_FIGURES += len(FRICTION_FIGURES)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "demo-output"
    result = CliRunner().invoke(app, ["demo", "--quick", "--out", str(out), "--seed", "3"])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    return out, result.output, summary


def rows(summary, paper, group_prefix, quantity_prefix=""):
    return [
        r
        for r in summary[paper]
        if r["group"].startswith(group_prefix) and r["quantity"].startswith(quantity_prefix)
    ]


def test_demo_writes_sessions_results_and_report(demo):
    out, _, summary = demo
    for name in (
        "summary.json",
        "report.html",
        "perturberator/session.h5",
        "perturberator/results.json",
        "perturberator/servo_bode.json",
        "capstan/ident/session.toml",
        "capstan/ident/spindown/runs.csv",
        "capstan/friction/friction.json",
        "capstan/control.json",
    ):
        assert (out / name).is_file(), name
    results = json.loads((out / "perturberator/results.json").read_text())
    assert {"platform_filters", "timing_points", "bench", "validation"} <= set(results)
    friction = json.loads((out / "capstan/friction/friction.json").read_text())
    assert {"inertia_kgm2", "viscous_nms_per_rad", "coulomb_nm", "fit"} <= set(friction)
    session = load_session(out / "perturberator/session.h5")
    quick = DemoSettings.quick(3)
    assert len(session.walking) == 4 * quick.trials_per_point + quick.n_unperturbed
    assert session.truth["reference"]["dorsi"]
    assert summary["anklelab_version"] == __version__
    assert summary["settings"] == quick.model_dump()
    assert set(summary["seeds"].values()) == {3}


def test_demo_prints_both_comparison_tables(demo):
    _, output, _ = demo
    assert "Paper 000, the Perturberator" in output and "Paper 001, the capstan platform" in output
    for text in ("paper", "anklelab (twin)", "twin truth", "≈200", "within 300 ms", "7.540e-4"):
        assert text in output, text


def test_walking_values_are_the_analysis_and_match_the_twin_truth(demo):
    out, _, summary = demo
    results = json.loads((out / "perturberator/results.json").read_text())
    dorsi = [tp for tp in results["timing_points"] if tp["direction"] == "dorsi"]
    stiffness = rows(summary, "paper_000", "walking", "stiffness")
    assert len(stiffness) == len(dorsi) == 4
    for row, tp in zip(stiffness, dorsi, strict=True):
        assert row["measured"] == tp["stiffness_nm_per_rad"]["mean"]  # from the run, not typed in
        tolerance = 0.03 * row["truth"] + 3 * row["measured_sd"]
        assert abs(row["measured"] - row["truth"]) < tolerance, row
    for row in rows(summary, "paper_000", "walking", "onset sd"):
        assert row["measured"] == pytest.approx(row["truth"], abs=1.0), row
    (inertia,) = rows(summary, "paper_000", "walking", "inertia")
    assert inertia["measured"] == pytest.approx(inertia["truth"], rel=0.15)
    for row in rows(summary, "paper_000", "bench", "bench stiffness"):
        assert row["measured"] == pytest.approx(row["truth"], rel=0.01), row
    (vaf,) = rows(summary, "paper_000", "platform filters")
    assert vaf["measured"] == pytest.approx(results["platform_filters"]["vaf_percent_mean"])
    bode = json.loads((out / "perturberator/servo_bode.json").read_text())
    servo = rows(summary, "paper_000", "servo")
    assert servo[0]["measured"] == bode["natural_frequency_hz"]
    assert servo[0]["paper"] == 200.0 and servo[0]["truth"] is None


def test_capstan_values_match_the_twin_truth(demo):
    out, _, summary = demo
    friction = rows(summary, "paper_001", "friction")[:7]
    assert [r["paper"] for r in friction] == [7.54e-4, 6.312e-4, 6.011e-4, 0.035, 0.038, 3.2, 0.045]
    for row in friction:
        assert abs(row["error_percent"]) < 5.0, row
    control = json.loads((out / "capstan/control.json").read_text())
    for name in COMPENSATIONS:
        settling = rows(summary, "paper_001", f"set-points, compensation: {name}")
        assert len(settling) == len(SETPOINTS_DEG)
        for row, run in zip(settling, control["setpoints"][name], strict=True):
            assert row["measured"] == pytest.approx(1e3 * run["measured"]["settling_time_5_s"])
            # the encoder's view of the set-point agrees with the true platform angle
            assert row["measured"] == pytest.approx(row["truth"], rel=0.1), row
        (bandwidth, gain, phase) = rows(summary, "paper_001", f"5° chirp, compensation: {name}")
        assert bandwidth["paper"] == 3.0
        assert gain["measured"] == pytest.approx(gain["truth"], abs=0.5)
        assert phase["measured"] == pytest.approx(phase["truth"], abs=3.0)
    observer = rows(summary, "paper_001", "torque observer", "VAF")
    assert [r["measured"] for r in observer] == [
        control["observer"][task]["vaf_percent"] for task in OBSERVER_TASKS
    ]
    assert all(r["measured"] > 80.0 for r in observer)


def test_demo_report_renders_in_headless_chromium(demo):
    out, _, _ = demo
    page = (out / "report.html").read_text()
    assert "<script" not in page and "http://" not in page and "https://" not in page
    seen = view(out / "report.html", "demo_report.png")
    assert seen.console_errors == []
    assert len(seen.images) == N_FIGURES
    for image in seen.images:
        assert image["complete"] and image["width"] > 0 and image["height"] > 0, image
    assert seen.screenshot.stat().st_size > 10_000


def test_every_departure_from_the_papers_is_explained_or_marked_a_miss(demo):
    out, output, summary = demo
    for paper in ("paper_000", "paper_001"):
        for row in summary[paper]:
            value, measured = row["paper"], row["measured"]
            departs = value is not None and (
                measured is None or abs(measured - value) > 0.1 * abs(value)
            )
            if departs:
                assert row["remark"], row
    control = json.loads((out / "capstan/control.json").read_text())
    for name in COMPENSATIONS:
        for row in rows(summary, "paper_001", f"set-points, compensation: {name}"):
            late = row["measured"] is None or row["measured"] > 300.0
            assert row["miss"] == late, row  # paper 001: "within 300 ms"
        (bandwidth, *_) = rows(summary, "paper_001", f"5° chirp, compensation: {name}")
        top = control["chirp"][name]["measured"]["frequency_hz"][-1]
        if bandwidth["measured"] is None:  # worded as the chirp figure's title words it
            assert bandwidth["note"] == f"> {top:.1f} (highest measured)"
    assert "against the paper" in output and "[1] " in output
