"""The `anklelab capstan` commands run end to end, write their results as one run (run.json),
refuse to replace them without --force, and turn bad input into one error line."""

import json
import shutil
from pathlib import Path

import pytest

from anklelab._runs import RunManifest
from anklelab.platforms import platform_file
from tests.test_docs import _anklelab


@pytest.fixture
def anklelab(monkeypatch, capsys):
    return lambda *args: _anklelab(list(args), Path.cwd(), monkeypatch, capsys)


@pytest.fixture
def cli(anklelab):
    return lambda *args: anklelab("capstan", *args)


def test_tune_prints_gains_and_records_its_run(cli, tmp_path):
    params = tmp_path / "capstan.toml"
    params.write_bytes(platform_file("capstan").read_bytes())
    out = tmp_path / "tune"
    code, text, err = cli(
        "tune", "--settling-time", "0.25", "--params", str(params), "--out", str(out)
    )
    assert code == 0 and "Kp (N·m/rad)" in text and "closed-loop poles" in text, err
    assert json.loads((out / "gains.json").read_text())["results"]["kp_nm_per_rad"] > 0
    run = RunManifest.load(out)
    assert run.command == "capstan tune" and run.settings["settling_time"] == 0.25
    assert [i["path"] for i in run.inputs] == [str(params.resolve())]
    assert set(run.files) == {"gains.json"}


def test_step_and_chirp_write_one_run_each_and_replace_only_with_force(cli, anklelab, tmp_path):
    steps_dir, chirp_dir = tmp_path / "steps", tmp_path / "chirp"
    step = ["step", "--degrees", "5", "--hold", "0.6", "--out", str(steps_dir)]
    code, out, err = cli(*step)
    assert code == 0, err
    assert "5 deg" in out
    steps = json.loads((steps_dir / "steps.json").read_text())["results"]
    assert steps[0]["rise_time_s"] < 0.3 and steps[0]["fault"] == "none"
    assert set(RunManifest.load(steps_dir).files) == {"steps.json", "steps.png"}
    first = RunManifest.load(steps_dir).run_id
    code, _, err = cli(*step)
    assert code == 2 and "--force" in err and str(steps_dir) in err
    assert RunManifest.load(steps_dir).run_id == first  # refused before any work
    code, _, err = cli(*step, "--force")
    assert code == 0 and RunManifest.load(steps_dir).run_id != first, err
    chirp = ["chirp", "--duration", "4", "--f1", "3", "--tracking", "feedforward"]
    code, _, err = cli(*chirp, "--out", str(steps_dir), "--force")
    assert code == 2 and "capstan step" in err  # another command's output is never replaced
    code, _, err = cli(*chirp, "--out", str(chirp_dir))
    assert code == 0, err
    assert RunManifest.load(chirp_dir).settings["tracking"] == "feedforward"
    assert json.loads((chirp_dir / "chirp.json").read_text())["results"]["rms_error_rad"] > 0
    assert (chirp_dir / "chirp.png").exists()
    code, _, err = anklelab("report", str(chirp_dir))
    assert code == 0 and "Capstan: chirp tracking" in (chirp_dir / "report.html").read_text()


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_a_nonfinite_set_point_latches_command_nan_and_is_reported(cli, value, tmp_path):
    code, out, err = cli(
        "step", "--degrees", f"5,{value}", "--hold", "0.3", "--out", tmp_path / "s"
    )
    assert code == 2
    assert "COMMAND_NAN" in out and "settled" not in out
    assert err.strip().splitlines() == [
        "error: capstan step: a set-point latched COMMAND_NAN (the commanded output was NaN or "
        "infinite)"
    ]
    steps = json.loads((tmp_path / "s" / "steps.json").read_text())["results"]  # still written
    assert [s["fault"] for s in steps] == ["none", "COMMAND_NAN"]
    assert RunManifest.load(tmp_path / "s").settings["degrees"] == [5.0, None]


def test_observer_render_and_scene(cli, tmp_path):
    out = tmp_path / "observe"
    code, text, err = cli("observe", "--task", "track", "--duration", "4", "--out", str(out))
    assert code == 0 and "VAF" in text and (out / "observer_track.json").exists(), err
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
        str(tmp_path / "render"),
    )
    assert code == 0 and "stiffness" in out and (tmp_path / "render" / "render.png").exists(), err
    assert RunManifest.load(tmp_path / "render").inputs[0]["path"] == str(terrain.resolve())
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


def test_identify_friction_refuses_a_flipped_velocity_sign(anklelab, tmp_path):
    source = tmp_path / "ident"
    code, _, err = anklelab("simulate", "capstan-ident", "--out", str(source))
    assert code == 0, err
    flipped = tmp_path / "flipped"
    shutil.copytree(source, flipped)
    for path in [*flipped.glob("spindown/*_*.csv"), *flipped.glob("chirp/*.csv")]:
        lines = path.read_text().splitlines()
        k = lines[0].split(",").index("velocity_rad_s")
        rows = [line.split(",") for line in lines[1:]]
        for row in rows:
            row[k] = repr(-float(row[k]))
        path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    code, _, err = anklelab("identify", "friction", str(flipped), "--out", str(tmp_path / "fit"))
    assert code == 2 and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1 and "sign flipped" in err
