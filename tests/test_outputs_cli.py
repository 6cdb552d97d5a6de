"""Issue 11, the command side: no file is lost, runs never mix, outputs are checked before any
work, and a full or read-only disk ends in one ``error:`` line with nothing left behind."""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from anklelab._lock import output_lock
from anklelab._runs import RUN_FILE, RunManifest, sha256_file
from anklelab.data import load_session, save_session
from anklelab.data._synthetic import random_session
from anklelab.report.sections import WALKING_FIGURES


def anklelab(monkeypatch, capsys, *args):
    """Run the ``anklelab`` entry point in-process: (exit code, stdout, stderr)."""
    from anklelab.cli import run

    monkeypatch.setattr(sys, "argv", ["anklelab", *map(str, args)])
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        run()
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err


def one_error(err):
    """The single ``error:`` line of stderr (and no traceback)."""
    lines = [line for line in err.splitlines() if line.startswith("error: ")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def snapshot(root):
    paths = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
    return {str(p): p.read_bytes() for p in paths}


def must_not_run(monkeypatch, module, name):
    """Make ``module.name`` fail the test if called: the command must stop before the work."""

    def called(*args, **kwargs):
        raise AssertionError(f"{name} ran although the output was bad")

    monkeypatch.setattr(module, name, called)


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    """A small twin session (native file and directory) and quick analysis settings."""
    from anklelab.experiments import simulate_perturberator

    root = tmp_path_factory.mktemp("twin")
    session = simulate_perturberator(
        trials_per_point=4, n_unperturbed=8, n_calibration=2, bench=False, seed=3
    )
    settings = root / "settings.toml"
    settings.write_text("bootstrap_reps = 5\n")
    return save_session(session, root / "s.h5"), settings


@pytest.fixture
def user_session(tmp_path):
    """A user's session directory (no run manifest)."""
    return save_session(random_session(seed=7), tmp_path / "s", format="dir")


# --- data loss ------------------------------------------------------------------------------


def test_simulate_never_replaces_a_file_without_force(tmp_path, monkeypatch, capsys):
    import anklelab.experiments.perturberator as perturberator

    out = tmp_path / "x.h5"
    out.write_text("precious\n")
    must_not_run(monkeypatch, perturberator, "simulate_perturberator")
    args = ["simulate", "perturberator", "--out", out, "--trials-per-point", "2"]
    code, _, err = anklelab(monkeypatch, capsys, *args, "--unperturbed", "4")
    assert code == 2
    assert one_error(err) == f"error: --out {out}: already exists; pass --force to replace it"
    assert out.read_text() == "precious\n"


def test_simulate_never_replaces_a_users_session_even_with_force(user_session, monkeypatch, capsys):
    import anklelab.experiments.perturberator as perturberator

    before = snapshot(user_session)
    must_not_run(monkeypatch, perturberator, "simulate_perturberator")
    args = ["simulate", "perturberator", "--out", user_session, "--format", "dir", "--force"]
    code, _, err = anklelab(monkeypatch, capsys, *args)
    assert code == 2
    assert one_error(err).startswith(f"error: {user_session}: not replaced: it has no run.json")
    assert snapshot(user_session) == before


def test_simulated_session_directory_is_one_run_replaced_only_by_its_kind(
    tmp_path, twin, monkeypatch, capsys
):
    out = tmp_path / "twin_dir"
    args = ["simulate", "perturberator", "--out", out, "--format", "dir"]
    args += ["--trials-per-point", "1", "--unperturbed", "1", "--no-bench"]
    assert anklelab(monkeypatch, capsys, *args, "--seed", "1")[0] == 0
    first = RunManifest.load(out)
    code, _, err = anklelab(monkeypatch, capsys, *args, "--seed", "2")
    assert code == 2 and "already exists; pass --force" in one_error(err)
    assert anklelab(monkeypatch, capsys, *args, "--seed", "2", "--force")[0] == 0
    manifest = RunManifest.load(out)
    assert manifest.command == "simulate perturberator" and manifest.settings["seed"] == 2
    assert manifest.run_id != first.run_id
    files = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    assert files == {*manifest.files, RUN_FILE}
    assert all(sha256_file(out / name) == f["sha256"] for name, f in manifest.files.items())
    assert len(load_session(out).walking) == 5
    assert sorted(p.name for p in tmp_path.iterdir()) == ["twin_dir"]  # no temporaries
    # an analysis never replaces a session, even one it could recognise as a run output
    code, _, err = anklelab(monkeypatch, capsys, "analyze", twin[0], "--out", out, "--force")
    assert code == 2 and "holds a session (session.toml)" in one_error(err)


def test_analyze_refuses_an_output_inside_its_input(user_session, monkeypatch, capsys):
    import anklelab.pipelines.walking as walking

    before = snapshot(user_session)
    must_not_run(monkeypatch, walking, "analyze_walking")
    link = user_session.parent / "link"
    link.symlink_to(user_session)
    for out, message in [
        (user_session / "walking", f"lies inside the input {user_session}"),
        (link / "results", f"lies inside the input {user_session}"),
        (user_session / ".." / "s" / "x", f"lies inside the input {user_session}"),
        (user_session.parent, f"holds the input {user_session}"),
    ]:
        code, _, err = anklelab(monkeypatch, capsys, "analyze", user_session, "--out", out)
        assert code == 2 and message in one_error(err), (out, err)
    assert snapshot(user_session) == before


def test_outputs_are_checked_before_any_work(user_session, tmp_path, monkeypatch, capsys):
    import anklelab.data as data
    import anklelab.pipelines.walking as walking

    must_not_run(monkeypatch, walking, "analyze_walking")
    must_not_run(monkeypatch, data, "load_session")
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine")
    cases = [
        (("analyze", user_session, "--out", a_file), "a file, not a directory"),
        (("analyze", user_session, "--out", a_file / "o"), "notes.txt is not a directory"),
        (("import", user_session, "--out", tmp_path), "a directory; expected a file"),
        (("import", user_session, "--out", user_session / "s.h5"), "lies inside the input"),
        (("analyze", user_session, "--out", tmp_path / "link"), "a symbolic link"),
    ]
    (tmp_path / "link").symlink_to(tmp_path / "elsewhere")
    for args, message in cases:
        code, _, err = anklelab(monkeypatch, capsys, *args)
        assert code == 2 and message in one_error(err), (args, err)
    assert a_file.read_text() == "mine"


@pytest.mark.parametrize(
    ("flag", "free", "message"),
    [(os.ST_RDONLY, 10**9, "read-only file system"), (0, 100, "no space left on device")],
)
def test_read_only_or_full_file_system_fails_before_work(
    user_session, tmp_path, monkeypatch, capsys, flag, free, message
):
    import anklelab.commands._files as files
    import anklelab.data as data

    real = os.statvfs

    class Full:
        def __init__(self, path):
            stats = real(path)
            self.f_flag, self.f_frsize, self.f_bavail = stats.f_flag | flag, 1, free

    monkeypatch.setattr(files.os, "statvfs", Full)
    must_not_run(monkeypatch, data, "load_session")
    code, _, err = anklelab(monkeypatch, capsys, "import", user_session, "--out", tmp_path / "o.h5")
    assert code == 2 and message in one_error(err)


@pytest.mark.parametrize(
    ("number", "hint"),
    [
        (errno.ENOSPC, "No space left on device; nothing was written, free some space"),
        (errno.EROFS, "Read-only file system; write somewhere else"),
        (errno.EACCES, "Permission denied; check the permissions or write somewhere else"),
    ],
)
def test_a_failing_disk_while_writing_leaves_nothing(
    user_session, tmp_path, monkeypatch, capsys, number, hint
):
    from anklelab._atomic import is_temporary

    real = Path.write_bytes

    def refuse(path, data):  # the writer filling its temporary
        if is_temporary(path.name):
            raise OSError(number, os.strerror(number), str(path))
        return real(path, data)

    monkeypatch.setattr(Path, "write_bytes", refuse)
    out = tmp_path / "new" / "s.h5"
    code, _, err = anklelab(monkeypatch, capsys, "import", user_session, "--out", out)
    assert code == 2 and one_error(err) == f"error: {out}: {hint}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s"]  # not even the new parent


