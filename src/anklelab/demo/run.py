"""The end-to-end demonstration on both digital twins (what ``anklelab demo`` runs).

Paper 000, the Perturberator (:func:`run_perturberator`): simulate the session (calibration,
perturbed walking, bench tests) and store it, measure the servo's position loop with a PRBS,
and analyse the session as a user's would be analysed (platform filters, walking impedance with
bootstrap, bench comparison)::

    OUT/perturberator/session.h5      the simulated session, with its truth group
    OUT/perturberator/results.json    DESIGN.md section 5
    OUT/perturberator/servo_bode.json the measured loop figures

Paper 001, the capstan platform (:func:`run_capstan`): simulate the spin-down and torque-chirp
tests, identify friction and inertia from them, then control the platform (5, 10, 15 deg
set-points and the 5 deg chirp) without compensation and with gravity plus the *identified*
friction compensated, and estimate the user's torque with the disturbance observer (built on the
identified model) while the platform holds and tracks::

    OUT/capstan/ident/                DESIGN.md section 6 (with truth.json)
    OUT/capstan/friction/friction.json
    OUT/capstan/control.json          set-point, chirp and observer metrics

Every figure compared later comes from these runs; the twins' ground truth is kept beside it
(the session's truth, the platform parameters, the true angle and torque of each run).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal, TypedDict

import numpy as np
from pydantic import Field

from anklelab._atomic import write_json_atomic
from anklelab._params import Parameters
from anklelab.data import save_session, session_hash
from anklelab.data.capstan_ident import IdentData, write_ident_directory
from anklelab.data.session import Session
from anklelab.experiments.capstan import (
    CapstanSetup,
    ChirpMetrics,
    ObserverMetrics,
    StepMetrics,
    chirp_metrics,
    chirp_tracking,
    observer_trial,
    simulate_ident,
    step_metrics,
    step_response,
)
from anklelab.experiments.perturberator import simulate_perturberator
from anklelab.experiments.perturberator_bode import ServoBode, measure_servo_bode
from anklelab.ident.friction import FrictionIdentifier
from anklelab.pipelines.walking import STEPS, WalkingResults, WalkingSettings, analyze_walking
from anklelab.platforms import load_platform
from anklelab.sim.capstan import SimulationResult

__all__ = [
    "CHIRP",
    "CHIRP_DEG",
    "COMPENSATIONS",
    "OBSERVER_TASKS",
    "SETPOINTS_DEG",
    "CapstanDemo",
    "ChirpRun",
    "DemoSettings",
    "PerturberatorDemo",
    "StepRun",
    "run_capstan",
    "run_perturberator",
]

Task = Callable[[str], Callable[[int, int], None]]
"""``task(description)`` starts a progress bar and returns its ``update(done, total)``."""

SETPOINTS_DEG = (5.0, 10.0, 15.0)
"""Set-points of paper 001's Fig. 4, degrees."""
COMPENSATIONS = ("none", "gravity + friction")
"""Controller variants: PID alone; PID with gravity and the identified friction compensated."""
OBSERVER_TASKS: tuple[Literal["hold", "track"], ...] = ("hold", "track")
"""The platform holds level, or tracks a slow multisine, while the user pushes."""
CHIRP_DEG = 5.0


class _Chirp(TypedDict):
    """The chirp's keyword arguments of :func:`~anklelab.experiments.capstan.chirp_tracking`."""

    f0_hz: float
    f1_hz: float
    duration_s: float


CHIRP: _Chirp = {"f0_hz": 0.2, "f1_hz": 5.0, "duration_s": 10.0}
"""Paper 001's chirp (Fig. 5): 5 deg, 0.2 to 5 Hz over 10 s."""
PRE_S = 0.2  # rest before each set-point step, s (experiments.capstan.step_response's default)


