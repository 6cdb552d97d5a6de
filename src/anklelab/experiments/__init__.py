"""Protocol runners: drive the digital twins through experiments."""

from anklelab.data.capstan_ident import IdentData, read_ident_directory, write_ident_directory
from anklelab.experiments.capstan import (
    CapstanSetup,
    FaultInjection,
    IdentProtocol,
    chirp_tracking,
    observer_trial,
    render,
    simulate_closed_loop,
    simulate_ident,
    step_response,
)
from anklelab.experiments.perturberator import TrialFault, simulate_perturberator
from anklelab.experiments.randomised import KINDS, TwinDraw, draw_twin, simulate_randomised

__all__ = [
    "KINDS",
    "CapstanSetup",
    "FaultInjection",
    "IdentData",
    "IdentProtocol",
    "TrialFault",
    "TwinDraw",
    "chirp_tracking",
    "draw_twin",
    "observer_trial",
    "read_ident_directory",
    "render",
    "simulate_closed_loop",
    "simulate_ident",
    "simulate_perturberator",
    "simulate_randomised",
    "step_response",
    "write_ident_directory",
]
