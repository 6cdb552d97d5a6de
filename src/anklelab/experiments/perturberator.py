"""Paper 000's protocols run on the Perturberator twin, returned as a :class:`Session`.

:func:`simulate_perturberator` runs the calibration trials (nobody on the plate, pseudorandom
ramp-and-hold moves), the walking trials (heel-contact trigger, delay counter, ramp
perturbations at the timing points, unperturbed trials in between, in random order) and, for
the prosthetic foot, the testing-machine bench tests of the prosthesis, and records them as the
16-bit 1 kHz DAQ would (see :mod:`anklelab.sim.sensors`). The physics is documented in
:mod:`anklelab.sim.drivetrain` (platform and servo), :mod:`anklelab.sim.foot` (how the foot's
torque reaches the plate), :mod:`anklelab.sim.gait` and :mod:`anklelab.sim.forceplate_dynamics`.

Safety, as in the lab: a drive fault in any trial stops the protocol with
:class:`~anklelab.errors.SafetyLimitError` naming the trial; bad force data at the trigger
(:mod:`anklelab.control.trigger`) refuses that trial's perturbation, and the trial is recorded
unperturbed with a ``note`` in its manifest row. :class:`TrialFault` injects either.

Ground truth (``Session.truth``, SI units):

- ``parameters``: every parameter used (``model_dump`` of the parameter set); ``foot``: kind
  and its parameters; ``artefacts``: the switches used.
- ``reference[direction][f"{delay_ms:g}"]``: what a perfect estimator of paper 000's method
  returns for the perturbed trials of that direction and timing point: the foot's
  ``stiffness_nm_per_rad``, ``damping_nms_per_rad`` and ``inertia_kgm2`` over the
  ``window_ms`` (100 ms) after each trial's true onset, and ``cop_m``, the nominal
  (unperturbed) lever arm ``dx``. Per trial, stiffness and ``cop_m`` are weighted by
  ``theta²`` and damping by ``theta'²``, ``theta`` the true perturbation of the ankle angle
  (the trial minus the same trial simulated without perturbation); then averaged over the
  trials. For the prosthetic foot the stiffness is the bench law at ``cop_m`` (the law is
  linear). ``stiffness_change_fraction``: how much the stiffness changes over the window,
  ``(k(end) - k(start)) / k``, mean over the trials. Also ``n_trials``, ``onset_sd_ms`` (sd
  of true onset minus true heel contact), ``window_ms``, and ``stiffness_fit_nm_per_rad``,
  ``damping_fit_nms_per_rad``, ``inertia_fit_kgm2``: a least-squares fit of
  ``T = I th'' + b th' + k th`` to the exact trial-averaged perturbation torque and angle over
  the window (shows how far the fit itself departs from the weighted reference when stiffness
  changes within the window).
- ``trials``: per walking trial in session order, ``heel_contact_s`` (vertical GRF crossing
  25 N) and ``onset_s`` (first step of the perturbation's motion plan; NaN if unperturbed or
  refused), both in the trial file's time.
- ``bench``: ``distances_m`` and ``stiffness_nm_per_rad`` (the law at those distances).
- ``time_courses`` (unless ``time_courses=False``): ``(n_trials, n_samples)`` arrays on the
  trial files' time base: ``ankle_torque_nm`` (true external ankle moment about the ankle
  centre, dorsiflexion positive), ``ankle_angle_rad`` (true ankle angle), ``lever_arm_m``
  (nominal dx, NaN off stance) and ``stiffness_nm_per_rad`` (the foot's stiffness, 0 off
  stance).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab._version import __version__
from anklelab.control.motion_plan import StepDirectionPlan
from anklelab.control.perturbation import RampHold, calibration_schedule
from anklelab.control.safety import Fault
from anklelab.control.trigger import (
    onset_updates,
    reading_limits,
    screen_readings,
    trigger_updates,
)
from anklelab.data.session import (
    BenchTest,
    Recording,
    Session,
    SessionInfo,
    WalkingTrial,
)
from anklelab.errors import ParameterError, SafetyLimitError
from anklelab.forceplate import CHANNELS, PlateGeometry
from anklelab.platforms import load_platform
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.drivetrain import (
    DriveFault,
    EncoderFault,
    FootLoad,
    PlatformRun,
    default_threads,
    force_delay_ms,
    simulate_platform,
)
from anklelab.sim.foot import FootModel, NominalStance, bench_law, foot_load, foot_model
from anklelab.sim.gait import (
    GaitTrials,
    heel_contact_times,
    sample_gait,
    stance_signals,
    vertical_force,
)
from anklelab.sim.sensors import (
    force_channels,
    goniometer_reading,
    load_cell_reading,
    motor_angle_output,
)

__all__ = ["TrialFault", "simulate_perturberator"]

Progress = Callable[[int, int], None]
BATCH = 50
MARGIN = 5  # samples either side of the window for derivatives
_ENCODER_FAULTS = {
    "encoder-nan": EncoderFault.NAN,
    "encoder-stale": EncoderFault.STALE,
    "encoder-jump": EncoderFault.JUMP,
}
_FORCE_FAULTS = ("force-nan", "force-saturated", "force-dropped")
_DIRECTIONS = ("none", "dorsi", "plantar")  # indexed by the sign (+1 dorsi, -1 plantar) mod 3


@dataclass(frozen=True)
class TrialFault:
    """A sensor fault injected into one walking trial (fault-injection tests and drills).

    Attributes
    ----------
    kind : str
        The drive's motor encoder: ``encoder-nan`` (reading lost), ``encoder-stale`` (no new
        frame) or ``encoder-jump`` (reads ``value`` rad off); the drive trips and the protocol
        stops with :class:`anklelab.errors.SafetyLimitError`. The microcontroller's reading of
        the vertical force: ``force-nan``, ``force-saturated`` (stuck at ``value`` N) or
        ``force-dropped`` (no new sample: the reading freezes); the trigger refuses the trial,
        which then runs unperturbed with a ``note`` in its manifest row.
    trial : int
        Walking trial number (1-based, session order).
    time_s : float
        Onset in the trial file's time, s.
    value : float
        Size of an ``encoder-jump`` (rad) or the ``force-saturated`` reading (N).
    """

    kind: str
    trial: int
    time_s: float
    value: float = 0.0

    def __post_init__(self) -> None:
        kinds = (*_ENCODER_FAULTS, *_FORCE_FAULTS)
        if self.kind not in kinds:
            raise ParameterError(f"fault kind must be one of {list(kinds)}; got {self.kind!r}")
        if self.kind in ("encoder-jump", "force-saturated") and self.value == 0.0:
            raise ParameterError(f"fault {self.kind}: give its size as value (got 0)")

    def corrupt(
        self,
        reading: NDArray[np.float64],
        counter: NDArray[np.float64],
        time_s: NDArray[np.float64],
    ) -> None:
        """Apply a force fault, in place, to one trial's readings and sample counter at
        ``time_s``."""
        hit = np.flatnonzero(time_s >= self.time_s)
        if self.kind not in _FORCE_FAULTS or hit.size == 0:
            return
        if self.kind == "force-nan":
            reading[hit] = np.nan
        elif self.kind == "force-saturated":
            reading[hit] = self.value
        else:
            k = hit[0]
            reading[hit] = reading[k - 1] if k else reading[0]
            counter[hit] = counter[k] - 1


@dataclass(frozen=True)
class _Setup:
    params: PerturberatorParameters
    art: Artefacts
    plan: StepDirectionPlan
    substeps: int
    threads: int | None = None

    @property
    def fs(self) -> float:
        return self.params.daq.sample_rate_hz

    def reference(self, planned: NDArray[np.float64], n_samples: int) -> NDArray[np.float64]:
        """Drive position command at the position-loop ticks covering ``n_samples``."""
        loop = self.params.servo.position_loop_rate_hz
        return self.plan.reference(planned, loop, round(n_samples * loop / self.fs))


def simulate_perturberator(
    params: PerturberatorParameters | None = None,
    *,
    seed: int | np.random.Generator = 0,
    foot: str = "prosthetic",
    trials_per_point: int | None = None,
    n_unperturbed: int | None = None,
    n_calibration: int | None = None,
    bench: bool | None = None,
    artefacts: bool | Artefacts = True,
    substeps: int = 1,
    time_courses: bool = True,
    progress: Progress | None = None,
    fault: TrialFault | None = None,
    threads: int | None = None,
) -> Session:
    """Simulate a whole Perturberator session (calibration, walking, bench) with ground truth.

    Parameters
    ----------
    params : PerturberatorParameters, optional
        Platform, subject and protocol parameters; the shipped set by default.
    seed : int or numpy.random.Generator
        Randomness of the protocols and sensors; the same seed gives the same session.
    foot : {"prosthetic", "human"}
        What walks on the plate.
    trials_per_point : int, optional
        Perturbed trials per timing point (default ``walking.trials_per_point``); each is dorsi
        or plantar with equal probability.
    n_unperturbed : int, optional
        Unperturbed walking trials (default ``walking.n_unperturbed``).
    n_calibration : int, optional
        Calibration trials (default ``calibration.n_trials``; 0 for none).
    bench : bool, optional
        Include the testing-machine tests of the prosthetic foot (paper 000, section 2.3).
        Default: with the prosthetic foot only; a human ankle has no bench law, so its walking
        estimates have nothing on the bench to be validated against.
    artefacts : bool or Artefacts
        Measurement artefacts: True all (default), False none, or a selection.
    substeps : int
        RK4 integration steps per 16 kHz velocity-loop period.
    time_courses : bool
        Store per-trial true time courses in the truth tree.
    progress : callable, optional
        Called as ``progress(done, total)`` with trial counts as the simulation advances.
    fault : TrialFault, optional
        A sensor fault to inject into one walking trial.
    threads : int, optional
        Threads that simulate trials side by side (default: the CPUs available, see
        :func:`anklelab.sim.drivetrain.default_threads`); the session does not depend on it.

    Returns
    -------
    Session
        With ``truth`` as described in the module docstring and ``provenance``.

    Examples
    --------
    >>> s = simulate_perturberator(trials_per_point=2, n_unperturbed=2, n_calibration=1,
    ...                            bench=False, seed=1)
    >>> len(s.walking), sorted(s.truth["reference"])
    (10, ['dorsi', 'plantar'])
    """
    params = load_platform("perturberator") if params is None else params
    model = foot_model(foot, params)
    bench = model.kind == "prosthetic" if bench is None else bench
    art = Artefacts.coerce(artefacts)
    setup = _Setup(params, art, StepDirectionPlan.from_params(params), substeps, threads)
    rng_cal, rng_walk, rng_bench = np.random.default_rng(seed).spawn(3)
    walk = params.walking
    per_point = walk.trials_per_point if trials_per_point is None else trials_per_point
    unperturbed = walk.n_unperturbed if n_unperturbed is None else n_unperturbed
    n_cal = params.calibration.n_trials if n_calibration is None else n_calibration
    n_bench = len(params.bench.distances_m) * params.bench.tests_per_distance if bench else 0
    n_walking = per_point * len(walk.timing_points_ms) + unperturbed
    if fault is not None and not 1 <= fault.trial <= n_walking:
        raise ParameterError(f"fault.trial: expected 1 ... {n_walking}, got {fault.trial}")
    total = n_cal + n_walking + n_bench
    done = [0]
    counting = threading.Lock()

    def advance(n: int) -> None:
        with counting:
            done[0] += n
            if progress is not None:
                progress(done[0], total)

    # the calibration has its own random stream, so with more than one thread it runs beside
    # the walking protocol (whose set-up is NumPy on one core) and the session is the same
    side = (threads or default_threads()) > 1 and n_cal > 0
    with ThreadPoolExecutor(1) as pool:  # starts no thread unless given the calibration
        calibrating = pool.submit(_calibration, setup, n_cal, rng_cal, advance) if side else None
        calibration = () if calibrating else _calibration(setup, n_cal, rng_cal, advance)
        walking, walk_truth = _walking(
            setup, model, per_point, unperturbed, rng_walk, advance, time_courses, fault
        )
        tests, bench_truth = _bench(setup, rng_bench, advance) if bench else ((), None)
        if calibrating is not None:
            calibration = calibrating.result()
    geo = params.geometry
    fp = params.force_plate
    info = SessionInfo(
        platform="perturberator",
        sample_rate_hz=setup.fs,
        subject=f"twin-{foot}",
        force_plate=PlateGeometry(
            a_m=fp.a_m, b_m=fp.b_m, az0_m=fp.az0_m, anterior_axis=fp.anterior_axis
        ),
        ankle_height_m=geo.ankle_height_m,
        heel_to_ankle_m=geo.heel_to_ankle_m,
        force_delay_ms=force_delay_ms(params, art),
    )
    truth: dict[str, Any] = {
        "parameters": params.model_dump(),
        "foot": model.describe(),
        "artefacts": asdict(art),
        **walk_truth,
    }
    if bench_truth is not None:
        truth["bench"] = bench_truth
    settings = {
        "foot": foot,
        "trials_per_point": per_point,
        "n_unperturbed": unperturbed,
        "n_calibration": n_cal,
        "bench": bench,
        "artefacts": asdict(art),
        "substeps": substeps,
    }
    provenance = {
        "anklelab_version": __version__,
        "created_by": "simulate perturberator",
        "seed": seed if isinstance(seed, int) else "generator",
        "settings": settings,
    }
    return Session(info, calibration, walking, tests, truth, provenance)


def _calibration(
    setup: _Setup, n_trials: int, rng: np.random.Generator, advance: Callable[[int], None]
) -> tuple[Recording, ...]:
    """Platform-only trials of pseudorandom ramp-and-hold moves (paper 000, section 2.2)."""
    if n_trials == 0:
        return ()
    cal = setup.params.calibration
    move = RampHold(cal.amplitude_rad, cal.ramp_s, cal.hold_s, cal.ramp_s)
    n = round(cal.trial_duration_s * setup.fs)
    times = setup.plan.update_times(cal.trial_duration_s)
    planned = np.zeros((n_trials, len(times)))
    for i in range(n_trials):
        onsets, signs = calibration_schedule(
            move, cal.n_perturbations, cal.trial_duration_s, cal.max_gap_s, cal.quiet_s, rng
        )
        planned[i] = move.sequence(times, onsets, signs)
    run = simulate_platform(
        setup.params,
        setup.reference(planned, n),
        artefacts=setup.art,
        substeps=setup.substeps,
        threads=setup.threads,
    )
    _check_faults(run, "calibration", 0)
    assert run.wrench is not None
    channels = force_channels(run.wrench, setup.params, setup.art, rng)
    motor = motor_angle_output(run.motor_angle, setup.params, setup.art)
    advance(n_trials)
    time = np.arange(n) / setup.fs
    return tuple(
        Recording(
            f"calibration_{i + 1:02d}.csv",
            {"time_s": time, "motor_angle": motor[i]}
            | dict(zip(CHANNELS, channels[i], strict=True)),
        )
        for i in range(n_trials)
    )


def _check_faults(run: PlatformRun, protocol: str, first: int) -> None:
    """Stop the protocol, as the lab would, when the drive tripped in any trial."""
    assert run.fault is not None and run.fault_s is not None
    for i in np.flatnonzero(run.fault):
        raise SafetyLimitError(
            f"{protocol} trial {first + i + 1}: the drive tripped "
            f"({DriveFault(int(run.fault[i])).name}) at {run.fault_s[i]:.4f} s"
        )


def _manifest(
    timing_points: tuple[float, ...], per_point: int, unperturbed: int, rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Delay (ms, NaN if unperturbed) and sign (+1 dorsi, -1 plantar, 0) of each trial, shuffled."""
    delays = np.concatenate([np.repeat(timing_points, per_point), np.full(unperturbed, np.nan)])
    signs = np.where(np.isnan(delays), 0.0, rng.choice([-1.0, 1.0], len(delays)))
    order = rng.permutation(len(delays))
    return delays[order], signs[order]