def test_disk_full_in_analyze_leaves_no_partial_directory(twin, tmp_path, monkeypatch, capsys):
    import anklelab.commands.analyze as analyze

    real = analyze.write_csv

    def full(path, rows):
        if path.name == "trials.csv":  # results.json and results.csv are already written
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(path, rows)

    monkeypatch.setattr(analyze, "write_csv", full)
    out = tmp_path / "o"
    args = ["analyze", twin[0], "--out", out, "--settings", twin[1], "--no-figures"]
    code, _, err = anklelab(monkeypatch, capsys, *args)
    assert code == 2
    assert one_error(err).startswith(f"error: {out}/trials.csv: No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_a_second_writer_fails_at_once_naming_the_lock(user_session, tmp_path, monkeypatch, capsys):
    out = tmp_path / "o.h5"
    with output_lock(out) as lock:
        code, _, err = anklelab(monkeypatch, capsys, "import", user_session, "--out", out)
    assert code == 2
    assert one_error(err) == (
        f"error: {out}: another anklelab process (pid {os.getpid()}) is writing it "
        f"(lock {lock}); wait for it to finish, or choose another output"
    )
    assert not out.exists()


# --- runs never mix -------------------------------------------------------------------------


def test_analysis_output_is_one_run_and_report_shows_only_it(twin, tmp_path, monkeypatch, capsys):
    """The issue's reproducer: analyze with figures, then without into the same directory."""
    session, settings = twin
    out = tmp_path / "o"
    base = ["analyze", session, "--out", out, "--settings", settings]
    assert anklelab(monkeypatch, capsys, *base)[0] == 0
    assert len(list(out.glob("*.png"))) == len(WALKING_FIGURES)
    code, _, err = anklelab(monkeypatch, capsys, *base, "--no-figures", "--seed", "9")
    assert code == 2 and "already exists; pass --force" in one_error(err)
    assert anklelab(monkeypatch, capsys, *base, "--no-figures", "--seed", "9", "--force")[0] == 0
    assert list(out.glob("*.png")) == []  # the old run's figures went with it
    manifest = RunManifest.load(out)
    assert manifest.command == "analyze" and manifest.settings["seed"] == 9
    assert set(manifest.files) == {"results.json", "results.csv", "trials.csv"}
    assert (
        manifest.inputs[0]["sha256"]
        == json.loads((out / "results.json").read_text())["session_sha256"]
    )
    code, _, err = anklelab(monkeypatch, capsys, "report", out)
    assert code == 0 and "figures not found" in err
    assert 'src="data:image/png' not in (out / "report.html").read_text()
    # an analysis output is not replaced by another command's output, even with --force
    ident = tmp_path / "ident"
    ident.mkdir()
    args = ["identify", "friction", ident, "--out", out, "--force"]
    code, _, err = anklelab(monkeypatch, capsys, *args)
    assert code == 2
    assert "it is an output of `anklelab analyze`, not of `anklelab identify friction`" in err


def test_capstan_ident_uses_force_and_keeps_its_run_manifest(tmp_path, monkeypatch, capsys):
    out = tmp_path / "ident"
    args = ["simulate", "capstan-ident", "--out", out]
    assert anklelab(monkeypatch, capsys, *args)[0] == 0
    assert RunManifest.load(out).command == "simulate capstan-ident"
    code, _, err = anklelab(monkeypatch, capsys, *args, "--overwrite")
    assert code == 2 and "No such option: --overwrite" in one_error(err)
    code, _, err = anklelab(monkeypatch, capsys, *args)
    assert code == 2 and "pass --force" in one_error(err)
    assert anklelab(monkeypatch, capsys, *args, "--force", "--seed", "5")[0] == 0
    assert RunManifest.load(out).settings["seed"] == 5


def test_report_never_replaces_its_inputs(twin, tmp_path, monkeypatch, capsys):
    session, settings = twin
    out = tmp_path / "o"
    args = ["analyze", session, "--out", out, "--settings", settings, "--no-figures"]
    assert anklelab(monkeypatch, capsys, *args)[0] == 0
    assert anklelab(monkeypatch, capsys, "report", out)[0] == 0
    code, _, err = anklelab(monkeypatch, capsys, "report", out)
    assert code == 2 and "report.html: already exists; pass --force" in one_error(err)
    assert anklelab(monkeypatch, capsys, "report", out, "--force")[0] == 0
    for name in ("results.json", RUN_FILE):
        code, _, err = anklelab(monkeypatch, capsys, "report", out, "--out", out / name, "--force")
        assert code == 2 and "lies inside the input" in one_error(err)
    assert RunManifest.load(out).read("results.json", limit=1 << 20)  # untouched


# --- a real full and read-only file system (a small tmpfs in a private mount namespace) ----


def in_tmpfs(script, options):
    """Run ``script`` (shell) with a fresh tmpfs mounted at $MNT; None if not possible here."""
    if shutil.which("unshare") is None:
        return None
    probe = subprocess.run(
        ["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt"],
        capture_output=True,
    )
    if probe.returncode != 0:
        return None
    wrapped = f"mount -t tmpfs -o {options} tmpfs /mnt && MNT=/mnt && {script}"
    return subprocess.run(
        ["unshare", "-rm", "sh", "-c", wrapped],
        capture_output=True,
        text=True,
        env=os.environ | {"PYTHON": sys.executable},
    )


ANKLELAB = '"$PYTHON" -c "from anklelab.cli import run; run()"'


@pytest.fixture(scope="module")
def big_session(tmp_path_factory):
    """A 7 MB session: more than the small file systems below hold."""
    session = random_session(n_walking=40, n_samples=2000)
    return save_session(session, tmp_path_factory.mktemp("big") / "big.h5")


@pytest.mark.parametrize(
    ("options", "command", "message"),
    [
        (  # checked before writing: the HDF5 writer cannot fail cleanly on a full disk
            "size=512k",
            "import {big} --out $MNT/s.h5",
            "/mnt/s.h5: no space left on device: it needs about 7.47 MB, 0.52 MB are free; "
            "nothing was written",
        ),
        (  # full while writing CSV files
            "size=512k",
            "simulate capstan-ident --out $MNT/ident",
            "/mnt/ident: No space left on device; nothing was written, free some space",
        ),
        (
            "size=1m,ro",
            "import {big} --out $MNT/s.h5",
            "/mnt/s.h5: cannot be written: read-only file system",
        ),
    ],
)
def test_real_full_and_read_only_file_systems(big_session, options, command, message):
    script = f'{ANKLELAB} {command.format(big=big_session)}; echo "rc=$?"; ls -A "$MNT"'
    proc = in_tmpfs(script, options)
    if proc is None:
        pytest.skip("no private mount namespace here (unshare -rm)")
    assert proc.stderr.strip().splitlines() == [f"error: {message}"]
    assert proc.stdout.split() == ["rc=2"]  # and the file system is empty: nothing left


def test_hdf5_writer_fails_cleanly_on_a_full_disk(big_session):
    """Without the command's space check: one OSError (h5py writing to the disk itself would
    report the full disk only when the file is closed, print errors from its destructors and
    crash the interpreter at exit)."""
    code = (
        "from anklelab.data import load_session, save_session\n"
        f"session = load_session({str(big_session)!r})\n"
        "try:\n    save_session(session, '/mnt/s.h5')\n"
        "except OSError as exc:\n    print('OSError', exc.errno)\n"
    )
    proc = in_tmpfs(f'"$PYTHON" -c "{code}"; echo "rc=$?"; ls -A "$MNT"', "size=512k")
    if proc is None:
        pytest.skip("no private mount namespace here (unshare -rm)")
    assert proc.stdout.split() == ["OSError", "28", "rc=0"] and proc.stderr == ""


# --- interrupted runs ---------------------------------------------------------------------


def test_an_interrupt_inside_a_finaliser_is_not_printed_as_a_traceback():
    """A signal handled inside ``__del__`` or a weak-reference callback cannot unwind from there;
    Python hands the exception to ``sys.unraisablehook``, which the command line keeps quiet
    about it (the interruption stops the next commit instead); other such errors still show."""
    from types import SimpleNamespace

    from anklelab._atomic import Interrupted
    from anklelab.cli import _unraisable

    shown = []
    hook = _unraisable(shown.append)
    hook(SimpleNamespace(exc_value=Interrupted(2)))
    assert shown == []
    other = SimpleNamespace(exc_value=ValueError("a real problem"))
    hook(other)
    assert shown == [other]


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT])
def test_an_interrupted_run_removes_its_temporaries(twin, tmp_path, number):
    """SIGTERM or SIGINT while the output is being built: one line, nothing left behind."""
    from anklelab._atomic import is_temporary

    args = ["analyze", twin[0], "--out", tmp_path / "o", "--settings", twin[1]]
    code = "from anklelab.cli import run; run()"
    proc = subprocess.Popen(
        [sys.executable, "-c", code, *map(str, args)], stderr=subprocess.PIPE, text=True
    )
    while proc.poll() is None and not any(is_temporary(p.name) for p in tmp_path.iterdir()):
        time.sleep(0.02)
    proc.send_signal(number)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 128 + number
    name = signal.Signals(number).name
    assert err.strip().splitlines()[-1] == (
        f"error: interrupted by {name}; unfinished outputs were removed"
    )
    assert "Traceback" not in err and list(tmp_path.iterdir()) == []
