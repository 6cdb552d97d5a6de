"""Digital twin of paper 001's capstan-driven haptic ankle platform."""

from anklelab.sim.capstan.friction_law import (
    friction_array,
    friction_step,
    friction_torque,
    kinetic_friction,
)
from anklelab.sim.capstan.plant import (
    STATE_NAMES,
    PlantConstants,
    Stepping,
    encoder_angle,
    plant_advance,
    plant_constants,
    stepping,
)
from anklelab.sim.capstan.result import SimulationResult
from anklelab.sim.capstan.transfer import (
    LinearPlatform,
    ankle_torque_to_motor_speed,
    disturbance_to_angle,
    linear_platform,
    reference_to_angle,
    voltage_to_motor_speed,
)
from anklelab.sim.capstan.twin import CapstanTwin
from anklelab.sim.capstan.user import voluntary_torque

__all__ = [
    "STATE_NAMES",
    "CapstanTwin",
    "LinearPlatform",
    "PlantConstants",
    "SimulationResult",
    "Stepping",
    "ankle_torque_to_motor_speed",
    "disturbance_to_angle",
    "encoder_angle",
    "friction_array",
    "friction_step",
    "friction_torque",
    "kinetic_friction",
    "linear_platform",
    "plant_advance",
    "plant_constants",
    "reference_to_angle",
    "stepping",
    "voltage_to_motor_speed",
    "voluntary_torque",
]
