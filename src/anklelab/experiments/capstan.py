"""Experiments on the capstan twin (paper 001): set-point steps, chirp tracking, torque
observation while holding or tracking, and haptic rendering, each with its metrics.

:class:`CapstanSetup` gathers what a closed-loop run needs (platform, user, gains, control rate,
compensation options, the controller's friction model); :func:`simulate_closed_loop` runs the
compiled loop (:mod:`anklelab.experiments._capstan_loop`) and returns a
:class:`~anklelab.sim.capstan.SimulationResult`. Measured signals are what the controller saw
(encoder, current sensor); ``angle_rad``, ``interaction_torque_nm`` and friends are the twin's
ground truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.haptics import TerrainProfile, VirtualEnvironment
from anklelab.control.observer import observer_constants
from anklelab.control.pid import PIDGains, control_constants, design_critically_damped
from anklelab.control.safety import SafetyLimits
from anklelab.errors import ParameterError
from anklelab.experiments._capstan_loop import FAULTS, MODES, SIGNALS, closed_loop
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters
from anklelab.sim.capstan import CapstanTwin, SimulationResult, voluntary_torque

__all__ = [
    "CapstanSetup",
    "ChirpMetrics",
    "FaultInjection",
    "ObserverMetrics",
    "RenderMetrics",
    "StepMetrics",
    "chirp_metrics",
    "chirp_reference",
    "chirp_tracking",
    "observer_metrics",
    "observer_trial",
    "render",
    "render_metrics",
    "simulate_closed_loop",
    "step_metrics",
    "step_response",
]

Mode = Literal["position", "admittance", "impedance", "open-loop"]


@dataclass(frozen=True)
class FaultInjection:
    """A sensor fault injected from ``time_s`` on.

    Attributes
    ----------
    kind : str
        ``encoder-nan``, ``encoder-stale`` (reading and sample counter freeze),
        ``encoder-jump`` (``value`` rad added), ``encoder-reversed`` (counts run backwards) or
        ``current-nan``.
    time_s : float
        Onset, s.
    value : float
        Size of an ``encoder-jump``, rad.
    """

    kind: str
    time_s: float
    value: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in FAULTS or self.kind == "none":
            raise ParameterError(
                f"fault kind must be one of {sorted(set(FAULTS) - {'none'})}; got {self.kind!r}"
            )


@dataclass(frozen=True)
class CapstanSetup:
    """Everything a closed-loop run of the capstan twin needs.

    Attributes
    ----------
    params : CapstanParameters
        The twin's (true) parameters.
    gains : PIDGains or None
        Controller gains; None designs critically damped ones from ``params``.
    fs : float
        Control rate, Hz.
    with_user : bool
        Put the user's foot (``params.user``) on the platform.
    gravity_compensation : bool
        Feed-forward gravity (paper 001, eqs. 3-4).
    friction_compensation : float
        Fraction of the model friction compensated (0: off).
    model_friction : FrictionParameters or None
        The controller's and observer's friction/inertia model (e.g. identified); None: truth.
    observer_cutoff_hz : float
        Disturbance-observer Q-filter cut-off, Hz.
    coupled : bool
        False disconnects the cable: the motor, gearhead and pinion turn alone (the
        identification rig); angles are then the pinion's divided by the capstan ratio.
    safety : SafetyLimits or None
        Safety limits (angle, speed, current); None takes them from ``params.safety``.
    max_step_s : float
        Longest physics sub-step, s.
    """

    params: CapstanParameters = field(default_factory=lambda: load_platform("capstan"))
    gains: PIDGains | None = None
    fs: float = 1000.0
    with_user: bool = True
    gravity_compensation: bool = True
    friction_compensation: float = 0.0
    model_friction: FrictionParameters | None = None
    observer_cutoff_hz: float = 20.0
    coupled: bool = True
    safety: SafetyLimits | None = None
    max_step_s: float = 2e-4

    def resolved_gains(self) -> PIDGains:
        """The gains in use."""
        return self.gains if self.gains is not None else design_critically_damped(self.params)

    def twin(self) -> CapstanTwin:
        """The plant."""
        user = self.params.user if self.with_user else None
        return CapstanTwin(self.params, user, coupled=self.coupled, max_step_s=self.max_step_s)

    def safety_limits(self) -> SafetyLimits:
        """The safety limits in force: ``safety``, or those of ``params.safety``."""
        if self.safety is not None:
            return self.safety
        s = self.params.safety
        return SafetyLimits(
            position_min=-s.angle_limit_rad,
            position_max=s.angle_limit_rad,
            velocity_max=s.velocity_limit_rad_s,
            output_max=self.params.drive.current_limit_a,
            output_trip=s.current_trip_a,
            sensor_min=-s.sensor_range_rad,
            sensor_max=s.sensor_range_rad,
            max_stale_ticks=s.max_stale_ticks,
        )


def simulate_closed_loop(
    setup: CapstanSetup,
    n_samples: int,
    *,
    mode: Mode = "position",
    reference: ArrayLike | None = None,
    reference_speed: ArrayLike | None = None,
    command: ArrayLike | None = None,
    voluntary: ArrayLike | None = None,
    environment: VirtualEnvironment | None = None,
    fault: FaultInjection | None = None,
    angle0: float = 0.0,
    seed: int | np.random.Generator = 0,
) -> SimulationResult:
    """Run the twin in closed loop for ``n_samples`` control ticks.

    Parameters
    ----------
    setup : CapstanSetup
        Plant, controller and options.
    n_samples : int
        Number of control ticks (duration ``n_samples / setup.fs``).
    mode : {"position", "admittance", "impedance", "open-loop"}
        ``position``: track ``reference`` (rad; NaN switches the motor off) with feed-forward
        ``reference_speed``; ``admittance``/``impedance``: render ``environment`` about the
        equilibrium angle ``reference``; ``open-loop``: apply ``command`` (A).
    reference, reference_speed, command, voluntary : array_like, shape (n_samples,), optional
        Defaults: zeros. ``voluntary`` is the user's voluntary ankle torque (N·m).
    environment : VirtualEnvironment, optional
        Required for the rendering modes.
    fault : FaultInjection, optional
        Sensor fault to inject.
    angle0 : float
        Initial platform angle, rad (at rest).
    seed : int or Generator
        Current-sensor noise.

    Returns
    -------
    SimulationResult
        Signals :data:`~anklelab.experiments._capstan_loop.SIGNALS` at ``setup.fs``.
    """
    if mode not in MODES:
        raise ParameterError(f"mode must be one of {list(MODES)}; got {mode!r}")
    if mode in ("admittance", "impedance") and environment is None:
        raise ParameterError(f"mode {mode!r} needs an environment")

    def signal(values: ArrayLike | None, name: str) -> NDArray[np.float64]:
        if values is None:
            return np.zeros(n_samples)
        array = np.ascontiguousarray(values, dtype=float)
        if array.shape != (n_samples,):
            raise ParameterError(f"{name} must have shape ({n_samples},); got {array.shape}")
        return array

    params = setup.params
    twin = setup.twin()
    gains = setup.resolved_gains()
    if mode in ("impedance", "open-loop"):
        gains = gains.replace({"kp_nm_per_rad": 0.0, "ki_nm_per_rad_s": 0.0, "kd_nms_per_rad": 0.0})
    ctrl = control_constants(
        params,
        gains,
        setup.fs,
        gravity_compensation=setup.gravity_compensation and mode != "open-loop",
        friction_compensation=0.0 if mode == "open-loop" else setup.friction_compensation,
        friction=setup.model_friction,
    )
    obs = observer_constants(
        params, setup.fs, cutoff_hz=setup.observer_cutoff_hz, friction=setup.model_friction
    )
    env = environment or VirtualEnvironment(stiffness_nm_per_rad=0, damping_nms_per_rad=0)
    rng = np.random.default_rng(seed)
    # single-precision draws are plenty for sensor noise and twice as fast
    noise = params.drive.current_noise_a * rng.standard_normal(n_samples, dtype=np.float32)
    noise = noise.astype(np.float64)
    out = closed_loop(
        twin.constants,
        twin.friction_law,
        twin.rest_state(angle0),
        MODES[mode],
        ctrl,
        obs,
        env.constants(),
        setup.safety_limits().to_array(),
        signal(reference, "reference"),
        signal(reference_speed, "reference_speed"),
        signal(command, "command"),
        signal(voluntary, "voluntary"),
        noise,
        FAULTS[fault.kind] if fault else 0,
        round(fault.time_s * setup.fs) if fault else 0,
        fault.value if fault else 0.0,
        twin.stepping(setup.fs),
        params.encoder.resolution_rad,
    )
    meta = {"mode": mode, "fs": setup.fs, "fault": fault.kind if fault else "none"}
    return SimulationResult(setup.fs, dict(zip(SIGNALS, out.T, strict=True)), meta)


# ----------------------------------------------------------------------------- set-point steps


@dataclass(frozen=True)
class StepMetrics:
    """Set-point response figures (platform angle as the encoder measures it).

    Attributes
    ----------
    amplitude_rad : float
        Step size.
    rise_time_s : float
        10 % to 90 % of the step.
    settling_time_s : float
        Last entry into the ±2 % band (inf if never settled).
    settling_time_5_s : float
        Same with a ±5 % band.
    overshoot_percent : float
        Peak beyond the set-point, % of the step (0 if none).
    steady_state_error_rad : float
        Mean of ``set-point - angle`` over the last 20 % of the record.
    """

    amplitude_rad: float
    rise_time_s: float
    settling_time_s: float
    settling_time_5_s: float
    overshoot_percent: float
    steady_state_error_rad: float


def _first_crossing(t: NDArray[np.float64], y: NDArray[np.float64], level: float) -> float:
    above = np.flatnonzero(y >= level)
    return float(t[above[0]]) if above.size else math.inf


def _settling(t: NDArray[np.float64], err: NDArray[np.float64], band: float) -> float:
    outside = np.flatnonzero(np.abs(err) > band)
    if outside.size == 0:
        return 0.0
    if outside[-1] == len(t) - 1:
        return math.inf
    return float(t[outside[-1] + 1])


def step_metrics(
    angle: ArrayLike, fs: float, amplitude_rad: float, *, start_s: float = 0.0
) -> StepMetrics:
    """Rise, settling, overshoot and steady-state error of a step from 0 to ``amplitude_rad``.

    Examples
    --------
    >>> fs = 1000.0
    >>> t = np.arange(1000) / fs
    >>> y = 0.1 * (1 - (1 + 20 * t) * np.exp(-20 * t))          # critically damped, w0 = 20
    >>> m = step_metrics(y, fs, 0.1)
    >>> round(m.rise_time_s, 3), round(m.settling_time_s, 3), m.overshoot_percent
    (0.168, 0.292, 0.0)
    """
    y = np.asarray(angle, dtype=float)
    t = np.arange(y.size) / fs - start_s
    keep = t >= 0
    t, y = t[keep], y[keep] / amplitude_rad
    err = 1.0 - y
    tail = max(1, y.size // 5)
    return StepMetrics(
        amplitude_rad=amplitude_rad,
        rise_time_s=_first_crossing(t, y, 0.9) - _first_crossing(t, y, 0.1),
        settling_time_s=_settling(t, err, 0.02),
        settling_time_5_s=_settling(t, err, 0.05),
        overshoot_percent=float(max(0.0, (y.max() - 1.0) * 100.0)),
        steady_state_error_rad=float(np.mean(err[-tail:]) * amplitude_rad),
    )


def step_response(
    setup: CapstanSetup,
    amplitude_rad: float,
    *,
    hold_s: float = 1.5,
    pre_s: float = 0.2,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, StepMetrics]:
    """Step the set-point from 0 to ``amplitude_rad`` after ``pre_s`` and hold ``hold_s``."""
    n = round((pre_s + hold_s) * setup.fs)
    reference = np.where(np.arange(n) >= round(pre_s * setup.fs), amplitude_rad, 0.0)
    result = simulate_closed_loop(setup, n, reference=reference, seed=seed)
    metrics = step_metrics(result["measured_angle_rad"], setup.fs, amplitude_rad, start_s=pre_s)
    return result, metrics


# ------------------------------------------------------------------------------ chirp tracking


@dataclass(frozen=True)
class ChirpMetrics:
    """Chirp-tracking figures.

    Attributes
    ----------
    rms_error_rad, max_error_rad : float
        Tracking error (reference minus measured angle).
    rms_error_to_3hz_rad : float
        RMS error while the chirp is below 3 Hz.
    frequency_hz, gain, phase_deg : ndarray
        Measured closed-loop frequency response, band-averaged.
    bandwidth_3db_hz : float
        First frequency where the gain falls below -3 dB (inf if it does not in the sweep).
    bandwidth_45deg_hz : float
        First frequency where the phase lag exceeds 45 degrees (inf if it does not).
    """

    rms_error_rad: float
    max_error_rad: float
    rms_error_to_3hz_rad: float
    frequency_hz: NDArray[np.float64]
    gain: NDArray[np.float64]
    phase_deg: NDArray[np.float64]
    bandwidth_3db_hz: float
    bandwidth_45deg_hz: float


def chirp_reference(
    amplitude_rad: float, f0_hz: float, f1_hz: float, duration_s: float, fs: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Linear chirp ``A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))`` and its derivative."""
    t = np.arange(round(duration_s * fs)) / fs
    rate = (f1_hz - f0_hz) / duration_s
    phase = 2 * np.pi * (f0_hz * t + 0.5 * rate * t**2)
    speed = amplitude_rad * np.cos(phase) * 2 * np.pi * (f0_hz + rate * t)
    return amplitude_rad * np.sin(phase), speed


