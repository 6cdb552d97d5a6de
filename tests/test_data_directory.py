"""The session directory is read safely: only regular files inside it, bounded sizes, clear
messages that never show more of a file than a short excerpt; CSV parsing and its fallback."""

import io
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.data import diff_sessions, load_session, read_directory, save_session, session_hash
from anklelab.data._csv import NUMBER, parse_numeric
from anklelab.data._synthetic import random_session
from anklelab.errors import SessionFormatError

SECRET = "root:$6$do-not-show-me:19000:0:99999:7:::"


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return save_session(random_session(), tmp_path_factory.mktemp("base") / "s", format="dir")


@pytest.fixture
def session_dir(base, tmp_path):
    return shutil.copytree(base, tmp_path / "s")


@pytest.fixture
def outside(tmp_path):
    """A file outside the session, holding something that must never be shown."""
    path = tmp_path / "shadow"
    path.write_text(SECRET + "\n")
    return path


def rejected(session, pattern):
    with pytest.raises(SessionFormatError, match=pattern) as caught:
        load_session(session)
    message = str(caught.value)
    assert "do-not-show" not in message and "\n" not in message
    return message


# --- what is read ---------------------------------------------------------------------------


def test_symlink_to_a_file_outside_the_session_is_refused(session_dir, outside):
    os.symlink(outside, session_dir / "calibration" / "calibration_99.csv")
    rejected(
        session_dir,
        r"s/calibration/calibration_99\.csv: is a link to .*shadow', outside the session "
        r"directory .*/s; links may only point to files inside the session",
    )


def test_symlinked_folder_leaving_the_session_is_refused(session_dir, tmp_path):
    elsewhere = shutil.move(session_dir / "walking", tmp_path / "elsewhere")
    os.symlink(elsewhere, session_dir / "walking")
    rejected(session_dir, r"s/walking/trials\.csv: is a link to .*elsewhere/trials\.csv', outside")


def test_symlinks_inside_the_session_are_followed(session_dir):
    target = session_dir / "walking" / "trial_0002.csv"
    moved = session_dir / "archive" / "t2.csv"
    moved.parent.mkdir()
    target.rename(moved)
    os.symlink(os.path.relpath(moved, target.parent), target)
    assert len(read_directory(session_dir).walking) == 6


def test_manifest_naming_a_link_outside(session_dir, outside):
    (session_dir / "walking" / "trial_0003.csv").unlink()
    os.symlink(outside, session_dir / "walking" / "trial_0003.csv")
    rejected(
        session_dir,
        r"s/walking/trials\.csv: line 4, column 'file': .*s/walking/trial_0003\.csv is a link to "
        r".*shadow', outside the session directory",
    )


def test_dangling_link(session_dir):
    (session_dir / "bench" / "bench_02.csv").unlink()
    os.symlink(session_dir / "nowhere.csv", session_dir / "bench" / "bench_02.csv")
    rejected(
        session_dir,
        r"s/bench/tests\.csv: line 3, column 'file': .*s/bench/bench_02\.csv is a dangling "
        r"symbolic link",
    )


@pytest.mark.parametrize(
    ("where", "pattern"),
    [
        (
            "walking/trial_0003.csv",
            r"s/walking/trials\.csv: line 4, column 'file': .*s/walking/trial_0003\.csv is a named "
            r"pipe \(FIFO\), not a regular file",
        ),
        (
            "calibration/cal_03.csv",
            r"s/calibration/cal_03\.csv: is a named pipe \(FIFO\), not a regular file",
        ),
        ("session.toml", r"s/session\.toml: is a named pipe \(FIFO\), not a regular file"),
    ],
)
def test_fifo_is_not_a_regular_file_and_never_blocks(session_dir, where, pattern):
    (session_dir / where).unlink(missing_ok=True)
    os.mkfifo(session_dir / where)
    rejected(session_dir, pattern)


def test_directory_named_like_a_recording(session_dir):
    (session_dir / "calibration" / "cal_03.csv").mkdir()
    rejected(session_dir, r"s/calibration/cal_03\.csv: is a directory, not a regular file")


