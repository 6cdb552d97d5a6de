"""Run the capstan twin in closed loop: the Python face of the compiled loop in
:mod:`anklelab.experiments.capstan._loop`.

Measured signals are what the controller saw (encoder, current sensor); ``angle_rad``,
``interaction_torque_nm`` and friends are the twin's ground truth.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from anklelab.control.haptics import VirtualEnvironment
from anklelab.control.observer import observer_constants
from anklelab.control.person_guard import guard_constants
from anklelab.control.pid import control_constants
from anklelab.errors import ParameterError
from anklelab.experiments.capstan._loop import (
    FAULTS,
    INPUTS,
    MODES,
    SCHEMES,
    SIGNALS,
    FeedforwardConstants,
    closed_loop,
)
from anklelab.experiments.capstan.config import (
    PERSON_FALLS,
    CapstanSetup,
    Channel,
    FaultInjection,
    Mode,
)
from anklelab.sim.capstan import SimulationResult
from anklelab.sim.capstan.person import person_constants, person_profile
from anklelab.sim.capstan.remote import arrivals, remote_constants

__all__ = ["simulate_closed_loop"]


def simulate_closed_loop(
    setup: CapstanSetup,
    n_samples: int,
    *,
    mode: Mode = "position",
    reference: ArrayLike | None = None,
    reference_speed: ArrayLike | None = None,
    reference_acceleration: ArrayLike | None = None,
    command: ArrayLike | None = None,
    voluntary: ArrayLike | None = None,
    environment: VirtualEnvironment | None = None,
    stiffness: ArrayLike | None = None,
    damping: ArrayLike | None = None,
    enabled: ArrayLike | None = None,
    stop: ArrayLike | None = None,
    remote_ground: ArrayLike | None = None,
    channel: Channel | None = None,
    fault: FaultInjection | None = None,
    angle0: float = 0.0,
    seed: int | np.random.Generator = 0,
) -> SimulationResult:
    """Run the twin in closed loop for ``n_samples`` control ticks.

    Parameters
    ----------
    setup : CapstanSetup
        Plant, controller, person and options.
    n_samples : int
        Number of control ticks (duration ``n_samples / setup.fs``).
    mode : {"position", "admittance", "impedance", "teleoperation", "open-loop"}
        ``position``: track ``reference`` (rad) with its speed and acceleration (for the
        derivative term and the feed-forward); ``admittance``/``impedance``: render
        ``environment`` (or the per-tick ``stiffness``/``damping``) about the equilibrium angle
        ``reference``; ``teleoperation``: display the remote robot over ``channel``;
        ``open-loop``: apply ``command`` (A) alone.
    reference, reference_speed, reference_acceleration : array_like, shape (n_samples,), optional
        Defaults: zeros. A non-finite reference makes a non-finite command, which the safety
        monitor latches as ``COMMAND_NAN``.
    command : array_like, shape (n_samples,), optional
        Current added to the controller's request, A (the whole command in ``open-loop``).
    voluntary : array_like, shape (n_samples,), optional
        The user's voluntary ankle torque, N·m (added to the person's own, if any).
    environment : VirtualEnvironment, optional
        Required for the rendering modes (its virtual inertia and angle limit; its stiffness
        and damping unless given per tick).
    stiffness, damping : array_like, shape (n_samples,), optional
        Per-tick virtual stiffness (``inf``: rigid ground in admittance) and damping.
    enabled : array_like of bool, shape (n_samples,), optional
        False switches the drive's output stage off for that tick (default: on throughout).
    stop : array_like of bool, shape (n_samples,), optional
        True requests the fall-safe stop (a fall detector, an operator).
    remote_ground : array_like, shape (n_samples,), optional
        Teleoperation: the slope of the ground under the remote robot's foot, rad.
    channel : Channel, optional
        Teleoperation: the network (default: wave variables, no delay).
    fault : FaultInjection, optional
        Sensor fault to inject.
    angle0 : float
        Initial platform angle, rad (at rest).
    seed : int or Generator
        Current-sensor noise and the person's sway.

    Returns
    -------
    SimulationResult
        Signals :data:`~anklelab.experiments.capstan._loop.SIGNALS` at ``setup.fs``.
    """
    if mode not in (*MODES, "open-loop"):
        raise ParameterError(f"mode must be one of {[*MODES, 'open-loop']}; got {mode!r}")
    if mode in ("admittance", "impedance") and environment is None:
        raise ParameterError(f"mode {mode!r} needs an environment")
    if fault is not None and fault.kind == PERSON_FALLS and setup.person is None:
        raise ParameterError("fault 'person-falls' needs a standing or stepping person")
    if not (isinstance(n_samples, int | np.integer) and n_samples > 0):
        raise ParameterError(f"n_samples must be a positive integer; got {n_samples!r}")
    params = setup.params
    rng = np.random.default_rng(seed)
    table = np.zeros((n_samples, len(INPUTS)))
    column = {name: k for k, name in enumerate(INPUTS)}

    def put(name: str, label: str, values: ArrayLike | None, default: float = 0.0) -> None:
        if values is None:
            table[:, column[name]] = default
            return
        array = np.asarray(values, dtype=float)
        if array.shape != (n_samples,):
            raise ParameterError(f"{label} must have shape ({n_samples},); got {array.shape}")
        table[:, column[name]] = array

    env = environment or VirtualEnvironment(stiffness_nm_per_rad=0, damping_nms_per_rad=0)
    put("reference_rad", "reference", reference)
    put("reference_speed_rad_s", "reference_speed", reference_speed)
    put("reference_acceleration_rad_s2", "reference_acceleration", reference_acceleration)
    put("feedforward_current_a", "command", command)
    put("stiffness_nm_per_rad", "stiffness", stiffness, env.stiffness_nm_per_rad)
    put("damping_nms_per_rad", "damping", damping, env.damping_nms_per_rad)
    put("enabled", "enabled", enabled, 1.0)
    put("voluntary_torque_nm", "voluntary", voluntary)
    put("stop", "stop", stop)
    put("remote_ground_rad", "remote_ground", remote_ground)
    if mode == "impedance" and not np.all(np.isfinite(table[:, column["stiffness_nm_per_rad"]])):
        raise ParameterError("impedance rendering needs a finite stiffness (inf is rigid ground)")
    # single-precision draws are plenty for sensor noise and twice as fast
    noise = params.drive.current_noise_a * rng.standard_normal(n_samples, dtype=np.float32)
    table[:, column["current_noise_a"]] = noise
    if setup.person is not None:
        profile = person_profile(
            setup.person, n_samples / setup.fs, setup.fs, params, setup.resolved_human(), seed=rng
        )
        table[:, column["person_stiffness_nm_per_rad"]] = profile.stiffness_nm_per_rad
        table[:, column["person_damping_nms_per_rad"]] = profile.damping_nms_per_rad
        table[:, column["person_load_nm"]] = profile.load_torque_nm
        table[:, column["person_contact"]] = profile.contact
        if fault is not None and fault.kind == PERSON_FALLS:
            gone = np.arange(n_samples) >= round(fault.time_s * setup.fs)
            for name in ("stiffness_nm_per_rad", "damping_nms_per_rad", "load_nm", "contact"):
                table[gone, column[f"person_{name}"]] = 0.0
    # a person falling is not a sensor fault: the loop itself sees nothing of it
    sensor = None if fault is None or fault.kind == PERSON_FALLS else fault
    channel = Channel() if channel is None else channel
    forward = arrivals(n_samples, setup.fs, channel.delay_s, channel.jitter_s, seed=rng)
    backward = arrivals(n_samples, setup.fs, channel.delay_s, channel.jitter_s, seed=rng)

    twin = setup.twin()
    gains = setup.resolved_gains()
    passive = mode in ("impedance", "teleoperation", "open-loop")
    if passive:
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
    w0 = 2.0 * math.pi * setup.observer_cutoff_hz
    lag = (2.0 / w0, 1.0 / w0**2) if setup.lag_compensation else (0.0, 0.0)
    foot = setup.foot()
    guard = guard_constants(
        params,
        setup.fs,
        foot_inertia_kgm2=foot.foot_inertia_kgm2 if foot else 0.0,
        enabled=setup.guard and foot is not None,
        detect_falls=setup.person is not None and setup.fall_detection,
    )
    out = closed_loop(
        twin.constants,
        twin.friction_law,
        twin.rest_state(angle0),
        MODES["position" if mode == "open-loop" else mode],
        ctrl,
        FeedforwardConstants(
            on=1.0 if setup.feedforward and not passive else 0.0,
            inertia=obs.inertia + (foot.foot_inertia_kgm2 if foot else 0.0),
            stiffness=foot.ankle_stiffness_nm_per_rad if foot else 0.0,
            damping=foot.ankle_damping_nms_per_rad if foot else 0.0,
        ),
        obs,
        env.constants(lag=lag, passivity_control=setup.passivity_control),
        guard,
        person_constants(params, setup.fs),
        remote_constants(params.teleop),
        SCHEMES[channel.scheme],
        forward,
        backward,
        setup.safety_limits().to_array(),
        table,
        FAULTS[sensor.kind] if sensor else 0,
        round(sensor.time_s * setup.fs) if sensor else 0,
        sensor.value if sensor else 0.0,
        twin.stepping(setup.fs),
        params.encoder.resolution_rad,
    )
    meta = {
        "mode": mode,
        "fs": setup.fs,
        "fault": fault.kind if fault else "none",
        "person": setup.person or ("seated" if setup.with_user else "none"),
    }
    return SimulationResult(setup.fs, dict(zip(SIGNALS, out.T, strict=True)), meta)
