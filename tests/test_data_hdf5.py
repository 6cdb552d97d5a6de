"""The native HDF5 store: the anklelab-h5/2 layout, integrity, links, declared sizes, and the
older anklelab-h5/1 layout."""

from dataclasses import replace

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.data import diff_sessions, hdf5, load_session, read_hdf5, save_session
from anklelab.data._synthetic import random_session
from anklelab.data._tree import create_group, link_name, read_h5_tree, write_h5_tree
from anklelab.data.hdf5 import H5_FORMAT
from anklelab.errors import SessionFormatError


@pytest.fixture(scope="module")
def session():
    return random_session()


@pytest.fixture
def h5(tmp_path, session):
    return save_session(session, tmp_path / "s.h5")


def store_unchecked(monkeypatch, session, path):
    """Store a session the writer would refuse, to test what the reader checks."""
    monkeypatch.setattr(hdf5, "validate_session", lambda s: None)
    return save_session(session, path)


def with_column(session, index, column, values):
    trial = session.walking[index]
    columns = dict(trial.recording.columns) | {column: values}
    trial = replace(trial, recording=replace(trial.recording, columns=columns))
    return replace(
        session, walking=(*session.walking[:index], trial, *session.walking[index + 1 :])
    )


def write_v1(session, path):
    """A file of the first layout, as anklelab 0.1 wrote it (one dataset per column)."""
    with h5py.File(path, "w", track_order=True) as f:
        f.attrs["format"] = "anklelab-h5/1"
        write_h5_tree(create_group(f, "session"), hdf5.info_to_mapping(session.info))
        sections = {
            "calibration": [(r, {}) for r in session.calibration],
            "walking": [
                (
                    t.recording,
                    dict(t.extra)
                    | {
                        "trial": np.int64(int(t.trial)),
                        "perturbed": np.bool_(t.perturbed),
                        "direction": t.direction,
                        "delay_ms": np.float64(t.delay_ms),
                    },
                )
                for t in session.walking
            ],
            "bench": [
                (
                    b.recording,
                    dict(b.extra) | {"test": np.int64(int(b.test)), "distance_m": b.distance_m},
                )
                for b in session.bench
            ],
        }
        for name, entries in sections.items():
            group = create_group(f, name)
            for recording, attrs in entries:
                member = create_group(group, recording.name)
                member.attrs.update(attrs)
                for column, values in recording.columns.items():
                    member.create_dataset(link_name(column), data=values, track_times=False)
        write_h5_tree(create_group(f, "truth"), session.truth)
        write_h5_tree(create_group(f, "provenance"), session.provenance)
    return path


# --- layout -------------------------------------------------------------------------------------


def test_layout_is_contiguous_per_section_checksummed_and_labelled_as_text(h5, session):
    with h5py.File(h5) as f:
        assert f.attrs["format"] == H5_FORMAT and len(f.attrs["content_sha256"]) == 64
        walking = f["walking"]
        # the first trial has an extra column, so two layouts; the other five share one
        data = walking["layout_1/data"]
        assert data.shape == (11, 5 * 50) and data.fletcher32 and data.chunks is not None
        assert list(walking["manifest/trial"].asstr()[()]) == ["1", "2", "3", "4", "5", "6"]
        assert list(walking["manifest/layout"][()]) == [0, 1, 1, 1, 1, 1]
        assert list(walking["manifest/start"][()]) == [0, 0, 50, 100, 150, 200]
        assert all(f[f"{s}/manifest/file"].fletcher32 for s in ("calibration", "walking", "bench"))
    back = read_hdf5(h5)
    assert diff_sessions(back, session) == []
    assert back.walking[3].trial == "4" and back.walking[3].recording["fz1"].flags.c_contiguous


@pytest.mark.parametrize("fmt", ["h5", "dir"])
def test_plate_type_empty_cop_and_text_labels_round_trip(tmp_path, fmt):
    s = random_session(plate="grf_cop", text_labels=True, n_walking=3, n_bench=1)
    back = load_session(save_session(s, tmp_path / "s", format=fmt))
    assert diff_sessions(back, s, provenance=False) == []
    assert back.info.force_plate.type == "grf_cop" and back.info.force_plate.plate_centre_m == (
        0.4,
        2.0,
    )
    assert [t.trial for t in back.walking] == ["S01 d1", "S01 d2", "S01 d3"]
    assert back.bench[0].test == "b1"
    assert np.isnan(back.walking[1].recording["cop_x_m"][:10]).all()


