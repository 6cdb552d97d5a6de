"""Calibration trials: the platform moves with nobody on it (paper 000 §2.2).

The sensors then feel only the top plate's inertia and weight as the hinge follows its motion
plan of ramp-and-hold moves; this is what platform filters are fitted on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import Config
from validation.cleanroom.drive import Hinge
from validation.cleanroom.forces import PlateSensors, plate_load
from validation.cleanroom.protocol import calibration_plan, ramp_hold_ramp

__all__ = ["CalibrationSimulation", "simulate_calibration"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CalibrationSimulation:
    """Clean calibration signals at the DAQ rate (trials first, time last).

    Attributes
    ----------
    time_s : ndarray, shape (n_times,)
        Sample times in each file, s.
    motor_angle : ndarray, shape (n_trials, n_times)
        Motor-side hinge angle referred to the platform output, rad.
    channels : ndarray, shape (8, n_trials, n_times)
        Plate channels before the DAQ's errors, N.
    onsets_s, signs : list of ndarray
        Each trial's move onsets (s) and directions (+1 dorsi, -1 plantar).
    """

    time_s: Array
    motor_angle: Array
    channels: Array
    onsets_s: list[Array]
    signs: list[Array]


def simulate_calibration(config: Config, rng: np.random.Generator) -> CalibrationSimulation:
    """Simulate ``config.protocol.n_calibration`` calibration trials.

    Parameters
    ----------
    config : Config
        The session.
    rng : numpy.random.Generator
        Source of the move timing and directions.
    """
    protocol = config.protocol
    fs, over = protocol.sample_rate_hz, protocol.oversample
    n_out = round(protocol.calibration_duration_s * fs)
    t = np.arange(n_out * over) / (fs * over)
    plans = calibration_plan(protocol, rng)
    reference = np.stack(
        [
            ramp_hold_ramp(
                t, onsets[:, None], signs[:, None], protocol, protocol.calibration_hold_s
            ).sum(axis=0)
            for onsets, signs in plans
        ]
    )
    motion = Hinge.build(config.drive, config.plate, fs * over).response(reference=reference)
    force, moment = plate_load(
        config.plate, motion["angle"], motion["velocity"], motion["acceleration"]
    )
    channels = PlateSensors.build(config.plate, fs * over).channels(force, moment)
    return CalibrationSimulation(
        time_s=t[::over],
        motor_angle=motion["motor_angle"][:, ::over],
        channels=channels[..., ::over],
        onsets_s=[onsets for onsets, _ in plans],
        signs=[signs for _, signs in plans],
    )
