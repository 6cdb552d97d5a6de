"""Plant models and digital twins (DESIGN.md section 2, ``sim``)."""

from anklelab.sim.capstan import CapstanTwin, SimulationResult, linear_platform

__all__ = [
    "CapstanTwin",
    "SimulationResult",
    "linear_platform",
]
