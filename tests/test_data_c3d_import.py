"""``anklelab import c3d DIR --map MAP``: a twin session exported to per-trial C3D files (with
ezc3d, here) imports back through the shipped mapping and analyses like the native session."""

from __future__ import annotations

import csv
import math
import re
import subprocess
import sys
import warnings
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from anklelab.data import load_session
from anklelab.data.c3d_import import import_c3d
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import CHANNELS
from anklelab.pipelines import WalkingSettings, analyze_walking
from tests.c3d_files import write_c3d
from tests.lab_twin import small_twin, with_twin_delay

MAP = Path(__file__).parents[1] / "examples" / "maps" / "c3d_kistler.toml"


# paper 000's analysis for both: the comparison is of the data. With a few trials per point the
# automatic model choice can fall either way on near-equal evidence, and the covariate adjustment,
# learnt from a handful of unperturbed trials, turns the formats' small differences (a COP left
# empty at low force) into up to 0.4 % of stiffness at one point (measured, seed of lab_twin)
SETTINGS = WalkingSettings(
    bootstrap_reps=20, stiffness_model="constant", covariate_adjustment=False
)
DEG = 180.0 / math.pi
LABEL = {"dorsi": "d", "plantar": "p", "none": "u"}


def export_trial(path, recording, geometry, *, events=(), walking_axis="+y"):
    """One recording as a C3D file: the plate as FORCE_PLATFORM 1 (type 3, mm) with its +x
    along the lab's ``walking_axis`` (z up), the motor angle and the goniometer (plantarflexion
    positive) in degrees."""
    assert geometry.anterior_axis == "+x"
    forward = {"+y": np.array([0.0, 1.0, 0.0]), "-x": np.array([-1.0, 0.0, 0.0])}[walking_axis]
    down = np.array([0.0, 0.0, -1.0])
    right = np.cross(down, forward)  # plate y (z down): to the walker's right
    centre = np.array([0.6, 1.2, 0.0])
    corners = [
        centre + sx * 0.2 * forward + sy * 0.3 * right
        for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))
    ]
    labels = [f"F{c}" for c in CHANNELS]
    analogs = dict(zip(labels, recording.stack(CHANNELS), strict=True))
    analogs["Motor"] = recording["motor_angle"] * DEG
    if "ankle_angle" in recording.columns:
        analogs["Gonio"] = -recording["ankle_angle"] * DEG
    plate = {
        "type": 3,
        "labels": labels,
        "origin": np.array([geometry.a_m, geometry.b_m, geometry.az0_m]) * 1000.0,
        "corners": np.array(corners) * 1000.0,
    }
    return write_c3d(
        path,
        analogs,
        units=dict.fromkeys(labels, "N") | {"Motor": "deg", "Gonio": "deg"},
        plates=[plate],
        per_frame=1,
        events=events,
    )


