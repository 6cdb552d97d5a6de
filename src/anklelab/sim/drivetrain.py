"""The servo-driven hinge of the Perturberator: drive cascade, drivetrain, hinge and plate load.

Model (all referred to the platform output, dorsiflexion positive)::

    current loop   tau' = 2 pi f_c (tau_cmd - tau),   |tau_cmd| <= min(653 N·m, N Kt I_peak)
    motor+gearhead J_m w_m' = tau - T_s - b_m w_m - T_c tanh(w_m / w_e)
    hinge + plate  J_h w_h' = T_s - b_h w_h - k_g sin(th_h) + M_foot
    coupler        T_s = k_s (th_m - th_h) + c_s (w_m - w_h)

with ``J_m = (J_rotor + J_gearhead) N²`` and ``k_s`` the coupler + transmission stiffness (paper
000: 12 N·m/arcmin). ``M_foot`` is the moment of the foot's load about the hinge axis (see
:mod:`anklelab.sim.foot`). The drive closes, on the quantised motor encoder, a proportional
position loop at the position-loop rate (8 kHz) and a PI velocity loop (backward-difference
velocity) at the velocity-loop rate (16 kHz), whose torque command takes effect one velocity
sample later. The plant is integrated by RK4 with the command held, ``substeps`` steps per
velocity-loop period (the integration step the convergence test halves); the Coulomb term and
the hinge's tilt (sin, cos) are evaluated once per integration step.

Faults and the fault reaction. Every velocity-loop sample the drive checks, in this order: the
encoder reading is finite (else ``ENCODER``); a new encoder frame arrived within
``encoder_timeout_samples`` samples (else ``ENCODER_STALE``); the encoder speed is within
``velocity_limit_rad_per_s`` (else ``VELOCITY``: a runaway, or an encoder jump, which reads as
a speed spike); the angle is within ``angle_limit_rad`` (else ``POSITION``); the position
command minus the encoder is within ``following_error_limit_rad`` (else ``FOLLOWING_ERROR``).
The first fault latches, and the drive stops the hinge as a Kollmorgen AKD does (AKD user
guide, sections "Controlled Stop" and "Dynamic Braking"; AKD fault card):

- feedback it can trust (``POSITION``, ``FOLLOWING_ERROR``): *controlled stop* — the position
  loop is dropped and the velocity loop is commanded to zero speed at once (``CS.DEC`` set
  above what the torque limit allows), within the torque limit; it then keeps commanding zero
  speed, which holds the shaft where it stopped (the integral action is a stiff position hold;
  the real drive would hand over to the holding brake, which the twin need not model);
- feedback lost or suspect (``ENCODER``, ``ENCODER_STALE``, ``VELOCITY``): *dynamic brake* —
  the drive shorts the windings in phase with the back EMF, which needs no feedback; the
  motor feels ``-b_db w_m`` with ``b_db = 2 Kt² N² / (3 R)`` (three-phase short of line-to-line
  resistance ``R``, ``Kt`` per rms ampere; winding inductance neglected) within the torque
  limit (``DRV.DBILIMIT`` at the peak current), and the spring-applied holding brake, released
  only while the power stage is enabled (``MOTOR.BRAKEIMM = 1``, as for a load that must not
  drop), locks the motor shaft ``brake_engage_s`` later. A dynamic brake alone holds no
  steady load (someone standing on the plate would push it round at ``M / b_db``).

:func:`stopping_distance` bounds how far the hinge travels after a trip.
"""

from __future__ import annotations

import itertools
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import ParameterError, SafetyLimitError
from anklelab.iir import butterworth_sos, group_delay_at_dc, resonance_sos
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim import _kernels as K
from anklelab.sim.artefacts import Artefacts

__all__ = [
    "GRAVITY",
    "DriveFault",
    "EncoderFault",
    "FootLoad",
    "PlatformRun",
    "default_threads",
    "dynamic_brake_nms_per_rad",
    "force_delay_ms",
    "kernel_needs_compiling",
    "platform_constants",
    "simulate_platform",
    "stopping_distance",
]

