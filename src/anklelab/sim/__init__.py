"""Plant models and digital twins (DESIGN.md section 2, ``sim``)."""

from anklelab.sim.artefacts import Artefacts
from anklelab.sim.capstan import CapstanTwin, SimulationResult, linear_platform
from anklelab.sim.drivetrain import (
    DriveFault,
    EncoderFault,
    FootLoad,
    PlatformRun,
    simulate_platform,
    stopping_distance,
)
from anklelab.sim.foot import FootModel, NominalStance, bench_law, foot_load, foot_model
from anklelab.sim.gait import (
    GaitTrials,
    StanceSignals,
    heel_contact_times,
    sample_gait,
    stance_signals,
    vertical_force,
)

__all__ = [
    "Artefacts",
    "CapstanTwin",
    "DriveFault",
    "EncoderFault",
    "FootLoad",
    "FootModel",
    "GaitTrials",
    "NominalStance",
    "PlatformRun",
    "SimulationResult",
    "StanceSignals",
    "bench_law",
    "foot_load",
    "foot_model",
    "heel_contact_times",
    "linear_platform",
    "sample_gait",
    "simulate_platform",
    "stance_signals",
    "stopping_distance",
    "vertical_force",
]
