"""C3D files: force platforms of type 2, 3 and 4 against the known load and ezc3d's own
computation, analog scaling, events, malformed files (fuzzed) and ``anklelab forceplate``."""

from __future__ import annotations

import csv
import json
import re
import struct
import subprocess
import sys
import warnings
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.data import load_session, save_session
from anklelab.data._c3d_worker import check_structure
from anklelab.data._synthetic import random_session
from anklelab.data.c3d import plate_load, read_c3d, read_c3d_files
from anklelab.data.grf import GRF_COLUMNS, write_grf_tables
from anklelab.errors import SessionFormatError
from anklelab.forceplate import CHANNELS
from tests.c3d_files import UNITS, write_c3d, write_plate_file

CASES = [(kind, up, unit) for kind in (2, 3, 4) for up in ("z", "y") for unit in ("mm", "m")]


@pytest.fixture(scope="module")
def plate_files(tmp_path_factory):
    root = tmp_path_factory.mktemp("c3d")
    files = {
        case: write_plate_file(root / f"type{case[0]}_{case[1]}up_{case[2]}.c3d", *case)
        for case in CASES
    }
    read = read_c3d_files([path for path, _ in files.values()])
    return {case: (c3d, files[case][1]) for case, c3d in zip(CASES, read, strict=True)}


def _vertical(up, vectors):
    return vectors[2 if up == "z" else 1]


@pytest.mark.parametrize(("kind", "up", "unit"), CASES)
def test_plate_load_agrees_with_ezc3d_and_the_known_load(plate_files, kind, up, unit):
    c3d, truth = plate_files[(kind, up, unit)]
    load = plate_load(c3d, c3d.plates[0], min_force_n=1.0)
    n = load.grf.shape[1]
    reference = ezc3d.c3d(str(c3d.path), extract_forceplat_data=True)["data"]["platform"][0]
    scale = UNITS[unit]
    peak = np.abs(truth.grf).max()
    fz = np.abs(_vertical(up, truth.grf[:, :n]))
    loaded = fz > 0.05 * fz.max()
    # acceptance: ezc3d's force is the plate's load (on the plate), ours the plate on the body
    assert np.abs(load.grf + reference["force"]).max() <= 0.005 * peak
    cop_ezc3d = reference["center_of_pressure"] * scale
    assert np.abs(load.cop - cop_ezc3d)[:, loaded].max() <= 0.002
    tz = c3d.plates[0].axes()[:, 2] @ reference["Tz"] * scale
    np.testing.assert_allclose(load.free_moment[loaded], tz[loaded], atol=1e-6)
    # and the known load itself (float32 storage is the only loss)
    assert np.abs(load.grf - truth.grf[:, :n]).max() <= 1e-6 * peak
    np.testing.assert_allclose(load.cop[:, loaded], truth.cop[:, :n][:, loaded], atol=1e-6)
    np.testing.assert_allclose(load.free_moment[loaded], truth.free_moment[:n][loaded], atol=1e-4)
    # the GRF is up where the foot stands; the COP stays on the plate surface
    assert _vertical(up, load.grf).max() > 700
    surface = _vertical(up, c3d.plates[0].centre_m[:, None])
    np.testing.assert_allclose(_vertical(up, load.cop)[loaded], surface[0], atol=1e-9)


def test_cop_is_empty_below_the_threshold(plate_files):
    c3d, _truth = plate_files[(2, "z", "mm")]
    load = plate_load(c3d, c3d.plates[0], min_force_n=50.0)
    fz = load.grf[2]
    assert np.isnan(load.cop[:, fz < 49.9]).all() and np.isnan(load.free_moment[fz < 49.9]).all()
    assert np.isfinite(load.cop[:, fz > 50.1]).all()