GRAVITY = 9.81


class DriveFault(IntEnum):
    """Why the servo drive disabled its output (0: it did not)."""

    NONE = 0
    ENCODER = K.D_ENCODER  # non-finite (lost) position feedback
    POSITION = K.D_POSITION  # beyond the hinge's angle limit
    VELOCITY = K.D_VELOCITY  # overspeed
    FOLLOWING_ERROR = K.D_FOLLOWING  # command minus encoder beyond its threshold
    ENCODER_STALE = K.D_STALE  # no new encoder frame within the watchdog's timeout

    @property
    def controlled_stop(self) -> bool:
        """Whether the drive stops under velocity control (else by the dynamic brake)."""
        return self in (DriveFault.POSITION, DriveFault.FOLLOWING_ERROR)


class EncoderFault(IntEnum):
    """An injected encoder failure (fault-injection tests)."""

    NAN = K.E_NAN  # the reading is lost (non-finite)
    STALE = K.E_STALE  # no new frame arrives: the reading freezes
    JUMP = K.E_JUMP  # the reading jumps by a fixed offset


@dataclass(frozen=True)
class FootLoad:
    """What stands on the plate, per trial, in the form the kernel integrates.

    Attributes
    ----------
    channels : ndarray, shape (n_trials, 8, n_samples)
        Lab GRF on the foot (anterior, right, up; N), nominal ankle torque (N·m), lateral COP
        (m), foot stiffness (N·m/rad), damping (N·m·s/rad) and contact (0/1), sampled at ``fs``
        from the start of the trial (order of :mod:`anklelab.sim._kernels` ``G_*``).
    fs : float
        Sample rate of ``channels``, Hz.
    scalars : ndarray, shape (n_trials, 7)
        Foot inertia (kg·m²), ankle anterior position on the plate (m), ankle height above the
        surface (m), misalignment gain ``e_z / shank length``, leg stiffness (N/m), shell
        stiffness (N·m/rad, 0 = rigid contact), shell damping (order of ``F_*``).
    """

    channels: NDArray[np.float64]
    fs: float
    scalars: NDArray[np.float64]


@dataclass(frozen=True)
class PlatformRun:
    """Recorded true signals of a batch of trials, each ``(n_trials, n_samples)`` at ``fs``.

    ``ankle_angle`` is the ankle's rotation caused by the platform (foot relative to shank);
    ``ankle_torque`` the external dorsiflexing moment on the foot about the ankle centre;
    ``wrench`` (``(n_trials, 6, n_samples)``, or None) the plate load of
    :mod:`anklelab.sim.forceplate_dynamics`; ``loop`` (or None) the position loop's encoder,
    controller output and velocity command at the position-loop rate; ``snapshot`` (or None)
    each trial's full state at its ``fork`` step, to resume from; ``fault`` each trial's latched
    :class:`DriveFault` code and ``fault_s`` when it tripped (NaN if it did not).
    """

    fs: float
    motor_angle: NDArray[np.float64]
    hinge_angle: NDArray[np.float64]
    ankle_angle: NDArray[np.float64]
    ankle_torque: NDArray[np.float64]
    motor_torque: NDArray[np.float64]
    wrench: NDArray[np.float64] | None
    loop: dict[str, NDArray[np.float64]] | None
    snapshot: NDArray[np.float64] | None = None
    fault: NDArray[np.int64] | None = None
    fault_s: NDArray[np.float64] | None = None


def dynamic_brake_nms_per_rad(params: PerturberatorParameters) -> float:
    """Braking coefficient of the shorted windings referred to the output, N·m·s/rad.

    ``2 Kt² N² / (3 R)``: each phase's back EMF ``Kt w / 3`` drives ``2 Kt w / (3 R)`` rms
    amperes through half the line-to-line resistance ``R``, and ``Kt`` turns it into torque.
    """
    m = params.motor
    n = params.transmission.ratio
    return 2 * m.torque_constant_nm_per_a**2 * n * n / (3 * m.winding_resistance_ohm)


