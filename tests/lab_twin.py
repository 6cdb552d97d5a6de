"""One small twin session shared by the lab-format tests (simulated once per test process)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from anklelab.experiments import simulate_perturberator


@cache
def small_twin(seed: int = 3, bench: bool = False):
    """5 perturbed trials per timing point, 10 unperturbed, 2 calibration trials."""
    return simulate_perturberator(
        trials_per_point=5,
        n_unperturbed=10,
        n_calibration=2,
        seed=seed,
        bench=bench,
        time_courses=False,
    )


def with_twin_delay(shipped: Path, session, directory: Path, old: str = "", new: str = "") -> Path:
    """A shipped example map (which leaves ``delay_ms`` at 0) with the twin ``session``'s
    amplifier delay, and ``old`` replaced by ``new``, written into ``directory``."""
    text = shipped.read_text()
    assert text.count("delay_ms = 0.0") == 1, f"{shipped.name}: expected one 'delay_ms = 0.0'"
    assert old in text, f"{shipped.name}: no {old!r}"
    path = directory / f"twin_{shipped.name}"
    delay = f"delay_ms = {session.info.force_delay_ms!r}"
    path.write_text(text.replace("delay_ms = 0.0", delay).replace(old, new))
    return path
