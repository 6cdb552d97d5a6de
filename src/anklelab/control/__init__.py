"""Controllers, trajectories, observers and safety limits (DESIGN.md section 2, ``control``).

Each name loads its module on first use: the servo-loop measurement tools
(:mod:`anklelab.control.servo`) need ``scipy.signal``, and a simulation of the perturberator
needs neither the haptics nor the observer.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "TerrainProfile": "haptics",
    "VirtualEnvironment": "haptics",
    "admittance_update": "haptics",
    "impedance_torque": "haptics",
    "StepDirectionPlan": "motion_plan",
    "DisturbanceObserver": "observer",
    "observer_constants": "observer",
    "observer_update": "observer",
    "RampHold": "perturbation",
    "calibration_schedule": "perturbation",
    "PIDGains": "pid",
    "PositionController": "pid",
    "control_constants": "pid",
    "design_critically_damped": "pid",
    "position_control_update": "pid",
    "Fault": "safety",
    "SafetyLimits": "safety",
    "SafetyMonitor": "safety",
    "new_safety_state": "safety",
    "safety_update": "safety",
    "CascadeGains": "servo",
    "LoopMargins": "servo",
    "bandwidth_hz": "servo",
    "fit_second_order": "servo",
    "loop_margins": "servo",
    "periodic_frf": "servo",
    "phase_crossing_hz": "servo",
    "prbs": "servo",
    "second_order_response": "servo",
    "onset_updates": "trigger",
    "reading_limits": "trigger",
    "screen_readings": "trigger",
    "trigger_updates": "trigger",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