def export_session(session, root, *, events=False, other_foot_s=None):
    """Calibration and walking trials as C3D files, with trials.csv (text labels); with
    ``events``, the heel strikes (context Right) and the onsets, and with ``other_foot_s`` the
    left foot's strikes that long after the right's."""
    root.mkdir()
    geometry = session.info.force_plate
    rows = [["file", "role", "label", "perturbed", "direction", "delay_ms"]]
    for i, rec in enumerate(session.calibration, start=1):
        export_trial(root / f"cal_{i:02d}.c3d", rec, geometry)
        rows.append([f"cal_{i:02d}.c3d", "calibration", "", "", "", ""])
    for w in session.walking:
        name = f"walk_{int(w.trial):03d}.c3d"
        marks = ()
        if events:
            fz = w.recording.stack(CHANNELS)[4:].sum(axis=0)
            strike = w.recording.time_s[np.argmax(fz > 25.0)]
            marks = [("Foot Strike", "Right", strike)]
            if other_foot_s is not None:
                marks.append(("Foot Strike", "Left", strike + other_foot_s))
            if w.perturbed:
                onset = strike + (w.delay_ms + 3.0) / 1000.0  # an onset a little late
                marks.append(("Dorsi" if w.direction == "dorsi" else "Plantar", "General", onset))
        export_trial(root / name, w.recording, geometry, events=marks)
        delay = "" if not w.perturbed else f"{w.delay_ms:g}"
        label = f"S03_{LABEL[w.direction]}{delay}_{w.trial}"
        rows.append([name, "walking", label, str(int(w.perturbed)), w.direction, delay])
    with open(root / "trials.csv", "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return root


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    session = small_twin()
    root = export_session(session, tmp_path_factory.mktemp("c3d") / "trials")
    return session, root, analyze_walking(session, SETTINGS)


def test_c3d_round_trip_gives_the_native_stiffness(twin, tmp_path):
    session, root, native = twin
    imported = import_c3d(root, with_twin_delay(MAP, session, tmp_path))
    plate = imported.info.force_plate
    assert plate.type == "kistler8" and plate.anterior_axis == "+x"
    assert (plate.a_m, plate.b_m, plate.az0_m) == pytest.approx(
        (session.info.force_plate.a_m, session.info.force_plate.b_m, session.info.force_plate.az0_m)
    )
    assert imported.walking[0].trial.startswith("S03_")
    results = analyze_walking(imported, SETTINGS)
    assert [tp.key for tp in results.timing_points] == [tp.key for tp in native.timing_points]
    for a, b in zip(results.timing_points, native.timing_points, strict=True):
        # float32 storage is the only loss
        assert a.stiffness.mean == pytest.approx(b.stiffness.mean, rel=1e-3)
    assert imported.provenance["import"]["importer"] == "c3d"


@pytest.mark.parametrize(
    ("kind", "min_force_n", "tolerance"),
    [
        # lossless
        ("six_axis", None, 1e-3),
        # the COP kept wherever Fz != 0 (the default): only the samples where the float32 Fz
        # is 0 lose their moment
        ("grf_cop", None, 3e-3),
        # the COP empty below 10 N, as processed exports leave it: the platform's moment is
        # not removed and the analysis says so
        ("grf_cop", 10.0, 0.15),
    ],
)
def test_c3d_plate_stored_as_six_axis_or_grf_cop(twin, tmp_path, kind, min_force_n, tolerance):
    session, root, native = twin
    plate = f'type = "{kind}"' + ("" if min_force_n is None else f"\nmin_force_n = {min_force_n}")
    imported = import_c3d(root, with_twin_delay(MAP, session, tmp_path, 'type = "kistler8"', plate))
    assert imported.info.force_plate.type == kind
    blanked = min_force_n is not None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = analyze_walking(imported, SETTINGS)
    assert bool(caught) == blanked
    for a, b in zip(results.timing_points, native.timing_points, strict=True):
        assert a.stiffness.mean == pytest.approx(b.stiffness.mean, rel=tolerance)
        assert a.stiffness.bias_unknown == blanked
    assert bool(results.warnings) == blanked


def _events_map(tmp_path, extra=""):
    text = MAP.read_text().replace(
        '[trials]\nsource = "csv"\nfile = "trials.csv"',
        '[trials]\nsource = "events"\ncalibration = ["cal_*.c3d"]\nheel_strike = "Foot Strike"\n'
        'dorsi = "Dorsi"\nplantar = "Plantar"\ntiming_points_ms = [100, 225, 350, 475]' + extra,
    )
    (tmp_path / "map.toml").write_text(text)
    return tmp_path / "map.toml"


def test_a_misspelt_key_of_the_events_trial_list_gets_a_hint_at_its_place(tmp_path):
    """pydantic places the [trials] table's keys under its `source` tag (trials.events....):
    the message names the key as the file has it, with the hint."""

    mapping = _events_map(tmp_path, '\ncalibrationn = ["cal_*.c3d"]')
    with pytest.raises(ParameterError, match=r"trials\.calibrationn: unknown key \(did you mean "
                                             r"'calibration'\?\)"):  # fmt: skip
        import_c3d(tmp_path, mapping)


def _events_export(session, root, **options):
    small = type(session)(session.info, session.calibration, session.walking[:12], (), None, {})
    export_session(small, root, events=True, **options)
    (root / "trials.csv").unlink()
    want = [
        (f"walk_{int(w.trial):03d}", w.perturbed, w.direction, w.delay_ms) for w in small.walking
    ]
    return root, want


def _conditions(imported):
    return [(w.trial, w.perturbed, w.direction, w.delay_ms) for w in imported.walking]


def test_trial_roles_from_events(twin, tmp_path):
    session, _, _ = twin
    root, want = _events_export(session, tmp_path / "ev")
    imported = import_c3d(root, _events_map(tmp_path))
    assert len(imported.calibration) == 2
    got = _conditions(imported)
    assert [g[:3] for g in got] == [w[:3] for w in want]
    np.testing.assert_array_equal([g[3] for g in got], [w[3] for w in want])


def test_events_take_every_c3d_file_and_name_the_role_of_one_that_is_no_trial(twin, tmp_path):
    """A file ending in .C3D is a trial too; a bench test in the directory is named as one
    (it is no walking trial: it has no motor channel and no plate) until it is ignored."""
    session, _, _ = twin
    root, want = _events_export(session, tmp_path / "ev")
    (root / "walk_012.c3d").rename(root / "walk_012.C3D")
    (root / "cal_02.c3d").rename(root / "cal_02.C3D")
    t = np.arange(500) / 1000.0
    write_c3d(root / "bench_01.c3d", {"Disp": t, "Load": t}, per_frame=1)
    bench_map = (
        '\n[channels.displacement_m]\nlabel = "Disp"\n\n[channels.force_n]\nlabel = "Load"\n'
    )
    mapping = _events_map(tmp_path)
    text = mapping.read_text().replace("\n[trials]", bench_map + "\n[trials]")
    mapping.write_text(text)
    with pytest.raises(
        SessionFormatError,
        match=r"bench_01\.c3d: taken for a walking trial \(\[trials\] source = \"events\": it "
        r"matches no calibration or ignore pattern\), but it has no analog channel 'Motor', "
        r"'Gonio' and no force platform 1: it looks like a bench test \(it has 'Disp', 'Load'\); "
        r"list it in \[trials\] ignore, or list the trials in a CSV \(source = \"csv\"\)$",
    ):
        import_c3d(root, mapping)
    mapping.write_text(text + 'ignore = ["bench_*.c3d"]\n')
    imported = import_c3d(root, mapping)
    assert len(imported.calibration) == 2
    assert [g[:3] for g in _conditions(imported)] == [w[:3] for w in want]


def test_heel_strikes_of_the_foot_on_the_plate(twin, tmp_path):
    """Both feet's strikes marked (Nexus does): the plate foot's are chosen by their context,
    and without a choice the files are refused (the other foot's last strike, 450 ms later,
    filed a 475 ms trial under 100 ms)."""
    session, _, _ = twin
    root, want = _events_export(session, tmp_path / "ev", other_foot_s=0.45)
    with pytest.raises(
        SessionFormatError,
        match=r"walk_001\.c3d: 'Foot Strike' events of the contexts 'Left' and 'Right' "
        r"\(EVENT:CONTEXTS\); say which foot's strikes time the perturbation \(the foot on the "
        r'plate\): \[trials\] heel_strike_context = "Left" or "Right"$',
    ):
        import_c3d(root, _events_map(tmp_path))
    imported = import_c3d(root, _events_map(tmp_path, '\nheel_strike_context = "Right"'))
    np.testing.assert_array_equal([g[3] for g in _conditions(imported)], [w[3] for w in want])
    with pytest.raises(
        SessionFormatError,
        match=r"a 'Dorsi' event at \S+ s but no 'Foot Strike' event of context 'right' before it",
    ):
        import_c3d(root, _events_map(tmp_path, '\nheel_strike_context = "right"'))


def _edit(tmp_path, root, old, new, target="map"):
    if target == "map":
        (tmp_path / "map.toml").write_text(MAP.read_text().replace(old, new))
        return root, tmp_path / "map.toml"
    copy = tmp_path / "copy"
    copy.mkdir()
    for p in root.iterdir():
        (copy / p.name).symlink_to(p) if p.name != "trials.csv" else None
    (copy / "trials.csv").write_text((root / "trials.csv").read_text().replace(old, new))
    return copy, MAP


@pytest.mark.parametrize(
    ("old", "new", "target", "error", "message"),
    [
        (
            'label = "Motor"',
            'label = "motor"',
            "map",
            SessionFormatError,
            r"cal_01\.c3d: no analog channel 'motor' \('Motor' differs .* only in case",
        ),
        (
            'units = "deg"           # the file',
            'units = "grad"  # the file',
            "map",
            ParameterError,
            r"map\.toml: channels\.motor_angle\.units: expected one of rad, deg",
        ),
        (
            'walking_axis = "+y"',
            'walking_axis = "+z"',
            "map",
            SessionFormatError,
            r"cal_01\.c3d: plate 1 \(type 3\): no plate axis is within 10° of the walking axis \+z",
        ),
        (
            "number = 1 ",
            "number = 2 ",
            "map",
            SessionFormatError,
            r"cal_01\.c3d: no force platform 2; FORCE_PLATFORM:USED = 1",
        ),
        ('source = "csv"', 'source = "files"', "map", ParameterError, r"map\.toml: .*trials"),
        (
            'units = "deg"           # the file',
            'units = "rad"           # the file',
            "map",
            ParameterError,
            r"^\S+map\.toml: channels\.motor_angle\.units: 'rad', but \S+cal_01\.c3d gives "
            r"'Motor' in 'deg' \(ANALOG:UNITS\); give units = \"deg\" if the file is right \(or "
            r"the scale that converts it\)$",
        ),
        (
            'label = "Gonio"\nunits = "deg"\n',
            'label = "Gonio"\n',
            "map",
            ParameterError,
            r"channels\.ankle_angle\.units: 'rad' \(the default\), but \S+walk_001\.c3d gives "
            r"'Gonio' in 'deg'",
        ),
        (
            'label = "Motor"',
            'label = "Ffz1"',
            "map",
            ParameterError,
            r"channels\.motor_angle\.units: 'deg', but \S+cal_01\.c3d gives 'Ffz1' in 'N' "
            r"\(ANALOG:UNITS\): a unit of force, not of angle; is the label right\?",
        ),
        (
            'units = "deg"           # the file',
            'units = "deg"\nscale = inf  # the file',
            "map",
            ParameterError,
            r"map\.toml: invalid parameters: channels\.motor_angle\.scale: Input should be a "
            r"finite number; got inf",
        ),
        (
            'units = "deg"           # the file',
            'units = "deg"\nscale = 0.0  # the file',
            "map",
            ParameterError,
            r"channels\.motor_angle\.scale: expected a finite number other than 0; got 0\.0",
        ),
        (
            "walk_002.c3d,walking",
            "walk_999.c3d,walking",
            "csv",
            SessionFormatError,
            r"trials\.csv: line 5, column 'file': 'walk_999\.c3d' is not a file",
        ),
        (
            ",1,dorsi,",
            ",1,sideways,",
            "csv",
            SessionFormatError,
            r"trials\.csv: line \d+, column 'direction': got 'sideways'",
        ),
        (
            "calibration,",
            "calib,",
            "csv",
            SessionFormatError,
            r"trials\.csv: line 2, column 'role': got 'calib'; expected one of calibration",
        ),
    ],
)
def test_malformed_mapping_or_trial_list_is_named(twin, tmp_path, old, new, target, error, message):
    _, root, _ = twin
    directory, mapping = _edit(tmp_path, root, old, new, target)
    with pytest.raises(error, match=message):
        import_c3d(directory, mapping)


def test_a_scale_that_converts_the_files_unit_is_not_refused(twin, tmp_path):
    """`units` is the unit of stored x scale: a map that converts the file's degrees to
    radians by its scale reads the same motor angle as one that names the degrees."""
    _, root, _ = twin
    radians = 'units = "rad"\nscale = 0.017453292519943295  # the file'
    directory, mapping = _edit(tmp_path, root, 'units = "deg"           # the file', radians)
    converted = import_c3d(directory, mapping)
    as_named = import_c3d(root, MAP)
    for a, b in zip(converted.walking, as_named.walking, strict=True):
        np.testing.assert_allclose(a.recording["motor_angle"], b.recording["motor_angle"])


def _with_changed_file(tmp_path, root, name, change):
    """A copy of the C3D directory (links) whose file ``name`` is changed by ``change`` (an
    ezc3d c3d object)."""
    copy = tmp_path / "changed"
    copy.mkdir()
    for p in root.iterdir():
        if p.name not in (name, "trials.csv"):
            (copy / p.name).symlink_to(p)
    (copy / "trials.csv").write_text((root / "trials.csv").read_text())
    c = ezc3d.c3d(str(root / name))
    change(c)
    c.write(str(copy / name))
    return copy


def _analog_nan(label, sample):
    def change(c):
        analogs = c["data"]["analogs"]
        analogs[0, list(c["parameters"]["ANALOG"]["LABELS"]["value"]).index(label), sample] = np.nan
        c["data"]["analogs"] = analogs

    return change


def _origin_x(value):
    def change(c):
        origin = np.array(c["parameters"]["FORCE_PLATFORM"]["ORIGIN"]["value"], dtype=float)
        origin[0] = value
        c["parameters"]["FORCE_PLATFORM"]["ORIGIN"]["value"] = origin

    return change


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            _analog_nan("Motor", 300),
            r"walk_006\.c3d: analog channel 9 'Motor', sample 301: value nan; expected a finite "
            r"number$",
        ),
        (
            _analog_nan("Ffz2", 300),
            r"walk_006\.c3d: analog channel 6 'Ffz2', sample 301: value nan; expected a finite "
            r"number$",
        ),
        (
            _origin_x(150.0),
            r"walk_006\.c3d: plate 1 has a_m = 0\.15 \(cal_01\.c3d: 0\.12\); expected the same "
            r"plate in every file$",
        ),
    ],
)
def test_bad_channels_and_plates_name_the_c3d_file(twin, tmp_path, change, message):
    _, root, _ = twin
    with pytest.raises(SessionFormatError, match=message):
        import_c3d(_with_changed_file(tmp_path, root, "walk_006.c3d", change), MAP)