def _first_below(f: NDArray[np.float64], value: NDArray[np.float64], level: float) -> float:
    """First frequency where ``value`` drops below ``level`` (log-frequency interpolation)."""
    below = np.flatnonzero(value < level)
    if below.size == 0:
        return math.inf
    k = below[0]
    if k == 0:
        return float(f[0])
    frac = (value[k - 1] - level) / (value[k - 1] - value[k])
    return float(f[k - 1] * (f[k] / f[k - 1]) ** frac)


def chirp_metrics(
    reference: ArrayLike,
    angle: ArrayLike,
    fs: float,
    f0_hz: float,
    f1_hz: float,
    *,
    duration_s: float | None = None,
    n_bands: int = 24,
) -> ChirpMetrics:
    """Tracking error and closed-loop frequency response of a linear chirp.

    Parameters
    ----------
    reference, angle : array_like
        Reference and measured angle, rad: the sweep, optionally followed by a rest period
        (reference 0) that lets the response ring down, which makes ``Y(f) = H(f) R(f)`` hold
        for the record.
    fs : float
        Sample rate, Hz.
    f0_hz, f1_hz : float
        Sweep start and end frequencies.
    duration_s : float, optional
        Sweep length (default: the whole record); tracking errors are taken over the sweep.
    n_bands : int
        The response is the ratio of the Fourier transforms, averaged (weighted by the
        reference's power) over ``n_bands`` log-spaced bands in ``[f0, f1]``.
    """
    r = np.asarray(reference, dtype=float)
    y = np.asarray(angle, dtype=float)
    sweep = r.size if duration_s is None else round(duration_s * fs)
    err = (r - y)[:sweep]
    inst_f = f0_hz + (f1_hz - f0_hz) * np.arange(sweep) / sweep
    spec_r, spec_y = np.fft.rfft(r), np.fft.rfft(y)
    freqs = np.fft.rfftfreq(r.size, 1 / fs)
    power = np.abs(spec_r) ** 2
    cross = spec_y * spec_r.conj()
    band = np.digitize(freqs, np.geomspace(f0_hz, f1_hz, n_bands + 1))
    inside = (band >= 1) & (band <= n_bands)
    weight = np.bincount(band[inside], power[inside], n_bands + 1)[1:]
    used = weight > 0
    f = np.bincount(band[inside], (power * freqs)[inside], n_bands + 1)[1:][used] / weight[used]
    h = (
        np.bincount(band[inside], cross.real[inside], n_bands + 1)[1:][used]
        + 1j * np.bincount(band[inside], cross.imag[inside], n_bands + 1)[1:][used]
    ) / weight[used]
    gain = np.abs(h)
    phase = np.degrees(np.unwrap(np.angle(h)))
    return ChirpMetrics(
        rms_error_rad=float(np.sqrt(np.mean(err**2))),
        max_error_rad=float(np.max(np.abs(err))),
        rms_error_to_3hz_rad=float(np.sqrt(np.mean(err[inst_f <= 3.0] ** 2))),
        frequency_hz=f,
        gain=gain,
        phase_deg=phase,
        bandwidth_3db_hz=_first_below(f, gain, 10 ** (-3 / 20)),
        bandwidth_45deg_hz=_first_below(f, phase, -45.0),
    )


