"""``anklelab report RESULTS_DIR`` on `analyze` and `identify friction` outputs; bad directories."""

import json
import re
import sys

import pytest
from typer.testing import CliRunner

from anklelab.cli import app, run
from anklelab.errors import ResultsFormatError
from anklelab.report.sections import FRICTION_FIGURES, WALKING_FIGURES, results_report
from tests.browser import view

runner = CliRunner()


def invoke(*args):
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 0, (result.output, result.exception)
    return result


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    """A small twin session analysed by `anklelab analyze` (the user's own workflow)."""
    from anklelab.data import save_session
    from anklelab.experiments import simulate_perturberator

    root = tmp_path_factory.mktemp("analysed")
    session = simulate_perturberator(trials_per_point=8, n_unperturbed=16, n_calibration=2, seed=5)
    path = save_session(session, root / "session.h5")
    settings = root / "settings.toml"
    settings.write_text("bootstrap_reps = 10\n")
    invoke("analyze", path, "--out", root / "out", "--settings", settings)
    return root / "out"


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    root = tmp_path_factory.mktemp("identified")
    invoke("simulate", "capstan-ident", "--out", root / "ident", "--seed", 2)
    invoke("identify", "friction", root / "ident", "--out", root / "friction")
    return root / "friction"


def test_report_of_an_analyze_output_renders_in_chromium(analysed):
    result = invoke("report", analysed)
    assert f"report written to {analysed / 'report.html'}" in result.output.replace("\n", "")
    page = (analysed / "report.html").read_text()
    document = json.loads((analysed / "results.json").read_text())
    first = document["timing_points"][0]
    cell = (
        f"{first['stiffness_nm_per_rad']['mean']:.0f} ({first['stiffness_nm_per_rad']['sd']:.0f})"
    )
    assert f"<td>{first['direction']}/{first['delay_ms']:g}</td>" in page and cell in page
    assert "Testing machine (bench)" in page and "Figures not found" not in page
    assert f"<h1>Walking impedance: {document['session']}</h1>" in page
    assert "session SHA-256" in page and document["session_sha256"] in page
    seen = view(analysed / "report.html", "report_cli_walking.png")
    assert seen.console_errors == []
    assert [img["alt"] for img in seen.images] == [title for _, title, _ in WALKING_FIGURES]
    assert all(img["complete"] and img["width"] > 0 and img["height"] > 0 for img in seen.images)
    # laid out as a reader needs it: the key figure on the first screen, every figure at its
    # own size (none shrunk, none wider than the page), nothing overlapping, no code names
    key = seen.images[0]["box"]
    assert key["y"] + key["h"] < 900
    for img in seen.images:
        assert img["box"]["w"] == pytest.approx(img["width"], abs=1), img
    assert seen.page_width <= 1400 and seen.overlapping_images() == []
    assert not re.findall(r"\b[a-z]+_[a-z0-9_]+\b", seen.text), "code names on the page"
    assert "settings: seed=" not in seen.text and "anklelab report:" not in seen.text


def test_report_of_a_friction_output_to_another_file(identified, tmp_path):
    out = tmp_path / "friction_report.html"
    invoke("report", identified, "--out", out)
    page = out.read_text()
    friction = json.loads((identified / "friction.json").read_text())
    assert f"<td>{friction['coulomb_nm']['ccw']:.4g}</td>" in page
    assert page.count('src="data:image/png;base64,') == len(FRICTION_FIGURES)
    assert not (identified / "report.html").exists()


def test_missing_figures_are_reported_not_fatal(identified, tmp_path):
    bare = tmp_path / "bare"
    bare.mkdir()
    (bare / "friction.json").write_bytes((identified / "friction.json").read_bytes())
    path, missing = results_report(bare)
    assert missing == [f"{stem}.png" for stem, _, _ in FRICTION_FIGURES]
    assert "Figures not found in the directory: spindown_fit.png" in path.read_text()


def test_directories_that_are_not_analysis_outputs(tmp_path, analysed):
    with pytest.raises(ResultsFormatError, match="not a directory"):
        results_report(tmp_path / "absent")
    with pytest.raises(ResultsFormatError, match=r"no results\.json .* analysis output"):
        results_report(tmp_path)
    nested = tmp_path / "nested"
    (nested / "run1").mkdir(parents=True)
    (nested / "run1" / "results.json").write_text((analysed / "results.json").read_text())
    with pytest.raises(ResultsFormatError, match="found result files in: run1"):
        results_report(nested)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("[1", "results.json: not valid JSON"),
        ('{"session": "x"}', "missing key.*platform_filters, timing_points"),
        ('{"platform_filters": {}, "timing_points": 3}', "timing_points: expected a list"),
        (
            '{"platform_filters": {}, "timing_points": [{"delay_ms": 100, "direction": "dorsi"}]}',
            r"timing_points\[0\]\.stiffness_nm_per_rad: required key is missing",
        ),
    ],
)
def test_malformed_results_json_names_the_file_and_key(tmp_path, content, message):
    (tmp_path / "results.json").write_text(content)
    with pytest.raises(ResultsFormatError, match=message):
        results_report(tmp_path)


def test_malformed_friction_json_names_the_key(tmp_path):
    (tmp_path / "friction.json").write_text(
        '{"inertia_kgm2": 1e-3, "viscous_nms_per_rad": {"cw": 1e-4}, "coulomb_nm": {}}'
    )
    with pytest.raises(ResultsFormatError, match=r"viscous_nms_per_rad\.ccw: required key"):
        results_report(tmp_path)


def test_cli_error_is_one_line_and_exit_code_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["anklelab", "report", str(tmp_path)])
    with pytest.raises(SystemExit) as exit_info:
        run()
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path}: no results.json") and "Traceback" not in err
