"""Every rejected input names the file, the column and the row (DESIGN.md section 4)."""

import re
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from anklelab.data import load_session, read_directory, save_session
from anklelab.data._synthetic import random_session
from anklelab.errors import SessionFormatError


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return save_session(random_session(), tmp_path_factory.mktemp("base") / "s", format="dir")


@pytest.fixture
def session_dir(base, tmp_path):
    return shutil.copytree(base, tmp_path / "s")


def replace(path, old, new):
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1))


def set_cell(path, line, column, value):
    """Overwrite one cell (``line`` is the 1-based CSV line, line 1 the header)."""
    lines = path.read_text().split("\n")
    index = lines[0].split(",").index(column)
    fields = lines[line - 1].split(",")
    fields[index] = value
    lines[line - 1] = ",".join(fields)
    path.write_text("\n".join(lines))


def set_times(path, times):
    lines = path.read_text().split("\n")
    for k, t in enumerate(times):
        fields = lines[k + 1].split(",")
        lines[k + 1] = ",".join([repr(float(t)), *fields[1:]])
    path.write_text("\n".join(lines))


TRIAL = "walking/trial_0002.csv"
N = 50  # samples per synthetic recording


# (case id, mutation of the session directory, regex every part of which must appear)
CASES = [
    (
        "missing column",
        lambda d: replace(d / TRIAL, "fz3", "fz_3"),
        r"trial_0002\.csv: missing required column\(s\) 'fz3' in the header \(line 1\)"
        r" \(found 'fz_3': rename it to 'fz3'\)",
    ),
    (
        "wrong-case column",  # not accepted, but hinted as a case slip (not as 'fz3')
        lambda d: replace(d / TRIAL, "fz4", "Fz4"),
        r"trial_0002\.csv: missing required column\(s\) 'fz4' in the header \(line 1\) "
        r"\(found 'Fz4': rename it to 'fz4'; names are case-sensitive\)",
    ),
    (
        "duplicate column",
        lambda d: replace(d / TRIAL, "fz3", "fz2"),
        r"trial_0002\.csv: column 'fz2' appears twice in the header \(line 1\)",
    ),
    (
        "non-monotonic time",
        lambda d: set_cell(d / TRIAL, 6, "time_s", "0.002"),
        r"trial_0002\.csv: column 'time_s', line 6: time 0\.002 s does not increase.*"
        r"strictly increasing",
    ),
    (
        "NaN",
        lambda d: set_cell(d / TRIAL, 8, "fz1", "nan"),
        r"trial_0002\.csv: column 'fz1', line 8: value nan; expected a finite number",
    ),
    (
        "infinity",
        lambda d: set_cell(d / TRIAL, 9, "motor_angle", "inf"),
        r"trial_0002\.csv: column 'motor_angle', line 9: value inf",
    ),
    (
        "empty cell",
        lambda d: set_cell(d / TRIAL, 8, "fy14", ""),
        r"trial_0002\.csv: column 'fy14', line 8: an empty cell; expected a number",
    ),
    (
        "non-numeric cell",
        lambda d: set_cell(d / TRIAL, 10, "fx12", "abc"),
        r"trial_0002\.csv: column 'fx12', line 10: 'abc'; expected a number",
    ),
    (
        "ragged row",
        lambda d: set_cell(d / TRIAL, 10, "fz4", "1.0,2.0"),
        r"trial_0002\.csv: line 10 has 12 fields; expected 11 like the header",
    ),
    (
        "wrong sample rate",
        lambda d: set_times(d / TRIAL, np.arange(N) / 500.0),
        r"trial_0002\.csv: column 'time_s', line 3: time step 0\.002 s from the previous row; "
        r"expected 0\.001 s ± 2% \(session\.toml sample_rate_hz = 1000\); the median time step "
        r"0\.002 s \(500 Hz\) does not match it either",
    ),
    (
        "sample rate changes after ten samples",  # the row named is where the steps go wrong
        lambda d: set_times(
            d / TRIAL, np.r_[np.arange(10) / 1e3, 0.009 + np.arange(1, N - 9) / 500]
        ),
        r"trial_0002\.csv: column 'time_s', line 12: time step 0\.002 s from the previous row; "
        r"expected 0\.001 s",
    ),
    (
        "dropped sample",
        lambda d: set_times(d / TRIAL, (np.arange(N) + (np.arange(N) >= 20)) / 1e3),
        r"trial_0002\.csv: column 'time_s', line 22: time step 0\.002 s; expected 0\.001 s",
    ),
    (
        "time in milliseconds",
        lambda d: set_times(d / TRIAL, np.arange(N) * 1.0),
        r"trial_0002\.csv: column 'time_s', line 3: time step 1 s .*is time in ms\?",
    ),
    (
        "semicolons",
        lambda d: (d / TRIAL).write_text((d / TRIAL).read_text().replace(",", ";")),
        r"trial_0002\.csv: header \(line 1\) 'time_s;motor_angle.*' .*is not comma-separated",
    ),
    (
        "unnamed column",
        lambda d: replace(d / TRIAL, "fz4", "fz4,"),
        r"trial_0002\.csv: column 12 of the header \(line 1\) has no name",
    ),
    (
        "empty file",
        lambda d: (d / TRIAL).write_text(""),
        r"trial_0002\.csv: empty file.*expected a header line naming the columns time_s",
    ),
    (
        "header only",
        lambda d: (d / TRIAL).write_text((d / TRIAL).read_text().split("\n")[0]),
        r"trial_0002\.csv: no data rows after the header",
    ),
    (
        "not UTF-8",
        lambda d: (d / TRIAL).write_bytes(b"time_s,\xe9\n"),
        r"trial_0002\.csv: not UTF-8 text",
    ),
    (
        "calibration column",
        lambda d: replace(d / "calibration/cal_02.csv", "motor_angle", "mot"),
        r"calibration/cal_02\.csv: missing required column\(s\) 'motor_angle' in the header",
    ),
    (
        "bench column",
        lambda d: replace(d / "bench/bench_01.csv", "force_n", "force"),
        r"bench/bench_01\.csv: missing required column\(s\) 'force_n'",
    ),
    # manifests
    (
        "manifest names a missing file",
        lambda d: (d / "walking/trial_0003.csv").unlink(),
        r"walking/trials\.csv: line 4, column 'file': .*trial_0003\.csv does not exist",
    ),
    (
        "manifest path escapes folder",
        lambda d: replace(d / "walking/trials.csv", "trial_0003.csv", "../session.toml"),
        r"walking/trials\.csv: line 4, column 'file': got '\.\./session\.toml'",
    ),
    (
        "perturbed without direction",
        lambda d: replace(d / "walking/trials.csv", "1,dorsi,100.0", "1,none,100.0"),
        r"walking/trials\.csv: line 3, column 'direction': a perturbed trial needs 'dorsi' or "
        r"'plantar'",
    ),
    (
        "unperturbed with delay",
        lambda d: replace(d / "walking/trials.csv", "0,none,", "0,none,75"),
        r"walking/trials\.csv: line 2, column 'delay_ms': an unperturbed trial .* needs an empty",
    ),
    (
        "perturbed without delay",
        lambda d: replace(d / "walking/trials.csv", "dorsi,100.0", "dorsi,"),
        r"walking/trials\.csv: line 3, column 'delay_ms': a perturbed trial needs a delay",
    ),
    (
        "unperturbed with direction",
        lambda d: replace(d / "walking/trials.csv", "0,none", "0,plantar"),
        r"walking/trials\.csv: line 2, column 'direction': an unperturbed trial .* needs 'none'",
    ),
    (
        "unknown direction",
        lambda d: replace(d / "walking/trials.csv", "plantar", "sideways"),
        r"walking/trials\.csv: line 4, column 'direction': got 'sideways'; expected one of dorsi",
    ),
    (
        "perturbed not 0/1",
        lambda d: replace(d / "walking/trials.csv", ",0,none", ",yes,none"),
        r"walking/trials\.csv: line 2, column 'perturbed': got 'yes'; expected 0 or 1",
    ),
    (
        "empty trial label",
        lambda d: replace(d / "walking/trials.csv", "3,trial_0003", ",trial_0003"),
        r"walking/trials\.csv: line 4, column 'trial': empty cell; expected a label",
    ),
    (
        "duplicate trial id",
        lambda d: replace(d / "walking/trials.csv", "3,trial_0003", "2,trial_0003"),
        r"walking/trials\.csv: line 4: duplicate trial '2' \(already at line 3\)",
    ),
    (
        "duplicate file",
        lambda d: replace(d / "walking/trials.csv", "3,trial_0003", "3,trial_0002"),
        r"walking/trials\.csv: line 4: duplicate file 'trial_0002\.csv' \(already at line 3\)",
    ),
    (
        "manifest column missing",
        lambda d: replace(d / "walking/trials.csv", "delay_ms", "delay"),
        r"walking/trials\.csv: missing required column\(s\) 'delay_ms' in the header \(line 1\)",
    ),
    (
        "manifest ragged",
        lambda d: replace(d / "walking/trials.csv", "step 1", "step 1,x"),
        r"walking/trials\.csv: line 3 has 7 fields; expected 6",
    ),
    (
        "manifest empty",
        lambda d: (d / "walking/trials.csv").write_text(
            "trial,file,perturbed,direction,delay_ms\n"
        ),
        r"walking/trials\.csv: no rows after the header",
    ),
    (
        "manifest missing",
        lambda d: (d / "walking/trials.csv").unlink(),
        r"walking/trials\.csv: missing; a walking/ folder needs its manifest",
    ),
    (
        "bench distance",
        lambda d: replace(d / "bench/tests.csv", "0.06", "-0.06"),
        r"bench/tests\.csv: line 2, column 'distance_m': got -0\.06; expected a distance > 0 m",
    ),
    (
        "bench distance text",
        lambda d: replace(d / "bench/tests.csv", "0.06", "six cm"),
        r"bench/tests\.csv: line 2, column 'distance_m': got 'six cm'; expected a number",
    ),
    # session.toml
    ("no session.toml", lambda d: (d / "session.toml").unlink(), r"session\.toml: file not found"),
    (
        "format version",
        lambda d: replace(d / "session.toml", "session/1", "session/9"),
        r"session\.toml: format: expected 'anklelab-session/1', got 'anklelab-session/9'",
    ),
    (
        "unknown platform",
        lambda d: replace(d / "session.toml", '"perturberator"', '"perturbator"'),
        r"session\.toml: platform: unknown platform 'perturbator'; expected one of",
    ),
    (
        "bad sample rate",
        lambda d: replace(d / "session.toml", "= 1000.0", "= 0.0"),
        r"session\.toml: sample_rate_hz: expected a number > 0, got 0\.0",
    ),
    (
        "sample rate text",
        lambda d: replace(d / "session.toml", "= 1000.0", '= "1 kHz"'),
        r"session\.toml: sample_rate_hz: expected a finite number, got '1 kHz'",
    ),
    (
        "plate key missing",
        lambda d: replace(d / "session.toml", "a_m = 0.12\n", ""),
        r"session\.toml: force_plate\.a_m: required key is missing",
    ),
    (
        "plate sign",
        lambda d: replace(d / "session.toml", "az0_m = -0.045", "az0_m = 0.045"),
        r"session\.toml: force_plate\.az0_m: .*less than 0; got 0\.045",
    ),
    (
        "plate table missing",
        lambda d: replace(d / "session.toml", "[force_plate]", "[forceplate]"),
        r"session\.toml: force_plate: required table is missing \(found 'forceplate': rename it "
        r"to 'force_plate'\)",
    ),
    (
        "geometry key",
        lambda d: replace(d / "session.toml", "ankle_height_m", "ankle_heigth_m"),
        r"session\.toml: geometry\.ankle_height_m: required key is missing \(found "
        r"'ankle_heigth_m': rename it to 'ankle_height_m'\)",
    ),
    (
        "negative ankle height",
        lambda d: replace(d / "session.toml", "ankle_height_m = 0.08", "ankle_height_m = -0.08"),
        r"session\.toml: geometry\.ankle_height_m: expected a number > 0",
    ),
    (
        "heel-to-ankle in centimetres",
        lambda d: replace(d / "session.toml", "heel_to_ankle_m = 0.04", "heel_to_ankle_m = 4.0"),
        r"s/session\.toml: geometry\.heel_to_ankle_m = 4 m: did you give centimetres\? "
        r"expected 0–0\.25 m",
    ),
    (
        "ankle height in millimetres",
        lambda d: replace(d / "session.toml", "ankle_height_m = 0.08", "ankle_height_m = 80"),
        r"s/session\.toml: geometry\.ankle_height_m = 80 m: did you give millimetres\? "
        r"expected 0\.02–0\.25 m",
    ),
    (
        "plate offset in centimetres",
        lambda d: replace(d / "session.toml", "a_m = 0.12", "a_m = 12.0"),
        r"s/session\.toml: force_plate\.a_m = 12 m: did you give centimetres\?",
    ),
    (
        "implausible without a unit slip",
        lambda d: replace(d / "session.toml", "heel_to_ankle_m = 0.04", "heel_to_ankle_m = -0.3"),
        r"s/session\.toml: geometry\.heel_to_ankle_m = -0\.3 m; expected 0–0\.25 m",
    ),
    (
        "capstan platform in a walking session",
        lambda d: replace(d / "session.toml", '"perturberator"', '"capstan"'),
        r"s/session\.toml: platform: 'capstan' does not record walking sessions; expected "
        r"one of 'perturberator'",
    ),
    (
        "subject not text",
        lambda d: replace(d / "session.toml", 'subject = "S01"', "subject = 1"),
        r"session\.toml: subject: expected a string, got 1",
    ),
    (
        "TOML syntax",
        lambda d: replace(d / "session.toml", "subject =", "subject =="),
        r"session\.toml: not valid TOML: .*line 4",
    ),
    (
        "truth JSON syntax",
        lambda d: replace(d / "truth.json", '"count":3', '"count":3,'),
        r"truth\.json: line 1, column \d+: .*expected JSON",
    ),
]


