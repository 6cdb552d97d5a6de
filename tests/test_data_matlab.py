"""MATLAB import: the documented ``session`` struct, v5/v7 (scipy) and v7.3 (HDF5) files."""

import math

import h5py
import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.data import diff_sessions, load_session, read_matlab
from anklelab.data._checks import info_to_mapping
from anklelab.data._synthetic import random_session
from anklelab.errors import SessionFormatError


def struct_array(elements):
    """A 1xN MATLAB struct array (all elements share the union of fields; missing ones [])."""
    names = list(dict.fromkeys(k for e in elements for k in e))
    array = np.empty((1, len(elements)), dtype=[(n, object) for n in names])
    for i, e in enumerate(elements):
        array[0, i] = tuple(e.get(n, np.zeros((0, 0))) for n in names)
    return array


def struct_list(elements):
    """The same struct array as a list of dicts (for the v7.3 writer below)."""
    names = list(dict.fromkeys(k for e in elements for k in e))
    return [{n: e.get(n, np.zeros((0, 0))) for n in names} for e in elements]


def as_matlab(session, arrays=struct_array):
    """The documented ``session`` struct for ``session`` (columns as MATLAB column vectors)."""

    def columns(rec):
        return {k: np.asarray(v)[:, None] for k, v in rec.columns.items()}

    root = info_to_mapping(session.info)
    root["calibration"] = arrays([{"file": r.name, **columns(r)} for r in session.calibration])
    root["walking"] = arrays(
        [
            {
                "trial": float(t.trial),
                "file": t.recording.name,
                "perturbed": float(t.perturbed),
                "direction": t.direction,
                "delay_ms": t.delay_ms,
                **t.extra,
                **columns(t.recording),
            }
            for t in session.walking
        ]
    )
    root["bench"] = arrays(
        [
            {
                "test": b.test,
                "file": b.recording.name,
                "distance_m": b.distance_m,
                **columns(b.recording),
            }
            for b in session.bench
        ]
    )
    return root


def write_mat73(path, variables):
    """A MAT v7.3 file laid out as MATLAB writes one: a 512-byte user block with the text
    header, MATLAB_class attributes, arrays transposed, char as uint16, scalar structs as
    groups, struct arrays as groups of reference datasets into '#refs#'."""
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")
        counter = iter(range(10**6))

        def put(parent, name, value):
            if isinstance(value, dict):
                group = parent.create_group(name)
                group.attrs["MATLAB_class"] = np.bytes_("struct")
                field_names = np.empty(len(value), dtype=object)
                field_names[:] = [np.array(list(k), dtype="S1") for k in value]
                group.attrs.create(
                    "MATLAB_fields", field_names, dtype=h5py.vlen_dtype(np.dtype("S1"))
                )
                for key, v in value.items():
                    put(group, key, v)
            elif isinstance(value, list):  # struct array
                group = parent.create_group(name)
                group.attrs["MATLAB_class"] = np.bytes_("struct")
                for key in value[0]:
                    targets = []
                    for element in value:
                        ref_name = f"r{next(counter)}"
                        put(refs, ref_name, element[key])
                        targets.append(refs[ref_name].ref)
                    group.create_dataset(key, data=np.array(targets, dtype=h5py.ref_dtype)[:, None])
            elif isinstance(value, str):
                ds = parent.create_dataset(name, data=np.array([[ord(c)] for c in value], "u2"))
                ds.attrs["MATLAB_class"] = np.bytes_("char")
            else:
                array = np.atleast_2d(np.asarray(value, dtype=float))
                if array.size == 0:
                    ds = parent.create_dataset(name, data=np.array([0, 0], dtype="u8"))
                    ds.attrs["MATLAB_empty"] = np.uint8(1)
                else:
                    ds = parent.create_dataset(name, data=array.T)
                ds.attrs["MATLAB_class"] = np.bytes_("double")

        for name, value in variables.items():
            put(f, name, value)
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 ."
    with open(path, "r+b") as f:
        f.write(header.ljust(116) + b"\0" * 8 + b"\x00\x02IM")


