"""Tiny timing harness: best-of-N wall time of ours vs a baseline, printed as one table row."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Result:
    name: str
    ours_s: float
    baseline_s: float
    baseline: str

    @property
    def speedup(self) -> float:
        return self.baseline_s / self.ours_s


def best_time(func: Callable[[], object], repeat: int = 3) -> float:
    """Best wall time of ``repeat`` calls, s (after one warm-up call, e.g. for JIT compilation)."""
    func()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def compare(
    name: str,
    ours: Callable[[], object],
    baseline: Callable[[], object],
    baseline_name: str,
    repeat: int = 3,
) -> Result:
    """Time ``ours`` and ``baseline`` and return the row."""
    return Result(name, best_time(ours, repeat), best_time(baseline, repeat), baseline_name)


def report(results: list[Result]) -> None:
    """Print the results as an aligned table."""
    print(f"{'benchmark':44s} {'ours (s)':>10s} {'baseline (s)':>13s} {'speed-up':>9s}  baseline")
    for r in results:
        print(f"{r.name:44s} {r.ours_s:10.4f} {r.baseline_s:13.4f} {r.speedup:8.1f}x  {r.baseline}")
