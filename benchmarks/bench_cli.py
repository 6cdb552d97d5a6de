"""``anklelab --help`` as a whole process vs a CLI that imports its implementation up front.

Ours is the command as installed: its group lists every subcommand from its name and one-line
help and imports no command module (``anklelab.cli.COMMANDS``), so the figure is Python's
start-up, typer and the ``anklelab`` package. The baseline runs the same ``--help`` after
importing what the commands use (NumPy, SciPy's signal processing, matplotlib, the walking
analysis and the session stores), as a command-line program does that imports its
implementation at module level. Issue 14 asks for < 0.3 s warm.
"""

from __future__ import annotations

import subprocess
import sys

from benchmarks._harness import Result, compare

CLI = "from anklelab.cli import program; program()"  # the console script's entry point
EAGER = (
    "import numpy, scipy.signal, matplotlib.pyplot, anklelab.pipelines.walking.analysis, "
    "anklelab.data.store; " + CLI
)


def _help(code: str) -> None:
    subprocess.run([sys.executable, "-c", code, "--help"], check=True, stdout=subprocess.DEVNULL)


def run() -> list[Result]:
    return [
        compare(
            "anklelab --help (whole process)",
            lambda: _help(CLI),
            lambda: _help(EAGER),
            "implementation imported at start",
            repeat=5,
        )
    ]