@pytest.fixture
def session():
    return random_session(seed=4, truth=False)


def test_v5_import_equals_session(tmp_path, session):
    path = tmp_path / "s.mat"
    scipy.io.savemat(path, {"session": as_matlab(session)})
    imported = load_session(path)
    assert diff_sessions(imported, session, provenance=False) == []
    assert imported.provenance["import"]["importer"] == "matlab"
    assert len(imported.provenance["source_sha256"]) == 64


def test_v73_import_equals_session(tmp_path, session):
    path = tmp_path / "s73.mat"
    write_mat73(path, {"session": as_matlab(session, arrays=struct_list)})
    assert h5py.is_hdf5(path)
    assert diff_sessions(read_matlab(path), session, provenance=False) == []


def test_defaults_row_vectors_and_empty_delay(tmp_path, session):
    root = as_matlab(session)
    for element in root["walking"][0]:
        element["time_s"] = element["time_s"].T  # row vectors are fine too
        if element["perturbed"] == 0:
            element["delay_ms"] = np.zeros((0, 0))  # [] for unperturbed
    root["calibration"] = struct_array(
        [
            {k: v for k, v in zip(root["calibration"].dtype.names, e, strict=True) if k != "file"}
            for e in root["calibration"][0]
        ]
    )
    scipy.io.savemat(tmp_path / "s.mat", {"session": root})
    imported = read_matlab(tmp_path / "s.mat")
    assert [r.name for r in imported.calibration] == ["calibration_001.csv", "calibration_002.csv"]
    assert math.isnan(imported.walking[0].delay_ms)
    np.testing.assert_array_equal(
        imported.walking[0].recording.time_s, session.walking[0].recording.time_s
    )


def mutated(tmp_path, session, change):
    root = as_matlab(session)
    change(root)
    path = tmp_path / "bad.mat"
    scipy.io.savemat(path, {"session": root})
    return path


def walking_field(i, name, value):
    def change(root):
        root["walking"][0, i][name] = value

    return change


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        (lambda r: r.update(platform="nope"), r"bad\.mat: session\.platform: unknown platform"),
        (
            lambda r: r["force_plate"].pop("b_m"),
            r"bad\.mat: session\.force_plate\.b_m: required key is missing",
        ),
        (
            walking_field(1, "fz2", np.full((50, 1), np.nan)),
            r"bad\.mat: session\.walking\(2\): column 'fz2', sample 1: value nan",
        ),
        (
            walking_field(2, "direction", 3.0),
            r"bad\.mat: session\.walking\(3\)\.direction: expected text",
        ),
        (
            walking_field(0, "perturbed", 2.0),
            r"bad\.mat: session\.walking\(1\)\.perturbed: expected 0 or 1, got 2\.0",
        ),
        (
            walking_field(1, "delay_ms", np.nan),
            r"bad\.mat: session\.walking\(2\), column 'delay_ms': a perturbed trial needs a delay",
        ),
        (
            walking_field(1, "fz3", np.zeros((7, 1))),
            r"bad\.mat: session\.walking\(2\)\.fz3: expected a numeric vector as long as time_s "
            r"\(50 samples\)",
        ),
        (
            walking_field(2, "trial", 2.0),
            r"bad\.mat: session\.walking\(3\): duplicate trial '2' "
            r"\(already at session\.walking\(2\)\)",
        ),
    ],
)
def test_errors_name_the_matlab_field(tmp_path, session, change, pattern):
    with pytest.raises(SessionFormatError, match=pattern):
        read_matlab(mutated(tmp_path, session, change))


