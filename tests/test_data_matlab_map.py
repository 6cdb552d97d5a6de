"""``anklelab import matlab FILE --map MAP``: a per-subject, dorsiflexion/plantarflexion,
processed GRF/COP MATLAB layout (written here from a twin session) read with the shipped map,
wildcards, units, sign flips, and malformed maps and files."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.data.matlab_map import import_matlab
from anklelab.errors import AnklelabError, ParameterError, SessionFormatError
from anklelab.forceplate import CHANNELS
from anklelab.pipelines import WalkingSettings, analyze_walking
from tests.lab_twin import small_twin, with_twin_delay

MAP = Path(__file__).parents[1] / "examples" / "maps" / "matlab_grf_cop.toml"
# paper 000's analysis for both: the comparison is of the data. With a few trials per point the
# automatic model choice can fall either way on near-equal evidence, and the covariate adjustment,
# learnt from a handful of unperturbed trials, turns the formats' small differences (a COP left
# empty at low force) into up to 0.4 % of stiffness at one point (measured, seed of lab_twin)
SETTINGS = WalkingSettings(
    bootstrap_reps=20, stiffness_model="constant", covariate_adjustment=False
)
DEG = 180.0 / math.pi


def struct_array(elements):
    array = np.empty((1, len(elements)), dtype=[(name, object) for name in elements[0]])
    for i, element in enumerate(elements):
        array[0, i] = tuple(element.values())
    return array


def processed(recording, geometry):
    """The lab's processed signals: lab x backwards, z up (so y points right), COP in mm
    (origin 2 m behind the plate), angles in degrees, the goniometer plantarflexion-positive."""
    lab = geometry.lab_load(recording.stack(CHANNELS), min_fz_n=0.0)
    out = {
        "angle": recording["motor_angle"] * DEG,
        "Fx": -lab.grf_x,
        "Fy": -lab.grf_y,
        "Fz": lab.grf_z,
        "CoPx": (2.0 - lab.cop_x) * 1000.0,
        "CoPy": -lab.cop_y * 1000.0,
    }
    if "ankle_angle" in recording.columns:
        out["ankle"] = -recording["ankle_angle"] * DEG
    return out


def matrices(trials, geometry):
    """Signal matrices, one trial per column, NaN after each trial's end."""
    signals = [processed(t.recording, geometry) for t in trials]
    n = max(s["Fz"].size for s in signals)
    out = {}
    for name in signals[0]:
        block = np.full((n, len(signals)), np.nan)
        for k, s in enumerate(signals):
            block[: s[name].size, k] = s[name]
        out[name] = block
    return out


def write_layout(path, session, subject="S07"):
    geometry = session.info.force_plate
    calibration = []
    for rec in session.calibration:
        p = processed(rec, geometry)
        calibration.append(
            {
                "angle": p["angle"][:, None],
                "GRF": np.column_stack([p["Fx"], p["Fy"], p["Fz"]]),
                "COP": np.column_stack([p["CoPx"], p["CoPy"]]),
            }
        )
    root = {"fs": session.info.sample_rate_hz, "calibration": struct_array(calibration)}
    names = {"dorsi": "dorsiflexion", "plantar": "plantarflexion"}
    for direction, name in names.items():
        root[name] = {}
        for delay in sorted({w.delay_ms for w in session.walking if w.direction == direction}):
            group = [w for w in session.walking if w.direction == direction and w.delay_ms == delay]
            root[name][f"t{delay:g}"] = matrices(group, geometry)
    root["control"] = matrices([w for w in session.walking if not w.perturbed], geometry)
    scipy.io.savemat(path, {subject: root})
    return path


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    session = small_twin()
    path = write_layout(tmp_path_factory.mktemp("mat") / "S07.mat", session)
    return session, path


