"""Paper 000's protocols on the twin: session layout, ground truth, determinism, storage."""

import numpy as np
import pytest
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.data import diff_sessions, load_session, save_session, session_hash
from anklelab.experiments import simulate_perturberator
from anklelab.forceplate import CHANNELS, ankle_torque, resultants, sagittal_load
from anklelab.platforms import load_platform
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.foot import bench_law

SMALL = dict(trials_per_point=2, n_unperturbed=2, n_calibration=1)


@pytest.fixture(scope="module")
def session():
    return simulate_perturberator(seed=7, **SMALL)


@pytest.fixture(scope="module")
def ideal():
    """No artefacts, 10 perturbed trials per point: for checks against exact values."""
    return simulate_perturberator(
        seed=3, trials_per_point=10, n_unperturbed=4, n_calibration=0, bench=False, artefacts=False
    )


def plate_torque(session, trial):
    """Ankle torque and vertical force from the recorded plate channels (DESIGN.md section 3)."""
    info = session.info
    res = resultants(trial.recording.stack(), info.force_plate, axis=0)
    load = sagittal_load(res, info.force_plate.anterior_axis)
    hc = int(np.argmax(res.fz >= 25.0))
    torque, _ = ankle_torque(
        load, hc, heel_to_ankle_m=info.heel_to_ankle_m, ankle_height_m=info.ankle_height_m
    )
    return torque, res.fz


def test_session_follows_the_protocols(session):
    params = load_platform("perturberator")
    assert len(session.calibration) == 1 and len(session.bench) == 15
    assert len(session.walking) == 2 * 4 + 2
    delays = sorted(t.delay_ms for t in session.walking if t.perturbed)
    assert delays == [100, 100, 225, 225, 350, 350, 475, 475]
    for trial in session.walking:
        assert trial.perturbed == (trial.direction != "none") == np.isfinite(trial.delay_ms)
        assert tuple(trial.recording.columns)[:3] == ("time_s", "motor_angle", "ankle_angle")
    info = session.info
    assert info.sample_rate_hz == 1000.0 and info.platform == "perturberator"
    assert info.ankle_height_m == params.geometry.ankle_height_m
    truth = session.truth
    assert set(truth) >= {"parameters", "foot", "reference", "trials", "bench", "time_courses"}
    assert truth["foot"]["kind"] == "prosthetic"
    onset = truth["trials"]["onset_s"]
    assert np.isnan(onset).sum() == 2
    assert truth["bench"]["stiffness_nm_per_rad"] == pytest.approx([1300.0, 1137.5, 975.0])
    assert session.provenance["created_by"] == "simulate perturberator"
    assert session.provenance["seed"] == 7


def test_walking_trials_start_with_the_foot_off_the_plate(session):
    hc = session.truth["trials"]["heel_contact_s"]
    for trial, contact in zip(session.walking, hc, strict=True):
        fz = sum(trial.recording[c] for c in ("fz1", "fz2", "fz3", "fz4"))
        before = trial.recording.time_s < contact - 0.01
        assert np.sum(before & (np.abs(fz) < 5.0)) >= 100  # >= 100 ms of noise and drift only
        assert fz.max() > 600.0


def test_perturbations_move_the_platform_by_the_commanded_ramp(session):
    onset = session.truth["trials"]["onset_s"]
    for trial, start in zip(session.walking, onset, strict=True):
        angle = trial.recording["motor_angle"]
        if not trial.perturbed:
            assert np.abs(angle).max() <= 1e-4  # the analog output's resolution
            continue
        sign = 1 if trial.direction == "dorsi" else -1
        after = trial.recording.time_s - start
        held = (after > 0.085) & (after < 0.1)
        assert sign * angle[held] == pytest.approx(0.035, abs=2e-4)
        assert np.abs(angle[after < -0.001]).max() <= 1e-4


def test_calibration_trial_has_platform_forces_and_nobody_on_the_plate():
    cal = simulate_perturberator(seed=1, trials_per_point=1, n_unperturbed=0, bench=False)
    for rec in cal.calibration:
        assert rec.time_s[-1] == pytest.approx(20.0, abs=0.01)
        moving = np.abs(np.gradient(rec["motor_angle"], rec.time_s)) > 0.1
        assert 0.25 < np.abs(rec["motor_angle"]).max() / 0.1 < 0.4  # +-0.035 rad moves
        fx = rec["fx12"] + rec["fx34"]
        assert np.abs(fx[moving]).max() > 10 * np.abs(fx[:300]).std()  # inertial forces


