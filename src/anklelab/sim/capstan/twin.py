"""The capstan platform's digital twin, driven open loop by a current command."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters, UserParameters
from anklelab.sim.capstan.friction_law import friction_array
from anklelab.sim.capstan.plant import (
    STATE_NAMES,
    PlantConstants,
    Stepping,
    plant_advance,
    plant_constants,
    stepping,
)
from anklelab.sim.capstan.result import SimulationResult

__all__ = ["CapstanTwin"]


class CapstanTwin:
    """Plant model of paper 001's platform with its drive, cable, friction and (optionally) a foot.

    Parameters
    ----------
    params : CapstanParameters, optional
        Platform parameters; the shipped set by default.
    user : UserParameters or None
        The foot and ankle on the platform; None (default) for an empty platform.
    coupled : bool
        False disconnects the cable (motor, gearhead and pinion alone, as identified in paper
        001, section 3.3).
    max_step_s : float
        Longest physics sub-step, s; each control period is split into equal sub-steps.

    Examples
    --------
    >>> twin = CapstanTwin()
    >>> run = twin.simulate(np.full(200, 1.0), fs=1000.0)   # 1 A for 0.2 s
    >>> bool(run["angle_rad"][-1] > 0)                      # the platform dorsiflexes
    True
    """

    def __init__(
        self,
        params: CapstanParameters | None = None,
        user: UserParameters | None = None,
        *,
        coupled: bool = True,
        max_step_s: float = 2e-4,
    ) -> None:
        if not max_step_s > 0:
            raise ParameterError(f"max_step_s must be > 0; got {max_step_s}")
        self.params = load_platform("capstan") if params is None else params
        self.user = user
        self.coupled = coupled
        self.max_step_s = max_step_s
        self.constants: PlantConstants = plant_constants(self.params, user, coupled=coupled)
        self.friction_law: NDArray[np.float64] = friction_array(self.params.friction)

    def stepping(self, fs: float) -> Stepping:
        """Sub-steps of a control period at ``fs`` Hz (see :func:`~.plant.stepping`)."""
        return stepping(self.constants, fs, self.max_step_s)

    def gravity_torque(self, angle: ArrayLike) -> NDArray[np.float64]:
        """Torque the actuator must supply to hold the platform against gravity, N·m (eq. 3)."""
        c = self.constants
        return c.gravity_torque * np.sin(np.asarray(angle, dtype=float) + c.com_angle)

    def rest_state(self, angle: float = 0.0) -> NDArray[np.float64]:
        """State holding the platform still at ``angle`` with the current that balances it.

        The cable stretch carries gravity and the ankle's passive torque; the motor current
        supplies exactly that torque, so nothing moves at ``t = 0``. With the cable disconnected
        the pinion simply rests at ``angle`` times the capstan ratio.
        """
        c = self.constants
        if not self.coupled:  # the pinion alone, at the referred angle
            return np.array([0.0, angle * c.pulley_radius / c.pinion_radius, 0.0, angle, 0.0])
        load = float(self.gravity_torque(angle)) + c.ankle_stiffness * (angle - c.rest_angle)
        stretch = load / (c.pulley_radius * (c.k_cable + c.k_spring_strand))
        pinion = (c.pulley_radius * angle + stretch) / c.pinion_radius
        current = load / (c.torque_constant * c.gear_ratio * c.pulley_radius / c.pinion_radius)
        return np.array([current, pinion, 0.0, angle, 0.0])

    def simulate(
        self,
        current_a: ArrayLike,
        fs: float,
        *,
        voluntary_torque_nm: ArrayLike | None = None,
        angle0: float = 0.0,
        state0: ArrayLike | None = None,
        current_noise: NDArray[np.float64] | None = None,
    ) -> SimulationResult:
        """Apply a current command sampled at ``fs`` Hz (zero-order hold) and record the plant.

        Parameters
        ----------
        current_a : array_like, shape (n,)
            Current command, A.
        fs : float
            Command rate, Hz.
        voluntary_torque_nm : array_like, shape (n,), optional
            The user's voluntary ankle torque, N·m.
        angle0 : float
            Initial platform angle, rad (started at rest, see :meth:`rest_state`).
        state0 : array_like, shape (5,), optional
            Full initial state (see :data:`~anklelab.sim.capstan.STATE_NAMES`); overrides
            ``angle0``.
        current_noise : ndarray, shape (n,), optional
            The drive's current-sensor error each period, A.

        Returns
        -------
        SimulationResult
            The state at the end of each period (``current_a``, ``pinion_angle_rad``, ...,
            ``angle_rad``, ``speed_rad_s``) and the period means ``interaction_torque_nm``,
            ``friction_torque_nm`` (at the pinion) and ``voltage_v``.
        """
        command = np.ascontiguousarray(current_a, dtype=float)
        n = len(command)
        vol = np.zeros(n) if voluntary_torque_nm is None else np.asarray(voluntary_torque_nm, float)
        noise = np.zeros(n) if current_noise is None else np.asarray(current_noise, float)
        if vol.shape != (n,) or noise.shape != (n,):
            raise ParameterError(
                "voluntary_torque_nm and current_noise must match current_a's length"
            )
        x0 = self.rest_state(angle0) if state0 is None else np.array(state0, dtype=float)
        if x0.shape != (len(STATE_NAMES),):
            raise ParameterError(f"state0 must have shape ({len(STATE_NAMES)},); got {x0.shape}")
        states, extra = _open_loop(
            self.constants,
            self.friction_law,
            self.stepping(fs),
            x0,
            command,
            noise,
            vol,
        )
        signals = dict(zip(STATE_NAMES, states.T, strict=True))
        signals |= {
            "interaction_torque_nm": extra[:, 0],
            "friction_torque_nm": extra[:, 1],
            "voltage_v": extra[:, 2],
            "current_command_a": command,
        }
        return SimulationResult(fs, signals, {"protocol": "open-loop current"})


@njit(cache=True)
def _open_loop(c, law, step, x0, command, noise, voluntary):  # type: ignore[no-untyped-def]
    n = len(command)
    x = x0.copy()
    states = np.empty((n, 5))
    extra = np.empty((n, 3))
    for k in range(n):
        extra[k, 0], extra[k, 1], extra[k, 2] = plant_advance(
            c, law, step, x, command[k], noise[k], voluntary[k]
        )
        states[k] = x
    return states, extra
