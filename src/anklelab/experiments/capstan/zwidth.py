"""The Z-width measured on the twin, with a human-like ankle on the platform, next to the
analytic boundary (:mod:`anklelab.control.zwidth`); and what the passivity controller costs.

A trial renders ``K`` and ``B`` by impedance about level while the foot pushes once, then
lets go: a *stomp* (40 N·m for 30 ms, enough to swing the platform into the sampled-viscous
mode) or a *nudge* (10 N·m for 40 ms, which only the quantisation mode turns into a buzz). The
rendering is *stable* when, in the last second of a 3 s trial, the platform has come to rest
(the rms of its true angle's change per tick below 1e-5 rad) and no fault latched. The person
guard is off: the rendering itself is measured. For each virtual damping, bisection (in
log stiffness) finds the largest stable stiffness.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.haptics import VirtualEnvironment
from anklelab.control.zwidth import ZWidthBoundary, zwidth_boundary
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.experiments.capstan.rendering import RenderMetrics, render

__all__ = [
    "PUSHES",
    "PassivityCost",
    "ZWidthMeasurement",
    "analytic_zwidth",
    "measure_zwidth",
    "passivity_cost",
    "push_trial",
]

PUSHES = {"stomp": (40.0, 0.03), "nudge": (10.0, 0.04)}
"""Name: (torque N·m, duration s) of the foot's push."""
TRIAL_S, PUSH_AT_S, AT_REST_RAD = 3.0, 0.3, 1e-5


def push_trial(
    setup: CapstanSetup,
    stiffness_nm_per_rad: float,
    damping_nms_per_rad: float,
    push: str,
    *,
    seed: int | np.random.Generator = 0,
) -> bool:
    """Render ``K``, ``B`` while the foot pushes once; True if the platform comes to rest."""
    if push not in PUSHES:
        raise ParameterError(f"push must be one of {list(PUSHES)}; got {push!r}")
    torque, width = PUSHES[push]
    n = round(TRIAL_S * setup.fs)
    voluntary = np.zeros(n)
    start = round(PUSH_AT_S * setup.fs)
    voluntary[start : start + round(width * setup.fs)] = torque
    env = VirtualEnvironment(
        stiffness_nm_per_rad=stiffness_nm_per_rad, damping_nms_per_rad=damping_nms_per_rad
    )
    run = simulate_closed_loop(
        dataclasses.replace(setup, guard=False),
        n,
        mode="impedance",
        voluntary=voluntary,
        environment=env,
        seed=seed,
    )
    last = run["angle_rad"][-round(setup.fs) :]
    return bool(run["fault"].max() == 0 and np.std(np.diff(last)) < AT_REST_RAD)


@dataclass(frozen=True)
class ZWidthMeasurement:
    """The largest stable stiffness per virtual damping, by push, and the analytic boundary.

    Attributes
    ----------
    damping_nms_per_rad : ndarray
        Virtual damping.
    measured_nm_per_rad : dict of str to ndarray
        Per push (:data:`PUSHES`), the bisection's largest stable stiffness.
    analytic : ZWidthBoundary
        The sampled-data passivity boundary for the same platform, rate, filter and ankle.
    """

    damping_nms_per_rad: NDArray[np.float64]
    measured_nm_per_rad: dict[str, NDArray[np.float64]]
    analytic: ZWidthBoundary

    def error_percent(self, push: str, mode: str) -> NDArray[np.float64]:
        """``100 (measured - analytic) / analytic`` for a push and a mode (``viscous`` or
        ``quantization``); NaN where the analytic boundary is 0 (nothing renders passively)."""
        a = self.analytic
        reference = np.broadcast_to(
            a.viscous_nm_per_rad if mode == "viscous" else a.quantization_nm_per_rad,
            self.damping_nms_per_rad.shape,
        )
        with np.errstate(divide="ignore", invalid="ignore"):
            error = 100.0 * (self.measured_nm_per_rad[push] - reference) / reference
        return np.where(reference > 0, error, np.nan)


