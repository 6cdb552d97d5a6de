"""Protocol runners: drive the digital twins through experiments.

Each name loads its module on first use: simulating the perturberator never imports the
capstan's experiments or controllers.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "IdentData": "anklelab.data.capstan_ident",
    "read_ident_directory": "anklelab.data.capstan_ident",
    "write_ident_directory": "anklelab.data.capstan_ident",
    "CapstanSetup": "capstan",
    "FaultInjection": "capstan",
    "IdentProtocol": "capstan",
    "chirp_tracking": "capstan",
    "observer_trial": "capstan",
    "render": "capstan",
    "simulate_closed_loop": "capstan",
    "simulate_ident": "capstan",
    "step_response": "capstan",
    "TrialFault": "perturberator",
    "simulate_perturberator": "perturberator",
    "KINDS": "randomised",
    "TwinDraw": "randomised",
    "draw_twin": "randomised",
    "simulate_randomised": "randomised",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