# gait channels that load the plate; the others (stiffness, damping, the COP's lateral position)
# act only through a load or a deflection
_LOAD_CHANNELS = [K.G_X, K.G_Y, K.G_Z, K.G_TNOM, K.G_CONTACT]


def platform_constants(
    params: PerturberatorParameters, *, hinge_height_m: float, quantisation: bool = True
) -> NDArray[np.float64]:
    """The kernel's constant vector (indices ``anklelab.sim._kernels`` ``J_M`` ... ``DT``)."""
    m, tr, hg, sv, fp = (
        params.motor,
        params.transmission,
        params.hinge,
        params.servo,
        params.force_plate,
    )
    n = tr.ratio
    pc = np.zeros(K.N_PC)
    pc[K.J_M] = (m.rotor_inertia_kgm2 + m.gearhead_input_inertia_kgm2) * n * n
    pc[K.K_S] = tr.series_stiffness_nm_per_rad
    pc[K.C_S] = tr.series_damping_nms_per_rad
    pc[K.B_M] = tr.viscous_nms_per_rad
    pc[K.T_COUL] = tr.coulomb_nm
    pc[K.W_EPS] = tr.coulomb_smoothing_rad_per_s
    pc[K.J_H] = hg.inertia_kgm2
    pc[K.B_H] = hg.viscous_nms_per_rad
    pc[K.K_G] = hg.gravity_stiffness_nm_per_rad
    pc[K.TAU_MAX] = min(tr.peak_output_torque_nm, m.torque_constant_nm_per_a * m.peak_current_a * n)
    pc[K.INV_TC] = 2 * np.pi * sv.current_bandwidth_hz
    pc[K.KPP] = sv.position_gain_per_s
    pc[K.KVP] = sv.velocity_gain_nms_per_rad
    pc[K.WI] = 2 * np.pi * sv.velocity_integral_hz
    pc[K.ENC_Q] = sv.encoder_resolution_rad / n if quantisation else 0.0
    pc[K.AZ0] = fp.az0_m
    pc[K.X_H] = hg.axis_anterior_m
    pc[K.H_H] = hinge_height_m
    pc[K.M_T] = fp.top_plate_mass_kg
    pc[K.I_T] = fp.top_plate_inertia_kgm2
    pc[K.X_T] = fp.top_plate_com_x_m
    pc[K.Z_T] = fp.top_plate_com_z_m
    pc[K.GRAV] = GRAVITY
    pc[K.DT] = 1.0 / sv.velocity_loop_rate_hz
    pc[K.POS_MAX] = hg.angle_limit_rad
    pc[K.VEL_MAX] = sv.velocity_limit_rad_per_s
    pc[K.FOLLOW_MAX] = sv.following_error_limit_rad
    pc[K.ENC_TIMEOUT] = sv.encoder_timeout_samples
    pc[K.B_DB] = dynamic_brake_nms_per_rad(params)
    pc[K.BRAKE_STEPS] = round(m.brake_engage_s * sv.velocity_loop_rate_hz)
    return pc