def test_sparse_2_gb_recording_is_refused_before_reading(session_dir):
    trial = session_dir / "walking" / "trial_0005.csv"
    os.truncate(trial, 2 * 2**30)  # as `truncate -s 2G` does: sparse, nothing on disk
    code = (
        "import re\n"
        "from anklelab.data import load_session\n"
        "try:\n"
        f"    load_session({str(session_dir)!r})\n"
        "except Exception as exc:\n"
        "    print(exc)\n"
        "print(re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read())[1])\n"
    )
    out = subprocess.run(
        [sys.executable, "-X", "faulthandler", "-c", code], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-3000:]
    message, peak_kib = out.stdout.strip().rsplit("\n", 1)
    assert "trial_0005.csv: is 2 GiB, more than the limit of 1 GiB for a CSV file" in message
    # the process's own peak (VmHWM; ru_maxrss would count the forking test process): the
    # interpreter and libraries, not the file
    assert int(peak_kib) < 400 * 1024


def test_file_that_grows_while_read_is_refused(session_dir, monkeypatch):
    """Only the bytes the file held when opened are asked for: a file still being written (here
    one seen 10 bytes shorter than it is) is named, never parsed half-written."""
    import anklelab.data._files as files

    real = files.os.fstat

    def shorter(fd):
        info = real(fd)
        return os.stat_result((*info[:6], info.st_size - 10, *info[7:10]))

    monkeypatch.setattr(files.os, "fstat", shorter)
    rejected(session_dir, r"session\.toml: changed size while being read .*still being written")


def test_oversized_manifest_and_toml(session_dir):
    with (session_dir / "session.toml").open("a") as f:
        f.write("# " + "x" * 2**20 + "\n")
    rejected(session_dir, r"s/session\.toml: is 1 MiB, more than the limit of 1 MiB for a TOML")


@pytest.mark.parametrize(
    ("name", "text", "pattern"),
    [
        ("session.toml", "a = " + "[" * 5000 + "]" * 5000 + "\n", r"nested too deeply"),
        ("truth.json", "[" * 100_000 + "]" * 100_000, r"s/truth\.json: nested too deeply"),
    ],
)
def test_deeply_nested_documents(session_dir, name, text, pattern):
    path = session_dir / name
    path.write_text(text + (path.read_text() if name == "session.toml" else ""))
    rejected(session_dir, pattern)


def test_session_hash_reads_nothing_outside(session_dir, outside):
    os.symlink(outside, session_dir / "calibration" / "calibration_99.csv")
    with pytest.raises(SessionFormatError, match=r"outside the session directory"):
        session_hash(session_dir)


# --- CSV cells and lines --------------------------------------------------------------------


def set_cell(path, line, column, value):
    lines = path.read_text().split("\n")
    index = lines[0].split(",").index(column)
    fields = lines[line - 1].split(",")
    fields[index] = value
    lines[line - 1] = ",".join(fields)
    path.write_text("\n".join(lines))


@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        ("1_000", r"column 'fx12', line 10: '1_000'; expected a number"),
        ("١٢", r"column 'fx12', line 10: '١٢'; expected a number"),
        ("0x10", r"column 'fx12', line 10: '0x10'; expected a number"),
        ("y" * 200_000, r"line 10: field larger than field limit \(131072\); expected"),
        ("ab" * 60, r"column 'fx12', line 10: 'ababab.*…' \(120 characters\); expected a number"),
        ("1.5\x00\x00", r"line 10 holds a NUL byte"),
    ],
    ids=["underscore", "arabic digits", "hex", "200 KB cell", "long cell", "NUL"],
)
def test_bad_cells_name_line_and_column(session_dir, value, pattern):
    set_cell(session_dir / "walking/trial_0002.csv", 10, "fx12", value)
    message = rejected(session_dir, r"s/walking/trial_0002\.csv: " + pattern)
    assert len(message) < 400


def test_spaces_only_line_is_skipped_like_a_blank_line(session_dir):
    path = session_dir / "walking/trial_0002.csv"
    lines = path.read_text().split("\n")
    lines.insert(3, "   ")
    path.write_text("\n".join(lines))
    assert read_directory(session_dir).walking[1].recording.n_samples == 50


def test_fast_and_slow_parsers_agree():
    rng = np.random.default_rng(1)
    values = rng.normal(0, 1e3, (3, 40))
    values[1, 5] = np.nan
    text = "a,b,c\n" + "".join(",".join(repr(float(v)) for v in row) + "\n" for row in values.T)
    fast, line = parse_numeric("f.csv", text.encode(), ["a", "b", "c"])
    slow, slow_line = parse_numeric("f.csv", (text + "  \n").encode(), ["a", "b", "c"])
    assert fast.tobytes() == slow.tobytes() == values.tobytes()
    assert line(4) == slow_line(4) == "line 6"


