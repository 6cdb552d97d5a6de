"""The clean-room session generator (validation/cleanroom): plate signs, truth, determinism,
the directory format, and anklelab's walking analysis on its sessions."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from typer.testing import CliRunner
from validation.cleanroom import (
    KINDS,
    Config,
    NoiseConfig,
    PlateConfig,
    ProstheticFoot,
    ProtocolConfig,
    draw_config,
    generate,
    write_session_dir,
)
from validation.cleanroom.forces import PlateSensors, foot_load
from validation.cleanroom.plate import (
    CHANNELS,
    cop_from_resultants,
    resultants_from_channels,
)
from validation.cleanroom.protocol import walking_plan
from validation.cleanroom.sample import Kind, app
from validation.cleanroom.walking import simulate_walking

from anklelab.data import load_session

SMALL = {"n_calibration": 1, "calibration_duration_s": 2.0}


def _walking_grf_and_cop(channels, plate: PlateConfig):
    """DESIGN §3: GRF_z, GRF_x and the COP along the walking direction, for any mounting."""
    force, moment = resultants_from_channels(channels, plate.a_m, plate.b_m)
    with np.errstate(invalid="ignore", divide="ignore"):  # no COP while nobody stands on it
        ax, ay = cop_from_resultants(force, moment, plate.az0_m)
    fx, fy, fz = force
    grf_x, cop = {
        "+x": (-fx, ax),
        "-x": (fx, -ax),
        "+y": (-fy, ay),
        "-y": (fy, -ay),
    }[plate.anterior_axis]
    return fz, grf_x, cop


# --- the plate: a static load at a known point ------------------------------------------------


# A foot standing still with 700 N down and 50 N backward on the plate (GRF 50 N forward), its
# COP 0.05 m in front of and 0.02 m right of the plate centre; a = 0.2, b = 0.1, az0 = -0.04.
# By hand, in the plate frame of "+x" (load on the plate: F = (-50, 0, 700) N at
# r = (0.05, 0.02, -0.04) m): M = r × F = (14, -33, 1) N·m, so the shear sensors split Mz as
# ±b·Mz/(2(a²+b²)) = ±1 N and ±a·Mz/(2(a²+b²)) = ±2 N, the vertical ones carry
# Fz/4 ± Mx/(4b) ∓ My/(4a) = 175 ± 35 ± 41.25 N.
HAND_CHANNELS = {
    "+x": [-26.0, -24.0, 2.0, -2.0, 251.25, 168.75, 98.75, 181.25],
    # plate x to the left, y forward: F = (0, -50, 700) N at r = (-0.02, 0.05, -0.04) m,
    # M = (33, 14, 1) N·m: 175 ± 82.5 ∓ 17.5 N on the vertical sensors
    "+y": [-1.0, 1.0, -23.0, -27.0, 240.0, 275.0, 110.0, 75.0],
}


@pytest.mark.parametrize("mounting", ["+x", "-x", "+y", "-y"])
def test_a_static_load_gives_the_hand_computed_channels_and_back(mounting):
    plate = PlateConfig(
        a_m=0.2, b_m=0.1, az0_m=-0.04, anterior_axis=mounting, hinge_x_m=0.0,
        vertical_frequency_hz=0.0, horizontal_frequency_hz=0.0,
    )  # fmt: skip
    grf = np.array([50.0, 0.0, 700.0])[:, None]  # anterior, rightward, upward, N
    ankle_x, dz, cop_x = -0.01, 0.08, 0.05
    torque = grf[2] * (cop_x - ankle_x) + grf[0] * dz  # the moment that puts the COP there
    force, moment = foot_load(
        grf, np.zeros(1), torque, np.array([ankle_x]), np.array([0.02]), np.zeros(1),
        np.ones(1, bool), plate, dz,
    )  # fmt: skip
    channels = PlateSensors.build(plate, 1000.0).channels(force, moment)[:, 0]
    if mounting in HAND_CHANNELS:
        np.testing.assert_allclose(channels, HAND_CHANNELS[mounting], atol=1e-9)
    fz, grf_x, cop = _walking_grf_and_cop(channels, plate)
    np.testing.assert_allclose([fz, grf_x, cop], [700.0, 50.0, cop_x], atol=1e-12)
    opposite = {"+x": "-x", "-x": "+x", "+y": "-y", "-y": "+y"}[mounting]
    mirrored = PlateSensors.build(dataclasses.replace(plate, anterior_axis=opposite), 1000.0)
    swapped = mirrored.channels(force, moment)[:, 0]
    order = [CHANNELS.index(name) for name in ("fx34", "fx12", "fy23", "fy14")]
    order += [CHANNELS.index(name) for name in ("fz3", "fz4", "fz1", "fz2")]
    # turning the plate by 180° swaps sensors 1 <-> 3, 2 <-> 4 and flips the shear signs
    np.testing.assert_allclose(swapped[order], channels * [-1, -1, -1, -1, 1, 1, 1, 1], atol=1e-9)


# --- the truth: artefacts off, the foot's torque is k θ + b θ' + I θ'' -------------------------


def _bare_config(mounting: str = "+y") -> Config:
    return Config(
        protocol=ProtocolConfig(trials_per_point=2, n_unperturbed=2, n_calibration=1),
        plate=PlateConfig(
            anterior_axis=mounting,
            top_mass_kg=0.0,
            top_inertia_kgm2=0.0,
            vertical_frequency_hz=0.0,
            horizontal_frequency_hz=0.0,
        ),
        foot=ProstheticFoot(
            stiffness_nm_per_rad=(1100.0, 1100.0), damping_nms_per_rad=3.0, inertia_kgm2=0.3
        ),
        noise=NoiseConfig(scale=0.0),
    )


def test_with_artefacts_off_the_plate_shows_the_ankle_torque_k_theta_b_dtheta_i_ddtheta():
    config = _bare_config()
    rng = np.random.default_rng(4)
    plan = walking_plan(config.protocol, rng)
    sim = simulate_walking(config, plan, rng, nominal_channels=True)
    foot = config.foot
    fs = config.protocol.sample_rate_hz
    checked = 0
    for i in np.flatnonzero(plan.perturbed):
        onset = sim.onset_s[i]
        fz0, grf_x0, cop0 = _walking_grf_and_cop(sim.channels_nominal[:, i], config.plate)
        fz, grf_x, cop = _walking_grf_and_cop(sim.channels[:, i], config.plate)
        cop_hc = np.interp(sim.heel_contact_s[i], sim.time_s, cop0)
        dz = foot.ankle_height_m

        def ankle_torque(fz, grf_x, cop, cop_hc=cop_hc, dz=dz):
            return fz * (cop - cop_hc - foot.heel_to_ankle_m) + grf_x * dz  # DESIGN §3

        window = slice(int(onset * fs), int(onset * fs) + 300)
        measured = ankle_torque(fz, grf_x, cop)[window] - ankle_torque(fz0, grf_x0, cop0)[window]
        theta = sim.perturbation[i, window]
        model = (
            1100.0 * theta
            + foot.damping_nms_per_rad * sim.perturbation_velocity[i, window]
            + foot.inertia_kgm2 * sim.perturbation_acceleration[i, window]
        )
        assert np.max(np.abs(theta)) == pytest.approx(config.protocol.amplitude_rad, rel=0.1)
        assert np.max(np.abs(sim.perturbation[i, : int(onset * fs)])) == 0.0
        np.testing.assert_allclose(measured, model, atol=1e-4 * np.max(np.abs(model)))
        # the nominal lever arm is the COP relative to heel contact, as the truth defines it
        np.testing.assert_allclose(
            (cop0 - cop_hc - foot.heel_to_ankle_m)[window], sim.lever_arm[i, window], atol=1e-5
        )
        checked += 1
    assert checked == 8


def test_truth_of_a_constant_foot_is_its_stiffness_and_the_weighted_lever_arm():
    config = _bare_config("+x")
    session = generate(config, 2)
    for direction in ("dorsi", "plantar"):
        for entry in session.truth["reference"][direction].values():
            assert entry["stiffness_nm_per_rad"] == pytest.approx(1100.0, rel=1e-12)
            assert entry["stiffness_nm_per_rad_75"] == pytest.approx(1100.0, rel=1e-12)
            assert entry["stiffness_change_fraction"] == 0.0
            assert entry["damping_nms_per_rad"] == 3.0 and entry["inertia_kgm2"] == 0.3
            assert 0.0 < entry["cop_m"] < 0.15
    trials = session.truth["trials"]
    perturbed = np.array([trial.perturbed for trial in session.walking])
    assert np.all(np.isnan(trials["onset_s"]) == ~perturbed)
    delay = (trials["onset_s"] - trials["heel_contact_s"])[perturbed] * 1000
    intended = np.array([trial.delay_ms for trial in session.walking])[perturbed]
    assert np.all(np.abs(delay - intended) < 25)


def test_a_rising_human_stiffness_shows_in_the_truth():
    config = draw_config("human", 7, trials_per_point=4, **SMALL)
    config = dataclasses.replace(config, foot=dataclasses.replace(config.foot, rise_per_150ms=0.5))
    reference = generate(config, 7).truth["reference"]["dorsi"]
    # +50 % over any 150 ms: about +31 % over a 100 ms window, relative to the weighted value
    for entry in reference.values():
        assert 0.2 < entry["stiffness_change_fraction"] < 0.35
    assert reference["475"]["stiffness_nm_per_rad"] > 2 * reference["100"]["stiffness_nm_per_rad"]


# --- determinism, the directory, the sample script ---------------------------------------------


def _arrays(session):
    recordings = [*session.calibration, *(t.recording for t in session.walking)]
    recordings += [t.recording for t in session.bench]
    return [value for r in recordings for value in r.columns.values()]


def test_same_seed_same_bytes_other_seed_other_data():
    config = draw_config("random", 11, trials_per_point=3, **SMALL)
    first, again, other = generate(config, 5), generate(config, 5), generate(config, 6)
    assert all(
        a.tobytes() == b.tobytes() for a, b in zip(_arrays(first), _arrays(again), strict=True)
    )
    assert _same_tree(first.truth, again.truth)
    assert not all(
        np.array_equal(a, b) for a, b in zip(_arrays(first), _arrays(other), strict=True)
    )
    assert draw_config("random", 11, trials_per_point=3, **SMALL) == config


def _same_tree(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same_tree(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        return np.array_equal(a, np.asarray(b), equal_nan=True)
    return a == b or (a != a and b != b)


def test_directory_round_trip_through_anklelab_reader(tmp_path):
    config = draw_config("mounted_y", 2, trials_per_point=2, **SMALL)
    config = dataclasses.replace(
        config, protocol=dataclasses.replace(config.protocol, bench_duration_s=0.5)
    )
    session = generate(config, 2)
    path = write_session_dir(session, tmp_path / "session")
    back = load_session(path)
    assert back.info == session.info
    for ours, theirs in (
        (session.calibration, back.calibration),
        ([t.recording for t in session.walking], [t.recording for t in back.walking]),
        ([t.recording for t in session.bench], [t.recording for t in back.bench]),
    ):
        assert [r.name for r in ours] == [r.name for r in theirs]
        for a, b in zip(ours, theirs, strict=True):
            assert list(a.columns) == list(b.columns)
            assert all(np.array_equal(a[c], b[c]) for c in a.columns)
    for a, b in zip(session.walking, back.walking, strict=True):
        assert (a.trial, a.perturbed, a.direction) == (b.trial, b.perturbed, b.direction)
        assert a.delay_ms == b.delay_ms or (np.isnan(a.delay_ms) and np.isnan(b.delay_ms))
    assert [(t.test, t.distance_m) for t in session.bench] == [
        (t.test, t.distance_m) for t in back.bench
    ]
    assert _same_tree(session.truth, back.truth)
    assert {k: back.provenance[k] for k in session.provenance} == session.provenance
    with pytest.raises(FileExistsError, match="already exists"):
        write_session_dir(session, path)
    write_session_dir(session, path, force=True)
    assert load_session(path).info == session.info


def test_bench_regression_recovers_the_true_stiffness():
    session = generate(draw_config("nominal", 3, trials_per_point=1, **SMALL), 3)
    truth = session.truth["bench"]
    for test in session.bench:
        slope = np.polyfit(test.recording["displacement_m"], test.recording["force_n"], 1)[0]
        k = slope * test.distance_m**2  # θ = x / d, T = F d
        expected = np.interp(test.distance_m, truth["distances_m"], truth["stiffness_nm_per_rad"])
        assert k == pytest.approx(expected, rel=0.01)


def test_bad_kind_and_impossible_configs_are_named():
    with pytest.raises(ValueError, match="kind: expected one of nominal"):
        draw_config("humanoid", 0)
    with pytest.raises(ValueError, match="anterior_axis"):
        PlateConfig(anterior_axis="x")
    with pytest.raises(ValueError, match=r"gait\.stance_s"):
        Config(gait=dataclasses.replace(Config().gait, stance_s=0.5))


def test_sample_script_writes_a_session_and_refuses_to_overwrite(tmp_path):
    assert {kind.value for kind in Kind} == set(KINDS)
    out = tmp_path / "s"
    args = ["--kind", "human", "--seed", "3", "--out", str(out), "--trials-per-point", "1"]
    args += ["--calibration-trials", "1"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert load_session(out).info.subject == "cleanroom-human"
    again = CliRunner().invoke(app, args)
    assert again.exit_code == 2 and "already exists" in again.output


# --- anklelab's walking analysis on clean-room sessions -----------------------------------------

# Prosthetic kinds: 30 trials per timing point (~15 per condition) put every condition within a
# few percent. A human ankle (100-400 N·m/rad) gives a perturbation torque of only 5-15 N·m
# against the same step-to-step variability; with 100 trials per point the per-condition
# scatter was measured at ±10-25 %, so there the average over conditions is held to 15 % and each
# condition to 30 %. Tolerances are deliberately loose: this checks generator and analysis agree
# on signs, geometry and scale, not the analysis's accuracy.
ANALYSIS_CASES = {
    "nominal": 30,
    "stiff_prosthetic": 30,
    "noisy": 30,
    "mounted_y": 30,
    "human": 100,
    "random": 100,
}


@pytest.mark.parametrize("kind", sorted(ANALYSIS_CASES))
def test_walking_analysis_lands_near_the_truth(kind):
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config(
        kind, 0, trials_per_point=ANALYSIS_CASES[kind], n_calibration=2,
        calibration_duration_s=10.0, bench=False,
    )  # fmt: skip
    session = generate(config, 0)
    results = analyze_walking(session, WalkingSettings(bootstrap_reps=20))
    misses = []
    for point in results.timing_points:
        truth = session.truth["reference"][point.direction][f"{point.delay_ms:g}"]
        k = truth["stiffness_nm_per_rad"]
        low, high = point.stiffness.ci95
        # within 3 % of the truth beyond its 95 % interval (the accuracy criterion)
        if not low - 0.03 * k <= k <= high + 0.03 * k:
            misses.append((point.key, point.stiffness.mean, (low, high), k))
    assert len(results.timing_points) == 8 and not misses, misses


def test_the_coupler_twist_correction_removes_the_plate_inertia_left_under_load():
    """The foot's torque twists the coupler, so under load the plate lags the motor angle the
    platform filters were fitted on; without the correction a noise-free nominal session's
    inertia reads about 8 % high and its stiffness about 2 % (10 trials per point here); the
    correction brings them to about 5 % and 1 %."""
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config("nominal", 100, trials_per_point=10, n_calibration=2, bench=False)
    session = generate(dataclasses.replace(config, noise=NoiseConfig(scale=0.0)), 100)

    def errors(**settings):
        results = analyze_walking(session, WalkingSettings(bootstrap_reps=5, **settings))
        rows = []
        for point in results.timing_points:
            truth = session.truth["reference"][point.direction][f"{point.delay_ms:g}"]
            rows.append(
                [
                    point.stiffness.mean / truth["stiffness_nm_per_rad"] - 1,
                    point.inertia.mean / truth["inertia_kgm2"] - 1,
                ]
            )
        return np.array(rows).T

    k_plain, inertia_plain = errors(transmission_stiffness_nm_per_rad=0.0)
    k_corrected, inertia_corrected = errors()
    assert np.mean(inertia_plain) > 0.06
    assert np.mean(inertia_corrected) < 0.6 * np.mean(inertia_plain)
    assert 0 < np.mean(k_corrected) < 0.6 * np.mean(k_plain)


def test_the_twist_correction_delayed_by_the_coupler_lag_takes_the_damping_bias_out():
    """A damped coupler twists ``c / K`` behind ``T / K`` (1.8 ms on this stiff prosthetic
    session): taken without that delay the twist's own forces put the plate's inertia into the
    damping (about +65 % of the foot's), taken 2 ms late they leave a few percent."""
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config("stiff_prosthetic", 101, trials_per_point=10, n_calibration=2)
    session = generate(dataclasses.replace(config, noise=NoiseConfig(scale=0.0)), 101)

    def damping_error(**settings):
        results = analyze_walking(session, WalkingSettings(bootstrap_reps=5, **settings))
        truth = session.truth["reference"]
        return np.mean(
            [
                p.damping.mean / truth[p.direction][f"{p.delay_ms:g}"]["damping_nms_per_rad"] - 1
                for p in results.timing_points
            ]
        )

    assert abs(damping_error()) < 0.15
    assert damping_error(coupler_lag_ms=0.0) > 0.4


def test_the_contact_cop_is_read_without_the_heavy_plates_own_moment_at_heel_strike():
    """A 25 kg top plate on a compliant coupler: the heel's strike twists it, and its own
    moment, while the load is a few tens of newtons, moved the COP at contact forward. In this
    noise-free session of 10 trials per point every lever arm read about 28 mm short (37 mm
    in the guide's session of the same seed, with its drawn trial counts and noise); without
    the strike's own forces about 6 mm (the rest is the early COP path's shape, see the
    walking-analysis guide)."""
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config("stiff_prosthetic", 101, trials_per_point=10, n_calibration=2)
    session = generate(dataclasses.replace(config, noise=NoiseConfig(scale=0.0)), 101)
    results = analyze_walking(session, WalkingSettings(bootstrap_reps=5))
    reference = session.truth["reference"]
    errors = [
        p.cop_m - reference[p.direction][f"{p.delay_ms:g}"]["cop_m"] for p in results.timing_points
    ]
    assert abs(np.mean(errors)) < 0.012, errors


def test_a_session_sampled_below_twice_the_contact_twist_cutoff_is_analysed():
    """At 100 Hz the 60 Hz low-pass of the strike's twist lies above the Nyquist frequency: the
    twist is taken unfiltered (it stopped the analysis, naming cutoff_hz)."""
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config(
        "nominal", 1, trials_per_point=4, n_calibration=2, sample_rate_hz=100.0, bench=False
    )
    results = analyze_walking(generate(config, 1), WalkingSettings(bootstrap_reps=5, cutoff_hz=10))
    stiffness = [p.stiffness.mean for p in results.timing_points]
    assert len(stiffness) == 8 and np.all(np.isfinite(stiffness))


def test_the_change_within_the_window_is_read_from_the_neighbouring_points():
    """A human-like ankle whose stiffness rises 50 % in any 150 ms (+26 to +31 % over each
    window): the neighbouring timing points' stiffnesses give each window's change closer to
    the truth than the window's own linear model, and the diagnostic says it at every point."""
    from anklelab.pipelines import WalkingSettings, analyze_walking

    config = draw_config(
        "human", 2, trials_per_point=40, n_calibration=2, calibration_duration_s=10.0, bench=False
    )
    config = dataclasses.replace(config, foot=dataclasses.replace(config.foot, rise_per_150ms=0.5))
    session = generate(config, 2)
    reference = session.truth["reference"]
    errors = {}
    for basis in ("neighbours", "window"):
        results = analyze_walking(session, WalkingSettings(bootstrap_reps=20, change_basis=basis))
        points = results.timing_points
        truth = [
            reference[p.direction][f"{p.delay_ms:g}"]["stiffness_change_fraction"] for p in points
        ]
        errors[basis] = np.array([p.stiffness_change.mean for p in points]) - truth
        if basis == "neighbours":
            assert all(p.stiffness_change_verdict == "changes" for p in points)
            held = [
                p.stiffness_change.ci95[0] <= t <= p.stiffness_change.ci95[1]
                for p, t in zip(points, truth, strict=True)
            ]
            assert all(held), errors[basis]
    assert np.abs(errors["neighbours"]).mean() < 0.5 * np.abs(errors["window"]).mean(), errors
