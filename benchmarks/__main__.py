"""Run every benchmark module (``bench_*.py``) and print one table."""

from __future__ import annotations

import importlib
import pkgutil

import benchmarks
from benchmarks._harness import report


def main() -> None:
    results = []
    for info in sorted(pkgutil.iter_modules(benchmarks.__path__), key=lambda m: m.name):
        if info.name.startswith("bench_"):
            results += importlib.import_module(f"benchmarks.{info.name}").run()
    report(results)


if __name__ == "__main__":
    main()