def csv_text(values, empty=()):
    """``values`` (columns a, b, c) as CSV; the (row, column) cells in ``empty`` left empty."""
    rows = [[repr(float(v)) for v in row] for row in values.T]
    for i, j, cell in empty:
        rows[i][j] = cell
    return "a,b,c\n" + "".join(",".join(row) + "\n" for row in rows)


def test_empty_cells_of_nullable_columns_read_as_nan_in_both_parsers():
    values = np.random.default_rng(2).normal(0, 1e3, (3, 30))
    values[1, [3, 7, 8]] = np.nan
    text = csv_text(values, [(3, 1, ""), (7, 1, '""'), (8, 1, "")])
    fast, line = parse_numeric("f.csv", text.encode(), ["a", "b", "c"], ("b",))
    # a cell of spaces, and a line of spaces, are read row by row
    slow_text = csv_text(values, [(3, 1, "  "), (7, 1, '""'), (8, 1, "")]) + "  \n"
    slow, slow_line = parse_numeric("f.csv", slow_text.encode(), ["a", "b", "c"], ("b",))
    assert fast.tobytes() == slow.tobytes() == values.tobytes()
    assert line(8) == slow_line(8) == "line 10"


@pytest.mark.parametrize("tail", ["", "  \n"], ids=["fast", "slow"])
@pytest.mark.parametrize("cell", ["", '""', " "])
def test_an_empty_cell_outside_the_nullable_columns_is_named(tail, cell):
    values = np.ones((3, 10))
    text = csv_text(values, [(2, 1, ""), (5, 2, cell)]) + tail
    with pytest.raises(
        SessionFormatError,
        match=r"^f\.csv: column 'c', line 7: an empty cell; expected a number$",
    ):
        parse_numeric("f.csv", text.encode(), ["a", "b", "c"], ("b",))
    with pytest.raises(
        SessionFormatError,
        match=r"^f\.csv: column 'b', line 4: an empty cell; expected a number$",
    ):
        parse_numeric("f.csv", text.encode(), ["a", "b", "c"], ("a",))


def test_grf_cop_session_directory_with_empty_cop_cells(tmp_path):
    session = random_session(plate="grf_cop", n_walking=3, n_bench=0)
    root = save_session(session, tmp_path / "s", format="dir")
    for path in [*root.glob("calibration/*.csv"), *root.glob("walking/trial_*.csv")]:
        path.write_text(path.read_text().replace("nan", ""))  # as exported: empty cells
    assert ",," in (root / "walking/trial_0002.csv").read_text()
    back = read_directory(root)
    assert np.isnan(back.walking[1].recording["cop_y_m"][:10]).all()
    assert diff_sessions(back, session) == []
    set_cell(root / "walking/trial_0002.csv", 6, "grf_z_n", "")
    rejected(
        root,
        r"s/walking/trial_0002\.csv: column 'grf_z_n', line 6: an empty cell; expected a number$",
    )


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="0123456789+-.eEinfatyINFATY_ x", max_size=12))
def test_number_grammar_matches_the_fast_parser(cell):
    import pyarrow as pa
    import pyarrow.csv as pacsv

    try:
        table = pacsv.read_csv(
            pa.BufferReader(f"v\n{cell}\n".encode()),
            convert_options=pacsv.ConvertOptions(
                column_types={"v": pa.float64()}, null_values=[], strings_can_be_null=False
            ),
        )
        fast = table.num_rows == 1
    except pa.ArrowInvalid:
        fast = False
    assert bool(NUMBER.fullmatch(cell.strip(" \t"))) == fast or cell.strip() == ""


# --- fuzzing: any bad CSV ends in SessionFormatError ----------------------------------------------


@pytest.fixture(scope="module")
def trial_bytes(base):
    return (base / "walking" / "trial_0002.csv").read_bytes()


