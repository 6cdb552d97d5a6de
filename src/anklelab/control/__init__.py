"""Controllers, trajectories, observers and safety limits (DESIGN.md section 2, ``control``)."""

from anklelab.control.safety import (
    Fault,
    SafetyLimits,
    SafetyMonitor,
    new_safety_state,
    safety_update,
)

__all__ = [
    "Fault",
    "SafetyLimits",
    "SafetyMonitor",
    "new_safety_state",
    "safety_update",
]
