"""Controllers, trajectories, observers and safety limits (DESIGN.md section 2, ``control``)."""

from anklelab.control.haptics import (
    TerrainProfile,
    VirtualEnvironment,
    admittance_update,
    impedance_torque,
)
from anklelab.control.observer import (
    DisturbanceObserver,
    observer_constants,
    observer_update,
)
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

__all__ = [
    "DisturbanceObserver",
    "Fault",
    "PIDGains",
    "PositionController",
    "SafetyLimits",
    "SafetyMonitor",
    "TerrainProfile",
    "VirtualEnvironment",
    "admittance_update",
    "control_constants",
    "design_critically_damped",
    "impedance_torque",
    "new_safety_state",
    "observer_constants",
    "observer_update",
    "position_control_update",
    "safety_update",
]
