"""Studies on Dask: study files, identical tables however they run, resume after a kill,
failed cells reported, the design preset checked by simulation, and batches of sessions."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from anklelab._runs import RunManifest
from anklelab.errors import AnklelabWarning, ParameterError
from anklelab.studies import (
    attempt,
    checkpoint_for,
    design_trials,
    run_study,
    study_from_mapping,
)
from anklelab.studies.tables import results_table, summary_table

ROOT = Path(__file__).resolve().parents[1]
TINY = {
    "name": "tiny",
    "seeds": [0, 1],
    "twin": {"trials_per_point": 3, "n_unperturbed": 6, "n_calibration": 2, "bench": False},
    "analysis": {"bootstrap_reps": 10},
    "grid": {"params.geometry.misalignment_anterior_m": [0.0, 0.016]},
}
TINY_TOML = """
name = "tiny"
seeds = [0, 1]
[twin]
trials_per_point = 3
n_unperturbed = 6
n_calibration = 2
bench = false
[analysis]
bootstrap_reps = 10
[grid]
"params.geometry.misalignment_anterior_m" = [0.0, 0.016]
"""


def test_a_grid_expands_to_every_combination_times_every_seed():
    doc = TINY | {"grid": {"analysis.window_ms": [75.0, 100.0, 125.0], "twin.foot": ["human"]}}
    cells = study_from_mapping(doc, origin="s").cells()
    assert len(cells) == 3 * 1 * 2
    assert [c.seed for c in cells[:2]] == [0, 1]
    assert cells[2].analysis == {"bootstrap_reps": 10, "window_ms": 100.0}
    assert len({c.key for c in cells}) == len(cells)


def test_a_sample_is_drawn_from_its_own_seed():
    doc = {k: v for k, v in TINY.items() if k != "grid"} | {
        "twin": {"n_unperturbed": 6, "n_calibration": 2, "bench": False},
        "sample": {
            "n": 4,
            "seed": 3,
            "params.geometry.misalignment_anterior_m": {"uniform": [0.0, 0.02]},
            "twin.trials_per_point": {"integers": [3, 5]},
            "twin.foot": {"choice": ["prosthetic", "human"]},
        },
    }
    first = study_from_mapping(doc, origin="s").points()
    assert first == study_from_mapping(doc, origin="s").points()
    assert len(first) == 4
    assert all(0 <= p["params.geometry.misalignment_anterior_m"] <= 0.02 for p in first)
    assert {p["twin.trials_per_point"] for p in first} <= {3, 4, 5}


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"colour": 1}, "colour: unknown key"),
        ({"grid": {"window_ms": [75.0]}}, "expected twin.KEY"),
        ({"grid": {"analysis.window_ms": [75.0, -1.0]}}, "window_ms = -1.0.*window_ms"),
        ({"grid": {"params.geometry.misalignment_anterior": [0.0]}}, "did you mean"),
        ({"seeds": 0}, "seeds: expected a count"),
        ({"twin": {"foot": "robot"}}, "foot"),
        ({"grid": {"analysis.window_ms": [75.0, float("nan")]}}, r"window_ms\[1\]: .*finite"),
        ({"grid": {"twin.trials_per_point": [3, 5]}}, "fixed setting and in \\[grid\\]"),
        ({"grid": 1.5}, "\\[grid\\]: expected a table"),
        (
            {"twin": TINY["twin"] | {"unperturbed_per_point": 4.0}},
            "n_unperturbed and unperturbed_per_point: give one of them",
        ),
        # a mistake in the fixed settings is theirs, not the grid point's
        (
            {"analysis": {"bootstrap_reps": 10, "colour": 1}},
            r"study\.toml: fixed settings: \[analysis\] 'colour': unknown parameter",
        ),
        # what would fail only once a session is simulated is found before any is
        (
            {"analysis": {"bootstrap_reps": 10, "cutoff_hz": 5000.0}},
            r"\[analysis\] cutoff_hz = 5000: expected below the twin's Nyquist frequency, 500 Hz",
        ),
        (
            {"grid": {"analysis.window_ms": [100.0, 900.0]}},
            r"window_ms = 900\.0: \[analysis\] window_ms: the 900 ms window of the last timing "
            r"point \(475 ms\) ends after toe-off",
        ),
        (
            {"grid": {"params.walking.timing_points_ms": [[100.0, 2000.0]]}},
            r"\[params\] walking\.timing_points_ms: the last \(2000 ms after heel contact\)",
        ),
        (
            {"grid": {"twin.trials_per_point": [4, 100000]}, "twin": {"n_unperturbed": 6}},
            "trials_per_point = 100000: .*less than or equal to 1000",
        ),
    ],
)
def test_a_bad_study_file_is_one_clear_error_naming_the_key(change, match):
    with pytest.raises(ParameterError, match=match):
        study_from_mapping(TINY | change, origin="study.toml")


def test_a_failing_task_is_retried_then_recorded_with_its_error():
    calls = []

    def flaky(x):
        calls.append(x)
        raise RuntimeError("the twin\nfell over")

    record = attempt(flaky, (1,), retries=2)
    assert record == {"ok": False, "attempts": 3, "error": "RuntimeError: the twin fell over"}
    assert len(calls) == 3
    ok = attempt(lambda: {"rows": []}, (), retries=2)
    assert ok == {"ok": True, "attempts": 1, "rows": []}


def test_a_failed_cell_stays_in_the_tables():
    row = {"direction": "dorsi", "delay_ms": 100.0, "n_perturbed": 3, "quantity": "cop_m",
           "truth": 0.06, "estimate": 0.061, "sd": np.nan, "ci95_low": np.nan,
           "ci95_high": np.nan, "interval_kind": "", "error": 0.001, "error_percent": 1.0 / 0.6,
           "half_width_percent": np.nan, "covered": None, "poorly_determined": None,
           "warnings": ""}  # fmt: skip
    records = [
        ({"cell": "a", "cell_index": 0, "seed": 0, "x": 1.0}, {"ok": True, "rows": [row]}),
        ({"cell": "b", "cell_index": 1, "seed": 1, "x": 1.0}, {"ok": False, "error": "E: x"}),
    ]
    results = results_table(records, ["x"])
    assert list(results["status"]) == ["ok", "failed"]
    assert results["failure"].iloc[1] == "E: x"
    summary = summary_table(results, ["x"])
    assert summary["n_sessions"].tolist() == [1] and summary["n_failed"].tolist() == [1]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The tiny study, uninterrupted, on the default local scheduler."""
    out = tmp_path_factory.mktemp("study") / "default"
    run = run_study(study_from_mapping(TINY, origin="tiny"), out, workers=2)
    assert run.ran == 4 and run.failed.empty
    return out, run