@pytest.mark.parametrize(
    ("section", "name", "pattern"),
    [
        ("walking", "../../victim.csv",
         r"walking\[0\]: recording name '\.\./\.\./victim\.csv' is not a plain file name"),
        ("calibration", "sub/cal.csv", r"calibration\[0\]: recording name 'sub/cal\.csv' is not"),
        ("bench", ".hidden.csv", r"bench\[0\]: recording name '\.hidden\.csv' is not"),
    ],
)  # fmt: skip
def test_a_recording_name_that_leaves_its_folder_is_refused(tmp_path, session, section, name,
                                                            pattern):  # fmt: skip
    """Names become the files that `anklelab forceplate` writes (a name with '..' overwrote a
    file outside --out): every reader refuses them."""
    from anklelab.data import load_session

    def change(root):
        root[section][0, 0]["file"] = name

    with pytest.raises(SessionFormatError, match=r"bad\.mat: " + pattern):
        load_session(mutated(tmp_path, session, change))


def test_repeated_calibration_file_names_are_refused(tmp_path, session):
    """Two calibration recordings of one name would be one table, one file: refused as the
    walking and bench sections' are."""
    from anklelab.data import load_session

    def change(root):
        root["calibration"][0, 1]["file"] = root["calibration"][0, 0]["file"]

    with pytest.raises(SessionFormatError, match=r"calibration\[1\]: duplicate file"):
        load_session(mutated(tmp_path, session, change))


def test_forceplate_refuses_two_recordings_of_one_table_name(tmp_path, session):
    """'t1' and 't1.csv' are two names, but one table ('.csv' is added): refused, not one table
    silently written over the other."""
    from anklelab.data.grf import write_grf_tables

    def change(root):
        root["walking"][0, 0]["file"] = "t1"
        root["walking"][0, 1]["file"] = "t1.csv"

    with pytest.raises(SessionFormatError, match=r"walking: two recordings would both be "
                                                 r"written as 't1\.csv'"):  # fmt: skip
        write_grf_tables(mutated(tmp_path, session, change), tmp_path / "grf")
    assert not (tmp_path / "grf").exists()


def test_missing_field_and_missing_variable(tmp_path, session):
    root = as_matlab(session)
    names = [n for n in root["walking"].dtype.names if n != "delay_ms"]
    root["walking"] = struct_array([{n: e[n] for n in names} for e in root["walking"][0]])
    scipy.io.savemat(tmp_path / "a.mat", {"session": root})
    with pytest.raises(
        SessionFormatError, match=r"session\.walking\(1\)\.delay_ms: field is missing"
    ):
        read_matlab(tmp_path / "a.mat")
    scipy.io.savemat(tmp_path / "b.mat", {"data": 1.0})
    with pytest.raises(
        SessionFormatError,
        match=r"b\.mat: no variable 'session' \(found: data\); a MATLAB file of another layout "
        r"is read with 'anklelab import matlab FILE --map MAP\.toml'",
    ):
        read_matlab(tmp_path / "b.mat")
    (tmp_path / "c.mat").write_bytes(b"not a mat file at all")
    with pytest.raises(SessionFormatError, match=r"c\.mat: cannot read as a MAT file"):
        read_matlab(tmp_path / "c.mat")


def test_labels_are_text_or_integers(tmp_path, session):
    """A trial label may be a char array ('d060_1') or an integer; the default file name
    follows it, and different labels ('7' and '07', 'bench A' and 'bench_A') never share one."""
    root = as_matlab(session)
    labels = ["d060_1", 2, "02", "trial_0002", "7", "07"]
    for element, label in zip(root["walking"][0], labels, strict=False):
        element["trial"] = label
    for element, label in zip(root["bench"][0], ["bench A", "bench_A"], strict=False):
        element["test"] = label
    for name in ("walking", "bench"):
        names = [n for n in root[name].dtype.names if n != "file"]
        root[name] = struct_array([{n: e[n] for n in names} for e in root[name][0]])
    scipy.io.savemat(tmp_path / "t.mat", {"session": root})
    again = read_matlab(tmp_path / "t.mat")
    assert [t.trial for t in again.walking[: len(labels)]] == [str(x) for x in labels]
    assert [t.recording.name for t in again.walking[: len(labels)]] == [
        "d060_1.csv",
        "trial_0002.csv",
        "02.csv",
        "trial%5F0002.csv",
        "trial_0007.csv",
        "07.csv",
    ]
    assert [(b.test, b.recording.name) for b in again.bench[:2]] == [
        ("bench A", "bench%20A.csv"),
        ("bench_A", "bench_A.csv"),
    ]


