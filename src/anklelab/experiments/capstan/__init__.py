"""Experiments on the capstan twin (paper 001), one module per job.

- :mod:`.config`: :class:`CapstanSetup` (platform, controller, limits), :class:`FaultInjection`;
- :mod:`.closed_loop`: :func:`simulate_closed_loop`, the compiled loop's Python face;
- :mod:`.steps`, :mod:`.chirp`: set-point steps and chirp tracking with their metrics;
- :mod:`.observation`: the torque observer scored against the truth;
- :mod:`.rendering`: haptic rendering and the impedance the foot felt;
- :mod:`.ident_protocol`: paper 001's friction-identification tests on the twin.
"""

from anklelab.experiments.capstan.chirp import (
    ChirpMetrics,
    chirp_metrics,
    chirp_reference,
    chirp_tracking,
)
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup, FaultInjection, Mode
from anklelab.experiments.capstan.ident_protocol import (
    IdentProtocol,
    friction_truth,
    simulate_ident,
)
from anklelab.experiments.capstan.observation import (
    ObserverMetrics,
    observer_metrics,
    observer_trial,
)
from anklelab.experiments.capstan.rendering import RenderMetrics, render, render_metrics
from anklelab.experiments.capstan.steps import StepMetrics, step_metrics, step_response

__all__ = [
    "CapstanSetup",
    "ChirpMetrics",
    "FaultInjection",
    "IdentProtocol",
    "Mode",
    "ObserverMetrics",
    "RenderMetrics",
    "StepMetrics",
    "chirp_metrics",
    "chirp_reference",
    "chirp_tracking",
    "friction_truth",
    "observer_metrics",
    "observer_trial",
    "render",
    "render_metrics",
    "simulate_closed_loop",
    "simulate_ident",
    "step_metrics",
    "step_response",
]
