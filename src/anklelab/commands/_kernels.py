"""Say so when a command is about to compile the twin's kernel (the first run after install)."""

from __future__ import annotations

from collections.abc import Callable

from anklelab.platforms.perturberator import PerturberatorParameters

__all__ = ["prepare_kernel"]


def prepare_kernel(
    params: PerturberatorParameters, task: Callable[[str], Callable[[int, int], None]]
) -> None:
    """Compile the Perturberator twin's kernel now, under one progress line, if it must be.

    numba caches the compiled kernel on disk, so this happens once per install (and after an
    upgrade); every later run loads it in a fraction of a second and prints nothing.
    """
    from anklelab.experiments import simulate_perturberator
    from anklelab.sim.drivetrain import kernel_needs_compiling

    if kernel_needs_compiling():
        progress = task("compiling simulation kernels, once")
        # a walking protocol of four one-trial points: the platform kernel and the trigger's
        simulate_perturberator(params, trials_per_point=1, n_unperturbed=1, n_calibration=0,
                               bench=False, time_courses=False, threads=1)  # fmt: skip
        progress(1, 1)
