"""Protocol runners: drive the digital twins through experiments (DESIGN.md section 2)."""

from anklelab.experiments.capstan import (
    CapstanSetup,
    FaultInjection,
    chirp_tracking,
    observer_trial,
    render,
    simulate_closed_loop,
    step_response,
)
from anklelab.experiments.perturberator import simulate_perturberator

__all__ = [
    "CapstanSetup",
    "FaultInjection",
    "chirp_tracking",
    "observer_trial",
    "render",
    "simulate_closed_loop",
    "simulate_perturberator",
    "step_response",
]
