"""Capstan friction identification: accuracy against the twin and an independent generator,
input validation, the friction.json round trip and the command line."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.data.capstan_ident import (
    IdentData,
    IdentRun,
    read_ident_directory,
    write_ident_directory,
)
from anklelab.errors import NotFittedError, ParameterError, SessionFormatError
from anklelab.experiments.capstan import simulate_ident
from anklelab.ident.friction import FrictionIdentifier, read_friction_json
from anklelab.platforms import load_platform

P = load_platform("capstan")
OTHER = {  # heavier, stickier shaft with a slower Stribeck curve
    "friction.inertia_kgm2": 1.1e-3,
    "friction.viscous_cw_nms_per_rad": 4.0e-4,
    "friction.viscous_ccw_nms_per_rad": 5.0e-4,
    "friction.coulomb_cw_nm": 0.05,
    "friction.coulomb_ccw_nm": 0.045,
    "friction.stribeck_velocity_rad_s": 2.0,
    "friction.static_friction_nm": 0.07,
}
LIGHT = {  # lighter shaft, lower Coulomb friction, faster Stribeck curve
    "friction.inertia_kgm2": 5.0e-4,
    "friction.viscous_cw_nms_per_rad": 8.0e-4,
    "friction.viscous_ccw_nms_per_rad": 9.0e-4,
    "friction.coulomb_cw_nm": 0.025,
    "friction.coulomb_ccw_nm": 0.02,
    "friction.stribeck_velocity_rad_s": 5.0,
    "friction.static_friction_nm": 0.035,
}


def errors(model, truth):
    """Relative errors (%) of every identified value against the truth dictionary."""
    got = model.to_dict()
    out = {"inertia_kgm2": got["inertia_kgm2"] / truth["inertia_kgm2"] - 1}
    for key in ("viscous_nms_per_rad", "coulomb_nm"):
        for d in ("cw", "ccw"):
            out[f"{key}.{d}"] = got[key][d] / truth[key][d] - 1
    for key in ("stribeck_velocity_rad_s", "static_friction_nm"):
        out[key] = got[key] / truth[key] - 1
    return {k: 100 * v for k, v in out.items()}


def assert_accurate(model, truth):
    err = errors(model, truth)
    loose = ("stribeck_velocity_rad_s", "static_friction_nm")
    assert all(abs(v) < 5.0 for k, v in err.items() if k not in loose), err
    assert all(abs(err[k]) < 15.0 for k in loose), err


@pytest.mark.parametrize(
    ("changes", "seed"),
    [({}, 0), ({}, 1), ({}, 2), (OTHER, 3), (OTHER, 4), (LIGHT, 5), (LIGHT, 6)],
)
def test_recovers_the_twin(changes, seed):
    params = P.replace(changes) if changes else P
    data = simulate_ident(params, seed=seed)
    model = FrictionIdentifier().fit(data)
    assert_accurate(model, data.truth)
    assert model.spindown_vaf_percent_ > 99.0 and model.chirp_vaf_percent_ > 95.0


def independent_session(fs=2000.0, noise=0.05, seed=0):
    """Spin-downs and a one-way torque chirp from scipy's solve_ivp on a smooth model.

    Unlike the twin: instantaneous velocity samples with Gaussian noise, no encoder, no drive,
    no start from rest, coasts end by an event at zero speed.
    """
    rng = np.random.default_rng(seed)
    p = {"J": 9e-4, "b": {1: 5e-4, -1: 7e-4}, "tc": {1: 0.04, -1: 0.03}, "ts": 0.055, "ws": 2.5}

    def friction(w):
        s = 1 if w > 0 else -1
        return s * (p["tc"][s] + (p["ts"] - p["tc"][s]) * math.exp(-((w / p["ws"]) ** 2))) + (
            p["b"][s] * w
        )

    runs = []
    for k, w0 in enumerate([20.0, 35.0, 50.0, 65.0, -20.0, -35.0, -50.0, -65.0]):
        hold, t = 0.2, np.arange(round(1.6 * fs)) / fs
        stop = lambda _t, w: w[0]  # noqa: E731
        stop.terminal = True
        coast = solve_ivp(
            lambda _t, w: [-friction(w[0]) / p["J"]],
            (0, t[-1]),
            [w0],
            events=stop,
            max_step=1e-3,
            rtol=1e-9,
            atol=1e-9,
            dense_output=True,
        )
        tc = t - hold
        w = np.where(tc <= 0, w0, 0.0)
        moving = (tc > 0) & (tc < coast.t[-1])
        w[moving] = coast.sol(tc[moving])[0]
        torque = np.where(tc <= 0, friction(w0), 0.0)
        runs.append(IdentRun(f"r{k}.csv", t, w + rng.normal(0, noise, t.size), torque))
    t = np.arange(round(12 * fs)) / fs
    tau = lambda s: 0.12 + 0.1 * np.sin(2 * np.pi * (0.5 * s + 0.2 * s**2))  # noqa: E731
    sol = solve_ivp(
        lambda s, w: [(tau(s) - friction(w[0])) / p["J"]],
        (0, t[-1]),
        [15.0],
        t_eval=t,
        max_step=2e-4,
        rtol=1e-9,
        atol=1e-9,
    )
    chirp = IdentRun("c.csv", t, sol.y[0] + rng.normal(0, noise, t.size), tau(t))
    truth = {
        "inertia_kgm2": p["J"],
        "viscous_nms_per_rad": {"cw": p["b"][1], "ccw": p["b"][-1]},
        "coulomb_nm": {"cw": p["tc"][1], "ccw": p["tc"][-1]},
        "stribeck_velocity_rad_s": p["ws"],
        "static_friction_nm": p["ts"],
    }
    return IdentData(fs, tuple(runs), (chirp,), truth)


def test_recovers_an_independently_generated_session(tmp_path):
    data = independent_session()
    write_ident_directory(data, tmp_path / "indep")
    model = FrictionIdentifier().fit(read_ident_directory(tmp_path / "indep"))
    assert_accurate(model, data.truth)


def test_predict_before_fit_names_the_class():
    with pytest.raises(NotFittedError, match="FrictionIdentifier is not fitted"):
        FrictionIdentifier().predict(np.zeros(10))


def test_friction_json_round_trip(tmp_path):
    model = FrictionIdentifier().fit(simulate_ident(seed=7))
    path = tmp_path / "friction.json"
    path.write_text(json.dumps(model.to_dict()))
    assert set(model.to_dict()) == {
        "inertia_kgm2",
        "viscous_nms_per_rad",
        "coulomb_nm",
        "stribeck_velocity_rad_s",
        "static_friction_nm",
        "fit",
    }
    params = read_friction_json(path)
    assert params.inertia_kgm2 == model.inertia_kgm2_
    assert params.coulomb_ccw_nm == model.coulomb_nm_["ccw"]
    broken = model.to_dict()
    del broken["coulomb_nm"]["cw"]
    path.write_text(json.dumps(broken))
    with pytest.raises(ParameterError, match=r"coulomb_nm\.cw: required key is missing"):
        read_friction_json(path)


@pytest.fixture(scope="module")
def session_dir(tmp_path_factory):
    path = tmp_path_factory.mktemp("ident") / "session"
    small = simulate_ident(seed=8)
    write_ident_directory(small, path)
    return path


def nan_velocity_on_line(text, line):
    lines = text.split("\n")
    time, _, torque = lines[line - 1].split(",")
    lines[line - 1] = f"{time},nan,{torque}"
    return "\n".join(lines)


def copy_of(src, dst):
    import shutil

    shutil.copytree(src, dst)
    return dst


@pytest.mark.parametrize(
    ("target", "edit", "message"),
    [
        (
            "session.toml",
            lambda s: s.replace('"capstan"', '"perturberator"'),
            r"session\.toml: platform = 'perturberator'; expected 'capstan'",
        ),
        (
            "session.toml",
            lambda s: s.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 500.0"),
            r"cw_15\.csv: column 'time_s', line 3: time step 0\.001 s .*expected 0\.002 s.*"
            r"median time step .* does not match",
        ),
        (
            "spindown/cw_15.csv",
            lambda s: s.replace("velocity_rad_s", "speed"),
            r"cw_15\.csv: missing required column\(s\) 'velocity_rad_s'",
        ),
        (
            "spindown/ccw_30.csv",
            lambda s: nan_velocity_on_line(s, 7),
            r"ccw_30\.csv: column 'velocity_rad_s', line 7: value nan; expected a finite number",
        ),
        (
            "spindown/runs.csv",
            lambda s: s + "9,missing.csv\n",
            r"runs\.csv: line 10, column 'file': .*missing\.csv does not exist",
        ),
    ],
)
def test_bad_directories_are_rejected_with_file_column_line(
    session_dir, tmp_path, target, edit, message
):
    path = copy_of(session_dir, tmp_path / "bad")
    file = path / target
    file.write_text(edit(file.read_text()))
    with pytest.raises(SessionFormatError, match=message):
        read_ident_directory(path)


def test_command_line_end_to_end(tmp_path):
    runner = CliRunner()
    ident = tmp_path / "ident"
    result = runner.invoke(app, ["simulate", "capstan-ident", "--out", str(ident), "--seed", "9"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["identify", "friction", str(ident), "--out", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    assert "static_friction_nm" in result.output
    written = json.loads((tmp_path / "o" / "friction.json").read_text())
    assert written["fit"]["spindown_vaf_percent"] > 99
    for figure in ("spindown_fit.png", "chirp_fit.png", "friction_map.png"):
        assert (tmp_path / "o" / figure).stat().st_size > 1000