def chirp_tracking(
    setup: CapstanSetup,
    *,
    amplitude_rad: float = math.radians(5.0),
    f0_hz: float = 0.2,
    f1_hz: float = 5.0,
    duration_s: float = 10.0,
    rest_s: float = 2.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, ChirpMetrics]:
    """Paper 001's chirp: 5 degrees, 0.2 to 5 Hz over 10 s (then ``rest_s`` at 0), with metrics."""
    reference, speed = chirp_reference(amplitude_rad, f0_hz, f1_hz, duration_s, setup.fs)
    rest = np.zeros(round(rest_s * setup.fs))
    reference, speed = np.concatenate([reference, rest]), np.concatenate([speed, rest])
    result = simulate_closed_loop(
        setup, reference.size, reference=reference, reference_speed=speed, seed=seed
    )
    metrics = chirp_metrics(
        reference, result["measured_angle_rad"], setup.fs, f0_hz, f1_hz, duration_s=duration_s
    )
    return result, metrics


# --------------------------------------------------------------------------- torque observation


@dataclass(frozen=True)
class ObserverMetrics:
    """How well the disturbance observer tracked the true human (interaction) torque.

    Attributes
    ----------
    vaf_percent : float
        Variance accounted for, ``100 (1 - var(true - estimate) / var(true))``.
    delay_s : float
        Lag of the estimate maximising its cross-correlation with the truth.
    vaf_delay_compensated_percent : float
        VAF after shifting the estimate back by ``delay_s``.
    rms_error_nm : float
        RMS of ``true - estimate``.
    """

    vaf_percent: float
    delay_s: float
    vaf_delay_compensated_percent: float
    rms_error_nm: float


