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
    unit: str = "s"
    """What ours_s and baseline_s count: seconds, or "MiB" for peak memory rows."""

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
    print(f"{'benchmark':56s} {'ours':>10s} {'baseline':>10s} {'ratio':>7s}  baseline")
    for r in results:
        ours, base = (
            (f"{r.ours_s:8.4f} s", f"{r.baseline_s:8.4f} s")
            if r.unit == "s"
            else (f"{r.ours_s:6.0f} {r.unit}", f"{r.baseline_s:6.0f} {r.unit}")
        )
        print(f"{r.name:56s} {ours:>10s} {base:>10s} {r.speedup:6.1f}x  {r.baseline}")
