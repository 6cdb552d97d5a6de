"""Session I/O round trips: directory <-> Session <-> HDF5, exact arrays, deterministic bytes."""

import hashlib
import math
import shutil
import time
from dataclasses import replace

import numpy as np
import pytest

from anklelab.data import (
    diff_sessions,
    load_session,
    load_session_hashed,
    read_directory,
    read_hdf5,
    save_session,
    session_hash,
)
from anklelab.data._synthetic import random_session
from anklelab.data.hdf5 import h5_content_hash


def sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_dir_h5_dir_round_trip_is_exact(tmp_path):
    original = random_session(seed=3)
    first = save_session(original, tmp_path / "a", format="dir")
    from_dir = read_directory(first)
    assert diff_sessions(original, from_dir) == []
    h5 = save_session(from_dir, tmp_path / "a.h5")
    from_h5 = read_hdf5(h5)
    assert diff_sessions(from_dir, from_h5) == []
    second = save_session(from_h5, tmp_path / "b", format="dir")
    files = sorted(p.relative_to(first) for p in first.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(second) for p in second.rglob("*") if p.is_file())
    for name in files:
        assert (first / name).read_bytes() == (second / name).read_bytes(), name


def test_round_trip_keeps_unknown_columns_manifest_extras_and_tables(tmp_path):
    s = read_directory(save_session(random_session(), tmp_path / "s", format="dir"))
    assert "emg" in s.walking[0].recording.columns
    assert s.walking[1].extra == {"note": "step 1"}
    assert s.info.extra["notes"] == {"operator": "synthetic"}
    assert math.isnan(s.walking[0].delay_ms) and s.walking[1].delay_ms == 100.0


def test_floats_survive_text_round_trip_bit_for_bit(tmp_path):
    s = random_session(n_walking=1, n_calibration=0, n_bench=0)
    tricky = np.array([0.1, 1 / 3, 5e-324, 1.7976931348623157e308, -0.0] + [0.0] * 45)
    rec = s.walking[0].recording
    columns = dict(rec.columns) | {"ankle_angle": tricky}

    s = replace(s, walking=(replace(s.walking[0], recording=replace(rec, columns=columns)),))
    back = read_directory(save_session(s, tmp_path / "s", format="dir"))
    got = back.walking[0].recording["ankle_angle"]
    assert got.tobytes() == tricky.tobytes()


def test_two_saves_of_one_session_are_byte_identical(tmp_path):
    s = random_session(seed=5)
    a = save_session(s, tmp_path / "a.h5")
    time.sleep(1.1)  # HDF5 timestamps have 1 s resolution: a stored time would now differ
    b = save_session(s, tmp_path / "b.h5")
    assert sha(a) == sha(b)
    # and independent of dict insertion order in the trees
    flipped = dict(reversed(list(s.truth.items())))

    c = save_session(replace(s, truth=flipped), tmp_path / "c.h5")
    assert sha(a) == sha(c)


def test_load_session_detects_kind_and_records_import_provenance(tmp_path):
    s = random_session()
    d = save_session(s, tmp_path / "d", format="dir")
    h = save_session(s, tmp_path / "s.h5")
    from_dir = load_session(d)
    assert from_dir.provenance["source_sha256"] == session_hash(d)
    assert from_dir.provenance["import"]["importer"] == "csv-directory"
    assert from_dir.provenance["created_by"] == "random_session"
    assert diff_sessions(load_session(h), s) == []  # native files come back as stored
    assert diff_sessions(from_dir, s, provenance=False) == []


def test_a_session_read_with_its_hash_gives_the_hash_of_what_was_read(tmp_path):
    s = random_session()
    for path in (save_session(s, tmp_path / "d", format="dir"), save_session(s, tmp_path / "s.h5")):
        session, digest = load_session_hashed(path)
        assert digest == session_hash(path)
        assert diff_sessions(session, load_session(path)) == []


