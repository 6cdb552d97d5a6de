"""Controllers, trajectories, observers and safety limits (DESIGN.md section 2, ``control``).

The servo-loop measurement tools (:mod:`anklelab.control.servo`) load on first use: they need
``scipy.signal``, which would otherwise cost every simulation a second of imports.
"""

from importlib import import_module
from typing import Any

from anklelab.control.haptics import (
    TerrainProfile,
    VirtualEnvironment,
    admittance_update,
    impedance_torque,
)
from anklelab.control.motion_plan import StepDirectionPlan
from anklelab.control.observer import (
    DisturbanceObserver,
    observer_constants,
    observer_update,
)
from anklelab.control.perturbation import RampHold, calibration_schedule
from anklelab.control.pid import (
    PIDGains,
    PositionController,
    control_constants,
    design_critically_damped,
    position_control_update,
)
from anklelab.control.safety import (
    Fault,
    SafetyLimits,
    SafetyMonitor,
    new_safety_state,
    safety_update,
)
from anklelab.control.trigger import (
    onset_updates,
    reading_limits,
    screen_readings,
    trigger_updates,
)

__all__ = [
    "CascadeGains",
    "DisturbanceObserver",
    "Fault",
    "LoopMargins",
    "PIDGains",
    "PositionController",
    "RampHold",
    "SafetyLimits",
    "SafetyMonitor",
    "StepDirectionPlan",
    "TerrainProfile",
    "VirtualEnvironment",
    "admittance_update",
    "bandwidth_hz",
    "calibration_schedule",
    "control_constants",
    "design_critically_damped",
    "fit_second_order",
    "impedance_torque",
    "loop_margins",
    "new_safety_state",
    "observer_constants",
    "observer_update",
    "onset_updates",
    "periodic_frf",
    "phase_crossing_hz",
    "position_control_update",
    "prbs",
    "reading_limits",
    "safety_update",
    "screen_readings",
    "second_order_response",
    "trigger_updates",
]


def __getattr__(name: str) -> Any:
    """The servo-loop tools (the names of :mod:`anklelab.control.servo`), loaded on first use."""
    if not name.startswith("_"):  # introspection (``__wrapped__``...) never loads SciPy
        servo = import_module("anklelab.control.servo")  # not `from . import`: that recurses
        if name in servo.__all__:
            return getattr(servo, name)
    raise AttributeError(f"module 'anklelab.control' has no attribute {name!r}")