@pytest.mark.parametrize(
    ("edits", "message"),
    [
        (
            [("walk_003.c3d,walking,S03_p100_3", "walk_003.c3d,walking,S03_p350_2")],
            r"trials\.csv: line 6, column 'label': 'S03_p350_2' is already the label of line 5$",
        ),
        (
            [
                ("walk_001.c3d,walking,S03_d225_1", "walk_001.c3d,walking,walk_003"),
                ("walk_003.c3d,walking,S03_p100_3", "walk_003.c3d,walking,"),
            ],
            r"trials\.csv: line 6, column 'label': 'walk_003' \(the file name, as the label is "
            r"empty\) is already the label of line 4$",
        ),
        (
            [(",", ";")],
            r"trials\.csv: line 1 is separated by semicolons \('file;role;label;perturbed;"
            r"direction;delay_ms'\); expected a comma-separated CSV$",
        ),
    ],
)
def test_trial_list_errors_name_the_line(twin, tmp_path, edits, message):
    _, root, _ = twin
    directory, mapping = _edit(tmp_path, root, *edits[0], "csv")
    for old, new in edits[1:]:
        listed = directory / "trials.csv"
        listed.write_text(listed.read_text().replace(old, new))
    with pytest.raises(SessionFormatError, match=message):
        import_c3d(directory, mapping)


