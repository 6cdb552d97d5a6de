"""Writes are atomic: a failure mid-write leaves no partial target and no leftovers."""

import pytest

import anklelab.data.directory as directory
import anklelab.data.hdf5 as hdf5
from anklelab.data import diff_sessions, load_session, save_session
from anklelab.data._synthetic import random_session

# the function each writer calls once per recording, to make fail part-way through
WRITERS = {"dir": (directory, "write_csv_recording"), "h5": (hdf5, "_write_layout")}


def fail_on_third_call(monkeypatch, fmt, error=None):
    module, name = WRITERS[fmt]
    real = getattr(module, name)
    calls = []

    def flaky(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise error or OSError("disk full")
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, flaky)
    return calls


def snapshot(root):
    paths = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
    return {str(p): p.read_bytes() for p in paths}


@pytest.mark.parametrize("fmt", ["dir", "h5"])
@pytest.mark.parametrize("error", [OSError("disk full"), KeyboardInterrupt()])
def test_failed_write_leaves_nothing(tmp_path, monkeypatch, fmt, error):
    calls = fail_on_third_call(monkeypatch, fmt, error)
    with pytest.raises(type(error)):
        save_session(random_session(), tmp_path / "out", format=fmt)
    assert len(calls) == 3  # it really failed part-way
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", ["dir", "h5"])
def test_failed_overwrite_keeps_previous_version(tmp_path, monkeypatch, fmt):
    old = random_session(seed=1)
    target = save_session(old, tmp_path / "out", format=fmt)
    before = snapshot(target)
    fail_on_third_call(monkeypatch, fmt)
    with pytest.raises(OSError, match="disk full"):
        save_session(random_session(seed=2), target, format=fmt)
    assert snapshot(target) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert diff_sessions(load_session(target), old, provenance=False) == []


@pytest.mark.parametrize("fmt", ["dir", "h5"])
def test_overwrite_replaces_and_cleans_up(tmp_path, fmt):
    target = save_session(random_session(seed=1), tmp_path / "out", format=fmt)
    new = random_session(seed=2)
    save_session(new, target, format=fmt)
    assert diff_sessions(load_session(target), new, provenance=False) == []
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


@pytest.mark.parametrize("fmt", ["dir", "h5"])
def test_overwrite_false_refuses(tmp_path, fmt):
    target = save_session(random_session(), tmp_path / "out", format=fmt)
    with pytest.raises(FileExistsError, match="already exists"):
        save_session(random_session(), target, format=fmt, overwrite=False)


@pytest.fixture
def interrupted():
    """A signal noted as the command line's handler notes it; forgotten afterwards."""
    from anklelab._atomic import forget_interrupts, note_interrupt

    note_interrupt(2)
    yield
    forget_interrupts()


def test_after_an_interrupt_nothing_is_committed(tmp_path, interrupted):
    """A signal whose exception was swallowed (a handler that fired inside ``__del__``) still
    keeps the outputs from being committed: the temporary is removed, the target untouched."""
    from anklelab._atomic import Interrupted, atomic_directory, write_text_atomic

    (tmp_path / "kept.txt").write_text("old")
    with pytest.raises(Interrupted):
        write_text_atomic(tmp_path / "kept.txt", "new")
    with pytest.raises(Interrupted), atomic_directory(tmp_path / "out") as building:
        (building / "results.json").write_text("{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]
    assert (tmp_path / "kept.txt").read_text() == "old"