def test_the_study_table_holds_truth_estimate_interval_error_and_coverage(reference):
    out, _ = reference
    table = pd.read_parquet(out / "results.parquet")
    assert set(table["quantity"]) >= {
        "stiffness_nm_per_rad", "damping_nms_per_rad", "inertia_kgm2", "vaf_percent",
        "stiffness_change_fraction", "cop_m",
    }  # fmt: skip
    stiffness = table[table["quantity"] == "stiffness_nm_per_rad"]
    # the analysis's 95 % interval; a condition of one trial has none, and is poorly determined
    assert set(stiffness["interval_kind"]) == {"ci95", ""}
    single = stiffness[stiffness["interval_kind"] == ""]
    assert (single["n_perturbed"] == 1).all() and single["poorly_determined"].all()
    assert single["ci95_low"].isna().all() and single["covered"].isna().all()
    bounded = stiffness[stiffness["interval_kind"] == "ci95"]
    assert (bounded["ci95_low"] <= bounded["ci95_high"]).all()
    assert set(stiffness["stiffness_model"]) <= {"constant", "linear"}
    assert stiffness["poorly_determined"].isin([True, False]).all()
    assert table.loc[table["quantity"] == "cop_m", "poorly_determined"].isna().all()
    change = table[table["quantity"] == "stiffness_change_fraction"]
    assert change["truth"].notna().all()  # the twin's within-window change, for the estimate
    np.testing.assert_allclose(stiffness["error"], stiffness["estimate"] - stiffness["truth"])
    assert stiffness["error_percent"].abs().max() < 25  # tiny sessions, but the right answer
    summary = pd.read_csv(out / "summary.csv")
    assert {"bias_percent", "sd_percent", "rmse_percent", "coverage",
            "poorly_determined_fraction"} <= set(summary.columns)  # fmt: skip
    figure = "stiffness_error_vs_params.geometry.misalignment_anterior_m.png"  # the full key
    assert (out / "figures" / figure).is_file()
    assert len(pd.read_csv(out / "cells.csv")) == 4


def test_a_local_cluster_over_tcp_gives_identical_tables(reference, tmp_path):
    out, _ = reference
    study = study_from_mapping(TINY, origin="tiny")
    run_study(study, tmp_path / "cluster", scheduler="local-cluster", workers=2, figures=False)
    for name in ("results.parquet", "results.csv", "summary.parquet", "summary.csv"):
        assert (tmp_path / "cluster" / name).read_bytes() == (out / name).read_bytes(), name