def _vaf(true: NDArray[np.float64], estimate: NDArray[np.float64]) -> float:
    return float(100.0 * (1.0 - np.var(true - estimate) / np.var(true)))


def observer_metrics(
    true: ArrayLike, estimate: ArrayLike, fs: float, *, max_delay_s: float = 0.2
) -> ObserverMetrics:
    """VAF, delay (cross-correlation peak) and error of a torque estimate against the truth."""
    y = np.asarray(true, dtype=float)
    e = np.asarray(estimate, dtype=float)
    max_lag = round(max_delay_s * fs)
    yc, ec = y - y.mean(), e - e.mean()
    lags = np.arange(0, max_lag + 1)
    corr = np.array([np.dot(yc[: yc.size - k], ec[k:]) for k in lags])
    lag = int(lags[np.argmax(corr)])
    return ObserverMetrics(
        vaf_percent=_vaf(y, e),
        delay_s=lag / fs,
        vaf_delay_compensated_percent=_vaf(y[: y.size - lag], e[lag:]),
        rms_error_nm=float(np.sqrt(np.mean((y - e) ** 2))),
    )


def observer_trial(
    setup: CapstanSetup,
    task: Literal["hold", "track"] = "hold",
    *,
    duration_s: float = 20.0,
    torque_rms_nm: float = 3.0,
    band_hz: tuple[float, float] = (0.1, 3.0),
    track_amplitude_rad: float = math.radians(10.0),
    settle_s: float = 1.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, ObserverMetrics]:
    """The user pushes with a random voluntary torque while the platform holds or tracks.

    ``hold``: the set-point is level. ``track``: the set-point is a smooth multisine
    (0.1-0.5 Hz, ``track_amplitude_rad`` peak). Metrics ignore the first ``settle_s``.
    ``seed`` (int or Generator) draws the voluntary torque, the tracked multisine and the
    current-sensor noise; the same seed gives the same run.
    """
    if task not in ("hold", "track"):
        raise ParameterError(f"task must be 'hold' or 'track'; got {task!r}")
    rng = np.random.default_rng(seed)
    n = round(duration_s * setup.fs)
    torque = voluntary_torque(duration_s, setup.fs, rms_nm=torque_rms_nm, band_hz=band_hz, seed=rng)
    reference = np.zeros(n)
    speed = np.zeros(n)
    if task == "track":
        reference = voluntary_torque(duration_s, setup.fs, band_hz=(0.1, 0.5), seed=rng)
        reference *= track_amplitude_rad / np.max(np.abs(reference))
        speed = np.gradient(reference, 1.0 / setup.fs)
    result = simulate_closed_loop(
        setup, n, reference=reference, reference_speed=speed, voluntary=torque, seed=rng
    )
    skip = round(settle_s * setup.fs)
    metrics = observer_metrics(
        result["interaction_torque_nm"][skip:], result["estimated_torque_nm"][skip:], setup.fs
    )
    return result, metrics


