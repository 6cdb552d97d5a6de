"""The `anklelab capstan` commands run end to end and write their results."""

import json

from typer.testing import CliRunner

from anklelab.cli import app

runner = CliRunner()


def invoke(*args):
    result = runner.invoke(app, ["capstan", *args])
    assert result.exit_code == 0, result.output
    return result.output


def test_tune_prints_gains_and_poles(tmp_path):
    out = invoke("tune", "--settling-time", "0.25", "--out", str(tmp_path))
    assert "Kp (N·m/rad)" in out and "closed-loop poles" in out
    gains = json.loads((tmp_path / "gains.json").read_text())
    assert gains["kp_nm_per_rad"] > 0


def test_step_and_chirp_write_results(tmp_path):
    out = invoke("step", "--degrees", "5", "--hold", "0.6", "--out", str(tmp_path))
    assert "5 deg" in out
    assert json.loads((tmp_path / "steps.json").read_text())[0]["rise_time_s"] < 0.3
    invoke("chirp", "--duration", "4", "--f1", "3", "--out", str(tmp_path))
    chirp = json.loads((tmp_path / "chirp.json").read_text())
    assert chirp["rms_error_rad"] > 0 and len(chirp["frequency_hz"]) > 5
    assert (tmp_path / "steps.png").exists() and (tmp_path / "chirp.png").exists()


def test_observer_and_render(tmp_path):
    out = invoke("observe", "--task", "track", "--duration", "6", "--out", str(tmp_path))
    assert "VAF" in out and (tmp_path / "observer_track.json").exists()
    terrain = tmp_path / "ramp.csv"
    terrain.write_text("distance_m,height_m\n0,0\n3,0\n6,0.5\n12,0.5\n")
    out = invoke(
        "render",
        "--terrain",
        str(terrain),
        "--mode",
        "impedance",
        "--duration",
        "8",
        "--out",
        str(tmp_path),
    )
    assert "stiffness" in out and (tmp_path / "render.png").exists()


def test_bad_mode_is_rejected():
    result = runner.invoke(app, ["capstan", "render", "--mode", "teleport"])
    assert result.exit_code != 0 and "admittance or impedance" in result.output


def test_control_rate_outside_the_supported_range_is_a_usage_error():
    result = runner.invoke(app, ["capstan", "step", "--fs", "50"])
    assert result.exit_code == 2
    assert "--fs" in result.output