def _onsets(
    setup: _Setup,
    trials: GaitTrials,
    delays: NDArray[np.float64],
    signs: NDArray[np.float64],
    rng: np.random.Generator,
    fault: TrialFault | None,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """The microcontroller's trigger on its reading of the vertical force at its update instants:
    the safety monitor screens each reading, the first above the threshold starts the delay
    counter, the count's end starts the perturbation. A monitor fault up to that update refuses
    the trial.

    Returns the onsets (s; NaN if unperturbed or refused), the monitor's
    :class:`~anklelab.control.safety.Fault` code of refused trials (0 otherwise) and when it
    latched (s; NaN if it did not).
    """
    p, plan = setup.params, setup.plan
    threshold = p.walking.heel_contact_threshold_n
    rate = plan.update_rate_hz
    n_trials = len(trials)
    offset = np.zeros(n_trials)
    counter = np.zeros(n_trials)
    if setup.art.onset_jitter:
        limit = threshold - 5.0
        offset = np.clip(p.trigger.input_offset_sd_n * rng.standard_normal(n_trials), -limit, limit)
        counter = p.trigger.counter_error_sd_fraction * rng.standard_normal(n_trials)
    delay_s = np.nan_to_num(delays) / 1000.0
    # from the update before heel contact through the loading phase and the longest delay
    first = np.floor(trials.contact_s * rate).astype(np.int64)
    width = int(np.ceil(trials.loading_s.max() * rate)) + 3
    width += int(np.ceil(np.max(delay_s * (1 + counter)) * rate))
    window = first[:, None] + np.arange(width)
    reading = vertical_force(trials, p.gait, window / rate) + offset[:, None]
    samples = np.tile(np.arange(width, dtype=float), (n_trials, 1))
    if fault is not None:
        row = fault.trial - 1
        fault.corrupt(reading[row], samples[row], window[row] / rate)
    limits = reading_limits(p.trigger.force_limit_n, p.trigger.max_dropped_updates)
    code, at = screen_readings(reading, samples, limits)
    # from the update the monitor latches on, the reading is never compared
    compared = np.where(np.arange(width) < at[:, None], reading, -np.inf)
    rows = np.flatnonzero((compared >= threshold).any(axis=1) | (code == 0))
    trigger = np.full(n_trials, width, dtype=np.int64)
    trigger[rows] = trigger_updates(compared[rows], threshold, np.zeros(rows.size))
    start = onset_updates(first + trigger, delay_s, rate, counter)
    refused = (code != 0) & (first + at <= start)
    onset = np.where((signs != 0) & ~refused, start / rate, np.nan)
    return onset, np.where(refused, code, 0), np.where(refused, (first + at) / rate, np.nan)


@dataclass(frozen=True)
class _WalkingRun:
    """True signals of all walking trials (``(n_trials, n)``; wrench ``(n_trials, 6, n)``) and
    the exact perturbation of the ankle angle and torque around each onset."""

    motor: NDArray[np.float64]
    angle: NDArray[np.float64]
    torque: NDArray[np.float64]
    wrench: NDArray[np.float64]
    pert_angle: NDArray[np.float64]
    pert_torque: NDArray[np.float64]


def _run_walking(
    setup: _Setup,
    load: FootLoad,
    onset: NDArray[np.float64],
    signs: NDArray[np.float64],
    advance: Callable[[int], None],
    fault: TrialFault | None,
) -> _WalkingRun:
    """Simulate the trials in batches; re-run each perturbed one from just before its onset
    without the perturbation, so that the difference is the exact perturbation."""
    p = setup.params
    walk = p.walking
    n_trials, n = load.channels.shape[0], load.channels.shape[2]
    move = RampHold(walk.amplitude_rad, walk.ramp_s, walk.hold_s, walk.return_s)
    updates = setup.plan.update_times(n / setup.fs)
    per_sample = round(p.servo.velocity_loop_rate_hz / setup.fs)
    width = round(walk.window_ms * setup.fs / 1000) + 4 * MARGIN
    motor, angle, torque = (np.zeros((n_trials, n)) for _ in range(3))
    out = _WalkingRun(motor, angle, torque, np.zeros((n_trials, 6, n)),
                      np.zeros((n_trials, n)), np.zeros((n_trials, n)))  # fmt: skip
    for start in range(0, n_trials, BATCH):
        b = slice(start, min(start + BATCH, n_trials))
        planned = move(updates[None, :], np.nan_to_num(onset[b])[:, None], signs[b][:, None])
        sub = FootLoad(load.channels[b], load.fs, load.scalars[b])
        first = np.ceil(np.nan_to_num(onset[b]) * setup.fs - 1e-9).astype(np.int64)
        fork = np.where(signs[b] != 0, (first - 2 * MARGIN) * per_sample, -1)
        lost = np.full(b.stop - b.start, np.nan)
        if fault is not None and fault.kind in _ENCODER_FAULTS and b.start < fault.trial <= b.stop:
            lost[fault.trial - 1 - b.start] = fault.time_s
        run = simulate_platform(
            p, setup.reference(planned, n), load=sub, artefacts=setup.art,
            substeps=setup.substeps, fork=fork, encoder_fault_s=lost,
            encoder_fault=_ENCODER_FAULTS.get(fault.kind if fault else "", EncoderFault.NAN),
            encoder_jump_rad=fault.value if fault else 0.0, threads=setup.threads,
        )  # fmt: skip
        _check_faults(run, "walking", start)
        assert run.wrench is not None and run.snapshot is not None
        out.motor[b], out.angle[b], out.torque[b], out.wrench[b] = (
            run.motor_angle, run.ankle_angle, run.ankle_torque, run.wrench
        )  # fmt: skip
        moved = np.flatnonzero(signs[b] != 0)
        if moved.size:
            still = simulate_platform(
                p, np.zeros((moved.size, n * per_sample // 2)),
                load=FootLoad(sub.channels[moved], load.fs, sub.scalars[moved]),
                artefacts=setup.art, plate=False, substeps=setup.substeps,
                resume=(fork[moved], run.snapshot[moved]), stop=fork[moved] + width * per_sample,
                threads=setup.threads,
            )  # fmt: skip
            for m, i in enumerate(moved):
                span = slice(first[i] - 2 * MARGIN, first[i] - 2 * MARGIN + width)
                k = start + i
                out.pert_angle[k, span] = out.angle[k, span] - still.ankle_angle[m, span]
                out.pert_torque[k, span] = out.torque[k, span] - still.ankle_torque[m, span]
        advance(b.stop - b.start)
    return out


def _walking(
    setup: _Setup,
    foot: FootModel,
    per_point: int,
    unperturbed: int,
    rng: np.random.Generator,
    advance: Callable[[int], None],
    time_courses: bool,
    fault: TrialFault | None,
) -> tuple[tuple[WalkingTrial, ...], dict[str, Any]]:
    """Walking trials with heel-contact-triggered perturbations (paper 000, section 2.4)."""
    p, art = setup.params, setup.art
    walk, gait = p.walking, p.gait
    delays, signs = _manifest(walk.timing_points_ms, per_point, unperturbed, rng)
    n_trials = len(delays)
    trials = sample_gait(gait, n_trials, rng, variability=art.gait_variability)
    n = round(gait.trial_duration_s * setup.fs)
    time = np.arange(n) / setup.fs
    heel_contact = heel_contact_times(trials, gait, walk.heel_contact_threshold_n)
    # the foot's load first: the trigger's screening waits while the calibration's thread loads
    # the platform kernel (numba compiles or loads one function at a time), this is NumPy
    load, nominal = foot_load(foot, trials, stance_signals(trials, gait, time), heel_contact, time)
    onset, refused, refused_s = _onsets(setup, trials, delays, signs, rng, fault)
    notes = [
        _refusal_note(int(refused[i]), refused_s[i], signs[i], delays[i]) for i in range(n_trials)
    ]
    delays = np.where(refused != 0, np.nan, delays)
    signs = np.where(refused != 0, 0.0, signs)
    run = _run_walking(setup, load, onset, signs, advance, fault)
    channels = force_channels(run.wrench, p, art, rng)
    true_angle = nominal.angle_rad + run.angle
    recorded_motor = motor_angle_output(run.motor, p, art)
    recorded_angle = goniometer_reading(true_angle, p, art, rng)
    walking = tuple(
        WalkingTrial(
            trial=str(i + 1),
            recording=Recording(
                f"trial_{i + 1:04d}.csv",
                {"time_s": time, "motor_angle": recorded_motor[i], "ankle_angle": recorded_angle[i]}
                | dict(zip(CHANNELS, channels[i], strict=True)),
            ),
            perturbed=bool(signs[i] != 0),
            direction=_DIRECTIONS[int(signs[i]) % 3],  # type: ignore[arg-type]
            delay_ms=float(delays[i]),
            extra=notes[i],
        )
        for i in range(n_trials)
    )
    truth: dict[str, Any] = {
        "reference": _reference(setup, foot, delays, signs, onset, heel_contact, run, nominal),
        "trials": {"heel_contact_s": heel_contact, "onset_s": onset},
    }
    if time_courses:
        truth["time_courses"] = {
            "ankle_torque_nm": run.torque,
            "ankle_angle_rad": true_angle,
            "lever_arm_m": nominal.lever_arm_m,
            "stiffness_nm_per_rad": nominal.stiffness_nm_per_rad,
        }
    return walking, truth


def _refusal_note(fault: int, time_s: float, sign: float, delay_ms: float) -> dict[str, str]:
    """Manifest note of a trial whose trigger refused bad force data (empty if it did not)."""
    if not fault:
        return {}
    intended = _DIRECTIONS[int(sign) % 3]
    intended += "" if np.isnan(delay_ms) else f" {delay_ms:g} ms"
    return {
        "note": f"trigger refused ({Fault(fault).name} in the force reading at {time_s:.4f} s); "
        f"intended: {intended}"
    }


def _reference(
    setup: _Setup,
    foot: FootModel,
    delays: NDArray[np.float64],
    signs: NDArray[np.float64],
    onset: NDArray[np.float64],
    heel_contact: NDArray[np.float64],
    run: _WalkingRun,
    nominal: NominalStance,
) -> dict[str, dict[str, dict[str, float]]]:
    """Per direction and timing point: the values a perfect estimator should return."""
    window_ms = setup.params.walking.window_ms
    width = round(window_ms * setup.fs / 1000)
    fs = setup.fs
    pert, pert_torque = run.pert_angle, run.pert_torque
    pert_rate = np.gradient(pert, 1 / fs, axis=1)
    out: dict[str, dict[str, dict[str, float]]] = {}
    for sign, direction in ((1.0, "dorsi"), (-1.0, "plantar")):
        out[direction] = {}
        for delay in setup.params.walking.timing_points_ms:
            idx = np.flatnonzero((signs == sign) & (delays == delay))
            if idx.size == 0:
                continue
            first = np.ceil(onset[idx] * fs - 1e-9).astype(int)
            cols = first[:, None] + np.arange(width)
            rows = idx[:, None]
            theta = pert[rows, cols]
            rate = pert_rate[rows, cols]
            w = theta**2
            wr = rate**2
            cop = np.sum(w * nominal.lever_arm_m[rows, cols], axis=1) / w.sum(axis=1)
            k_window = nominal.stiffness_nm_per_rad[rows, cols]
            k = np.sum(w * k_window, axis=1) / w.sum(axis=1)
            b = np.sum(wr * nominal.damping_nms_per_rad[rows, cols], axis=1) / wr.sum(axis=1)
            lag_ms = (onset[idx] - heel_contact[idx]) * 1000
            wide = first[:, None] + np.arange(-MARGIN, width + MARGIN)
            fit = _second_order_fit(pert[rows, wide].mean(0), pert_torque[rows, wide].mean(0), fs)
            out[direction][f"{delay:g}"] = {
                "stiffness_nm_per_rad": float(k.mean()),
                "damping_nms_per_rad": float(b.mean()),
                "inertia_kgm2": foot.inertia_kgm2,
                "cop_m": float(cop.mean()),
                "stiffness_change_fraction": float(np.mean((k_window[:, -1] - k_window[:, 0]) / k)),
                "n_trials": int(idx.size),
                "onset_sd_ms": float(lag_ms.std(ddof=1)) if idx.size > 1 else 0.0,
                "window_ms": float(window_ms),
                **fit,
            }
    return out


def _second_order_fit(angle: NDArray, torque: NDArray, fs: float) -> dict[str, float]:
    """Least-squares ``T = I a'' + b a' + k a`` on exact, trial-averaged perturbations.

    ``angle`` and ``torque`` cover the window plus ``MARGIN`` samples on each side (for the
    central-difference derivatives); the fit uses the window.

    Within the window the prosthetic stiffness changes with the lever arm, and part of that
    change is explained by the damping term; this is the fit's own answer (``*_fit`` keys),
    which the theta²-weighted reference differs from by a fraction of a percent.
    """
    rate = np.gradient(angle, 1 / fs)
    design = np.column_stack([np.gradient(rate, 1 / fs), rate, angle])[MARGIN:-MARGIN]
    target = (torque - torque[MARGIN])[MARGIN:-MARGIN]
    inertia, damping, stiffness = np.linalg.lstsq(design, target, rcond=None)[0]
    return {
        "stiffness_fit_nm_per_rad": float(stiffness),
        "damping_fit_nms_per_rad": float(damping),
        "inertia_fit_kgm2": float(inertia),
    }


def _bench(
    setup: _Setup, rng: np.random.Generator, advance: Callable[[int], None]
) -> tuple[tuple[BenchTest, ...], dict[str, Any]]:
    """Testing-machine tests: deflection ramp at each actuator distance (paper 000, 2.3)."""
    p, art = setup.params, setup.art
    bp = p.bench
    n = round(bp.duration_s * setup.fs) + 1
    time = np.arange(n) / setup.fs
    displacement = bp.deflection_m * time / bp.duration_s
    distances = np.asarray(bp.distances_m)
    law = bench_law(p, distances)
    tests = []
    for j, (distance, stiffness) in enumerate(zip(distances, law, strict=True)):
        # torque k*theta with theta = x/d and force = torque/d: linear stiffness k/d²
        force = stiffness / distance**2 * displacement
        for r in range(bp.tests_per_distance):
            number = j * bp.tests_per_distance + r + 1
            rec = Recording(
                f"bench_{number:02d}.csv",
                {"time_s": time, "displacement_m": displacement,
                 "force_n": load_cell_reading(force, p, art, rng)},
            )  # fmt: skip
            tests.append(BenchTest(str(number), rec, float(distance)))
    advance(len(tests))
    return tuple(tests), {"distances_m": distances, "stiffness_nm_per_rad": law}