# ---------------------------------------------------------------------------- haptic rendering


@dataclass(frozen=True)
class RenderMetrics:
    """The impedance the foot actually felt.

    The felt impedance ``Z(f) = S_theta,T(f) / S_theta,theta(f)`` (Welch cross- and
    auto-spectra of the twin's true platform angle and interaction torque, the angle measured
    from the equilibrium) is fitted by ``K - J w^2 + j B w`` over ``band_hz``; a spectral fit
    keeps the friction's stick-slip, which is not linear, from biasing the coefficients.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad, inertia_kgm2 : float
        Felt impedance.
    stiffness_error_percent, damping_error_percent : float
        Relative to the rendered environment's.
    equilibrium_rms_error_rad : float
        RMS of ``theta - theta_eq``.
    """

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float
    inertia_kgm2: float
    stiffness_error_percent: float
    damping_error_percent: float
    equilibrium_rms_error_rad: float


def render(
    setup: CapstanSetup,
    environment: VirtualEnvironment,
    *,
    mode: Literal["admittance", "impedance"] = "admittance",
    terrain: TerrainProfile | None = None,
    walking_speed_m_s: float = 1.0,
    duration_s: float = 30.0,
    torque_rms_nm: float = 2.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, RenderMetrics]:
    """Render ``environment`` to a user pushing with a random voluntary torque.

    Without ``terrain`` the equilibrium is level (a plain virtual spring-damper); with it, the
    equilibrium follows the slope under a user walking at ``walking_speed_m_s``. ``seed`` (int
    or Generator) draws the voluntary torque and the current-sensor noise; the same seed gives
    the same run.
    """
    rng = np.random.default_rng(seed)
    n = round(duration_s * setup.fs)
    equilibrium = (
        np.zeros(n)
        if terrain is None
        else terrain.equilibrium(duration_s, setup.fs, walking_speed_m_s)
    )
    torque = voluntary_torque(duration_s, setup.fs, rms_nm=torque_rms_nm, seed=rng)
    result = simulate_closed_loop(
        setup,
        n,
        mode=mode,
        reference=equilibrium,
        voluntary=torque,
        environment=environment,
        seed=rng,
    )
    return result, render_metrics(result, equilibrium, environment)