@pytest.mark.parametrize(("mutate", "pattern"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_directory_rejections_name_file_column_and_line(session_dir, mutate, pattern):
    mutate(session_dir)
    with pytest.raises(SessionFormatError, match=pattern):
        load_session(session_dir)


def test_line_numbers_count_blank_lines(session_dir):
    path = session_dir / TRIAL
    lines = path.read_text().split("\n")
    lines.insert(3, "")  # a blank line 4: data row 8 is now on line 9
    path.write_text("\n".join(lines))
    set_cell(path, 9, "fz1", "nan")
    with pytest.raises(SessionFormatError, match=r"column 'fz1', line 9:"):
        read_directory(session_dir)


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize("ending", ["", "one newline", "blank lines"])
@pytest.mark.parametrize("blank_inside", [False, True])
def test_line_numbers_hold_for_any_line_ending(session_dir, newline, ending, blank_inside):
    """The line a message names, whatever ends the lines and the file."""
    path = session_dir / TRIAL
    set_cell(path, 8, "fz1", "nan")
    lines = path.read_text().rstrip("\n").split("\n")
    if blank_inside:
        lines.insert(3, "")  # the bad cell moves to line 9
    tail = {"": "", "one newline": newline, "blank lines": newline * 3}[ending]
    path.write_bytes((newline.join(lines) + tail).encode())
    with pytest.raises(SessionFormatError, match=rf"column 'fz1', line {8 + blank_inside}:"):
        read_directory(session_dir)


def test_tolerated_variations(session_dir):
    """BOM, CRLF, spaces after commas, quoted numbers, unknown files, integer sample rate."""
    path = session_dir / TRIAL
    text = path.read_text().replace(",", ", ").replace("\n", "\r\n")
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    set_cell(session_dir / "walking/trial_0003.csv", 5, "fz1", '"12.5"')
    (session_dir / "walking/README.txt").write_text("notes")
    replace(session_dir / "session.toml", "= 1000.0", "= 1000")
    s = read_directory(session_dir)
    assert s.info.sample_rate_hz == 1000.0
    assert s.walking[2].recording["fz1"][3] == 12.5
    assert s.walking[1].recording.n_samples == N


def test_nan_in_unknown_column_is_kept(session_dir):
    set_cell(session_dir / "walking/trial_0001.csv", 5, "emg", "nan")
    s = read_directory(session_dir)
    assert np.isnan(s.walking[0].recording["emg"][3])


def test_unperturbed_delay_written_as_nan_is_accepted(session_dir):
    replace(session_dir / "walking/trials.csv", "0,none,", "0,none,NaN")
    assert np.isnan(read_directory(session_dir).walking[0].delay_ms)


# --- any input ------------------------------------------------------------------------------


def test_neither_directory_nor_session_file(tmp_path):
    path = tmp_path / "notes.h5"
    path.write_text("hello")
    with pytest.raises(SessionFormatError, match=r"notes\.h5: expected a session directory"):
        load_session(path)
    with pytest.raises(SessionFormatError, match=r"missing: no such file"):
        load_session(tmp_path / "missing")


# --- writers validate too -----------------------------------------------------------------------


@pytest.mark.parametrize("fmt", ["h5", "dir"])
def test_writers_refuse_invalid_sessions(tmp_path, fmt):
    from dataclasses import replace as dc_replace

    s = random_session()
    rec = s.walking[1].recording
    bad = dict(rec.columns) | {"fz1": np.where(np.arange(rec.n_samples) == 4, np.nan, 1.0)}
    s = dc_replace(
        s,
        walking=(
            s.walking[0],
            dc_replace(s.walking[1], recording=dc_replace(rec, columns=bad)),
            *s.walking[2:],
        ),
    )
    with pytest.raises(
        SessionFormatError, match=r"session\.walking\[1\] 'trial_0002\.csv': column 'fz1', sample 5"
    ):
        save_session(s, tmp_path / "out", format=fmt)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        (
            lambda s: {"truth": {"fit": {"model": object()}}},
            r"session\.truth: fit\.model: unsupported value of type object",
        ),
        (
            lambda s: {"truth": {"ragged": [[1.0, 2.0], [3.0]]}},
            r"session\.truth: ragged: ragged nested sequence",
        ),
        (
            lambda s: {
                "walking": (
                    s.walking[0],
                    type(s.walking[1])(**{**s.walking[1].__dict__, "extra": {"trial": "7"}}),
                    *s.walking[2:],
                )
            },
            r"session\.walking\[1\] 'trial_0002\.csv': extra manifest field 'trial'",
        ),
        (
            lambda s: {
                "calibration": (
                    type(s.calibration[0])(
                        "cal_01.csv", dict(s.calibration[0].columns) | {" emg": np.zeros(N)}
                    ),
                )
            },
            r"session\.calibration\[0\] 'cal_01\.csv': column name ' emg'",
        ),
    ],
)
def test_writers_check_trees_names_and_extras(tmp_path, change, pattern):
    from dataclasses import replace as dc_replace

    s = random_session()
    with pytest.raises(SessionFormatError, match=pattern):
        save_session(dc_replace(s, **change(s)), tmp_path / "out.h5")
    assert list(tmp_path.iterdir()) == []