@settings(
    max_examples=80,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    cut=st.floats(0, 1),
    insert=st.binary(max_size=30) | st.text(max_size=30).map(str.encode),
    where=st.floats(0, 1),
)
def test_fuzz_recording_files(tmp_path_factory, base, trial_bytes, cut, insert, where):
    root = tmp_path_factory.mktemp("fuzz") / "s"
    shutil.copytree(base, root)
    data = trial_bytes[: max(1, int(cut * len(trial_bytes)))] if cut < 0.5 else trial_bytes
    at = int(where * len(data))
    (root / "walking" / "trial_0002.csv").write_bytes(data[:at] + insert + data[at:])
    try:
        read_directory(root)
    except SessionFormatError as exc:
        assert "trial_0002.csv" in str(exc) and "\n" not in str(exc)


@settings(max_examples=150, deadline=None)
@given(
    st.lists(st.sampled_from(["1", "-2.5e3", "nan", "", " ", '""', "x", "1_0", ","]), max_size=40)
)
def test_fuzz_nullable_cells(cells):
    """Any mix of numbers, empty and bad cells: NaN exactly where column b is empty, or one
    clear error; the fast parser and the row-by-row one agree."""
    text = "a,b,c\n" + "".join(",".join(cells[i : i + 3]) + "\n" for i in range(0, len(cells), 3))
    results = []
    for tail in ("", "  \n"):  # the second is read row by row
        try:
            values, _ = parse_numeric("f.csv", (text + tail).encode(), ["a", "b", "c"], ("b",))
            results.append(values.tobytes())
        except SessionFormatError as exc:
            assert str(exc).startswith("f.csv: ") and "\n" not in str(exc)
            results.append(str(exc))
    assert results[0] == results[1]


# --- the truth tree's .npy arrays -----------------------------------------------------------


def npy_bytes(array):
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=True)
    return buffer.getvalue()


def npy_header(shape):
    """A .npy file's header for float64 values of ``shape``, without the values."""
    buffer = io.BytesIO()
    header = {"descr": "<f8", "fortran_order": False, "shape": shape}
    np.lib.format.write_array_header_1_0(buffer, header)
    return buffer.getvalue()


@pytest.mark.parametrize(
    ("name", "content", "pattern"),
    [
        ("x.npy", npy_bytes(np.array([{"a": 1}], dtype=object)), r"holds object values"),
        ("x.npy", npy_bytes(np.array(["a", "b"])), r"holds <U1 values"),
        ("x.npy", npy_bytes(np.zeros(1000))[:-8], r"header gives 8000 bytes of data, the file "),
        ("x.npy", npy_header((10**13,)), r"header gives 80000000000000 bytes of data, the "),
        ("x.npy", b"not an array", r"not a NumPy \.npy file"),
        ("parameters.npy", npy_bytes(np.zeros(3)), r"parameters: given twice"),
        ("foot/x.npy", npy_bytes(np.zeros(3)), r"foot: holds a value, not a mapping"),
    ],
)
def test_bad_tree_arrays_are_named(session_dir, name, content, pattern):
    truth = json.loads((session_dir / "truth.json").read_text())
    truth["foot"] = 1.0
    (session_dir / "truth.json").write_text(json.dumps(truth))
    path = session_dir / "truth" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(content)
    message = rejected(session_dir, pattern)
    assert message.startswith(f"{path}: ")


def test_a_tree_array_linked_from_outside_is_refused(session_dir, outside):
    (session_dir / "truth").mkdir()
    os.symlink(outside, session_dir / "truth" / "x.npy")
    rejected(session_dir, r"s/truth/x\.npy: is a link to .*outside the session directory")


def test_a_linked_tree_array_folder_is_followed_inside_and_refused_outside(session_dir, tmp_path):
    (session_dir / "truth" / "inner").mkdir(parents=True)
    np.save(session_dir / "truth" / "inner" / "x.npy", np.arange(5.0))
    os.rename(session_dir / "truth" / "inner", session_dir / "arrays")
    os.symlink("../arrays", session_dir / "truth" / "inner")
    assert load_session(session_dir).truth["inner"]["x"].tolist() == [0, 1, 2, 3, 4]
    elsewhere = tmp_path / "elsewhere"
    os.rename(session_dir / "arrays", elsewhere)
    os.unlink(session_dir / "truth" / "inner")
    os.symlink(elsewhere, session_dir / "truth" / "inner")
    rejected(session_dir, r"s/truth/inner/x\.npy: is a link to .*outside the session directory")
    os.unlink(session_dir / "truth" / "inner")
    os.symlink("..", session_dir / "truth" / "loop")
    rejected(session_dir, r"s/truth/loop/truth: a link leads back to a folder already read")
