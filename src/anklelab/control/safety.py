"""Generic safety monitor: limits, sensor sanity checks, a latched fault and a safe output.

Any one-degree-of-freedom controller passes every control tick through :func:`safety_update`
(compiled, for simulation loops) or :class:`SafetyMonitor` (the same arithmetic, for hardware or
Python loops). Each tick it checks, in this order:

1. the sensor values (position, velocity, measured output) are finite, else ``SENSOR_NAN``;
2. the position reading lies in the sensor's physical range, else ``SENSOR_RANGE``;
3. the sensor's sample counter advanced within ``max_stale_ticks`` ticks, else ``SENSOR_STALE``;
4. the position is inside ``[position_min, position_max]``, else ``POSITION``;
5. ``|velocity| <= velocity_max``, else ``VELOCITY``;
6. ``|measured output| <= output_trip`` (over-current or over-torque), else ``OUTPUT``;
7. the requested output is finite, else ``COMMAND_NAN``.

The first failed check latches its fault; from then on the output is ``safe_output`` until
:meth:`SafetyMonitor.reset`. Without a fault the request is clamped to ``±output_max``. Units are
the caller's (rad or m for position, N·m or A for output): the monitor only compares numbers.
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np
from numba import njit
from numpy.typing import NDArray
from pydantic import Field, model_validator

from anklelab._params import Parameters

__all__ = ["Fault", "SafetyLimits", "SafetyMonitor", "new_safety_state", "safety_update"]


class Fault(IntEnum):
    """Why a safety monitor tripped (0: it did not); :attr:`meaning` says it in words.

    Codes 1-7 are this monitor's; ``FALL_STOP`` is latched by the person guard
    (:mod:`anklelab.control.person_guard`) of the capstan platform.

    Examples
    --------
    >>> Fault(7).describe()
    'COMMAND_NAN (the commanded output was NaN or infinite)'
    """

    NONE = 0
    SENSOR_NAN = 1
    SENSOR_RANGE = 2
    SENSOR_STALE = 3
    POSITION = 4
    VELOCITY = 5
    OUTPUT = 6
    COMMAND_NAN = 7
    FALL_STOP = 8

    @property
    def meaning(self) -> str:
        """What tripped, in words."""
        return _MEANINGS[self]

    def describe(self) -> str:
        """``NAME (meaning)``, for messages and tables."""
        return f"{self.name} ({self.meaning})"


_MEANINGS = {
    Fault.NONE: "no fault",
    Fault.SENSOR_NAN: "a sensor reading was NaN or infinite",
    Fault.SENSOR_RANGE: "the position reading left the sensor's physical range",
    Fault.SENSOR_STALE: "the position sensor stopped delivering new samples",
    Fault.POSITION: "the position left the allowed range",
    Fault.VELOCITY: "the speed exceeded its limit",
    Fault.OUTPUT: "the measured output (current) exceeded its trip level",
    Fault.COMMAND_NAN: "the commanded output was NaN or infinite",
    Fault.FALL_STOP: "a fall was detected or a stop requested: braked, then the current cut",
}


class SafetyLimits(Parameters):
    """Limits enforced by a :class:`SafetyMonitor`.

    Attributes
    ----------
    position_min, position_max : float
        Allowed position range (rad or m); leaving it trips ``POSITION``.
    velocity_max : float
        Largest allowed speed (rad/s or m/s).
    output_max : float
        Requests are clamped to ``±output_max`` (N·m, N or A).
    output_trip : float
        A measured output beyond ``±output_trip`` trips ``OUTPUT`` (over-current).
    sensor_min, sensor_max : float
        Physically possible position readings; outside them the sensor is broken.
    max_stale_ticks : int
        Ticks the sensor's sample counter may stay unchanged before ``SENSOR_STALE``.
    safe_output : float
        Output once a fault is latched (usually 0: motor torque off).
    """

    position_min: float
    position_max: float
    velocity_max: float = Field(gt=0)
    output_max: float = Field(gt=0)
    output_trip: float = Field(gt=0)
    sensor_min: float = -math.inf
    sensor_max: float = math.inf
    max_stale_ticks: int = Field(default=3, ge=1)
    safe_output: float = 0.0

    @model_validator(mode="after")
    def _ordered(self) -> SafetyLimits:
        if not self.position_min < self.position_max:
            raise ValueError(
                f"position_min must be < position_max; got {self.position_min} >= "
                f"{self.position_max}"
            )
        if not self.sensor_min <= self.position_min or not self.position_max <= self.sensor_max:
            raise ValueError("the sensor range must contain [position_min, position_max]")
        if abs(self.safe_output) > self.output_max:
            raise ValueError("|safe_output| must not exceed output_max")
        return self

    def to_array(self) -> NDArray[np.float64]:
        """The limits as the float array :func:`safety_update` takes."""
        return np.array(
            [
                self.position_min,
                self.position_max,
                self.velocity_max,
                self.output_max,
                self.output_trip,
                self.sensor_min,
                self.sensor_max,
                float(self.max_stale_ticks),
                self.safe_output,
            ]
        )


@njit(cache=True)
def new_safety_state() -> NDArray[np.float64]:
    """A fresh monitor state: ``[latched fault, last counter, ticks without a new sample]``."""
    return np.array([0.0, -1.0, 0.0])


@njit(cache=True, inline="always")
def safety_update(
    limits: NDArray[np.float64],
    state: NDArray[np.float64],
    position: float,
    velocity: float,
    counter: float,
    measured_output: float,
    request: float,
) -> float:
    """One tick of the safety monitor (compiled).

    Parameters
    ----------
    limits : ndarray
        :meth:`SafetyLimits.to_array`.
    state : ndarray, shape (3,)
        Monitor state from :func:`new_safety_state`, updated in place; ``state[0]`` is the
        latched :class:`Fault` code.
    position, velocity : float
        Latest sensor readings (rad, rad/s or m, m/s).
    counter : float
        The sensor's sample counter (any number that changes when a new sample arrives).
    measured_output : float
        Measured actuator output (A or N·m).
    request : float
        Output the controller asks for.

    Returns
    -------
    float
        The output to apply: the clamped request, or ``safe_output`` once a fault is latched.
    """
    if state[0] == 0.0:
        fault = 0
        if counter == state[1]:
            state[2] += 1.0
        else:
            state[2] = 0.0
        state[1] = counter
        if not (np.isfinite(position) and np.isfinite(velocity) and np.isfinite(measured_output)):
            fault = 1
        elif position < limits[5] or position > limits[6]:
            fault = 2
        elif state[2] > limits[7]:
            fault = 3
        elif position < limits[0] or position > limits[1]:
            fault = 4
        elif abs(velocity) > limits[2]:
            fault = 5
        elif abs(measured_output) > limits[4]:
            fault = 6
        elif not np.isfinite(request):
            fault = 7
        state[0] = fault
    if state[0] != 0.0:
        return limits[8]
    return min(max(request, -limits[3]), limits[3])


class SafetyMonitor:
    """Stateful wrapper of :func:`safety_update` for Python or hardware control loops.

    Parameters
    ----------
    limits : SafetyLimits
        The limits to enforce.

    Examples
    --------
    >>> limits = SafetyLimits(position_min=-0.7, position_max=0.7, velocity_max=3.0,
    ...                       output_max=6.0, output_trip=8.0)
    >>> monitor = SafetyMonitor(limits)
    >>> monitor.check(0.1, 0.0, counter=1, measured_output=0.5, request=9.0)
    6.0
    >>> monitor.check(float("nan"), 0.0, counter=2, measured_output=0.5, request=1.0)
    0.0
    >>> monitor.fault.name, monitor.check(0.1, 0.0, counter=3, measured_output=0.0, request=1.0)
    ('SENSOR_NAN', 0.0)
    """

    def __init__(self, limits: SafetyLimits) -> None:
        self.limits = limits
        self._limits = limits.to_array()
        self._state = new_safety_state()

    @property
    def fault(self) -> Fault:
        """The latched fault (``Fault.NONE`` while healthy)."""
        return Fault(int(self._state[0]))

    def check(
        self,
        position: float,
        velocity: float,
        *,
        counter: float,
        measured_output: float,
        request: float,
    ) -> float:
        """Check one tick's readings; return the output to apply (see :func:`safety_update`)."""
        return float(
            safety_update(
                self._limits,
                self._state,
                float(position),
                float(velocity),
                float(counter),
                float(measured_output),
                float(request),
            )
        )

    def reset(self) -> None:
        """Clear a latched fault (an operator's deliberate action)."""
        self._state = new_safety_state()