def test_a_trial_list_without_walking_trials_is_refused(twin, tmp_path):
    _, root, _ = twin
    lines = (root / "trials.csv").read_text().splitlines()
    kept = [line for line in lines if ",walking," not in line]
    directory, mapping = _edit(tmp_path, root, "\n".join(lines), "\n".join(kept), "csv")
    with pytest.raises(
        SessionFormatError,
        match=r"copy: no walking trial among the 2 C3D file\(s\) the map lists \(its \[trials\] "
        r"table says which are calibration, walking or bench trials\)",
    ):
        import_c3d(directory, mapping)


def test_a_directory_of_c3d_trials_given_as_a_session_says_to_import_it(twin):
    _, root, _ = twin
    with pytest.raises(
        SessionFormatError,
        match=r"trials: no session\.toml, but \d+ C3D file\(s\): a directory of C3D trials is "
        r"read with 'anklelab import c3d DIR --map MAP\.toml'",
    ):
        load_session(root)


def test_import_c3d_command_and_default_import(twin, tmp_path):
    from typer.testing import CliRunner

    from anklelab.cli import app

    _, root, _ = twin
    out = tmp_path / "s.h5"
    result = CliRunner().invoke(
        app, ["import", "c3d", str(root), "--map", str(MAP), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "(kistler8 plate)" in result.output

    def run(*args):
        code = "from anklelab.cli import run; run()"
        return subprocess.run(
            [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True
        )

    proc = run("import", "c3d", root, "--map", MAP, "--out", out)
    assert proc.returncode == 2 and re.search(r"s\.h5: already exists; pass --force", proc.stderr)
    proc = run("import", "c3d", root, "--map", MAP, "--out", root / "inside.h5")
    assert proc.returncode == 2 and "lies inside the input" in proc.stderr
    assert not (root / "inside.h5").exists()
    # the plain `anklelab import SOURCE` still takes a session
    result = CliRunner().invoke(app, ["import", str(out), "--out", str(tmp_path / "again.h5")])
    assert result.exit_code == 0, result.output
    assert len(load_session(tmp_path / "again.h5").walking) == len(load_session(out).walking)


def _cli(*args):
    code = "from anklelab.cli import run; run()"
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True
    )


def test_import_c3d_never_writes_over_its_inputs(twin, tmp_path):
    """The mapping and the trial list are inputs like the directory: --out may not name them,
    even with --force; nor may --out be a symbolic link (as for `anklelab import`)."""
    _, root, _ = twin
    mapping = tmp_path / "map.toml"
    mapping.write_text(MAP.read_text())
    (tmp_path / "link.h5").symlink_to(tmp_path / "target.h5")
    cases = {
        mapping: "lies inside the input",
        root / "trials.csv": "lies inside the input",
        tmp_path / "link.h5": "a symbolic link",
    }
    before = mapping.read_bytes(), (root / "trials.csv").read_bytes()
    for out, message in cases.items():
        proc = _cli("import", "c3d", root, "--map", mapping, "--out", out, "--force")
        assert proc.returncode == 2, proc.stderr
        assert re.fullmatch(rf"error: --out \S+: .*{message}.*\n", proc.stderr), proc.stderr
    assert (mapping.read_bytes(), (root / "trials.csv").read_bytes()) == before
    assert not (tmp_path / "target.h5").exists()