def test_shipped_map_reads_the_layout_and_gives_the_native_stiffness(twin, tmp_path):
    """The shipped map leaves delay_ms at 0; the twin's amplifier records 1.031 ms late."""
    session, path = twin
    imported = import_matlab(path, with_twin_delay(MAP, session, tmp_path))
    assert imported.info.subject == "S07" and imported.info.force_plate.type == "grf_cop"
    assert len(imported.calibration) == 2 and len(imported.walking) == len(session.walking)
    labels = {w.trial for w in imported.walking}
    assert "S07.dorsiflexion.t225(1)" in labels and "S07.control(10)" in labels
    # NaN padding removed: every trial has its own length back
    native_lengths = sorted(w.recording.n_samples for w in session.walking)
    assert sorted(w.recording.n_samples for w in imported.walking) == native_lengths
    trial = next(w for w in imported.walking if w.trial == "S07.dorsiflexion.t100(2)")
    source = [w for w in session.walking if w.direction == "dorsi" and w.delay_ms == 100][1]
    np.testing.assert_allclose(trial.recording["ankle_angle"], source.recording["ankle_angle"])
    np.testing.assert_allclose(trial.recording["motor_angle"], source.recording["motor_angle"])
    native = analyze_walking(session, SETTINGS)
    results = analyze_walking(imported, SETTINGS)
    assert [tp.key for tp in results.timing_points] == [tp.key for tp in native.timing_points]
    for a, b in zip(results.timing_points, native.timing_points, strict=True):
        # the same loss as grf_cop (tests/test_plate_types.py): measured 0.10 % at most
        assert a.stiffness.mean == pytest.approx(b.stiffness.mean, rel=2e-3)
    assert imported.provenance["import"]["importer"] == "matlab-map"


