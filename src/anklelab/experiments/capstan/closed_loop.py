"""Run the capstan twin in closed loop: the Python face of the compiled loop in
:mod:`anklelab.experiments.capstan._loop`.

Measured signals are what the controller saw (encoder, current sensor); ``angle_rad``,
``interaction_torque_nm`` and friends are the twin's ground truth.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.haptics import VirtualEnvironment
from anklelab.control.observer import observer_constants
from anklelab.control.pid import control_constants
from anklelab.errors import ParameterError
from anklelab.experiments.capstan._loop import FAULTS, MODES, SIGNALS, closed_loop
from anklelab.experiments.capstan.config import CapstanSetup, FaultInjection, Mode
from anklelab.sim.capstan import SimulationResult

__all__ = ["simulate_closed_loop"]


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
        Signals :data:`~anklelab.experiments.capstan._loop.SIGNALS` at ``setup.fs``.
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
