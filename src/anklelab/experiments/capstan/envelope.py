"""The display envelope checked on the twin: at each frequency, the largest sinusoid the
platform follows without reaching any limit, found by bisection, next to the analytic envelope
(:func:`anklelab.control.envelope.display_envelope`).

A trial asks for ``A sin(2 pi f t)`` about level, faded in over a period (at least 0.5 s), held
for two periods (at least 1 s) and faded out, tracked with the inverse-dynamics feed-forward and
the zero-phase-error tracking controller. It is *renderable* when no limit is reached: no
latched fault (workspace, speed, ...), no clamp by the person guard (torque, jerk), no current
at the drive's limit, no voltage at the supply's, and the angle follows the sinusoid within
10 % in amplitude and 20 degrees in phase while it is held (or within 0.25 degree: a person's
sway and load disturb a small sinusoid by a fixed amount). The person guard's fall detector is
off during the trials (a stepping person unloading the platform while it is driven looks like a
fall); its torque and jerk limits stay.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.envelope import DisplayEnvelope, PersonLoad, display_envelope
from anklelab.control.tracking import reference_derivatives, zpetc_reference
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.sim.capstan.person import person_profile

__all__ = ["EnvelopeCheck", "analytic_envelope", "check_envelope", "sine_trial"]

AMPLITUDE_TOLERANCE = 0.10
PHASE_TOLERANCE_DEG = 20.0
ABSOLUTE_TOLERANCE_RAD = math.radians(0.25)


@dataclass(frozen=True)
class EnvelopeCheck:
    """The analytic envelope and the one found on the twin.

    Attributes
    ----------
    analytic : DisplayEnvelope
        From the model.
    simulated_rad : ndarray
        Largest renderable amplitude found on the twin at each frequency, rad.
    reasons : list of str
        What stopped the first trial above it (``fault: NAME``, ``torque or jerk limit``,
        ``current limit``, ``supply voltage``, ``tracking``).
    error_percent : ndarray
        ``100 (simulated - analytic) / analytic``.
    """

    analytic: DisplayEnvelope
    simulated_rad: NDArray[np.float64]
    reasons: list[str]
    error_percent: NDArray[np.float64]


def analytic_envelope(setup: CapstanSetup, frequency_hz: ArrayLike) -> DisplayEnvelope:
    """The model's envelope for this setup (its platform, gains, feed-forward and person: their
    mean stance impedance and largest load, sway included)."""
    person = None
    if setup.person is not None:
        profile = person_profile(setup.person, 20.0, setup.fs, setup.params, setup.resolved_human())
        loaded = profile.contact > 0
        person = PersonLoad(
            stiffness_nm_per_rad=float(np.mean(profile.stiffness_nm_per_rad[loaded])),
            damping_nms_per_rad=float(np.mean(profile.damping_nms_per_rad[loaded])),
            posture_time_constant_s=setup.params.person.posture_time_constant_s,
            load_nm=float(np.max(np.abs(profile.load_torque_nm))),
        )
    return display_envelope(
        frequency_hz,
        setup.params,
        setup.resolved_gains(),
        setup.fs,
        feedforward=setup.feedforward,
        user=setup.foot(),
        person_guard=setup.guard,
        model_friction=setup.model_friction,
        person=person,
    )


def _sine(frequency: float, amplitude: float, fs: float) -> tuple[NDArray[np.float64], slice]:
    period = 1.0 / frequency
    fade, hold = max(period, 0.5), max(2 * period, 1.0)
    t = np.arange(round((2 * fade + hold) * fs)) / fs
    ramp = np.clip(np.minimum(t, t[-1] - t) / fade, 0.0, 1.0)
    window = 0.5 * (1 - np.cos(np.pi * ramp))
    held = slice(round(fade * fs), round((fade + hold) * fs))
    return amplitude * window * np.sin(2 * np.pi * frequency * t), held


def sine_trial(
    setup: CapstanSetup,
    frequency_hz: float,
    amplitude_rad: float,
    *,
    seed: int | np.random.Generator = 0,
) -> str:
    """Render one sinusoid (see the module notes); ``""`` if renderable, else what stopped it."""
    desired, held = _sine(frequency_hz, amplitude_rad, setup.fs)
    reference = zpetc_reference(desired, setup.loop_model())
    speed, acceleration = reference_derivatives(reference, setup.fs)
    run = simulate_closed_loop(
        dataclasses.replace(setup, fall_detection=False),
        desired.size,
        reference=reference,
        reference_speed=speed,
        reference_acceleration=acceleration,
        seed=seed,
    )
    from anklelab.control.safety import Fault

    if run["fault"].max() > 0:
        return f"fault: {Fault(int(run['fault'].max())).name}"
    if run["guard_clamped"].max() > 0:
        return "torque or jerk limit"
    if np.abs(run["current_command_a"]).max() >= 0.999 * setup.params.drive.current_limit_a:
        return "current limit"
    if np.abs(run["voltage_v"]).max() >= 0.999 * setup.params.drive.supply_voltage_v:
        return "supply voltage"
    t = np.arange(desired.size)[held] / setup.fs
    basis = np.exp(2j * np.pi * frequency_hz * t)
    response = np.dot(run["measured_angle_rad"][held], basis.conj())
    wanted = np.dot(desired[held], basis.conj())
    ratio = response / wanted
    # the fundamental's error, also as an amplitude (rad): a person's sway and load disturb a
    # small sinusoid by a fixed amount
    off = abs(response - wanted) * 2 / t.size
    relative = abs(abs(ratio) - 1.0) > AMPLITUDE_TOLERANCE
    lagging = abs(np.angle(ratio, deg=True)) > PHASE_TOLERANCE_DEG
    if (relative or lagging) and off > ABSOLUTE_TOLERANCE_RAD:
        return "tracking"
    return ""


def check_envelope(
    setup: CapstanSetup,
    frequency_hz: ArrayLike,
    *,
    iterations: int = 8,
    seed: int | np.random.Generator = 0,
) -> EnvelopeCheck:
    """Find the largest renderable amplitude at each frequency by bisection (in log amplitude,
    bracketed around the analytic value) and compare it with the analytic envelope.

    Parameters
    ----------
    setup : CapstanSetup
        Platform, controller (give it ``feedforward=True`` to reach the envelope) and person.
    frequency_hz : array_like
        Frequencies, Hz.
    iterations : int
        Bisection steps (each halves the log-amplitude bracket, which starts a factor 4 wide).
    seed : int
        Sensor noise of every trial.
    """
    if not isinstance(iterations, int) or iterations < 1:
        raise ParameterError(f"iterations must be a positive integer; got {iterations!r}")
    analytic = analytic_envelope(setup, frequency_hz)
    simulated, reasons = [], []
    for f, guess in zip(analytic.frequency_hz, analytic.amplitude_rad, strict=True):
        lo, hi = guess / 2.0, guess * 2.0
        while sine_trial(setup, f, lo, seed=seed) and lo > guess / 64:
            lo, hi = lo / 2.0, lo
        reason = sine_trial(setup, f, hi, seed=seed)
        while not reason and hi < guess * 64:
            lo, hi = hi, hi * 2.0
            reason = sine_trial(setup, f, hi, seed=seed)
        for _ in range(iterations):
            mid = math.sqrt(lo * hi)
            failed = sine_trial(setup, f, mid, seed=seed)
            if failed:
                hi, reason = mid, failed
            else:
                lo = mid
        simulated.append(lo)
        reasons.append(reason)
    sim = np.array(simulated)
    return EnvelopeCheck(
        analytic=analytic,
        simulated_rad=sim,
        reasons=reasons,
        error_percent=100 * (sim - analytic.amplitude_rad) / analytic.amplitude_rad,
    )