class DemoSettings(Parameters):
    """How much of each experiment the demo runs.

    Attributes
    ----------
    seed : int
        Seed of every simulation and of the bootstrap.
    trials_per_point, n_unperturbed, n_calibration : int or None
        Perturberator session size; None takes the platform's protocol (paper 000: 100 per
        timing point, 400 unperturbed, 5 calibration trials).
    bootstrap_reps : int
        Bootstrap repetitions of the walking analysis (paper 000: 100).
    observer_duration_s : float
        Length of each observer trial, s.
    """

    seed: int = Field(0, ge=0)
    trials_per_point: int | None = Field(None, ge=2)
    n_unperturbed: int | None = Field(None, ge=2)
    n_calibration: int | None = Field(None, ge=2)
    bootstrap_reps: int = Field(100, ge=2)
    observer_duration_s: float = Field(20.0, ge=4.0)

    @classmethod
    def quick(cls, seed: int = 0) -> DemoSettings:
        """A small run for checks: 24 trials per timing point, 48 unperturbed, 3 calibration."""
        return cls(
            seed=seed,
            trials_per_point=24,
            n_unperturbed=48,
            n_calibration=3,
            bootstrap_reps=20,
            observer_duration_s=8.0,
        )

    def walking(self) -> WalkingSettings:
        """The walking-analysis settings (paper 000's, with this bootstrap size and seed)."""
        return WalkingSettings(bootstrap_reps=self.bootstrap_reps, seed=self.seed)


def _no_task(description: str) -> Callable[[int, int], None]:
    return lambda done, total: None


# ------------------------------------------------------------------------------- paper 000


@dataclass(frozen=True)
class PerturberatorDemo:
    """What the Perturberator part produced.

    Attributes
    ----------
    directory : Path
        ``OUT/perturberator``.
    session : Session
        The simulated session (its ``truth`` is the twin's ground truth).
    bode : ServoBode
        The servo loop measured with a PRBS.
    results : WalkingResults
        The walking analysis of the session.
    document : dict
        ``results.json``'s content.
    """

    directory: Path
    session: Session
    bode: ServoBode
    results: WalkingResults
    document: dict[str, Any]


def run_perturberator(
    out: str | Path, settings: DemoSettings, *, task: Task = _no_task
) -> PerturberatorDemo:
    """Simulate, store and analyse paper 000's experiment on the twin (see the module notes)."""
    directory = Path(out) / "perturberator"
    directory.mkdir(parents=True, exist_ok=True)
    session = simulate_perturberator(
        seed=settings.seed,
        trials_per_point=settings.trials_per_point,
        n_unperturbed=settings.n_unperturbed,
        n_calibration=settings.n_calibration,
        progress=task("Perturberator: simulating the session"),
    )
    path = directory / "session.h5"
    save_session(session, path, progress=task("Perturberator: writing session.h5"))
    measured = task("Perturberator: measuring the servo loop (PRBS)")
    bode = measure_servo_bode()
    write_json_atomic(directory / "servo_bode.json", bode.summary())
    measured(1, 1)
    step = task("Perturberator: analysing walking")
    names = list(STEPS)
    results = analyze_walking(
        session,
        settings.walking(),
        progress=lambda name: step(names.index(name), len(names)),
    )
    step(len(names), len(names))
    document = results.to_dict(
        session=path.name, session_sha256=session_hash(path), subject=session.info.subject
    )
    write_json_atomic(directory / "results.json", document)
    return PerturberatorDemo(directory, session, bode, results, document)


# ------------------------------------------------------------------------------- paper 001


@dataclass(frozen=True)
class StepRun:
    """One set-point step: the run, its metrics from the encoder and from the true angle."""

    result: SimulationResult
    measured: StepMetrics
    true: StepMetrics


@dataclass(frozen=True)
class ChirpRun:
    """The chirp: the run, its metrics from the encoder and from the true angle."""

    result: SimulationResult
    measured: ChirpMetrics
    true: ChirpMetrics


