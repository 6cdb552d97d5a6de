"""One small twin session shared by the lab-format tests (simulated once per test process)."""

from __future__ import annotations

from functools import cache

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