def test_a_killed_study_resumes_to_the_same_table(reference, tmp_path):
    out, _ = reference
    study_file = tmp_path / "tiny.toml"
    study_file.write_text(TINY_TOML, encoding="utf-8")
    target = tmp_path / "killed"
    command = [sys.executable, "-c", "from anklelab.cli import run; run()", "study",
               str(study_file), "--out", str(target), "--workers", "1", "--no-figures"]  # fmt: skip
    proc = subprocess.Popen(command, start_new_session=True, stderr=subprocess.DEVNULL)
    cells = checkpoint_for(target)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and len(list(cells.glob("*.json"))) < 1:
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)  # the command and its worker processes
    proc.wait()
    done = len(list(cells.glob("*.json")))
    assert 1 <= done < 4, f"{done} cells written before the kill"
    assert not target.exists()  # the output appears only when the study completes
    resumed = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert f"({done} already done, {4 - done} run)" in resumed.stdout
    assert (target / "results.csv").read_bytes() == (out / "results.csv").read_bytes()
    assert not cells.exists() and len(list((target / "cells").glob("*.json"))) == 4
    manifest = RunManifest.load(target)
    assert manifest.command == "study" and "results.parquet" in manifest.files
    assert manifest.settings["study"]["seeds"] == [0, 1]
    again = subprocess.run(command, capture_output=True, text=True, timeout=60)
    assert again.returncode == 2
    refused = f"error: --out {target}: already exists; pass --force to replace it"
    assert again.stderr.strip() == refused


