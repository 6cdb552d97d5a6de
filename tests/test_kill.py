"""A short kill campaign (the full one: ``python -m tests.kill_runs``): SIGKILL at random
points of a file and a directory output, two concurrent writers, SIGTERM."""

from tests.kill_runs import campaign, jobs


def test_killed_runs_never_leave_partial_or_mixed_outputs(tmp_path):
    names = ["import", "simulate capstan-ident"]
    assert set(names) <= {job.name for job in jobs()}
    tally = campaign(tmp_path, kills=4, pairs=1, terms=1, seed=1, names=names, repeat=False)
    assert tally.failures == []
    assert sum(tally.outcomes.values()) == 6
