"""The `anklelab capstan` commands run end to end, write their results, refuse to replace them
without --force, and turn bad input into one error line."""

import json
from pathlib import Path

import pytest

from tests.test_docs import _anklelab


@pytest.fixture
def cli(monkeypatch, capsys, tmp_path):
    return lambda *args: _anklelab(["capstan", *args], Path.cwd(), monkeypatch, capsys)


def test_tune_prints_gains_and_poles(cli, tmp_path):
    code, out, _ = cli("tune", "--settling-time", "0.25", "--out", str(tmp_path))
    assert code == 0 and "Kp (N·m/rad)" in out and "closed-loop poles" in out
    document = json.loads((tmp_path / "gains.json").read_text())
    assert document["results"]["kp_nm_per_rad"] > 0
    assert document["command"] == "anklelab capstan tune" and document["anklelab_version"]


def test_step_and_chirp_write_results_and_refuse_to_replace_them(cli, tmp_path):
    code, out, err = cli("step", "--degrees", "5", "--hold", "0.6", "--out", str(tmp_path))
    assert code == 0, err
    assert "5 deg" in out
    steps = json.loads((tmp_path / "steps.json").read_text())["results"]
    assert steps[0]["rise_time_s"] < 0.3 and steps[0]["fault"] == "none"
    code, _, err = cli("step", "--degrees", "5", "--hold", "0.6", "--out", str(tmp_path))
    assert code == 2 and "--force" in err and "steps.json" in err
    code, _, err = cli(
        "chirp", "--duration", "4", "--f1", "3", "--tracking", "feedforward", "--out", str(tmp_path)
    )
    assert code == 0, err
    chirp = json.loads((tmp_path / "chirp.json").read_text())
    assert chirp["settings"]["tracking"] == "feedforward" and chirp["results"]["rms_error_rad"] > 0
    assert (tmp_path / "steps.png").exists() and (tmp_path / "chirp.png").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_a_nonfinite_set_point_latches_command_nan_and_is_reported(cli, value):
    code, out, err = cli("step", "--degrees", f"5,{value}", "--hold", "0.3")
    assert code == 2
    assert "COMMAND_NAN" in out and "settled" not in out
    assert err.strip().splitlines() == [
        "error: capstan step: a set-point latched COMMAND_NAN (the commanded output was NaN or "
        "infinite)"
    ]


def test_observer_render_and_scene(cli, tmp_path):
    code, out, err = cli("observe", "--task", "track", "--duration", "4", "--out", str(tmp_path))
    assert code == 0 and "VAF" in out and (tmp_path / "observer_track.json").exists(), err
    terrain = tmp_path / "ramp.csv"
    terrain.write_text("distance_m,height_m\n0,0\n3,0\n6,0.5\n12,0.5\n")
    code, out, err = cli(
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
    assert code == 0 and "stiffness" in out and (tmp_path / "render.png").exists(), err
    code, out, err = cli("render", "--stiffness", "inf", "--duration", "6")
    assert code == 0 and "rigid" in out and "nan" not in out, err


def test_usage_errors_are_one_line(cli):
    for args, needle in [
        (["render", "--mode", "teleport"], "--mode"),
        (["step", "--sample-rate", "50"], "--sample-rate"),
        (["observe", "--task", "juggle"], "--task"),
        (["nosuch"], "No such command"),
    ]:
        code, _, err = cli(*args)
        assert code == 2, args
        assert len(err.strip().splitlines()) == 1 and err.startswith("error:") and needle in err