def test_a_directory_that_is_no_study_output_is_never_replaced(reference, tmp_path):
    out, _ = reference  # written by run_study itself: no run.json
    study_file = tmp_path / "other.toml"
    study_file.write_text(TINY_TOML.replace("[0, 1]", "[5]"), encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-c", "from anklelab.cli import run; run()", "study", str(study_file),
         "--out", str(out), "--force"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 2
    assert "not replaced: it has no run.json" in proc.stderr
    assert not checkpoint_for(out).exists()


def test_design_recommendation_reaches_the_target_when_simulated(tmp_path):
    target = 8.0
    options = dict(analysis={"bootstrap_reps": 30}, n_calibration=2, workers=2, figures=False)
    design = design_trials(tmp_path / "design", interval_percent=target, change_percent=15.0,
                           pilot=(6, 12), seeds=2, **options)  # fmt: skip
    assert design.recommended == max(design.for_interval, design.for_power)
    assert design.curve["half_width_percent"][design.recommended - 2] <= target
    assert (tmp_path / "design" / "design.json").is_file()
    # fresh sessions at the recommended count: every condition's interval within the target
    check = dict(TINY) | {
        "seeds": [20, 21],
        "twin": {"trials_per_point": design.recommended, "unperturbed_per_point": 4.0,
                 "n_calibration": 2, "bench": False},
        "analysis": {"bootstrap_reps": 30},
    }  # fmt: skip
    check.pop("grid")
    run = run_study(study_from_mapping(check, origin="check"), tmp_path / "check", workers=2,
                    figures=False)  # fmt: skip
    rows = run.results[run.results["quantity"] == "stiffness_nm_per_rad"]
    widths = rows.groupby(["direction", "delay_ms"])["half_width_percent"].mean()
    assert widths.max() <= target, widths.to_dict()


def test_a_batch_whose_every_session_fails_names_them_and_ends_cleanly(tmp_path):
    from typer.testing import CliRunner

    from anklelab.cli import app

    broken = tmp_path / "S1" / "day1"
    broken.mkdir(parents=True)
    result = CliRunner().invoke(app, ["batch", str(broken), "--out", str(tmp_path / "out")])
    assert result.exit_code == 1, result.output
    assert "0 of 1 sessions analysed (0 subjects)" in result.output
    assert "warning: day1: " in result.output and "Traceback" not in result.output


def test_batch_analyses_sessions_into_a_group_table(tmp_path):
    from typer.testing import CliRunner

    from anklelab.cli import app
    from anklelab.data import save_session
    from anklelab.experiments import simulate_perturberator

    paths = []
    for i, foot in enumerate(("prosthetic", "human")):
        session = simulate_perturberator(trials_per_point=4, n_unperturbed=8, n_calibration=2,
                                         bench=False, seed=i, foot=foot)  # fmt: skip
        paths.append(save_session(session, tmp_path / f"S{i}" / "day1.h5"))
    broken = tmp_path / "S9" / "day1"
    broken.mkdir(parents=True)
    settings = tmp_path / "settings.toml"
    settings.write_text("bootstrap_reps = 10\n")
    out = tmp_path / "out"
    args = ["batch", *map(str, [*paths, broken]), "--out", str(out), "--workers", "1",
            "--settings", str(settings)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, result.output  # one session failed, named
    assert "warning: S9-day1:" in result.output and "session.toml" in result.output
    group = pd.read_csv(out / "group.csv")
    assert set(group.loc[group["status"] == "ok", "subject"]) == {"twin-prosthetic", "twin-human"}
    assert (group["status"] == "failed").sum() == 1
    assert {"ci95_low", "ci95_high", "sd", "poorly_determined", "stiffness_model"} <= set(group)
    pooled = pd.read_csv(out / "pooled.csv")
    assert (pooled["n_subjects"] <= 2).all() and (pooled["n_subjects"] == 2).any()
    # a prosthetic foot and a human ankle pooled: the stiffness interval of two means spans zero
    stiffness = pooled[(pooled["quantity"] == "stiffness_nm_per_rad") & (pooled["n_subjects"] == 2)]
    spans_zero = (stiffness["ci95_low"] <= 0) & (stiffness["ci95_high"] >= 0)
    assert spans_zero.any() and (stiffness["poorly_determined"] >= spans_zero).all()
    # and wherever a session's own estimate is poorly determined (one subject: no interval)
    keys = ["direction", "delay_ms", "quantity"]
    members = group[group["status"] == "ok"].groupby(keys)["poorly_determined"].max()
    joined = pooled.set_index(keys)["poorly_determined"].astype(bool)
    flagged = members.reindex(joined.index).fillna(0).astype(bool)
    assert flagged.any() and (joined >= flagged).all()
    for name in ("S0-day1", "S1-day1"):
        assert (out / "sessions" / name / "results.json").is_file()
    assert (out / "figures" / "stiffness_pooled.png").is_file()
    manifest = RunManifest.load(out)
    assert manifest.command == "batch" and manifest.settings["bootstrap_reps"] == 10
    recorded = {Path(i["path"]).name for i in manifest.inputs}
    assert {"day1.h5", "settings.toml"} <= recorded and not checkpoint_for(out).exists()


EXAMPLE_STUDIES = sorted(
    (Path(__file__).resolve().parents[1] / "examples" / "studies").glob("*.toml")
)


@pytest.mark.parametrize("path", EXAMPLE_STUDIES, ids=lambda p: p.name)
def test_example_study_files_are_valid_studies(path):
    from anklelab.studies import load_study

    study = load_study(path)
    assert study.varied and len(study.cells()) >= 9


def test_a_bad_study_file_ends_in_one_error_line_and_exit_code_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(TINY_TOML.replace("[twin]", "colour = 1\n[twin]"), encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-c", "from anklelab.cli import run; run()", "study", str(bad),
         "--out", str(tmp_path / "out")],
        capture_output=True, text=True,
    )  # fmt: skip
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [f"error: {bad}: colour: unknown key"]
    assert not (tmp_path / "out").exists()


def test_design_table_shows_the_recommended_count_instead_of_a_neighbour(capsys):
    """The table's geometric rows (2 ... 2n) would put 123 beside a recommended 122: the
    recommended count takes the place of any row within 10 % of it."""
    import numpy as np

    from anklelab.commands.design import _print_curve

    n = np.arange(2, 245)
    curve = {
        "trials_per_point": n.tolist(),
        "half_width_percent": (33.0 / np.sqrt(n)).tolist(),
        "power": np.minimum(1.0, n / 50).tolist(),
        "recommended": 122,
        "pilot": {key: [] for key in ("trials_per_point", "half_width_percent", "left_out")},
    }
    curve["pilot"] |= {"fitted_half_width_percent": [], "rms_error_percent": []}
    _print_curve(curve, "ci95")
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    counts = [int(row[0]) for row in rows if len(row) >= 3 and row[0].isdigit()]
    assert 122 in counts and 123 not in counts and counts == sorted(counts)


def test_a_condition_of_one_trial_has_no_interval_and_is_poorly_determined():
    """results.json gives it no ci95 (null); the tables once drew mean ± 1.96 sd of identical
    subsets, a zero-width "interval" that counted as a miss in the coverage."""
    import math

    from anklelab.pipelines.walking.results import Estimate, TimingPoint, WalkingResults
    from anklelab.pipelines.walking.settings import WalkingSettings
    from anklelab.studies.rows import timing_point_rows

    one = Estimate(1200.0, 1e-13)  # one trial: its subsets are all the same trial
    many = Estimate(1200.0, 10.0, (1180.0, 1220.0))
    points = [
        TimingPoint(100.0, "dorsi", n, 20, 0.06, e, e, e, e, "constant", e, False)
        for n, e in ((1, one), (30, many))
    ]
    document = WalkingResults(WalkingSettings(), {}, points, []).to_dict(session="s")
    truth = {"stiffness_nm_per_rad": 1210.0}
    rows = timing_point_rows(document, {"dorsi": {"100": truth}})
    stiffness = {r["n_perturbed"]: r for r in rows if r["quantity"] == "stiffness_nm_per_rad"}
    single, several = stiffness[1], stiffness[30]
    assert single["poorly_determined"] is True and single["covered"] is None
    assert math.isnan(single["ci95_low"]) and math.isnan(single["sd"])
    assert single["interval_kind"] == "" and math.isnan(single["half_width_percent"])
    assert several["covered"] is True and several["interval_kind"] == "ci95"


def test_an_unreadable_stored_result_is_named_and_computed_again(tmp_path):
    from anklelab.errors import AnklelabWarning
    from anklelab.studies.execute import ResultStore

    store = ResultStore(tmp_path)
    store.write("good", {"ok": True, "rows": [1, 2]})
    (tmp_path / "cut.json").write_text('{"rows": [1, 2', encoding="utf-8")  # a file cut short
    (tmp_path / "list.json").write_text("[1, 2]", encoding="utf-8")
    assert store.has("good") and not store.has("missing")
    with pytest.warns(AnklelabWarning, match=r"cut\.json: an earlier run's result is unreadable"):
        assert not store.has("cut")
    with pytest.warns(AnklelabWarning, match=r"list\.json: .*not a JSON object"):
        assert not store.has("list")


def _pilot_rows(m: list[float], half_width: list[float], flagged: list[bool]) -> pd.DataFrame:
    """Stiffness rows of one condition (dorsi/100), one per pilot interval of ``m`` trials."""
    return pd.DataFrame(
        {"twin.trials_per_point": 2 * np.asarray(m), "seed": range(len(m)), "direction": "dorsi",
         "delay_ms": 100.0, "n_perturbed": m, "half_width_percent": half_width,
         "poorly_determined": flagged, "error_percent": 0.0, "interval_kind": "ci95"}
    )  # fmt: skip


def test_the_design_curve_follows_the_pilots_well_determined_intervals():
    """Least squares on the squared half-widths followed the smallest pilot's widest intervals
    and over-recommended. Here the larger pilots' intervals are exactly 10 % / sqrt(m); the
    smallest pilot has one wide interval and one the analysis flagged as poorly determined."""
    from scipy.stats import binom

    from anklelab.studies.design import _answer, _c_bound

    m = [4.0, 4.0, 16.0, 16.0, 32.0, 32.0]
    widths = [30.0, 80.0, *(10.0 / np.sqrt(m[2:]))]
    rows = _pilot_rows(m, widths, [False, True, False, False, False, False])
    vague = _pilot_rows([4.0, 16.0], [90.0, 50.0], [True, True]).assign(delay_ms=225.0)
    with pytest.warns(AnklelabWarning, match=r"design: dorsi/225: no pilot interval the fit can "
                                             r"use .*: left out of the design"):  # fmt: skip
        design = _answer(pd.concat([rows, vague]), None, target=3.0, change=10.0, power=0.8)
    (condition,) = design.conditions
    assert condition["c_percent"] == pytest.approx(10.0) and condition["intervals"] == 5
    bound = condition["c_bound_percent"]  # the wide interval's scatter raises the bound
    kept = np.array(m[:1] + m[2:])  # the flagged interval left out
    assert bound == pytest.approx(_c_bound(np.array([60.0, *[10.0] * 4]), kept)) and bound > 10
    n = design.for_interval  # a condition's 9-in-10 share of n trials: (bound / 3)² or more
    needed = (bound / 3.0) ** 2
    assert binom.ppf(0.1, n, 0.5) >= needed > binom.ppf(0.1, n - 1, 0.5)
    pilot = design.curve["pilot"]
    assert pilot["left_out"] == [2, 1, 0] and pilot["half_width_percent"][0] == 30.0
    # the fit against the same intervals: exact where they are c / sqrt(m)
    assert pilot["fitted_half_width_percent"] == pytest.approx([5.0, 2.5, 10.0 / np.sqrt(32)])
    assert pilot["half_width_percent"][1:] == pytest.approx(pilot["fitted_half_width_percent"][1:])


def test_the_pilots_c_bound_lies_above_the_true_c_four_times_in_five():
    """A condition's pilot intervals give c's that scatter by 25 % about the true c: the bound
    the design takes lies at or above the truth in about 80 % of pilots (of 6 intervals, two
    seeds at three counts), where the weighted median alone does in under half."""
    from anklelab.studies.design import _c_bound, _weighted_median

    rng = np.random.default_rng(3)
    weights = np.array([5.0, 5.0, 10.0, 10.0, 20.0, 20.0])
    above = {"median": 0, "bound": 0}
    for _ in range(4000):
        each = 10.0 * np.exp(0.25 * rng.standard_normal(6))
        median = _weighted_median(each, weights)
        above["median"] += median >= 10.0
        above["bound"] += max(median, _c_bound(each, weights)) >= 10.0
    assert above["median"] / 4000 < 0.5
    assert above["bound"] / 4000 == pytest.approx(0.8, abs=0.04)


def test_the_design_names_an_extrapolation_and_stops_at_the_twins_1000_trials():
    from anklelab.studies.design import DesignError, _answer

    m = [16.0, 16.0, 32.0, 32.0]  # pilots of 32 and 64 trials per point
    rows = _pilot_rows(m, list(10.0 / np.sqrt(m)), [False] * 4)
    with pytest.warns(AnklelabWarning, match=r"design: the recommended \d+ trials per timing "
                                             r"point are more than 2 times the largest pilot "
                                             r"\(64\): the curve is extrapolated"):  # fmt: skip
        design = _answer(rows, None, target=0.5, change=10.0, power=0.8)
    assert design.recommended > 500 and design.curve["trials_per_point"][-1] == 1000
    with pytest.raises(DesignError, match=r"±0\.3 % is out of reach at dorsi/100: .*more than "
                                          r"the twin's 1000 trials per timing point"):  # fmt: skip
        _answer(rows, None, target=0.3, change=10.0, power=0.8)


def test_a_grid_point_whose_every_session_failed_stays_in_the_summary():
    from anklelab.studies.tables import summary_table

    ok = {"status": "ok", "direction": "dorsi", "delay_ms": 100.0,
          "quantity": "stiffness_nm_per_rad", "truth": 1000.0, "estimate": 1010.0,
          "error": 10.0, "error_percent": 1.0, "half_width_percent": 3.0, "covered": True,
          "interval_kind": "ci95", "poorly_determined": False}  # fmt: skip
    failed = {"status": "failed", "failure": "SafetyLimitError: the drive tripped"}
    results = pd.DataFrame(
        [ok | {"twin.amplitude": 0.035, "seed": s} for s in (0, 1)]
        + [failed | {"twin.amplitude": 0.3, "seed": s} for s in (0, 1)]
    )
    summary = summary_table(results, ["twin.amplitude"])
    lost = summary[summary["twin.amplitude"] == 0.3]
    assert len(lost) == 1 and lost["n_sessions"].iloc[0] == 0 and lost["n_failed"].iloc[0] == 2
    kept = summary[summary["twin.amplitude"] == 0.035]
    assert kept["n_sessions"].tolist() == [2] and kept["n_failed"].tolist() == [0]


def test_a_session_given_twice_however_spelled_is_refused(tmp_path, monkeypatch):
    from anklelab.studies.batch import session_names

    (tmp_path / "sess").mkdir()
    (tmp_path / "sess" / "p2.h5").write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ParameterError, match=r"SESSIONS: sess/\.\./sess/p2\.h5 is sess/p2\.h5"):
        session_names([Path("sess/p2.h5"), Path("sess/../sess/p2.h5")])
    with pytest.raises(ParameterError, match="given again"):
        session_names([Path("sess/p2.h5"), tmp_path / "sess" / "p2.h5"])
    assert session_names([Path("./sess/p2.h5"), Path("other/p2.h5")]) == ["sess-p2", "other-p2"]