def test_ami_origin_sign_either_way(tmp_path):
    """ORIGIN with z > 0 (AMTI's convention) and z < 0 describe the same plate."""
    a, _truth = write_plate_file(tmp_path / "a.c3d", 2, "z", "mm", origin_sign=1.0)
    b, _ = write_plate_file(tmp_path / "b.c3d", 2, "z", "mm", origin_sign=-1.0)
    loads = [plate_load(c, c.plates[0]) for c in read_c3d_files([a, b])]
    np.testing.assert_allclose(loads[0].cop, loads[1].cop, atol=1e-9)


def test_type3_origin_z_is_read_as_minus_its_magnitude(tmp_path):
    """A type-3 ORIGIN with az0 > 0 is read as -|az0| (lab-formats.md): the COP stays the true
    one, where ezc3d's, which takes az0 as given, moves by up to 221 mm on this stance."""
    path, truth = write_plate_file(tmp_path / "neg.c3d", 3, "z", "mm")
    c = ezc3d.c3d(str(path))
    origin = np.array(c["parameters"]["FORCE_PLATFORM"]["ORIGIN"]["value"], dtype=float)
    assert origin[2, 0] < 0
    origin[2] = -origin[2]
    c["parameters"]["FORCE_PLATFORM"]["ORIGIN"]["value"] = origin
    c.write(str(tmp_path / "pos.c3d"))
    c3d = read_c3d(tmp_path / "pos.c3d")
    load = plate_load(c3d, c3d.plates[0], min_force_n=1.0)
    n = load.grf.shape[1]
    loaded = load.grf[2] > 0.05 * load.grf[2].max()
    np.testing.assert_allclose(load.cop[:, loaded], truth.cop[:, :n][:, loaded], atol=1e-6)
    reference = ezc3d.c3d(str(tmp_path / "pos.c3d"), extract_forceplat_data=True)
    ezc3d_cop = reference["data"]["platform"][0]["center_of_pressure"] * 1e-3
    assert np.abs(ezc3d_cop - truth.cop[:, :n])[:, loaded].max() > 0.2


def test_analog_scale_gen_scale_offset_and_events(tmp_path):
    t = np.arange(100) / 1000.0
    path = write_c3d(
        tmp_path / "s.c3d",
        {"Motor": np.sin(t), "Gonio": np.cos(t)},
        scale={"Motor": 0.5},
        gen_scale=2.0,
        events=[("Foot Strike", "Right", 0.031), ("Dorsi", "General", 0.052)],
        per_frame=1,
    )
    # stored: value / (SCALE * GEN_SCALE); now the file also says: subtract 3 from Gonio's
    # stored values, which is 3 * SCALE * GEN_SCALE = 6 in its units; an OFFSET of -3 is
    # applied as ezc3d applies it, by its magnitude (lab-formats.md)
    for offset in (3, -3):
        _patch_offset(path, [0, offset])
        c3d = read_c3d(path)
        np.testing.assert_allclose(c3d.analog("Motor"), np.sin(t), rtol=1e-6)
        np.testing.assert_allclose(c3d.analog("Gonio"), np.cos(t) - 3 * 1.0 * 2.0, rtol=1e-6)
    assert [(e.label, e.context) for e in c3d.events] == [
        ("Foot Strike", "Right"),
        ("Dorsi", "General"),
    ]
    assert [e.time_s for e in c3d.events] == pytest.approx([0.031, 0.052])
    np.testing.assert_allclose(np.diff(c3d.time_s), 1e-3)
    with pytest.raises(SessionFormatError, match=r"s\.c3d: no analog channel 'motor'.*case"):
        c3d.analog("motor")


def test_a_duplicated_analog_label_is_refused_where_it_is_used(tmp_path):
    t = np.arange(100) / 1000.0
    path = write_c3d(tmp_path / "d.c3d", {"Fx": t, "Gonio": t, "Motor": t, "Fz": t}, per_frame=1)
    c = ezc3d.c3d(str(path))
    c["parameters"]["ANALOG"]["LABELS"]["value"] = ["Motor", "Gonio", "Motor", "Motor"]
    c.write(str(path))
    c3d = read_c3d(path)
    np.testing.assert_array_equal(c3d.analog("Gonio"), t.astype(np.float32))
    with pytest.raises(
        SessionFormatError, match=r"^\S+d\.c3d: ANALOG:LABELS has 'Motor' at channels 1, 3 and 4$"
    ):
        c3d.analog("Motor")