def render_metrics(
    result: SimulationResult,
    equilibrium: ArrayLike,
    environment: VirtualEnvironment,
    *,
    band_hz: tuple[float, float] = (0.2, 3.0),
    segment_s: float = 5.0,
) -> RenderMetrics:
    """Fit the felt impedance (see :class:`RenderMetrics`)."""
    from scipy.signal import csd, welch

    fs = result.fs
    deflection = result["angle_rad"] - np.asarray(equilibrium, dtype=float)
    torque = result["interaction_torque_nm"]
    nperseg = min(deflection.size, round(segment_s * fs))
    f, s_xx = welch(deflection, fs, nperseg=nperseg)
    _, s_xt = csd(deflection, torque, fs, nperseg=nperseg)
    sel = (f >= band_hz[0]) & (f <= band_hz[1])
    if sel.sum() < 3:
        raise ParameterError(
            f"band_hz {band_hz} holds fewer than 3 frequencies at {segment_s} s segments"
        )
    z, w = s_xt[sel] / s_xx[sel], 2 * np.pi * f[sel]
    zero, one = np.zeros_like(w), np.ones_like(w)
    design = np.vstack([np.column_stack([one, zero, -(w**2)]), np.column_stack([zero, w, zero])])
    stiffness, damping, inertia = np.linalg.lstsq(
        design, np.concatenate([z.real, z.imag]), rcond=None
    )[0]
    k_env, b_env = environment.stiffness_nm_per_rad, environment.damping_nms_per_rad
    return RenderMetrics(
        stiffness_nm_per_rad=float(stiffness),
        damping_nms_per_rad=float(damping),
        inertia_kgm2=float(inertia),
        stiffness_error_percent=float(100 * (stiffness - k_env) / k_env) if k_env else math.nan,
        damping_error_percent=float(100 * (damping - b_env) / b_env) if b_env else math.nan,
        equilibrium_rms_error_rad=float(np.sqrt(np.mean(deflection**2))),
    )