def test_the_truth_is_taken_over_the_window_the_cell_analyses():
    """A study of the analysis window compared every window's estimate with the twin's 100 ms
    truth: a stiffness that changes within the window has another θ²-weighted average over
    125 ms, so the 125 ms intervals seemed to miss (coverage 0.79)."""
    from anklelab.platforms import load_platform
    from anklelab.studies.cell import simulate_cell
    from anklelab.studies.spec import Cell

    twin = {"trials_per_point": 2, "n_unperturbed": 4, "n_calibration": 1, "bench": False}

    def windows(analysis, params=None, base=None):
        cell = Cell(0, 3, twin, params or {}, analysis, {}, base)
        reference = simulate_cell(cell).truth["reference"]
        return {point["window_ms"] for points in reference.values() for point in points.values()}

    assert windows({"window_ms": 125.0}) == {125.0}
    assert windows({}) == {100.0}
    assert windows({"window_ms": 125.0}, {"walking.window_ms": 75.0}) == {75.0}
    # a base parameter set's own window gives way to the analysis's (100 ms by default)
    base = load_platform("perturberator").replace({"walking.window_ms": 75.0})
    assert windows({}, base=base.model_dump()) == {100.0}


def test_a_stored_session_of_other_code_is_not_reused(monkeypatch):
    """A source tree keeps its version across edits: the cell's key also hashes the code, so a
    resumed study never takes a session that other code computed for one of its own."""
    import anklelab.studies.spec as spec

    cell = study_from_mapping(TINY, origin="tiny").cells()[0]
    key = cell.key
    monkeypatch.setattr(spec, "code_fingerprint", lambda: "0" * 16)
    assert cell.key != key