def test_session_hash_pins_every_file_read_and_only_those(tmp_path):
    d = save_session(random_session(), tmp_path / "d", format="dir")
    before = session_hash(d)
    assert session_hash(d) == before
    (d / "walking" / "notes.txt").write_text("x")  # not read: not part of the session
    assert session_hash(d) == before
    for name in ("session.toml", "walking/trials.csv", "bench/bench_02.csv", "truth.json"):
        original = (d / name).read_bytes()
        (d / name).write_bytes(original + b"\n")
        assert session_hash(d) != before, name
        (d / name).write_bytes(original)
    (d / "calibration" / "cal_01.csv").rename(d / "calibration" / "cal_09.csv")
    assert session_hash(d) != before  # names count too


def test_session_hash_of_h5_is_its_verified_content_hash(tmp_path):
    s = random_session()
    a, b = save_session(s, tmp_path / "a.h5"), save_session(s, tmp_path / "b.h5")
    assert session_hash(a) == session_hash(b) == h5_content_hash(a)
    changed = save_session(replace(s, provenance={"note": "other"}), tmp_path / "c.h5")
    assert session_hash(changed) != session_hash(a)


def test_truth_none_and_empty_sections_round_trip(tmp_path):
    s = random_session(n_calibration=0, n_bench=0, truth=False)
    for fmt in ("h5", "dir"):
        back = load_session(save_session(s, tmp_path / f"s_{fmt}", format=fmt))
        assert back.truth is None and back.calibration == () and back.bench == ()
        assert diff_sessions(back, s, provenance=False) == []


def test_save_refuses_to_replace_unrelated_directory(tmp_path):
    (tmp_path / "precious").mkdir()
    (tmp_path / "precious" / "thesis.tex").write_text("...")
    with pytest.raises(FileExistsError, match=r"session\.toml"):
        save_session(random_session(), tmp_path / "precious", format="dir")
    assert (tmp_path / "precious" / "thesis.tex").exists()


def test_sessions_remember_where_they_were_read_from(tmp_path):
    s = random_session()
    assert s.source == ""
    for path in (save_session(s, tmp_path / "d", format="dir"), save_session(s, tmp_path / "s.h5")):
        back = load_session(path)
        assert back.source == str(path) and back == replace(back, source="elsewhere")


def test_large_tree_arrays_are_npy_files_beside_the_json_and_read_back(tmp_path):
    time_courses = {"angle.rad": np.linspace(0.0, 1.0, 5000).reshape(50, 100), "..": np.arange(9)}
    truth = {"time_courses": time_courses, "/odd key": np.ones(4096, dtype=bool)}
    s = replace(random_session(), truth=truth)
    d = save_session(s, tmp_path / "d", format="dir")
    stored = sorted(p.relative_to(d).as_posix() for p in (d / "truth").rglob("*.npy"))
    assert stored == ["truth/%2Fodd%20key.npy", "truth/time_courses/angle.rad.npy"]
    assert "angle.rad" not in (d / "truth.json").read_text()  # the small one stays inline
    assert diff_sessions(read_directory(d), s) == []
    before = session_hash(d)
    np.save(d / "truth" / "time_courses" / "angle.rad.npy", time_courses["angle.rad"] + 1)
    assert session_hash(d) != before


def test_a_directory_with_every_array_inside_its_json_still_reads(tmp_path):
    from anklelab.data._tree import to_json

    s = replace(random_session(), truth={"time_courses": {"a": np.arange(10_000.0)}})
    d = save_session(s, tmp_path / "d", format="dir")
    shutil.rmtree(d / "truth")
    (d / "truth.json").write_text(to_json(s.truth))  # as anklelab wrote it before the .npy files
    assert diff_sessions(read_directory(d), s) == []


def test_an_input_is_named_by_its_file_or_directory_even_as_dot(tmp_path, monkeypatch):
    from anklelab.data import input_name

    (tmp_path / "S03 été").mkdir()
    monkeypatch.chdir(tmp_path / "S03 été")
    assert input_name(".") == "S03 été" and input_name("..") == tmp_path.name
    assert input_name("a/b/session.h5") == "session.h5" and input_name("dir/") == "dir"
    (tmp_path / "link").symlink_to(tmp_path / "S03 été")
    assert input_name(tmp_path / "link") == "link"  # the name the user gave, not the target's
