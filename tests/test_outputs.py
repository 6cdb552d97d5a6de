"""Output safety building blocks: temporaries and their reaping, the directory swap, the lock,
the run manifest."""

import json
import os
import subprocess
import sys

import pytest

from anklelab._atomic import (
    _temporary,
    atomic_directory,
    atomic_file,
    is_temporary,
    reap_temporaries,
    untemporary,
    write_text_atomic,
)
from anklelab._lock import lock_path, output_lock, reap_locks
from anklelab._runs import RUN_FILE, NotEmbeddable, RunManifest, read_inside, write_run_manifest
from anklelab.errors import OutputError, ResultsFormatError


def dead_pid():
    """The process id of a process that has ended."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def temporary_of(pid, target):
    name = _temporary(target).name
    head, _, tail = name.rpartition(f"-{os.getpid()}-")
    return target.parent / f"{head}-{pid}-{tail}"


def test_temporaries_name_their_process_and_map_back_to_the_target(tmp_path):
    tmp = _temporary(tmp_path / "out")
    assert is_temporary(tmp.name) and f"-{os.getpid()}-" in tmp.name and tmp.name[0] == "."
    nested = _temporary(tmp) / "results.json"  # a temporary built beside a temporary
    assert (
        untemporary(f"error: {nested}: disk full")
        == f"error: {tmp_path}/out/results.json: disk full"  # both names map back
    )
    assert untemporary(str(_temporary(tmp_path / "bode.png", ".png"))) == str(tmp_path / "bode.png")
    assert not is_temporary("out.tmp") and not is_temporary(".out.anklelab.lock")


def test_reaping_removes_only_temporaries_of_dead_processes(tmp_path):
    gone = dead_pid()
    stale_file = temporary_of(gone, tmp_path / "s.h5")
    stale_file.write_bytes(b"half a session")
    stale_dir = temporary_of(gone, tmp_path / "out")
    (stale_dir / "sub").mkdir(parents=True)
    (stale_dir / "sub" / "x.csv").write_text("1")
    ours = _temporary(tmp_path / "mine")  # this process is alive
    ours.write_text("in progress")
    other_host = tmp_path / stale_file.name.replace(stale_file.name.split("-")[1], "abcdef")
    other_host.write_text("another machine's")
    user = tmp_path / ".notes.tmp"
    user.write_text("a user's own hidden file")
    assert sorted(reap_temporaries(tmp_path)) == sorted([stale_file, stale_dir])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [ours.name, other_host.name, user.name]
    )


def test_next_write_reaps_what_a_killed_writer_left(tmp_path):
    stale = temporary_of(dead_pid(), tmp_path / "a.json")
    stale.write_text("{")
    write_text_atomic(tmp_path / "b.json", "{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.json"]


def test_directory_is_swapped_in_one_step_and_the_old_one_removed(tmp_path):
    target = tmp_path / "out"
    with atomic_directory(target, marker=RUN_FILE) as tmp:
        (tmp / RUN_FILE).write_text("{}")
        (tmp / "old.png").write_text("old")
    with atomic_directory(target, marker=RUN_FILE) as tmp:
        (tmp / RUN_FILE).write_text("{}")
    assert sorted(p.name for p in target.iterdir()) == [RUN_FILE]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_an_empty_directory_is_replaced_and_a_foreign_one_is_not(tmp_path):
    (tmp_path / "empty").mkdir()
    with atomic_directory(tmp_path / "empty", overwrite=False) as tmp:
        (tmp / "x").write_text("1")
    assert (tmp_path / "empty" / "x").read_text() == "1"
    with pytest.raises(FileExistsError, match=r"has no session\.toml"):
        with atomic_directory(tmp_path / "empty"):
            pass
    with pytest.raises(FileExistsError, match="already exists"):
        with atomic_file(tmp_path / "empty" / "x", overwrite=False):
            pass


def test_lock_refuses_a_second_writer_naming_the_lock_and_the_process(tmp_path):
    target = tmp_path / "out"
    with output_lock(target) as lock:
        assert lock == lock_path(target) and lock.read_text().strip() == str(os.getpid())
        with pytest.raises(
            OutputError, match=rf"pid {os.getpid()}\) .*lock .*\.out\.anklelab\.lock"
        ):
            with output_lock(target):
                pass
    assert not lock.exists()  # released and removed
    with output_lock(target):  # free again
        pass


def test_lock_held_by_another_process(tmp_path):
    target = tmp_path / "out"
    code = (
        "import sys, time; from anklelab._lock import output_lock\n"
        f"with output_lock({str(target)!r}):\n    print('locked', flush=True); time.sleep(30)\n"
    )
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(OutputError, match=f"pid {holder.pid}"):
            with output_lock(target):
                pass
    finally:
        holder.kill()
        holder.wait()
    with output_lock(target):  # the kernel released it with the killed process
        pass


def test_run_manifest_lists_every_file_and_read_checks_them(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.json").write_text('{"k": 1}')
    (tmp_path / "sub" / "b.csv").write_text("x\n1\n")
    written = write_run_manifest(
        tmp_path, command="analyze", settings={"seed": 1}, inputs=[("s.h5", "0" * 64)]
    )
    document = json.loads((tmp_path / RUN_FILE).read_text())
    assert document["format"] == "anklelab-run/1" and document["command"] == "analyze"
    assert set(document["files"]) == {"a.json", "sub/b.csv"}
    assert document["inputs"][0]["path"] == os.path.abspath("s.h5")
    manifest = RunManifest.load(tmp_path)
    assert manifest.run_id == written.run_id and len(manifest.run_id) == 32
    assert manifest.read("a.json", limit=100) == b'{"k": 1}'
    (tmp_path / "a.json").write_text('{"k": 2}')
    with pytest.raises(NotEmbeddable, match="changed since the run wrote it"):
        manifest.read("a.json", limit=100)
    (tmp_path / "c.png").write_bytes(b"x")
    with pytest.raises(NotEmbeddable, match="not written by the run"):
        manifest.read("c.png", limit=100)


def test_read_inside_refuses_links_fifos_and_large_files(tmp_path):
    outside = tmp_path / "secret"
    outside.write_text("secret")
    out = tmp_path / "o"
    out.mkdir()
    (out / "link.png").symlink_to(outside)
    (out / "inner.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (out / "alias.png").symlink_to(out / "inner.png")
    os.mkfifo(out / "fifo.png")
    (out / "big.png").write_bytes(b"0" * 101)
    for name, message in [
        ("link.png", "leads outside"),
        ("alias.png", "a symbolic link"),
        ("fifo.png", "not a regular file"),
        ("big.png", "more than the 100"),
        ("../secret", "not a plain name"),
        ("absent.png", "not found"),
    ]:
        with pytest.raises(NotEmbeddable, match=message):
            read_inside(out, name, limit=100)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("[1", "not a valid run manifest"),
        ('{"format": "x"}', "expected an object with format"),
        ('{"format": "anklelab-run/1", "run_id": 1}', "run_id: expected text"),
        (
            '{"format": "anklelab-run/1", "run_id": "r", "command": "c", "anklelab_version": "v",'
            ' "files": {"a": {"size": 1, "sha256": "no"}}}',
            r"files\.a: expected \{size, sha256\}",
        ),
    ],
)
def test_malformed_run_manifest_is_an_error_naming_it(tmp_path, content, message):
    (tmp_path / RUN_FILE).write_text(content)
    with pytest.raises(ResultsFormatError, match=message):
        RunManifest.load(tmp_path)


def test_stale_lock_files_are_reaped_but_held_ones_kept(tmp_path):
    stale = lock_path(tmp_path / "old")
    stale.write_text("12345\n")  # its writer was killed: nobody holds it
    with output_lock(tmp_path / "busy") as held:
        assert reap_locks(tmp_path) == [stale]
        assert held.exists() and not stale.exists()