def test_import_matlab_command_writes_the_session(twin, tmp_path):
    from typer.testing import CliRunner

    from anklelab.cli import app
    from anklelab.data import load_session

    _, path = twin
    out = tmp_path / "s.h5"
    result = CliRunner().invoke(
        app, ["import", "matlab", str(path), "--map", str(MAP), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "(grf_cop plate)" in result.output
    assert len(load_session(out).walking) == len(twin[0].walking)


def _map(tmp_path, old, new):
    text = MAP.read_text()
    assert old in text, old
    path = tmp_path / "map.toml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    ("old", "new", "error", "message"),
    [
        (
            'type = "grf_cop"',
            'type = "amti"',
            ParameterError,
            r"map\.toml: plate\.type: expected one of kistler8",
        ),
        (
            '{ field = "Fz" }',
            '{ field = "Fz", units = "mm" }',
            ParameterError,
            r"grf_z_n\.units: expected one of N, kN for a force, got 'mm'",
        ),
        (
            '{ field = "Fz" }',
            '{ field = "F_z" }',
            SessionFormatError,
            r"S07\.dorsiflexion\.t100\(1\)\.F_z: field is missing \(did you mean 'Fz'\?\)",
        ),
        (
            'layout = "matrices"\nperturbed = true',
            'layout = "matrices"\nperturbed = true\nlag = 1',
            ParameterError,
            r"walking\.0\.lag: unknown key",
        ),
        (
            '"{subject}.control"',
            '"{subject}.controls"',
            SessionFormatError,
            r"nothing matches the struct path '\{subject\}\.controls'",
        ),
        ("t{delay_ms}", "t{delay}", ParameterError, r"unknown wildcard \{delay\}"),
        (
            "column = 3 }",
            "column = 4 }",
            SessionFormatError,
            r"calibration\(1\)\.GRF: column 4 requested of an array of shape \(20000, 3\)",
        ),
        (
            'format = "anklelab-matlab-map/1"',
            'format = "x"',
            ParameterError,
            r"format: expected 'anklelab-matlab-map/1'",
        ),
        (
            'sample_rate_path = "{subject}.fs"',
            'sample_rate_path = "{subject}.calibration"',
            SessionFormatError,
            r"S07\.calibration: expected one number",
        ),
        (
            'grf_y_n = { field = "Fy" }',
            "grf_y_n = { value = 1e400 }",
            ParameterError,
            r"map\.toml: invalid parameters: columns\.grf_y_n\.value: Input should be a finite "
            r"number; got inf$",
        ),
        (
            'grf_y_n = { field = "Fy" }',
            'grf_y_n = { value = 0, source = "assumed" }',
            ParameterError,
            r"map\.toml: invalid parameters: columns\.grf_y_n\.source: unknown key$",
        ),
        (
            'grf_y_n = { field = "Fy" }',
            'grf_y_n = { field = "Fy", value = 0 }',
            ParameterError,
            r"map\.toml: invalid parameters: columns\.grf_y_n: give either field \(where the "
            r"values are\) or value \(a constant\), not both",
        ),
        (
            'layout = "matrices"\nperturbed = true',
            'layout = "matrices"\nperturbed = true\ndelay_ms = 225',
            ParameterError,
            r"map\.toml: invalid parameters: walking\.0\.delay_ms: given both here and by the "
            r"\{delay_ms\} wildcard of path '\{subject\}\.\{direction\}\.t\{delay_ms\}'; give "
            r"one; got 225",
        ),
        (
            'layout = "matrices"\nperturbed = true',
            'layout = "matrices"\nperturbed = true\ndirection = "dorsi"',
            ParameterError,
            r"walking\.0\.direction: given both here and by the \{direction\} wildcard",
        ),
    ],
)
def test_malformed_maps_and_files_name_the_key_or_path(twin, tmp_path, old, new, error, message):
    _, path = twin
    with pytest.raises(error, match=message):
        import_matlab(path, _map(tmp_path, old, new))


@pytest.mark.parametrize(
    ("constant", "newtons"),
    [("{ value = 0 }", 0.0), ("{ value = 1.5, scale = 2, units = 'kN' }", 3000.0)],
)
def test_a_constant_column(tmp_path, constant, newtons):
    """A column the file lacks, given as a constant `{ value = ... }` (lab-formats.md); the
    calibration group maps its own."""
    mapping = _map(tmp_path, 'grf_y_n = { field = "Fy" }', f"grf_y_n = {constant}")
    session = import_matlab(_tiny(tmp_path), mapping)
    for trial in session.walking:
        assert trial.recording["grf_y_n"].shape == (300,)
        np.testing.assert_array_equal(trial.recording["grf_y_n"], newtons)


def _tiny_with(tmp_path, change):
    """The tiny layout with ``change`` applied to its walking fields (t225 and control)."""
    root = scipy.io.loadmat(_tiny(tmp_path), simplify_cells=True)["S01"]
    change(root)
    path = tmp_path / "changed.mat"
    scipy.io.savemat(path, {"S01": root})
    return path


def _set(where, value):
    def change(root):
        node = root
        for key in where[:-1]:
            node = node[key]
        node[where[-1][0]][where[-1][1:]] = value

    return change


@pytest.mark.parametrize(
    ("where", "value", "message"),
    [
        (
            ("dorsiflexion", "t225", ("angle", 100, 0)),
            np.nan,
            r"changed\.mat: S01\.dorsiflexion\.t225\(1\)\.angle: sample 101: value nan; expected "
            r"a finite number \(mapped to column 'motor_angle'\)$",
        ),
        (
            ("control", ("CoPx", 7, 1)),
            np.inf,
            r"changed\.mat: S01\.control\(2\)\.CoPx: sample 8: value inf; expected a finite number "
            r"or NaN \(mapped to column 'cop_x_m'\)$",
        ),
        (
            ("calibration", ("GRF", 11, 2)),
            np.nan,
            r"changed\.mat: S01\.calibration\(1\)\.GRF\(:, 3\): sample 12: value nan; expected a "
            r"finite number \(mapped to column 'grf_z_n'\)$",
        ),
    ],
)
def test_values_that_are_not_finite_are_named_by_struct_path(tmp_path, where, value, message):
    with pytest.raises(SessionFormatError, match=message):
        import_matlab(_tiny_with(tmp_path, _set(where, value)), MAP)


def test_an_empty_cop_is_read_as_nan(tmp_path):
    """grf_cop: the COP may be empty (NaN) where the plate carries too little."""
    session = import_matlab(_tiny_with(tmp_path, _set(("control", ("CoPx", 7, 1)), np.nan)), MAP)
    trial = next(w for w in session.walking if w.trial == "S01.control(2)")
    assert np.isnan(trial.recording["cop_x_m"][7]) and np.isfinite(trial.recording["grf_x_n"]).all()


def test_a_directory_is_named_as_one(tmp_path):
    with pytest.raises(
        SessionFormatError,
        match=r"\S+: is a directory, not a regular file; expected a MATLAB \.mat file$",
    ):
        import_matlab(tmp_path, MAP)
    with pytest.raises(ParameterError, match=r"\S+: a directory; expected a mapping file$"):
        import_matlab(_tiny(tmp_path), tmp_path)


def test_a_key_under_the_wrong_table_gets_no_false_hint(tmp_path):
    """`walking = []` written after [[calibration]] belongs to that table (TOML)."""
    text = MAP.read_text()
    mapping = tmp_path / "map.toml"
    mapping.write_text(text[: text.index("[[walking]]")] + "walking = []\n")
    with pytest.raises(
        ParameterError,
        match=r"map\.toml: invalid parameters: calibration\.0\.walking: unknown key; walking: "
        r"required key is missing$",
    ):
        import_matlab(_tiny(tmp_path), mapping)


def test_subjects_are_chosen_by_wildcard(twin, tmp_path):
    session, _ = twin
    small = type(session)(session.info, session.calibration[:1], session.walking[:12], (), None, {})
    path = tmp_path / "two.mat"
    write_layout(path, small, subject="S07")
    both = scipy.io.loadmat(path, simplify_cells=False)
    scipy.io.savemat(path, {"S07": both["S07"], "S08": both["S07"]})
    with pytest.raises(SessionFormatError, match=r"matches the subjects S07, S08; choose one"):
        import_matlab(path, MAP)
    assert import_matlab(path, MAP, subject="S08").info.subject == "S08"
    with pytest.raises(SessionFormatError, match=r"subject 'S09' not found"):
        import_matlab(path, MAP, subject="S09")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    lines=st.lists(st.integers(0, 60), min_size=1, max_size=3),
    junk=st.text(st.characters(codec="utf-8", exclude_categories=["Cs"]), max_size=12),
)
def test_fuzzed_maps_fail_with_one_message(tmp_path, lines, junk):
    """Any edit of the map either imports or fails with one AnklelabError (never another)."""
    text = MAP.read_text().split("\n")
    for k in lines:
        if k < len(text):
            cut = len(text[k]) // 2
            text[k] = text[k][:cut] + junk + text[k][cut:]
    path = tmp_path / "fuzz.toml"
    path.write_text("\n".join(text), encoding="utf-8")
    mat = tmp_path / "tiny.mat"
    if not mat.exists():
        shutil.copy(_tiny(tmp_path), mat)
    try:
        import_matlab(mat, path)
    except AnklelabError as exc:
        assert str(exc) and re.match(r"^\S", str(exc))


