"""The ``anklelab`` entry point run in-process by a test, as a user runs it."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest


def run_anklelab(
    args: list[str],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    cwd: Path | None = None,
) -> tuple[int, str, str]:
    """Run ``anklelab ARGS`` (in ``cwd`` if given): (exit code, stdout, stderr)."""
    from anklelab.cli import run

    if cwd is not None:
        monkeypatch.chdir(cwd)
    monkeypatch.setattr(sys, "argv", ["anklelab", *args])
    capsys.readouterr()
    try:
        run()
        code = 0
    except SystemExit as exit:
        code = exit.code if isinstance(exit.code, int) else 1
    captured = capsys.readouterr()
    return code, captured.out, captured.err