def analytic_zwidth(setup: CapstanSetup, damping_nms_per_rad: ArrayLike) -> ZWidthBoundary:
    """The analytic boundary for this setup's platform, rate, speed filter and ankle."""
    person = setup.person is not None
    ankle = None
    if person:
        human = setup.resolved_human()
        ankle = human.human.damping_nms_per_rad_per_kg * human.gait.body_mass_kg
    return zwidth_boundary(
        damping_nms_per_rad,
        setup.params,
        setup.fs,
        velocity_filter_hz=setup.resolved_gains().velocity_filter_hz,
        user=setup.foot(),
        ankle_damping_nms_per_rad=ankle,
    )


def measure_zwidth(
    setup: CapstanSetup,
    damping_nms_per_rad: ArrayLike,
    *,
    pushes: tuple[str, ...] = ("stomp", "nudge"),
    stiffness_range: tuple[float, float] = (100.0, 300000.0),
    iterations: int = 12,
    seed: int | np.random.Generator = 0,
) -> ZWidthMeasurement:
    """Bisect (log stiffness) for the largest stable stiffness at each damping and push.

    Parameters
    ----------
    setup : CapstanSetup
        Platform, rate, and who is on it (the human-like ankle).
    damping_nms_per_rad : array_like
        Virtual damping values.
    pushes : tuple of str
        Which pushes (:data:`PUSHES`).
    stiffness_range : (float, float)
        The bisection's bracket, N·m/rad; its low end must render stably.
    iterations : int
        Bisection steps.
    seed : int
        Sensor noise.
    """
    damping = np.asarray(damping_nms_per_rad, dtype=float)
    low, high = stiffness_range
    if not 0 < low < high or not isinstance(iterations, int) or iterations < 1:
        raise ParameterError("expected 0 < low < high stiffness and iterations >= 1")
    measured = {}
    for push in pushes:
        boundary = []
        for b in damping:
            lo, hi = low, high
            for _ in range(iterations):
                mid = math.sqrt(lo * hi)
                if push_trial(setup, mid, b, push, seed=seed):
                    lo = mid
                else:
                    hi = mid
            boundary.append(lo)
        measured[push] = np.array(boundary)
    return ZWidthMeasurement(damping, measured, analytic_zwidth(setup, damping))


@dataclass(frozen=True)
class PassivityCost:
    """Impedance rendering of one ``(K, B)`` without and with the passivity controller.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad : float
        Commanded.
    without, with_control : RenderMetrics
        What the foot felt.
    dissipated_j : float
        Energy the controller took out of the rendering over the trial (its damping torque
        times the platform's motion).
    """

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float
    without: RenderMetrics
    with_control: RenderMetrics
    dissipated_j: float


def passivity_cost(
    setup: CapstanSetup,
    settings: list[tuple[float, float]],
    *,
    duration_s: float = 20.0,
    seed: int | np.random.Generator = 0,
) -> list[PassivityCost]:
    """Felt stiffness and damping without and with the passivity controller, per ``(K, B)``."""
    out = []
    for k, b in settings:
        env = VirtualEnvironment(stiffness_nm_per_rad=k, damping_nms_per_rad=b)
        _, plain = render(
            dataclasses.replace(setup, passivity_control=False),
            env,
            mode="impedance",
            duration_s=duration_s,
            seed=seed,
        )
        run, controlled = render(
            dataclasses.replace(setup, passivity_control=True),
            env,
            mode="impedance",
            duration_s=duration_s,
            seed=seed,
        )
        nominal = -k * run["measured_angle_rad"] - b * run["speed_estimate_rad_s"]
        extra = run["rendered_torque_nm"] - nominal
        dissipated = float(-np.sum(extra[:-1] * np.diff(run["measured_angle_rad"])))
        out.append(PassivityCost(k, b, plain, controlled, dissipated))
    return out