def test_empty_cop_is_checked_like_any_value(tmp_path, monkeypatch):
    s = random_session(plate="grf_cop", n_walking=3)
    path = store_unchecked(
        monkeypatch, with_column(s, 1, "grf_x_n", np.full(50, np.nan)), tmp_path / "s.h5"
    )
    with pytest.raises(
        SessionFormatError, match=r"s\.h5:/walking/trial_0002\.csv: column 'grf_x_n', sample 1"
    ):
        read_hdf5(path)
    cop = np.full(50, np.inf)
    path = store_unchecked(monkeypatch, with_column(s, 2, "cop_y_m", cop), tmp_path / "t.h5")
    with pytest.raises(
        SessionFormatError,
        match=r"trial_0003\.csv: column 'cop_y_m', sample 1: value inf; expected a finite number "
        "or an empty cell",
    ):
        read_hdf5(path)


def test_empty_sections_and_no_truth(tmp_path):
    s = random_session(n_calibration=0, n_bench=0, truth=False)
    back = read_hdf5(save_session(s, tmp_path / "s.h5"))
    assert back.calibration == () and back.bench == () and back.truth is None
    assert diff_sessions(back, s) == []


def test_first_layout_still_reads(tmp_path, session):
    path = write_v1(session, tmp_path / "old.h5")
    assert diff_sessions(load_session(path), session) == []
    with h5py.File(path, "a") as f:
        f["walking/trial_0003.csv/fz2"][7] = np.nan
    with pytest.raises(
        SessionFormatError,
        match=r"old\.h5:/walking/trial_0003\.csv: column 'fz2', sample 8: value nan",
    ):
        load_session(path)


def test_first_layout_with_text_labels(tmp_path, session):
    """anklelab-h5/1 files written after labels became text hold them as text attributes."""
    path = write_v1(session, tmp_path / "old.h5")
    with h5py.File(path, "a") as f:
        f["walking/trial_0002.csv"].attrs["trial"] = "d060_1"
        f["bench/bench_01.csv"].attrs["test"] = "A"
    back = load_session(path)
    assert [t.trial for t in back.walking[:3]] == ["1", "d060_1", "3"]
    assert back.bench[0].test == "A"
    with h5py.File(path, "a") as f:
        f["walking/trial_0002.csv"].attrs["trial"] = 2.5
    with pytest.raises(
        SessionFormatError, match=r"old\.h5:/walking/trial_0002\.csv: attribute 'trial': got "
    ):
        load_session(path)


# --- format and content checks ------------------------------------------------------------------


def test_unknown_format_version(h5):
    with h5py.File(h5, "a") as f:
        f.attrs["format"] = "anklelab-h5/9"
    with pytest.raises(
        SessionFormatError,
        match=r"s\.h5: attribute 'format' = 'anklelab-h5/9'; expected 'anklelab-h5/2' \(or the "
        r"older 'anklelab-h5/1'\) \(written by a different anklelab version\)",
    ):
        load_session(h5)