@pytest.mark.parametrize("foot", ["prosthetic", "human"])
def test_plate_signals_reproduce_the_injected_ankle_torque(foot):
    s = simulate_perturberator(
        seed=5, foot=foot, trials_per_point=1, n_unperturbed=1, n_calibration=0, bench=False,
        artefacts=False,
    )  # fmt: skip
    injected = s.truth["time_courses"]["ankle_torque_nm"]
    for i, trial in enumerate(s.walking):
        torque, fz = plate_torque(s, trial)
        loaded = fz > 50.0
        error = np.abs(torque[loaded] - injected[i, loaded]).max()
        assert error < 0.005 * np.abs(injected[i]).max()


def test_a_rotated_plate_mounting_is_recorded_consistently():
    params = load_platform("perturberator").replace({"force_plate.anterior_axis": "-y"})
    s = simulate_perturberator(
        params, seed=5, trials_per_point=1, n_unperturbed=0, n_calibration=0, bench=False,
        artefacts=False,
    )  # fmt: skip
    assert s.info.force_plate.anterior_axis == "-y"
    torque, fz = plate_torque(s, s.walking[0])
    injected = s.truth["time_courses"]["ankle_torque_nm"][0]
    assert np.abs(torque[fz > 50] - injected[fz > 50]).max() < 0.005 * np.abs(injected).max()


def test_reference_is_the_foot_stiffness_at_the_weighted_lever_arm(ideal):
    params = load_platform("perturberator")
    ref = ideal.truth["reference"]
    perturbed = [t for t in ideal.walking if t.perturbed]
    assert sum(v["n_trials"] for d in ref.values() for v in d.values()) == len(perturbed)
    for points in ref.values():
        cops = [points[k]["cop_m"] for k in sorted(points, key=float)]
        assert np.all(np.diff(cops) > 0)  # the COP moves forward through stance
        for value in points.values():
            law = bench_law(params, np.array([value["cop_m"]]))[0]
            assert value["stiffness_nm_per_rad"] == pytest.approx(law, rel=1e-9)
            assert value["inertia_kgm2"] == 0.3 and value["window_ms"] == 100.0
            # an exact least-squares fit of the second-order model lands within 1.5 %
            assert value["stiffness_fit_nm_per_rad"] == pytest.approx(
                value["stiffness_nm_per_rad"], rel=0.015
            )
            assert value["inertia_fit_kgm2"] == pytest.approx(0.3, rel=0.05)
            assert value["onset_sd_ms"] < 0.2  # no jitter without artefacts: update period only
    assert 0.055 < ref["dorsi"]["100"]["cop_m"] < 0.065
    assert 0.10 < ref["dorsi"]["475"]["cop_m"] < 0.11


def test_ideal_recordings_recover_the_reference_by_paper_000s_averaging(ideal):
    """Average perturbed minus unperturbed (aligned on heel contact), fit T = I a'' + b a' + k a."""
    fs = ideal.info.sample_rate_hz
    hc = ideal.truth["trials"]["heel_contact_s"]
    onset = ideal.truth["trials"]["onset_s"]
    t = np.arange(ideal.walking[0].recording.n_samples) / fs
    curves = [(plate_torque(ideal, tr)[0], tr.recording["ankle_angle"]) for tr in ideal.walking]
    still = [i for i, tr in enumerate(ideal.walking) if not tr.perturbed]
    for delay in ("225", "350"):
        idx = [
            i for i, tr in enumerate(ideal.walking)
            if tr.direction == "dorsi" and f"{tr.delay_ms:g}" == delay
        ]  # fmt: skip
        torque, angle = [], []
        for i in idx:
            times = onset[i] + np.arange(-5, 105) / fs
            base = [[np.interp(hc[j] - hc[i] + times, t, c) for c in curves[j]] for j in still]
            base_torque, base_angle = np.mean(base, axis=0)
            torque.append(np.interp(times, t, curves[i][0]) - base_torque)
            angle.append(np.interp(times, t, curves[i][1]) - base_angle)
        torque, angle = np.mean(torque, axis=0), np.mean(angle, axis=0)
        rate = np.gradient(angle, 1 / fs)
        design = np.column_stack([np.gradient(rate, 1 / fs), rate, angle - angle[5]])[5:105]
        fit = np.linalg.lstsq(design, (torque - torque[5])[5:105], rcond=None)[0]
        reference = ideal.truth["reference"]["dorsi"][delay]["stiffness_nm_per_rad"]
        assert fit[2] == pytest.approx(reference, rel=0.015)