def test_ctrl_c_on_a_local_cluster_study_prints_one_line(tmp_path):
    """A terminal's Ctrl-C reaches the whole process group: the local cluster's workers each
    printed a KeyboardInterrupt traceback (and Dask's warnings) around the command's line."""
    study_file = tmp_path / "tiny.toml"
    study_file.write_text(TINY_TOML.replace("seeds = [0, 1]", "seeds = 8"), encoding="utf-8")
    target = tmp_path / "stopped"
    command = [sys.executable, "-c", "from anklelab.cli import run; run()", "study",
               str(study_file), "--out", str(target), "--scheduler", "local-cluster",
               "--workers", "2", "--no-figures"]  # fmt: skip
    err = tmp_path / "err"  # a file: the workers inherit it
    with err.open("w") as stderr:
        proc = subprocess.Popen(
            command, start_new_session=True, stdout=subprocess.DEVNULL, stderr=stderr
        )
        cells = checkpoint_for(target)
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and not list(cells.glob("*.json")):
            time.sleep(0.1)
        os.killpg(proc.pid, signal.SIGINT)
        assert proc.wait(timeout=120) == 128 + signal.SIGINT
    time.sleep(2.0)  # anything a worker still had to say
    lines = err.read_text().strip().splitlines()
    assert lines == ["error: interrupted by SIGINT; unfinished outputs were removed"], lines