def test_not_an_anklelab_file(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = [1, 2]
    with pytest.raises(
        SessionFormatError, match=r"other\.h5: attribute 'format' = None; .*not an anklelab session"
    ):
        load_session(path)


def test_bad_data_names_path_column_and_sample(tmp_path, monkeypatch, session):
    bad = with_column(session, 2, "fz2", np.where(np.arange(50) == 7, np.nan, 1.0))
    path = store_unchecked(monkeypatch, bad, tmp_path / "s.h5")
    with pytest.raises(
        SessionFormatError,
        match=r"s\.h5:/walking/trial_0003\.csv: column 'fz2', sample 8: value nan",
    ):
        load_session(path)


def test_bad_manifest_row(tmp_path, monkeypatch, session):
    walking = list(session.walking)
    walking[1] = replace(walking[1], direction="none")
    path = store_unchecked(monkeypatch, replace(session, walking=tuple(walking)), tmp_path / "s.h5")
    with pytest.raises(
        SessionFormatError,
        match=r"s\.h5:/walking/trial_0002\.csv, column 'direction': a perturbed trial needs",
    ):
        load_session(path)


def test_duplicate_label(tmp_path, monkeypatch, session):
    walking = list(session.walking)
    walking[3] = replace(walking[3], trial=2)
    path = store_unchecked(monkeypatch, replace(session, walking=tuple(walking)), tmp_path / "s.h5")
    with pytest.raises(
        SessionFormatError,
        match=r"s\.h5:/walking/manifest: row 4: duplicate trial '2' \(already at row 2\)",
    ):
        load_session(path)


def test_session_metadata_checked(tmp_path, monkeypatch, session):
    info = replace(session.info, platform="nope")
    path = store_unchecked(monkeypatch, replace(session, info=info), tmp_path / "s.h5")
    with pytest.raises(SessionFormatError, match=r"s\.h5: /session/platform: unknown platform"):
        load_session(path)


# --- integrity ----------------------------------------------------------------------------------


def test_a_flipped_bit_in_a_stored_channel_is_corruption(h5):
    with h5py.File(h5) as f:
        offset = f["walking/layout_1/data"].id.get_chunk_info(0).byte_offset
    raw = bytearray(h5.read_bytes())
    raw[offset + 8 * 60 + 3] ^= 0x10  # one bit of one sample of motor_angle
    h5.write_bytes(bytes(raw))
    with pytest.raises(
        SessionFormatError,
        match=r"s\.h5:/walking/layout_1/data: cannot be read, the stored data is corrupted",
    ):
        load_session(h5)


@pytest.mark.parametrize(
    ("edit", "part"),
    [
        (lambda f: f["walking/layout_1/data"].__setitem__((1, 60), 3e39), "walking"),
        (lambda f: f["bench/manifest/distance_m"].__setitem__(0, 0.07), "bench"),
        (lambda f: f["session/geometry"].attrs.__setitem__("ankle_height_m", 0.09), "session"),
        (lambda f: f["truth/trials/heel_contact_s"].__setitem__(0, 0.2), "truth"),
        (lambda f: f["provenance"].attrs.__setitem__("seed", 1), "provenance"),
    ],
    ids=["channel", "manifest", "metadata", "truth", "provenance"],
)
def test_content_changed_after_writing_is_corruption(h5, edit, part):
    # h5py recomputes fletcher32 when it writes, so only the content hash can tell
    with h5py.File(h5, "a") as f:
        edit(f)
    with pytest.raises(
        SessionFormatError, match=rf"s\.h5:/{part}: corrupted: its content does not"
    ):
        load_session(h5)


def test_forged_part_hash_is_caught_by_the_content_hash(h5):
    with h5py.File(h5, "a") as f:
        f["provenance"].attrs["seed"] = 1
        f.attrs["sha256_provenance"] = hdf5.sha256_tree(read_h5_tree(f["provenance"]))
    with pytest.raises(SessionFormatError, match=r"attribute 'content_sha256' does not match"):
        load_session(h5)


# --- links and declared sizes -------------------------------------------------------------------


@pytest.fixture
def secret(tmp_path):
    path = tmp_path / "elsewhere.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.full(50, 932.0)
        f.create_group("group").attrs["secret"] = "do not show me"
    return path


@pytest.mark.parametrize(
    ("edit", "pattern"),
    [
        (
            lambda f, other: (
                f["walking/layout_1"].__delitem__("data"),
                f["walking/layout_1"].__setitem__("data", h5py.ExternalLink(str(other), "/data")),
            ),
            r"s\.h5:/walking/layout_1/data: is an external link "
            r"\(to '/data' in '.*elsewhere\.h5'\)",
        ),
        (
            lambda f, other: f.__setitem__("extra", h5py.ExternalLink(str(other), "/group")),
            r"s\.h5:/extra: is an external link",
        ),
        (
            lambda f, other: f.__setitem__("truth/alias", h5py.SoftLink("/truth/parameters")),
            r"s\.h5:/truth/alias: is a soft link \(to '/truth/parameters'\)",
        ),
        (
            lambda f, other: f.__setitem__("truth/nowhere", h5py.SoftLink("/no/such/thing")),
            r"s\.h5:/truth/nowhere: is a soft link",
        ),
        (
            lambda f, other: f["truth/parameters"].__setitem__("loop", f["truth"]),
            r"s\.h5:/truth/parameters/loop: is the same object as /truth "
            r"\(a hard-link alias or cycle\)",
        ),
        (
            lambda f, other: f.create_dataset(
                "truth/outside", shape=(4,), dtype="u1", external=[(str(other), 0, 4)]
            ),
            r"s\.h5:/truth/outside: stores its data in external files",
        ),
    ],
    ids=["external dataset", "external group", "soft link", "dangling soft link", "cycle", "raw"],
)
def test_links_and_outside_data_are_refused(h5, secret, edit, pattern):
    with h5py.File(h5, "a") as f:
        edit(f, secret)
    with pytest.raises(SessionFormatError, match=pattern) as caught:
        load_session(h5)
    assert "932" not in str(caught.value) and "do not show" not in str(caught.value)


def test_links_are_refused_in_the_first_layout_too(tmp_path, session, secret):
    path = write_v1(session, tmp_path / "old.h5")
    with h5py.File(path, "a") as f:
        del f["walking/trial_0002.csv/fz1"]
        f["walking/trial_0002.csv/fz1"] = h5py.ExternalLink(str(secret), "/data")
    with pytest.raises(
        SessionFormatError, match=r"old\.h5:/walking/trial_0002\.csv/fz1: is an external"
    ):
        load_session(path)


@pytest.mark.parametrize("layout", ["v1", "v2"])
def test_datasets_declaring_more_than_the_file_holds_are_refused(tmp_path, session, layout):
    if layout == "v1":
        path, name = write_v1(session, tmp_path / "s.h5"), "walking/trial_0001.csv/fz1"
    else:
        path, name = save_session(session, tmp_path / "s.h5"), "walking/layout_1/data"
    with h5py.File(path, "a") as f:
        del f[name]
        shape = (11, 2_000_000_000) if layout == "v2" else (2_000_000_000,)
        f.create_dataset(name, shape=shape, dtype="f8")
    assert path.stat().st_size < 1e6
    with pytest.raises(
        SessionFormatError,
        match=rf"s\.h5:/{name}: declares \d+ values \(\d+(\.\d+)? GiB\) but the file holds only 0 "
        r"bytes for them",
    ):
        load_session(path)


def test_truncated_file(h5):
    h5.write_bytes(h5.read_bytes()[: h5.stat().st_size // 2])
    with pytest.raises(SessionFormatError, match=r"s\.h5: .*(truncated|damaged)"):
        load_session(h5)


# --- fuzzing: any damage ends in SessionFormatError -----------------------------------------------


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "s.h5"
    return save_session(random_session(n_walking=3, n_calibration=1, n_bench=1), path)


def _structural(path, choice, value):
    """One structural edit through h5py: delete, retype or rewrite an object or attribute."""
    with h5py.File(path, "a") as f:
        names = []
        f.visit(names.append)
        name = names[choice % len(names)]
        action = choice % 4
        if action == 0:
            del f[name]
        elif action == 1 and isinstance(f[name], h5py.Dataset):
            del f[name]
            f[name] = np.array([str(value)] * 3, dtype=h5py.string_dtype())
        elif action == 2:
            f[name].attrs["format" if choice % 2 else "x"] = str(value)
        else:
            f.attrs[["format", "content_sha256", "sha256_walking"][choice % 3]] = str(value)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    kind=st.sampled_from(["flip", "truncate", "structure"]),
    where=st.floats(0, 1, exclude_max=True),
    choice=st.integers(0, 10_000),
    value=st.one_of(
        st.text(st.characters(exclude_categories=["Cs"], exclude_characters="\x00"), max_size=20),
        st.integers(-(2**31), 2**31),
        st.floats(),
    ),
)
def test_fuzz_damaged_files_give_session_format_errors(pristine, kind, where, choice, value):
    path = pristine.with_name("fuzz.h5")
    raw = bytearray(pristine.read_bytes())
    if kind == "flip":
        raw[int(where * len(raw))] ^= 1 << (choice % 8)
    elif kind == "truncate":
        raw = raw[: int(where * len(raw))]
    path.write_bytes(bytes(raw))
    if kind == "structure":
        _structural(path, choice, value)
    try:
        read_hdf5(path)
    except SessionFormatError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        (
            lambda s: {"walking": (replace(s.walking[0], extra={"note": "a\x00"}), *s.walking[1:])},
            r"session\.walking\[0\] 'trial_0001\.csv': extra manifest field 'note' = 'a\\x00'",
        ),
        (
            lambda s: {
                "bench": (
                    replace(s.bench[0], recording=replace(s.bench[0].recording, name="b\x00")),
                    *s.bench[1:],
                )
            },
            r"session\.bench\[0\] 'b\\x00': recording name 'b\\x00'; expected non-empty text",
        ),
    ],
)
def test_writer_refuses_text_the_store_cannot_hold(tmp_path, session, change, pattern):
    with pytest.raises(SessionFormatError, match=pattern):
        save_session(replace(session, **change(session)), tmp_path / "s.h5")
    assert list(tmp_path.iterdir()) == []


def test_an_interruption_inside_h5py_is_not_reported_as_damage():
    """h5py turns Ctrl-C during a read into a SystemError caused by the KeyboardInterrupt."""
    from anklelab.data._h5safe import damaged

    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interrupt:
            raise SystemError("returned a result with an exception set") from interrupt
    except SystemError as exc:
        assert isinstance(damaged("s.h5", exc), KeyboardInterrupt)
        assert isinstance(damaged("s.h5", SystemError("bad")), SessionFormatError)
