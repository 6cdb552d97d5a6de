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
    named = f"{document['subject']} — {document['session']}"  # twin-prosthetic — session.h5
    assert f"<h1>Walking impedance: {named}</h1>" in page
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
    path, notes = results_report(bare)
    names = ", ".join(f"{stem}.png" for stem, _, _ in FRICTION_FIGURES)
    assert notes == [
        f"{bare}: no run.json (an older anklelab's output, or not anklelab's); its files cannot "
        "be checked against the run that wrote them",
        f"figures not found in {bare}: {names} (re-run the analysis with figures to include them)",
    ]
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


# --- what the report embeds: only the files the run wrote (issue 11) ---------------------------


def copy_of(directory, tmp_path):
    import shutil

    return shutil.copytree(directory, tmp_path / "o", symlinks=True)


def embedded(page):
    import base64

    return [base64.b64decode(m) for m in re.findall(r'src="data:image/png;base64,([^"]+)"', page)]


def test_report_never_embeds_what_a_figure_path_points_at(analysed, tmp_path):
    out = copy_of(analysed, tmp_path)
    secret = tmp_path / "shadow"
    secret.write_bytes(b"\x89PNG\r\n\x1a\nroot:secret")  # even with a PNG signature
    (out / "filters.png").unlink()
    (out / "filters.png").symlink_to(secret)
    (out / "model_fit.png").write_bytes((out / "stance_profiles.png").read_bytes())
    path, notes = results_report(out)
    assert notes == [
        f"{out}/filters.png: leads outside {out}; not embedded",
        f"{out}/model_fit.png: changed since the run wrote it (SHA-256 differs from run.json); "
        "not embedded",
    ]
    figures = embedded(path.read_text())
    assert len(figures) == 3 and all(b"root:secret" not in png for png in figures)
    assert figures == [
        (out / f"{n}.png").read_bytes()
        for n in ("impedance_summary", "impedance_vs_lever_arm", "stance_profiles")
    ]
    assert "Figures not embedded: " in path.read_text()


def test_directory_without_manifest_embeds_only_regular_png_files(analysed, tmp_path):
    out = copy_of(analysed, tmp_path)
    (out / "run.json").unlink()
    (out / "filters.png").write_text("not an image")
    (out / "model_fit.png").unlink()
    (out / "model_fit.png").symlink_to(out / "stance_profiles.png")
    path, notes = results_report(out)
    assert notes[0].startswith(f"{out}: no run.json (an older anklelab's output")
    assert notes[1:] == [
        f"{out}/filters.png: not a PNG image; not embedded",
        f"{out}/model_fit.png: a symbolic link; expected a regular file; not embedded",
    ]
    assert len(embedded(path.read_text())) == 3


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("friction", "friction.json: not written by the run (not listed in run.json)"),
        ("edit", "results.json: changed since the run wrote it"),
        ("link", "results.json: a symbolic link; expected a regular file"),
    ],
)
def test_result_files_must_be_the_ones_the_run_wrote(analysed, tmp_path, change, message):
    out = copy_of(analysed, tmp_path)
    if change == "friction":
        (out / "friction.json").write_text("{}")
    elif change == "edit":
        (out / "results.json").write_text((out / "results.json").read_text() + " ")
    else:
        (out / "results.json").unlink()
        (out / "results.json").symlink_to(out / "results.csv")
    with pytest.raises(ResultsFormatError, match=re.escape(message)):
        results_report(out)


def test_friction_json_holding_a_string_is_one_error_line(tmp_path, monkeypatch, capsys):
    (tmp_path / "friction.json").write_text('"a string"')
    monkeypatch.setattr(sys, "argv", ["anklelab", "report", str(tmp_path)])
    with pytest.raises(SystemExit) as exit_info:
        run()
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err
    assert [line for line in err.splitlines() if line.startswith("error:")] == [
        f"error: {tmp_path}/friction.json: expected a JSON object, got str"
    ]
    assert not (tmp_path / "report.html").exists()