def test_stored_results_none_of_which_is_reused_are_named(tmp_path):
    """A resume after the code changed runs everything again: the command says why."""
    from anklelab.errors import AnklelabWarning
    from anklelab.studies.execute import ResultStore, Task, run_tasks

    store = ResultStore(tmp_path / "cells")
    store.write("computed-by-other-code", {"ok": True})
    with pytest.warns(AnklelabWarning, match="none of its 1 stored results is for these"):
        run = run_tasks([Task("k", dict, ())], store, workers=1)
    assert run["ran"] == 1 and store.has("k")


def test_a_session_whose_worker_dies_is_recorded_with_a_hint(tmp_path):
    """A worker killed while it runs a session (out of memory, say) fails the session with
    Dask's KilledWorker, whose text sends the user to worker logs the study keeps quiet."""
    import dask

    from anklelab.studies.execute import ResultStore, Task, run_tasks

    store = ResultStore(tmp_path / "cells")
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        run_tasks([Task("k", os._exit, (1,))], store, scheduler="local-cluster", workers=1,
                  retries=0)  # fmt: skip
    record = store.read("k")
    assert not record["ok"]
    assert record["error"].startswith("the worker running it died (out of memory?): KilledWorker")


def test_a_randomised_study_window_is_checked_against_the_shortest_stance_drawn():
    """Each randomised session draws its stance (0.78-0.92 s); a window that fits the shipped
    0.80 s but not a 0.78 s stance failed some cells after the check had passed."""
    mapping = dict(TINY) | {"twin": TINY["twin"] | {"randomised": "prosthetic"}}
    mapping.pop("grid")
    mapping["analysis"] = {"bootstrap_reps": 10, "window_ms": 310.0, "sensitivity_windows_ms": []}
    with pytest.raises(ParameterError, match=r"window_ms: the 310 ms window .* after toe-off"):
        study_from_mapping(mapping, origin="w.toml")
    mapping["params"] = {"gait.stance_s": 0.8}  # a stance the study sets is not drawn
    study_from_mapping(mapping, origin="w.toml")


@pytest.mark.parametrize("twin", [{"unperturbed_per_point": 2.0}, {"n_unperturbed": 3}])
def test_a_randomised_draw_records_the_unperturbed_trials_simulated(twin):
    """``draw.n_unperturbed`` gave the draw's own count, not the one the study set."""
    from anklelab.studies.cell import simulate_cell
    from anklelab.studies.spec import Cell

    settings = twin | {"randomised": "prosthetic", "trials_per_point": 2, "n_calibration": 1,
                       "bench": False}  # fmt: skip
    session = simulate_cell(Cell(0, 1, settings, {}, {}, {}))
    simulated = sum(not trial.perturbed for trial in session.walking)
    assert simulated == twin.get("n_unperturbed", 4)
    assert session.truth["draw"]["n_unperturbed"] == simulated


def _summary_of(points: dict[str, list], n: int = 2) -> pd.DataFrame:
    """A summary table over ``points`` (full key: values, one row each) at two timing points."""
    rows = []
    for i in range(len(next(iter(points.values())))):
        for delay in (100.0, 225.0):
            rows.append(
                {key: values[i] for key, values in points.items()}
                | {"direction": "dorsi", "delay_ms": delay, "quantity": "stiffness_nm_per_rad",
                   "n_sessions": n, "n_failed": 0, "bias_percent": 0.1 * i, "sd_percent": 0.5,
                   "rmse_percent": 0.6, "abs_error_percent_max": 1.0, "coverage": 1.0,
                   "interval_kind": "ci95"}
            )  # fmt: skip
    return pd.DataFrame(rows)