def simulate_platform(
    params: PerturberatorParameters,
    reference: NDArray[np.float64],
    *,
    load: FootLoad | None = None,
    injection: NDArray[np.float64] | None = None,
    artefacts: Artefacts | None = None,
    plate: bool = True,
    record_loop: bool = False,
    substeps: int = 1,
    record_fs: float | None = None,
    fork: NDArray[np.int64] | None = None,
    resume: tuple[NDArray[np.int64], NDArray[np.float64]] | None = None,
    stop: NDArray[np.int64] | None = None,
    encoder_fault_s: NDArray[np.float64] | None = None,
    encoder_fault: EncoderFault = EncoderFault.NAN,
    encoder_jump_rad: float = 0.0,
    threads: int | None = None,
) -> PlatformRun:
    """Run the servo-controlled hinge on a batch of position references.

    Parameters
    ----------
    params : PerturberatorParameters
        Platform parameters (gains, drivetrain, plate).
    reference : ndarray, shape (n_trials, n_ticks)
        Position command at each position-loop tick, rad (the drive's step counter times the
        step size, see :mod:`anklelab.control.motion_plan`).
    load : FootLoad, optional
        Foot and gait on the plate; None for an empty plate.
    injection : ndarray, shape (n_trials, n_ticks), optional
        Velocity command added to the position controller's output, rad/s (loop measurement).
    artefacts : Artefacts, optional
        Which plate and quantisation effects to include (default: all).
    plate : bool
        Compute the plate wrench (False skips the plate chain, e.g. for reference runs).
    record_loop : bool
        Also record the position loop's signals at the position-loop rate.
    substeps : int
        RK4 steps per velocity-loop period.
    record_fs : float, optional
        Recording rate (default: the DAQ rate); must divide the position-loop rate.
    fork : ndarray of int, shape (n_trials,), optional
        Velocity-loop step at whose start each trial's state is saved (-1: none); returned as
        ``snapshot``.
    resume : (steps, states), optional
        Start each trial at velocity-loop step ``steps[i]`` from ``states[i]`` (a snapshot);
        samples before it are left at zero.
    stop : ndarray of int, shape (n_trials,), optional
        Velocity-loop step at which each trial ends (default: the end of ``reference``).
    encoder_fault_s : ndarray, shape (n_trials,), optional
        Fault injection: from this time (s; NaN for never) the encoder fails.
    encoder_fault : EncoderFault
        How it fails: reads NaN, freezes (no new frames) or jumps by ``encoder_jump_rad``.
    encoder_jump_rad : float
        Size of a jump, rad.
    threads : int, optional
        Trials are independent: split the batch across this many threads (default
        :func:`default_threads`). The result does not depend on it, bit for bit.

    Returns
    -------
    PlatformRun
    """
    art = Artefacts() if artefacts is None else artefacts
    sv = params.servo
    if sv.velocity_loop_rate_hz != 2 * sv.position_loop_rate_hz:
        raise ParameterError(
            "servo: the twin needs velocity_loop_rate_hz = 2 x position_loop_rate_hz"
        )
    if substeps < 1:
        raise ParameterError(f"substeps: expected >= 1, got {substeps}")
    ref = np.ascontiguousarray(np.atleast_2d(reference), dtype=float)
    if not np.isfinite(ref).all():
        raise SafetyLimitError("reference: the drive refuses a non-finite position command")
    n_trials, n_ticks = ref.shape
    fs_rec = params.daq.sample_rate_hz if record_fs is None else record_fs
    rec_every = round(sv.velocity_loop_rate_hz / fs_rec)
    if not np.isclose(rec_every * fs_rec, sv.velocity_loop_rate_hz) or rec_every % 2:
        raise ParameterError(f"record_fs: {fs_rec} Hz must divide the position-loop rate")
    geometry = params.geometry
    hinge_height = geometry.ankle_height_m - geometry.misalignment_vertical_m
    pc = platform_constants(params, hinge_height_m=hinge_height, quantisation=art.quantisation)
    constants = tuple(pc.tolist())  # the kernel keeps them in registers
    if load is None:
        g = np.zeros((n_trials, 2, K.N_G))
        fp = np.ones((n_trials, K.N_FP))
        gait_fs = 1.0
    else:
        g, fp, gait_fs = load.channels.transpose(0, 2, 1), load.scalars, load.fs
    inj = np.zeros((n_trials, 0)) if injection is None else np.atleast_2d(injection).astype(float)
    if inj.size and inj.shape != ref.shape:
        raise ParameterError(f"injection: expected shape {ref.shape}, got {inj.shape}")
    plate_sos, plate_sections = _plate_filters(params, art)
    flags = np.zeros(K.N_FL, dtype=np.int64)
    flags[K.FL_FOOT] = load is not None
    flags[K.FL_PLATE] = plate
    flags[K.FL_INERTIA] = art.plate_inertia
    flags[K.FL_LOOP] = record_loop
    flags[K.FL_NSUB] = substeps
    flags[K.FL_RESUME] = resume is not None
    n_steps = 2 * n_ticks
    span = np.zeros((n_trials, 2), dtype=np.int64)
    span[:, 1] = n_steps if stop is None else stop
    start_state = np.zeros((n_trials, K.N_SNAP))
    if resume is not None:
        span[:, 0], start_state = resume[0], np.ascontiguousarray(resume[1], dtype=float)
    forks = np.full(n_trials, -1, dtype=np.int64) if fork is None else fork.astype(np.int64)
    snap = np.zeros((n_trials, K.N_SNAP))
    enc_fault = np.full((n_trials, 2), -1, dtype=np.int64)
    enc_fault[:, 1] = EncoderFault(encoder_fault)
    if encoder_fault_s is not None:
        lost = np.isfinite(encoder_fault_s)
        enc_fault[lost, 0] = np.round(encoder_fault_s[lost] * sv.velocity_loop_rate_hz)
    if resume is None:  # skip what stays exactly at rest
        due = np.where(enc_fault[:, 0] >= 0, enc_fault[:, 0], n_steps)
        due = np.minimum(due, np.where(forks >= 0, forks, n_steps))
        rate = sv.velocity_loop_rate_hz
        span[:, 0] = _steps_at_rest(ref, inj, g if load is not None else None, gait_fs / rate, due)
    enc_jump = np.full(n_trials, float(encoder_jump_rad))
    fault = np.zeros((n_trials, 2), dtype=np.int64)
    n_rec = -(-2 * n_ticks // rec_every)
    mech = np.zeros((n_trials, K.N_MECH, n_rec))
    wrench = np.zeros((n_trials, K.N_WRENCH, n_rec if plate else 0))
    loop = np.zeros((n_trials, 3, n_ticks if record_loop else 0))
    per_trial = (
        np.ascontiguousarray(fp, dtype=float), np.ascontiguousarray(g, dtype=float), ref,
        np.ascontiguousarray(inj), span, start_state, forks, enc_fault, enc_jump, mech, wrench,
        loop, snap, fault,
    )  # fmt: skip

    def run(rows: slice) -> None:
        fp_, g_, ref_, inj_, span_, start_, fork_, enc_, jump_, mech_, wr_, loop_, snap_, fault_ = (
            a[rows] for a in per_trial
        )
        K.run_batch(
            constants, fp_, g_, float(gait_fs), ref_, inj_, flags, plate_sos, plate_sections, 2,
            rec_every, span_, start_, fork_, enc_, jump_, mech_, wr_, loop_, snap_, fault_,
        )  # fmt: skip

    n_threads = max(1, min(default_threads() if threads is None else threads, n_trials))
    edges = np.linspace(0, n_trials, n_threads + 1).round().astype(int)
    chunks = [slice(a, b) for a, b in itertools.pairwise(edges)]
    if n_threads == 1:
        run(chunks[0])
    else:  # the kernel releases the GIL
        with ThreadPoolExecutor(n_threads) as pool:
            list(pool.map(run, chunks))
    return PlatformRun(
        fs=fs_rec,
        motor_angle=mech[:, K.O_THM],
        hinge_angle=mech[:, K.O_THH],
        ankle_angle=mech[:, K.O_PHI],
        ankle_torque=mech[:, K.O_TA],
        motor_torque=mech[:, K.O_TAU],
        wrench=wrench if plate else None,
        loop=dict(zip(("encoder", "control", "command"), loop.transpose(1, 0, 2), strict=True))
        if record_loop
        else None,
        snapshot=snap if fork is not None else None,
        fault=fault[:, 0],
        fault_s=np.where(fault[:, 0] > 0, fault[:, 1] / sv.velocity_loop_rate_hz, np.nan),
    )


def _steps_at_rest(
    reference: NDArray[np.float64],
    injection: NDArray[np.float64],
    gait: NDArray[np.float64] | None,
    gait_samples_per_step: float,
    due: NDArray[np.int64],
) -> NDArray[np.int64]:
    """Velocity-loop steps during which each trial stays exactly at rest, from its start.

    The platform starts at rest (every state zero) and stays there, to the last bit, until the
    position command or the injection leaves zero, a load reaches the plate or a gait channel
    is not finite; ``due`` are steps that must be simulated whatever happens (a fault
    injection, a snapshot). The kernel starts each trial where this returns (with two steps of
    margin), so the samples before it hold the zeros the simulation would have produced (as
    +0.0: with both of the plate's filters off, the kernel writes Fx and Fy at rest as -0.0).

    Parameters
    ----------
    reference, injection : ndarray, shape (n_trials, n_ticks) (injection may be (n_trials, 0))
        The kernel's position command and velocity injection, per position-loop tick.
    gait : ndarray, shape (n_trials, n_gait, N_G), optional
        The kernel's gait channels (None: an empty plate).
    gait_samples_per_step : float
        Gait samples per velocity-loop step.
    due : ndarray of int, shape (n_trials,)
        First step that must be simulated regardless.
    """
    moving = reference != 0
    if injection.size:
        moving |= injection != 0
    first = np.where(moving.any(axis=1), 2 * moving.argmax(axis=1), 2 * reference.shape[1])
    if gait is not None:  # gait sample r is interpolated into every step after sample r - 1
        active = (gait[:, :, _LOAD_CHANNELS] != 0).any(axis=2) | ~np.isfinite(gait).all(axis=2)
        row = np.where(active.any(axis=1), active.argmax(axis=1), gait.shape[1])
        first = np.minimum(first, np.floor((row - 1) / gait_samples_per_step).astype(np.int64))
    return np.clip(np.minimum(first, due) - 2, 0, None)


def force_delay_ms(params: PerturberatorParameters, art: Artefacts) -> float:
    """How much later the plate's channels are recorded than the angles, ms: the group delay
    of the amplifier's anti-alias low-pass for slow signals (0 with it switched off), what a
    lab reads off its amplifier's data sheet and records as ``[force_plate] delay_ms``."""
    if not art.anti_alias:
        return 0.0
    fplate = params.servo.position_loop_rate_hz
    sos = butterworth_sos(params.daq.anti_alias_order, params.daq.anti_alias_hz, fplate)
    return 1000.0 * group_delay_at_dc(sos) / fplate


def _plate_filters(
    params: PerturberatorParameters, art: Artefacts
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The second-order sections that filter each plate-frame wrench component in the kernel
    (``(6, n_sections, 6)`` at the position-loop rate) and how many each uses: the plate's
    structural mode (vertical for Fz, Mx, My; horizontal for Fx, Fy, Mz), then the DAQ's
    anti-alias filter, as the artefacts switch them on."""
    fplate = params.servo.position_loop_rate_hz
    fpp = params.force_plate
    vertical = resonance_sos(fpp.vertical_natural_frequency_hz, fpp.damping_ratio, fplate)
    horizontal = resonance_sos(fpp.horizontal_natural_frequency_hz, fpp.damping_ratio, fplate)
    anti_alias = butterworth_sos(params.daq.anti_alias_order, params.daq.anti_alias_hz, fplate)
    chains = [
        ([mode] if art.resonance else []) + ([anti_alias] if art.anti_alias else [])
        for mode in (horizontal, horizontal, vertical, vertical, vertical, horizontal)
    ]
    stacked = [np.concatenate(chain) if chain else np.zeros((0, 6)) for chain in chains]
    sections = np.array([len(c) for c in stacked], dtype=np.int64)
    sos = np.zeros((K.N_WRENCH, max(1, int(sections.max())), 6))
    for c, chain in enumerate(stacked):
        sos[c, : len(chain)] = chain
    return sos, sections


def default_threads() -> int:
    """Threads a simulation uses by default: the CPUs this process may run on.

    ``ANKLELAB_SIM_THREADS`` overrides it (a study's workers set 1: they are the parallelism).
    """
    value = os.environ.get("ANKLELAB_SIM_THREADS")
    if value:
        return max(1, int(value))
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def kernel_needs_compiling() -> bool:
    """Whether the next simulation will compile the twin's kernel (neither in this process nor
    in numba's on-disk cache for these sources).

    Reads numba's cache index (an internal of numba: if it changes, this answers False and the
    compilation simply happens unannounced).
    """
    if K.run_batch.signatures:
        return False
    try:
        return not K.run_batch._cache._cache_file._load_index()  # type: ignore[attr-defined]
    except Exception:  # numba internals: never fail a simulation over a notice
        return False


def stopping_distance(
    params: PerturberatorParameters,
    speed: float,
    fault: DriveFault,
    *,
    load_nm: float = 0.0,
    load_inertia_kgm2: float = 0.0,
) -> float:
    """Upper bound on how far the hinge travels past where the drive tripped, rad.

    The sum of three terms, each an upper bound:

    - the reaction delay (the tripping sample, one sample of computation delay, the current
      loop's time constant and, for ``ENCODER_STALE``, the watchdog's timeout) at the trip
      speed;
    - the braking distance of the motor and hinge as one body ``J`` under the braking law, a
      viscous torque ``c w`` within the torque limit ``T`` (``c`` the velocity loop's
      proportional gain in a controlled stop, ``b_db`` under the dynamic brake):
      ``J w / c`` below ``w* = T / c``, plus ``J (w² - w*²) / (2 T)`` above it; under the
      dynamic brake a steady ``load_nm`` pushing the hinge along adds its creep ``M / b_db``
      until the holding brake closes (the controlled stop's integral action already carries
      the load);
    - the hinge's swing on the compliant coupler, at most ``w sqrt(J_h / k_s)`` (the swing if
      the motor stopped at once; ``J_h`` includes what stands on the plate).

    Parameters
    ----------
    params : PerturberatorParameters
        Platform parameters.
    speed : float
        Platform speed when the drive trips, rad/s.
    fault : DriveFault
        The fault (it selects the reaction).
    load_nm : float
        Steady moment on the hinge, N·m.
    load_inertia_kgm2 : float
        Inertia moving with the hinge (a foot flat on the plate), kg·m².

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("perturberator")
    >>> round(stopping_distance(p, 0.5, DriveFault.POSITION) * 1e3, 2)  # mrad
    2.68
    """
    fault = DriveFault(fault)
    pc = platform_constants(params, hinge_height_m=0.0)
    w = abs(speed)
    hinge = pc[K.J_H] + load_inertia_kgm2
    inertia = pc[K.J_M] + hinge
    timeout = pc[K.ENC_TIMEOUT] if fault == DriveFault.ENCODER_STALE else 0.0
    delay = (2 + timeout) * pc[K.DT] + 1 / pc[K.INV_TC]
    c = pc[K.KVP] if fault.controlled_stop else pc[K.B_DB]
    knee = pc[K.TAU_MAX] / c
    braking = inertia * min(w, knee) / c + inertia * max(w * w - knee * knee, 0.0) / (
        2 * pc[K.TAU_MAX]
    )
    if not fault.controlled_stop:
        braking += abs(load_nm) / c * params.motor.brake_engage_s
    swing = w * np.sqrt(hinge / pc[K.K_S])
    return float(w * delay + braking + swing)