# --- MAT v7.3 files that are damaged or point elsewhere ---------------------------------------


@pytest.fixture
def mat73(tmp_path, session):
    path = tmp_path / "s73.mat"
    write_mat73(path, {"session": as_matlab(session, arrays=struct_list)})
    return path


def first_ref(f, field="fz1"):
    return f["session/walking"][field][0, 0]


def test_v73_truncated(mat73):
    mat73.write_bytes(mat73.read_bytes()[: mat73.stat().st_size // 2])
    with pytest.raises(SessionFormatError, match=r"s73\.mat: cannot open as a MATLAB v7\.3 file"):
        read_matlab(mat73)


def test_v73_reference_cycle(mat73):
    with h5py.File(mat73, "a") as f:
        walking = f["session/walking"]
        refs = walking["fz1"][()]
        refs[1, 0] = walking.ref  # element 2's fz1 is the struct array itself
        del walking["fz1"]
        walking.create_dataset("fz1", data=refs)
    with pytest.raises(
        SessionFormatError,
        match=r"s73\.mat: session\.walking\(2\)\.fz1: refers back to a value that contains it",
    ):
        read_matlab(mat73)


def test_v73_dangling_reference(mat73):
    with h5py.File(mat73, "a") as f:
        walking = f["session/walking"]
        refs = walking["fz2"][()]
        refs[2, 0] = h5py.Reference()  # a null reference
        del walking["fz2"]
        walking.create_dataset("fz2", data=refs)
    with pytest.raises(SessionFormatError, match=r"session\.walking\(3\)\.fz2: a null reference"):
        read_matlab(mat73)


@pytest.mark.parametrize("kind", ["external", "soft", "dangling"])
def test_v73_links_are_refused_without_showing_linked_data(tmp_path, mat73, kind):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["secret"] = np.full(50, 12345.678)
    with h5py.File(mat73, "a") as f:
        del f["session/subject"]
        link = {
            "external": h5py.ExternalLink(str(other), "/secret"),
            "soft": h5py.SoftLink("/session/platform"),
            "dangling": h5py.SoftLink("/nothing/here"),
        }[kind]
        f["session/subject"] = link
    with pytest.raises(
        SessionFormatError, match=r"s73\.mat:/session/subject: is an? \w+ link"
    ) as e:
        read_matlab(mat73)
    assert "12345" not in str(e.value)


def test_v73_only_the_session_variable_is_read(tmp_path, session):
    path = tmp_path / "big.mat"
    write_mat73(path, {"session": as_matlab(session, arrays=struct_list), "other": np.ones((2, 2))})
    with h5py.File(path, "a") as f:
        del f["other"]
        f["other"] = h5py.SoftLink("/nowhere")  # refused anyway: no link is ever followed
    with pytest.raises(SessionFormatError, match=r"big\.mat:/other: is a soft link"):
        read_matlab(path)


@pytest.fixture(scope="module")
def pristine73(tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz73") / "s73.mat"
    write_mat73(path, {"session": as_matlab(random_session(n_walking=3), arrays=struct_list)})
    return path


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(truncate=st.booleans(), where=st.floats(0, 1, exclude_max=True), bit=st.integers(0, 7))
def test_fuzz_damaged_v73_files_give_session_format_errors(pristine73, truncate, where, bit):
    raw = bytearray(pristine73.read_bytes())
    at = 512 + int(where * (len(raw) - 512))  # past the MATLAB text header
    raw = raw[:at] if truncate else raw
    if not truncate:
        raw[at] ^= 1 << bit
    path = pristine73.with_name("fuzz.mat")
    path.write_bytes(bytes(raw))
    try:
        read_matlab(path)
    except SessionFormatError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
