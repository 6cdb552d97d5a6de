"""``anklelab design`` as a command: its options checked before any output, and what a failed
design leaves behind."""

from __future__ import annotations

from pathlib import Path

from anklelab.studies import checkpoint_for
from tests.cli_in_process import run_anklelab


def test_a_pilot_count_beyond_the_twin_names_the_option_before_any_output(
    tmp_path: Path, monkeypatch, capsys
):
    """``--pilot 10,2000`` was refused by the pilot study's internal key, twin.trials_per_point,
    once the output was staged."""
    out = tmp_path / "design"
    code, _, err = run_anklelab(
        ["design", "--out", str(out), "--pilot", "10,2000"], monkeypatch, capsys
    )
    assert code == 2
    assert err.strip().splitlines() == [
        "error: --pilot: expected two or more counts from 2 to 1000 trials per timing point, "
        "got [10, 2000]"
    ]
    assert list(tmp_path.iterdir()) == [] and not checkpoint_for(out).exists()


def test_a_target_out_of_reach_leaves_no_scratch_directory(tmp_path: Path, monkeypatch, capsys):
    """The pilot ran, then ±0.1 % was out of reach: the kept pilot sessions stayed behind in
    the hidden directory beside the output, which only a resumed run would use."""
    settings = tmp_path / "settings.toml"
    settings.write_text("bootstrap_reps = 10\n", encoding="utf-8")
    out = tmp_path / "design"
    args = ["design", "--out", str(out), "--pilot", "3,4", "--seeds", "1", "--interval", "0.1",
            "--settings", str(settings), "--workers", "1"]  # fmt: skip
    code, _, err = run_anklelab(args, monkeypatch, capsys)
    assert code == 2
    assert err.strip().splitlines()[-1].startswith("error: design: ±0.1 % is out of reach at ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["settings.toml"]


def test_workers_with_a_running_cluster_are_refused_before_any_output(
    tmp_path: Path, monkeypatch, capsys
):
    out = tmp_path / "design"
    args = ["design", "--out", str(out), "--scheduler", "tcp://127.0.0.1:9", "--workers", "2"]
    code, _, err = run_anklelab(args, monkeypatch, capsys)
    assert code == 2 and err.startswith("error: --workers: a running Dask cluster")
    assert list(tmp_path.iterdir()) == []