def test_onset_jitter_matches_paper_000_with_default_settings():
    s = simulate_perturberator(
        seed=11, trials_per_point=30, n_unperturbed=0, n_calibration=0, bench=False
    )
    lag = s.truth["trials"]["onset_s"] - s.truth["trials"]["heel_contact_s"]
    delays = np.array([t.delay_ms for t in s.walking])
    sd = {d: 1000 * lag[delays == d].std(ddof=1) for d in (100.0, 225.0, 350.0, 475.0)}
    assert all(2.5 < v < 6.5 for v in sd.values()), sd  # paper 000: 3.3, 3.2, 4.2, 5.2 ms
    assert sd[475.0] > sd[100.0]
    for delay in sd:
        assert 1000 * np.median(lag[delays == delay]) == pytest.approx(delay, abs=5.0)


def test_same_seed_same_session_and_same_bytes(session, tmp_path):
    again = simulate_perturberator(seed=7, **SMALL)
    assert diff_sessions(session, again) == []
    other = simulate_perturberator(seed=8, **SMALL)
    assert diff_sessions(session, other) != []
    a = save_session(session, tmp_path / "a.h5")
    b = save_session(again, tmp_path / "b.h5")
    assert a.read_bytes() == b.read_bytes()
    a_dir = save_session(session, tmp_path / "a", format="dir")
    b_dir = save_session(again, tmp_path / "b", format="dir")
    assert session_hash(a_dir) == session_hash(b_dir)


@pytest.mark.parametrize("fmt", ["h5", "dir"])
def test_session_round_trips_through_storage(session, tmp_path, fmt):
    path = save_session(session, tmp_path / ("s.h5" if fmt == "h5" else "s"), format=fmt)
    loaded = load_session(path)
    assert diff_sessions(session, loaded, provenance=False) == []


def test_counts_and_switches(session):
    art = Artefacts(noise=False)
    s = simulate_perturberator(
        seed=2, trials_per_point=1, n_unperturbed=0, n_calibration=0, bench=False, artefacts=art,
        time_courses=False, foot="human",
    )  # fmt: skip
    assert "time_courses" not in s.truth and s.truth["foot"]["kind"] == "human"
    assert s.truth["artefacts"]["noise"] is False and s.truth["artefacts"]["drift"] is True
    assert s.calibration == () and s.bench == ()
    assert all(c in s.walking[0].recording.columns for c in CHANNELS)
    with pytest.raises(ValueError, match="foot"):
        simulate_perturberator(foot="robot", trials_per_point=1)


def test_simulate_command_writes_a_session(tmp_path):
    out = tmp_path / "twin.h5"
    args = ["simulate", "perturberator", "--out", str(out), "--seed", "4",
            "--trials-per-point", "1", "--unperturbed", "1"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    loaded = load_session(out)
    assert len(loaded.walking) == 5 and loaded.truth["reference"]
    bad = CliRunner().invoke(app, [*args[:4], "--format", "csv"])
    assert bad.exit_code != 0


def test_bench_tests_come_with_the_prosthetic_foot_only(tmp_path):
    """A human ankle has no bench law: its session has no bench tests unless asked for."""
    kw = dict(trials_per_point=1, n_unperturbed=0, n_calibration=0, artefacts=False)
    human = simulate_perturberator(seed=2, foot="human", time_courses=False, **kw)
    assert human.bench == () and "bench" not in human.truth
    assert human.provenance["settings"]["bench"] is False
    asked = simulate_perturberator(seed=2, foot="human", bench=True, time_courses=False, **kw)
    assert len(asked.bench) == 15 and asked.provenance["settings"]["bench"] is True
    out = tmp_path / "human.h5"
    args = ["simulate", "perturberator", "--out", str(out), "--foot", "human", "--bench",
            "--trials-per-point", "1", "--unperturbed", "0", "--no-artefacts"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert len(load_session(out).bench) == 15