TOML_VALUES = st.recursive(
    st.none().map(lambda _: "x")
    | st.booleans()
    | st.integers(-(2**63), 2**63 - 1)
    | st.floats()
    | st.text(st.characters(exclude_categories=["Cs"]), max_size=30),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3)
    ),
    max_leaves=8,
)


@settings(max_examples=150, deadline=None)
@given(
    key=st.sampled_from(
        [
            ("format",),
            ("platform",),
            ("sample_rate_hz",),
            ("subject",),
            ("force_plate",),
            ("force_plate", "a_m"),
            ("force_plate", "az0_m"),
            ("force_plate", "anterior_axis"),
            ("force_plate", "type"),
            ("force_plate", "delay_ms"),
            ("geometry",),
            ("geometry", "heel_to_ankle_m"),
            ("extra",),
        ]
    ),
    value=TOML_VALUES,
)
def test_any_session_toml_value_is_accepted_or_named(key, value):
    from anklelab.data._checks import info_from_mapping, info_to_mapping

    document = info_to_mapping(random_session().info)
    table = document
    for part in key[:-1]:
        table = table[part]
    table[key[-1]] = value
    try:
        info_from_mapping(document, "session.toml")
    except SessionFormatError as exc:
        assert str(exc).startswith("session.toml: ") and len(str(exc)) < 600


