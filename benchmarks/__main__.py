"""Run every benchmark module (``bench_*.py``) and print one table."""

from __future__ import annotations

import importlib
import os
import pkgutil
import tempfile

import benchmarks
from benchmarks._harness import report


def _bytecode_as_installed(cache: str) -> None:
    """Give every process the benchmarks start Python's bytecode cache, as an installed package
    has it. A shell that sets ``PYTHONDONTWRITEBYTECODE`` would otherwise have each whole-process
    run compile the package's modules from source again (about 0.1 s of a paper-size
    ``analyze``, and as much again in its figure workers), which no user waits for. The cache
    lies outside the project (``PYTHONPYCACHEPREFIX``); each benchmark's warm-up run fills it."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = cache


def main() -> None:
    results = []
    with tempfile.TemporaryDirectory(prefix="anklelab-bench-pycache-") as cache:
        _bytecode_as_installed(cache)
        for info in sorted(pkgutil.iter_modules(benchmarks.__path__), key=lambda m: m.name):
            if info.name.startswith("bench_"):
                results += importlib.import_module(f"benchmarks.{info.name}").run()
    report(results)


if __name__ == "__main__":
    main()