def _patch_offset(path, values):
    """Write ANALOG:OFFSET values into a file (ezc3d always writes zeros)."""
    raw = bytearray(path.read_bytes())
    at = raw.index(b"OFFSET", (raw[0] - 1) * 512) + 6 + 2  # name, then the 2-byte link
    kind, ndim = struct.unpack("<bB", raw[at : at + 2])
    assert kind == 2 and ndim == 1 and raw[at + 2] == len(values)
    raw[at + 3 : at + 3 + 2 * len(values)] = struct.pack(f"<{len(values)}h", *values)
    path.write_bytes(bytes(raw))


def test_unsupported_type_and_missing_calibration_are_named(tmp_path):
    path, _ = write_plate_file(tmp_path / "p.c3d", 2, "z", "mm")
    c = ezc3d.c3d(str(path))
    c["parameters"]["FORCE_PLATFORM"]["TYPE"]["value"] = np.array([5])
    c.write(str(tmp_path / "t5.c3d"))
    c3d = read_c3d(tmp_path / "t5.c3d")
    with pytest.raises(
        SessionFormatError,
        match=r"t5\.c3d: plate 1 \(type 5\): unsupported force-platform type 5; expected type "
        r"2, 3, 4",
    ):
        plate_load(c3d, c3d.plates[0])
    c["parameters"]["FORCE_PLATFORM"]["TYPE"]["value"] = np.array([4])
    del c["parameters"]["FORCE_PLATFORM"]["CAL_MATRIX"]
    c.write(str(tmp_path / "t4.c3d"))
    with pytest.raises(SessionFormatError, match=r"t4\.c3d: plate 1 \(type 4\): .*CAL_MATRIX"):
        read_c3d(tmp_path / "t4.c3d")


def _changed_plate_file(tmp_path, name, change):
    """A type-2 plate file (z up, mm) changed by ``change`` (an ezc3d c3d object)."""
    path, _ = write_plate_file(tmp_path / "p.c3d", 2, "z", "mm")
    c = ezc3d.c3d(str(path))
    change(c)
    c.write(str(tmp_path / name))
    return tmp_path / name


def _set_parameter(name, values):
    def change(c):
        c["parameters"]["FORCE_PLATFORM"][name]["value"] = np.asarray(values, dtype=float)

    return change


def _set_analog(channel, sample, value):
    def change(c):
        analogs = c["data"]["analogs"]
        analogs[0, channel, sample] = value
        c["data"]["analogs"] = analogs

    return change