def test_a_plate_type_read_as_an_array_is_named():
    """A damaged MATLAB v7.3 file gave ``force_plate.type`` as a numeric array (found by the
    v7.3 fuzz test): named, not a NumPy truth-value error."""
    from anklelab.data._checks import info_from_mapping, info_to_mapping

    document = info_to_mapping(random_session().info)
    document["force_plate"]["type"] = np.array([107.0, 105.0])
    with pytest.raises(SessionFormatError, match=r"force_plate\.type: expected one of kistler8"):
        info_from_mapping(document, "session.toml")


@pytest.mark.parametrize(
    ("value", "expected"),
    [(-0.5, "expected 0 to 50 ms, got -0.5"), (80, "expected 0 to 50 ms, got 80"),
     ("1 ms", "expected a finite number, got '1 ms'"), (float("nan"), "expected a finite")],
)  # fmt: skip
def test_the_plates_recorded_delay_is_read_written_and_checked(tmp_path, value, expected):
    from dataclasses import replace as dc_replace

    from anklelab.data import load_session, save_session
    from anklelab.data._checks import info_from_mapping, info_to_mapping

    session = random_session()
    info = dc_replace(session.info, force_delay_ms=1.25)
    document = info_to_mapping(info)
    assert document["force_plate"]["delay_ms"] == 1.25
    assert info_from_mapping(document, "session.toml") == info
    assert "delay_ms" not in info_to_mapping(session.info)["force_plate"]  # 0: as before
    for fmt, name in (("dir", "s"), ("h5", "s.h5")):
        path = save_session(dc_replace(session, info=info), tmp_path / name, format=fmt)
        assert load_session(path).info.force_delay_ms == 1.25
    document["force_plate"]["delay_ms"] = value
    with pytest.raises(SessionFormatError, match=r"session\.toml: force_plate\.delay_ms: "):
        info_from_mapping(document, "session.toml")
    with pytest.raises(SessionFormatError, match=re.escape(expected)):
        info_from_mapping(document, "session.toml")
