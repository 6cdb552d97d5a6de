"""`anklelab import` and `anklelab session info` as a user runs them."""

import json
import re
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.data import diff_sessions, load_session, save_session
from anklelab.data._synthetic import random_session

runner = CliRunner()


def run_cli(*args):
    code = "from anklelab.cli import run; run()"
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True
    )


@pytest.fixture
def session_dir(tmp_path):
    return save_session(random_session(seed=7), tmp_path / "session", format="dir")


def test_import_directory_to_h5(session_dir, tmp_path):
    out = tmp_path / "s.h5"
    result = runner.invoke(app, ["import", str(session_dir), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "2 calibration, 6 walking, 2 bench recordings" in result.output
    imported = load_session(out)
    assert diff_sessions(imported, load_session(session_dir)) == []
    assert imported.provenance["import"]["source_name"] == "session"


def test_import_refuses_to_overwrite_without_force(session_dir, tmp_path):
    out = tmp_path / "s.h5"
    out.write_bytes(b"precious")
    proc = run_cli("import", session_dir, "--out", out)
    assert proc.returncode == 2
    assert f"{out}: already exists; pass --force" in proc.stderr
    assert out.read_bytes() == b"precious"
    result = runner.invoke(app, ["import", str(session_dir), "--out", str(out), "--force"])
    assert result.exit_code == 0, result.output
    assert load_session(out).walking


def test_import_of_bad_session_exits_2_naming_file_column_line(session_dir, tmp_path):
    trial = session_dir / "walking" / "trial_0004.csv"
    lines = trial.read_text().split("\n")
    lines[4] = lines[4].replace(",", ",x", 1)
    trial.write_text("\n".join(lines))
    out = tmp_path / "s.h5"
    proc = run_cli("import", session_dir, "--out", out)
    assert proc.returncode == 2
    assert "trial_0004.csv: column 'motor_angle', line 5:" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["session"]


def test_session_info_json(session_dir, tmp_path):
    result = runner.invoke(app, ["session", "info", str(session_dir), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["walking"]["n"] == 6 and summary["walking"]["n_unperturbed"] == 2
    assert {(p["direction"], p["delay_ms"]) for p in summary["walking"]["timing_points"]} == {
        ("dorsi", 100.0),
        ("plantar", 225.0),
    }
    assert summary["truth"] is True and summary["info"]["sample_rate_hz"] == 1000.0


def test_session_info_table(session_dir):
    result = runner.invoke(app, ["session", "info", str(session_dir)])
    assert result.exit_code == 0, result.output
    for text in ("perturberator", "1000 Hz", "dorsi 100 ms", "plantar 225 ms", "truth"):
        assert text in result.output


def test_session_info_folds_a_hash_and_never_cuts_it(tmp_path):
    session = random_session(n_calibration=1, n_walking=4, n_bench=0, seed=3)
    path = save_session(session, tmp_path / "session", format="dir")
    result = runner.invoke(app, ["session", "info", str(path)], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    assert "…" not in result.output
    lines = result.output.splitlines()
    (at,) = [i for i, w in enumerate(lines) if "provenance.source_sha256" in w]
    folded = lines[at].split()[-1] + lines[at + 1].strip()
    assert re.fullmatch(r"[0-9a-f]{64}", folded), folded


@pytest.mark.parametrize(("n_bench", "bench"), [(1, "1 test at 0.06 m"), (0, "0 tests")])
def test_session_info_counts_are_pluralised(tmp_path, n_bench, bench):
    session = random_session(n_calibration=1, n_walking=4, n_bench=n_bench, seed=3)
    path = save_session(session, tmp_path / "session", format="dir")
    result = runner.invoke(app, ["session", "info", str(path)])
    assert result.exit_code == 0, result.output
    cells = [re.split(r"\s{2,}", line.strip(), maxsplit=1) for line in result.output.splitlines()]
    rows = dict(cell for cell in cells if len(cell) == 2)
    assert rows["calibration"] == rows["dorsi 100 ms"] == rows["plantar 225 ms"] == "1 trial"
    assert rows["walking"] == "4 trials: 2 perturbed, 2 unperturbed"
    assert rows["bench"] == bench