@pytest.mark.parametrize(
    ("name", "change", "message"),
    [
        (
            "origin.c3d",
            _set_parameter("ORIGIN", [[np.nan], [0.0], [40.0]]),
            r"origin\.c3d: plate 1 \(type 2\): FORCE_PLATFORM:ORIGIN \[nan, 0, 40\] is not "
            r"finite; expected the vector from the plate's origin to its surface centre$",
        ),
        (
            "corners.c3d",
            _set_parameter("CORNERS", np.zeros((3, 4, 1))),
            r"corners\.c3d: plate 1 \(type 2\): FORCE_PLATFORM:CORNERS do not span a plane "
            r"\(corners \[\[0\.0, 0\.0, 0\.0\], ",
        ),
        (
            "corners_nan.c3d",
            _set_parameter("CORNERS", np.full((3, 4, 1), np.nan)),
            r"corners_nan\.c3d: plate 1 \(type 2\): FORCE_PLATFORM:CORNERS do not span a plane",
        ),
    ],
)
def test_plate_geometry_errors_name_the_parameter(tmp_path, name, change, message):
    path = _changed_plate_file(tmp_path, name, change)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning besides the one message
        with pytest.raises(SessionFormatError, match=message):
            read_c3d(path)


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_plate_channel_that_is_not_finite_is_named(tmp_path, value):
    """anklelab forceplate and import c3d stop at a NaN or infinite plate channel (never an
    infinite cell written with RuntimeWarnings)."""
    path = _changed_plate_file(tmp_path, "bad.c3d", _set_analog(2, 500, value))
    c3d = read_c3d(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(
            SessionFormatError,
            match=rf"bad\.c3d: analog channel 3 'Fz', sample 501: value {value}; expected a "
            r"finite number$",
        ):
            plate_load(c3d, c3d.plates[0])


def test_malformed_files_get_one_clear_error(tmp_path, plate_files):
    good = plate_files[(3, "z", "mm")][0].path.read_bytes()
    cases = {
        "empty.c3d": (b"", r"0 bytes; a C3D file starts with a 512-byte header"),
        "text.c3d": (b"x" * 600, r"not a C3D file"),
        "cut.c3d": (good[: len(good) // 2], r"truncated: the header announces"),
        "params.c3d": (good[:600], r"truncated: the parameter section needs"),
    }
    for name, (content, message) in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(SessionFormatError, match=rf"{name}: {message}"):
            read_c3d(tmp_path / name)
    with pytest.raises(SessionFormatError, match=r"missing\.c3d: no such file"):
        read_c3d(tmp_path / "missing.c3d")


mutations = st.lists(st.tuples(st.integers(0, 40000), st.integers(0, 255)), min_size=1, max_size=6)


@settings(max_examples=300, deadline=None)
@given(cut=st.integers(0, 40000), flips=mutations)
def test_structure_check_never_fails_otherwise(cut, flips):
    """The pre-check of the block layout only ever reports bad input, whatever the bytes."""
    raw = bytearray(_good_bytes())
    for at, value in flips:
        if at < len(raw):
            raw[at] = value
    try:
        check_structure("f.c3d", bytes(raw[:cut]))
    except ValueError as exc:
        assert str(exc).startswith("f.c3d: ")


_GOOD: list[bytes] = []


def _good_bytes():
    if not _GOOD:
        import tempfile

        with tempfile.TemporaryDirectory() as root:
            path, _ = write_plate_file(Path(root) / "g.c3d", 3, "z", "mm")
            _GOOD.append(path.read_bytes())
    return _GOOD[0]


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    cut=st.one_of(st.none(), st.integers(0, 40000)),
    flips=st.lists(st.tuples(st.integers(0, 2600), st.integers(0, 255)), max_size=6),
)
def test_fuzzed_files_read_or_fail_with_one_message(tmp_path, cut, flips):
    """Corrupt files (some crash or hang ezc3d itself) give a SessionFormatError naming the file,
    or read; never another exception."""
    raw = bytearray(_good_bytes())
    for at, value in flips:
        raw[at] = value
    path = tmp_path / "fuzz.c3d"
    path.write_bytes(bytes(raw[:cut]))
    try:
        c3d = read_c3d(path)
        for plate in c3d.plates:
            plate_load(c3d, plate)
    except SessionFormatError as exc:
        assert str(exc).startswith(f"{path}: ") and "\n" not in str(exc)


# --- anklelab forceplate -------------------------------------------------------------------------


def _table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_forceplate_writes_one_table_per_plate(tmp_path, plate_files):
    c3d, truth = plate_files[(4, "y", "mm")]
    out = tmp_path / "grf"
    write_grf_tables(c3d.path, out, min_force_n=20.0)
    header, rows = _table(out / "plate1.csv")
    assert tuple(header) == GRF_COLUMNS
    data = np.array([[float(v) if v else np.nan for v in row] for row in rows])
    n = len(rows)
    np.testing.assert_allclose(data[:, 1:4].T, truth.grf[:, :n], atol=1e-3)
    loaded = truth.grf[1, :n] > 20.5
    np.testing.assert_allclose(data[loaded, 4:7].T, truth.cop[:, :n][:, loaded], atol=1e-6)
    assert all(row[4] == "" for row, on in zip(rows, truth.grf[1, :n] < 19.5, strict=True) if on)
    manifest = json.loads((out / "forceplate.json").read_text())
    assert manifest["settings"] == {"min_force_n": 20.0} and manifest["files"] == ["plate1.csv"]
    with pytest.raises(SessionFormatError, match="already exists; pass --force"):
        write_grf_tables(c3d.path, out)
    write_grf_tables(c3d.path, out, overwrite=True)


def test_forceplate_never_deletes_its_input_nor_follows_a_link(tmp_path, plate_files):
    """An input inside an earlier output is not replaced with it (it was deleted), and a
    symbolic link as the output is named, not followed."""
    c3d, _ = plate_files[(4, "y", "mm")]
    out = tmp_path / "grf"
    write_grf_tables(c3d.path, out)
    kept = out / "trial.c3d"
    kept.write_bytes(Path(c3d.path).read_bytes())
    result = run_cli("forceplate", kept, "--out", out, "--force")
    assert result.returncode == 2 and kept.exists()
    assert result.stderr == f"error: --out {out}: holds the input {kept}; write elsewhere\n"
    with pytest.raises(SessionFormatError, match="holds the input"):
        write_grf_tables(kept, out, overwrite=True)
    link = tmp_path / "link"
    link.symlink_to(out)
    result = run_cli("forceplate", c3d.path, "--out", link, "--force")
    assert result.returncode == 2 and "a symbolic link" in result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["forceplate.json", "plate1.csv", "trial.c3d"]


def run_cli(*args):
    code = "from anklelab.cli import run; run()"
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True
    )


def test_forceplate_command_on_c3d_and_on_a_session(tmp_path, plate_files):
    c3d, _ = plate_files[(3, "z", "m")]
    proc = run_cli("forceplate", c3d.path, "--out", tmp_path / "a")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "a" / "plate1.csv").is_file()
    session = save_session(random_session(seed=3), tmp_path / "s", format="dir")
    proc = run_cli("forceplate", session, "--out", tmp_path / "b", "--min-force", "0")
    assert proc.returncode == 0, proc.stderr
    loaded = load_session(session)
    rec = loaded.walking[0].recording
    _header, rows = _table(tmp_path / "b" / "walking" / rec.name)
    expected = loaded.info.force_plate.lab_load(rec.stack(CHANNELS), min_fz_n=0.0)
    np.testing.assert_allclose([float(r[3]) for r in rows], expected.grf_z, rtol=1e-9)
    assert {p.name for p in (tmp_path / "b").iterdir()} == {
        "calibration",
        "walking",
        "forceplate.json",
    }


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nothing.c3d"], r"nothing\.c3d: no such file"),
        (["{s}", "--out", "{s}/inside"], r"--out .*inside: lies inside the input"),
        (["{bad}"], r"bad\.c3d: not a C3D file"),
        (["{c3d}", "--min-force", "-1"], r"Invalid value for '--min-force'"),
    ],
)
def test_forceplate_command_errors(tmp_path, plate_files, args, message):
    session = save_session(random_session(seed=3), tmp_path / "s", format="dir")
    (tmp_path / "bad.c3d").write_bytes(b"y" * 1000)
    names = {"s": session, "bad": tmp_path / "bad.c3d", "c3d": plate_files[(2, "z", "m")][0].path}
    args = [a.format(**names) for a in args]
    if "--out" not in args:
        args += ["--out", str(tmp_path / "out")]
    proc = run_cli("forceplate", *args)
    assert proc.returncode == 2
    assert re.search(message, proc.stderr), proc.stderr
    assert not (tmp_path / "out").exists()