def test_two_varied_keys_of_the_same_last_name_keep_their_own_figure_and_column(tmp_path, capsys):
    """``analysis.window_ms`` and ``params.walking.window_ms`` wrote the same figure (the second
    replaced the first) and showed the same column header."""
    from anklelab.commands.study import _print_summary
    from anklelab.studies.figures import study_figures

    keys = ["analysis.window_ms", "params.walking.window_ms"]
    summary = _summary_of({keys[0]: [75.0, 100.0], keys[1]: [100.0, 125.0]})
    written = study_figures(summary, keys, tmp_path, title="clash")
    assert [path.name for path in written] == [f"stiffness_error_vs_{key}.png" for key in keys]
    assert all(path.is_file() for path in written)
    _print_summary(summary, keys, pd.DataFrame())
    header = next(line for line in capsys.readouterr().out.splitlines() if "point" in line)
    assert all(key in header for key in keys), header


def test_a_list_valued_setting_is_drawn_with_its_values_as_labels(tmp_path):
    """A grid over ``params.walking.timing_points_ms`` ran every cell, then the figure step
    failed on the lists (unhashable) and the study ended in a traceback."""
    from anklelab.studies.figures import study_figures

    key = "params.walking.timing_points_ms"
    summary = _summary_of({key: [[100.0, 225.0], [100.0, 350.0]], "twin.noise_scale": [1.0, 2.0]})
    written = study_figures(summary, [key, "twin.noise_scale"], tmp_path, title="lists")
    assert written[0].name == f"stiffness_error_vs_{key}.png"
    assert all(path.is_file() for path in written)


def test_batch_sends_its_workers_absolute_paths(tmp_path, monkeypatch):
    """A cluster's workers have their own working directory: relative paths failed every
    session there."""
    import anklelab.studies.batch as batch
    from anklelab.pipelines.walking import WalkingSettings

    sent = []

    def run_tasks(tasks, store, **options):
        for task in tasks:
            sent.append(task.args[0])
            store.write(task.key, {"ok": False, "attempts": 1, "error": "E: not run"})
        return {"resumed": 0, "ran": len(tasks), "wall_s": 0.0}

    monkeypatch.setattr(batch, "run_tasks", run_tasks)
    (tmp_path / "S1").mkdir()
    (tmp_path / "S1" / "day1.h5").write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    run = batch.run_batch([Path("S1/./day1.h5")], tmp_path / "out", settings=WalkingSettings())
    assert sent == [os.path.join(tmp_path, "S1", "day1.h5")]
    assert run.failed == {"day1": "E: not run"}


def test_a_second_run_computes_only_the_sessions_that_failed(tmp_path):
    """A completed study with failed sessions could only be run again whole (--force); the same
    command now computes only the failed ones and replaces the output."""
    study_file = tmp_path / "fails.toml"
    text = TINY_TOML.replace("seeds = [0, 1]", "seeds = [0]").replace(
        '"params.geometry.misalignment_anterior_m" = [0.0, 0.016]',
        '"twin.noise_scale" = [1.0, 100000.0]',  # the second drowns the plate in noise
    )
    study_file.write_text(text, encoding="utf-8")
    target = tmp_path / "out"
    command = [sys.executable, "-c", "from anklelab.cli import run; run()", "study",
               str(study_file), "--out", str(target), "--workers", "1", "--retries", "0",
               "--no-figures"]  # fmt: skip
    first = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert first.returncode == 1, first.stderr
    failed = pd.read_csv(target / "cells.csv").query("status == 'failed'")["cell"].tolist()
    assert len(failed) == 1
    second = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert second.returncode == 1, second.stderr  # the noise is as loud the second time
    assert f"{target}: computing its 1 failed session again (1 kept)" in second.stdout
    assert "(1 already done, 1 run)" in second.stdout
    assert pd.read_csv(target / "cells.csv")["attempts"].tolist() == [1, 1]
    assert not checkpoint_for(target).exists()


def test_a_session_given_twice_is_named_as_typed(tmp_path, monkeypatch):
    """``batch S/./x.h5 S/x.h5`` said "S/x.h5 is S/x.h5 given again": the paths were
    normalised before they were named."""
    from typer.testing import CliRunner

    from anklelab.cli import app

    (tmp_path / "S").mkdir()
    (tmp_path / "S" / "x.h5").write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["batch", "S/./x.h5", "S/x.h5", "--out", "out"])
    assert str(result.exception) == "SESSIONS: S/x.h5 is S/./x.h5 given again"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["S"]
