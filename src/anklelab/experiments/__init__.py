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
from anklelab.experiments.capstan_ident import (
    IdentData,
    IdentProtocol,
    read_ident_directory,
    simulate_ident,
    write_ident_directory,
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