def _tiny(tmp_path):
    """A small file of the shipped layout (one calibration and few walking trials)."""
    rng = np.random.default_rng(0)
    n = 300
    walking = {k: rng.normal(size=(n, 2)) for k in ("angle", "ankle", "Fx", "Fy", "CoPx", "CoPy")}
    walking["Fz"] = 600 + rng.normal(size=(n, 2))
    cal = {
        "angle": rng.normal(size=(n, 1)),
        "GRF": rng.normal(size=(n, 3)),
        "COP": rng.normal(size=(n, 2)),
    }
    root = {
        "fs": 1000.0,
        "calibration": struct_array([cal]),
        "dorsiflexion": {"t225": walking},
        "control": walking,
    }
    path = tmp_path / "tiny_source.mat"
    scipy.io.savemat(path, {"S01": root})
    return path


@pytest.mark.parametrize("target", ["mat", "map", "link"])
def test_import_matlab_never_writes_over_its_inputs(twin, tmp_path, target):
    """The .mat file and the mapping are inputs: --out may not name them, even with --force;
    nor may --out be a symbolic link (as for `anklelab import`)."""
    import subprocess
    import sys

    _, source = twin
    mat, mapping = tmp_path / "S07.mat", tmp_path / "map.toml"
    shutil.copy(source, mat)
    shutil.copy(MAP, mapping)
    (tmp_path / "link.h5").symlink_to(tmp_path / "target.h5")
    out = {"mat": mat, "map": mapping, "link": tmp_path / "link.h5"}[target]
    before = mat.read_bytes(), mapping.read_bytes()
    code = "from anklelab.cli import run; run()"
    args = ["import", "matlab", mat, "--map", mapping, "--out", out, "--force"]
    proc = subprocess.run(
        [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True
    )
    assert proc.returncode == 2
    message = "a symbolic link" if target == "link" else "lies inside the input"
    assert re.fullmatch(rf"error: --out \S+: .*{message}.*\n", proc.stderr), proc.stderr
    assert (mat.read_bytes(), mapping.read_bytes()) == before
    assert not (tmp_path / "target.h5").exists()


MAP_3D = """
format = "anklelab-matlab-map/1"
sample_rate_hz = 1000.0

[session]
subject = "S01"
geometry = { ankle_height_m = 0.08, heel_to_ankle_m = 0.04 }

[plate]
type = "grf_cop"
anterior_axis = "+x"

[columns]
motor_angle = { field = "angle", units = "deg" }
ankle_angle = { field = "ankle", units = "deg" }
grf_x_n = { field = "GRF", column = 1 }
grf_y_n = { field = "GRF", column = 2 }
grf_z_n = { field = "GRF", column = 3 }
cop_x_m = { field = "COP", column = 1 }
cop_y_m = { field = "COP", column = 2 }

[[calibration]]
path = "S01.calibration"
layout = "matrices"

[[walking]]
path = "S01.dorsiflexion.t{delay_ms}"
layout = "matrices"
perturbed = true
direction = "dorsi"

[[walking]]
path = "S01.control"
layout = "matrices"
"""


@pytest.mark.parametrize("layout", ["samples x trials", "samples x components x trials"])
def test_matrices_count_trials_from_the_mapped_fields(tmp_path, layout):
    """MATLAB stores samples x 1 as a vector and samples x components x 1 as a matrix: a timing
    point with one trial is one trial, whatever unmapped fields (EMG, 4 channels) it holds."""
    rng = np.random.default_rng(1)
    n, three_d = 300, layout == "samples x components x trials"

    def point(k):
        fields = {
            "angle": rng.normal(size=(n, k)),
            "ankle": rng.normal(size=(n, k)),
            "EMG": rng.normal(size=(n, 4, k)),
        }
        if three_d:
            fields["GRF"] = rng.normal(size=(n, 3, k)) + np.array([0.0, 0.0, 600.0])[:, None]
            fields["COP"] = rng.normal(size=(n, 2, k))
        else:
            fields |= {c: rng.normal(size=(n, k)) for c in ("Fx", "Fy", "CoPx", "CoPy")}
            fields["Fz"] = 600 + rng.normal(size=(n, k))
        return fields

    root = {"fs": 1000.0, "dorsiflexion": {"t100": point(3), "t225": point(1)}, "control": point(2)}
    if three_d:
        root["calibration"] = point(1)
        mapping = tmp_path / "map.toml"
        mapping.write_text(MAP_3D)
    else:
        cal = {"angle": rng.normal(size=(n, 1)), "GRF": rng.normal(size=(n, 3))}
        root["calibration"] = struct_array([cal | {"COP": rng.normal(size=(n, 2))}])
        mapping = MAP
    path = tmp_path / "one_trial.mat"
    scipy.io.savemat(path, {"S01": root})
    session = import_matlab(path, mapping)
    labels = sorted(w.trial for w in session.walking)
    assert labels == [
        "S01.control(1)",
        "S01.control(2)",
        "S01.dorsiflexion.t100(1)",
        "S01.dorsiflexion.t100(2)",
        "S01.dorsiflexion.t100(3)",
        "S01.dorsiflexion.t225(1)",
    ]
    one = next(w for w in session.walking if w.trial == "S01.dorsiflexion.t225(1)")
    angle = root["dorsiflexion"]["t225"]["angle"][:, 0]
    np.testing.assert_allclose(one.recording["motor_angle"], np.radians(angle))
