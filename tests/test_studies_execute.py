"""Running tasks on Dask (:mod:`anklelab.studies.execute`): the store of finished tasks, retries,
dead workers, workers of other code, and what a run leaves behind."""

from __future__ import annotations

import os
import warnings

import pytest

from anklelab.errors import AnklelabWarning, ParameterError
from anklelab.studies.execute import ResultStore, Task, run_tasks


@pytest.mark.parametrize(
    ("record", "reason"),
    [
        ({"ok": True}, r"no 'rows'"),
        ({"ok": False}, r"no 'error'"),
        ({"rows": []}, r"no 'ok'"),
        ({"ok": "yes", "rows": []}, r"no 'ok'"),
    ],
)
def test_a_kept_result_that_is_json_but_no_result_is_computed_again(tmp_path, record, reason):
    """``{"ok": true}`` was taken for a finished session: the study then failed on a KeyError."""
    store = ResultStore(tmp_path, fields=("rows",))
    store.write("k", record)
    with pytest.warns(AnklelabWarning, match=rf"k\.json: an earlier run's result is unreadable "
                                             rf"\({reason}"):  # fmt: skip
        assert not store.has("k")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = run_tasks([Task("k", dict, ())], store, workers=1)
    assert run["ran"] == 1
    # the kept file is this task's: it is not "none of its stored results is for these tasks"
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1 and "unreadable" in messages[0], messages


def test_a_kept_result_or_failure_is_reused(tmp_path, recwarn):
    store = ResultStore(tmp_path, fields=("rows",))
    store.write("done", {"ok": True, "attempts": 1, "rows": []})
    store.write("failed", {"ok": False, "attempts": 2, "error": "E: x"})
    assert store.has("done") and store.has("failed") and not recwarn.list


def test_a_dead_worker_process_fails_its_task_and_the_others_go_on(tmp_path):
    """On the default scheduler a worker process that died (out of memory, a crash) broke the
    pool: the study ended in a BrokenProcessPool traceback, where a cluster records the task."""
    store = ResultStore(tmp_path / "cells")
    tasks = [Task("dies", os._exit, (1,)), *(Task(key, dict, ()) for key in "abc")]
    run = run_tasks(tasks, store, workers=2, retries=1)
    assert run["ran"] == 4
    record = store.read("dies")
    assert record == {
        "ok": False,
        "attempts": 2,
        "error": "the worker process running it died (out of memory, or killed?)",
    }
    assert all(store.read(key) == {"ok": True, "attempts": 1} for key in "abc")


def test_workers_of_other_anklelab_code_are_refused_naming_the_worker(tmp_path, monkeypatch):
    """A worker running another anklelab (here: this process claims other code) computed cells
    that were stored under this code's keys."""
    import anklelab.studies.execute as execute

    monkeypatch.setattr(execute, "code_fingerprint", lambda: "0123456789abcdef")
    store = ResultStore(tmp_path / "cells")
    match = (
        r"^--scheduler local-cluster: worker tcp://127\.0\.0\.1:\d+ runs anklelab \S+ "
        r"\(code [0-9a-f]{16}\); this command runs anklelab \S+ \(code 0123456789abcdef\)"
    )
    with pytest.raises(ParameterError, match=match):
        run_tasks([Task("k", dict, ())], store, scheduler="local-cluster", workers=1)
    assert not store.has("k")


def test_a_worker_that_joins_with_other_code_fails_its_tasks():
    from anklelab.studies.execute import _attempt_as

    record = _attempt_as(("0.0", "0123456789abcdef"), dict, (), 1)
    assert not record["ok"] and record["error"].startswith("this worker runs anklelab ")


def test_kept_results_of_other_sessions_are_named_as_removed_when_the_run_completes(tmp_path):
    """A command's hidden store of finished sessions is removed when its run completes: a
    resumed run that can use none of them says so before they are lost."""
    from anklelab.studies import checkpoint_for

    store = ResultStore(checkpoint_for(tmp_path / "out"))
    store.write("computed-by-other-code", {"ok": True})
    match = (r"none of its 1 stored results is for these sessions .*: all 1 run; the kept "
             r"sessions will be removed when this run completes")  # fmt: skip
    with pytest.warns(AnklelabWarning, match=match):
        run_tasks([Task("k", dict, ())], store, workers=1)


def test_a_command_prints_warnings_as_warning_lines(capsys):
    """Warnings came out as Python's ``FILE:LINE: AnklelabWarning: ...`` with source paths."""
    from anklelab.commands.study import warning_lines

    with warning_lines():
        warnings.warn("kept results\n  are unreadable", AnklelabWarning, stacklevel=1)
    assert capsys.readouterr().err == "warning: kept results are unreadable\n"


def test_workers_with_a_running_cluster_are_refused(tmp_path):
    """``--workers`` was ignored without a word with ``--scheduler tcp://...``: a running
    cluster has the workers it has."""
    from anklelab.studies.execute import check_scheduler

    match = r"^--workers: a running Dask cluster \(--scheduler tcp://127\.0\.0\.1:9\) has its own"
    with pytest.raises(ParameterError, match=match):
        run_tasks([Task("k", dict, ())], ResultStore(tmp_path), scheduler="tcp://127.0.0.1:9",
                  workers=2)  # fmt: skip
    check_scheduler("local-cluster", 2)
    check_scheduler("tcp://127.0.0.1:9", None)


def test_a_local_cluster_leaves_nothing_in_the_temporary_directory(tmp_path, monkeypatch):
    """Dask's workers kept their scratch space in TMPDIR/dask-scratch-space, left behind."""
    import tempfile

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    monkeypatch.setattr(tempfile, "tempdir", None)  # read TMPDIR again
    store = ResultStore(tmp_path / "cells")
    run_tasks([Task("k", dict, ())], store, scheduler="local-cluster", workers=1)
    assert store.has("k") and list(scratch.iterdir()) == []