@dataclass(frozen=True)
class CapstanDemo:
    """What the capstan part produced.

    Attributes
    ----------
    directory : Path
        ``OUT/capstan``.
    ident : IdentData
        The simulated identification tests (``truth``: the twin's Table 2 values).
    friction : FrictionIdentifier
        Fitted on ``ident``.
    steps : dict
        ``{compensation: [StepRun per set-point]}`` (:data:`COMPENSATIONS`, :data:`SETPOINTS_DEG`).
    chirps : dict
        ``{compensation: ChirpRun}``.
    observers : dict
        ``{task: (SimulationResult, ObserverMetrics)}``; metrics against the twin's true torque.
    """

    directory: Path
    ident: IdentData
    friction: FrictionIdentifier
    steps: dict[str, list[StepRun]]
    chirps: dict[str, ChirpRun]
    observers: dict[str, tuple[SimulationResult, ObserverMetrics]]

    def control_document(self) -> dict[str, Any]:
        """``control.json``: every metric, encoder-based (``measured``) and true (``true``)."""
        return {
            "setpoints": {
                name: [{"measured": _jsonable(r.measured), "true": _jsonable(r.true)} for r in runs]
                for name, runs in self.steps.items()
            },
            "chirp": {
                name: {"measured": _jsonable(r.measured), "true": _jsonable(r.true)}
                for name, r in self.chirps.items()
            },
            "observer": {task: _jsonable(m) for task, (_, m) in self.observers.items()},
        }


def _jsonable(metrics: Any) -> dict[str, Any]:
    """A metrics dataclass as JSON values: arrays as lists, never-reached (inf) as None."""
    return {
        key: value.tolist()
        if isinstance(value, np.ndarray)
        else None
        if isinstance(value, float) and not math.isfinite(value)
        else value
        for key, value in asdict(metrics).items()
    }


def _step(setup: CapstanSetup, degrees: float, seed: int) -> StepRun:
    amplitude = math.radians(degrees)
    result, measured = step_response(setup, amplitude, pre_s=PRE_S, seed=seed)
    true = step_metrics(result["angle_rad"], setup.fs, amplitude, start_s=PRE_S)
    return StepRun(result, measured, true)


def _chirp(setup: CapstanSetup, seed: int) -> ChirpRun:
    result, measured = chirp_tracking(
        setup, amplitude_rad=math.radians(CHIRP_DEG), **CHIRP, seed=seed
    )
    true = chirp_metrics(
        result["reference_rad"],
        result["angle_rad"],
        setup.fs,
        CHIRP["f0_hz"],
        CHIRP["f1_hz"],
        duration_s=CHIRP["duration_s"],
    )
    return ChirpRun(result, measured, true)


def run_capstan(out: str | Path, settings: DemoSettings, *, task: Task = _no_task) -> CapstanDemo:
    """Identify, control and observe paper 001's platform on the twin (see the module notes)."""
    directory = Path(out) / "capstan"
    directory.mkdir(parents=True, exist_ok=True)
    params = load_platform("capstan")
    seed = settings.seed

    bar = task("capstan: spin-down and chirp tests")
    ident = simulate_ident(params, seed=seed)
    write_ident_directory(ident, directory / "ident", overwrite=True)
    bar(1, 1)

    bar = task("capstan: identifying friction and inertia")
    friction = FrictionIdentifier(stribeck_exponent=params.friction.stribeck_exponent).fit(ident)
    (directory / "friction").mkdir(exist_ok=True)
    write_json_atomic(directory / "friction" / "friction.json", friction.to_dict())
    bar(1, 1)

    model = friction.to_parameters()
    setups = dict(
        zip(
            COMPENSATIONS,
            (
                CapstanSetup(params=params, gravity_compensation=False),
                CapstanSetup(params=params, friction_compensation=1.0, model_friction=model),
            ),
            strict=True,
        )
    )
    bar = task("capstan: set-point and chirp control")
    total, done = len(setups) * (len(SETPOINTS_DEG) + 1), 0
    steps: dict[str, list[StepRun]] = {name: [] for name in setups}
    chirps: dict[str, ChirpRun] = {}
    for name, setup in setups.items():
        for degrees in SETPOINTS_DEG:
            steps[name].append(_step(setup, degrees, seed))
            bar(done := done + 1, total)
        chirps[name] = _chirp(setup, seed)
        bar(done := done + 1, total)

    bar = task("capstan: torque observer")
    observed = CapstanSetup(params=params, model_friction=model)
    observers: dict[str, tuple[SimulationResult, ObserverMetrics]] = {}
    for k, name in enumerate(OBSERVER_TASKS):
        observers[name] = observer_trial(
            observed, name, duration_s=settings.observer_duration_s, seed=seed
        )
        bar(k + 1, len(OBSERVER_TASKS))
    demo = CapstanDemo(directory, ident, friction, steps, chirps, observers)
    write_json_atomic(directory / "control.json", demo.control_document())
    return demo
