"""Every script in examples/ runs to completion, writing only into the directory it is given."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


def test_examples_are_numbered_and_documented():
    assert len(EXAMPLES) >= 5
    for script in EXAMPLES:
        assert script.name[:3].rstrip("_").isdigit(), script.name
        assert script.read_text(encoding="utf-8").startswith('"""'), f"{script.name}: docstring"


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(script, tmp_path):
    out = tmp_path / "out"
    env = os.environ | {"MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, str(script), str(out)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, f"{script.name} failed:\n{proc.stdout}\n{proc.stderr}"
    assert proc.stdout.strip(), f"{script.name} printed nothing"
    assert sorted(p.name for p in tmp_path.iterdir()) in (["out"], []), (
        f"{script.name} wrote outside its output directory"
    )
