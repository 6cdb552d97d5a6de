"""What the instruments add to the twin's true signals: plate DAQ, servo analog output,
electrogoniometer and the testing machine's load cell.

Each function takes true values (time last), the parameter set, the :class:`Artefacts`
switches and a ``seed`` (int or numpy.random.Generator: pass the caller's generator to
continue its stream), and returns what the 16-bit 1 kHz DAQ records:

- force channels: the wrench mapped onto the eight channels of the mounted plate, plus a
  charge-amplifier drift per channel (a random rate, sd ``drift_n_per_s``, from zero at the
  start of each trial), white noise (``noise_n``) and quantisation over each channel's range;
- motor angle: the servo's analog output of the motor position referred to the platform,
  quantised to its ``analog_output_resolution_rad`` and then by the DAQ;
- ankle angle: the goniometer reading of the true ankle angle with its sensitivity error
  (``sensitivity_error_fraction``) and a precision error growing from ``precision_small_rad``
  to ``precision_full_scale_rad`` with the angle, then the DAQ (``sensitivity_rad_per_v``
  volts-to-angle scaling over the ±``input_range_v`` range);
- load cell: force plus ``load_cell_noise_n``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.forceplate import CHANNELS
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.forceplate_dynamics import daq_quantize, sensor_channels

__all__ = ["force_channels", "goniometer_reading", "load_cell_reading", "motor_angle_output"]

_VERTICAL = np.array([name.startswith("fz") for name in CHANNELS])


def force_channels(
    wrench: NDArray[np.float64],
    params: PerturberatorParameters,
    art: Artefacts,
    seed: int | np.random.Generator,
) -> NDArray[np.float64]:
    """Recorded force channels, shape ``(n_trials, 8, n_samples)``, N."""
    rng = np.random.default_rng(seed)
    fp = params.force_plate
    channels = sensor_channels(wrench, fp, yaw_rad=fp.yaw_rad)
    n_trials, _, n = channels.shape
    if art.drift:  # in place: channels is the fresh array sensor_channels returned
        t = np.arange(n) / params.daq.sample_rate_hz
        rate = fp.drift_n_per_s * rng.standard_normal((n_trials, len(CHANNELS), 1))
        channels += rate * t
    if art.noise:
        noise = rng.standard_normal(channels.shape)
        noise *= fp.noise_n
        channels += noise
        del noise
    if art.quantisation:
        full = np.where(_VERTICAL, fp.range_vertical_n, fp.range_horizontal_n)[:, None]
        channels = daq_quantize(channels, full, params.daq.bits)
    return channels


def motor_angle_output(
    angle_rad: NDArray[np.float64], params: PerturberatorParameters, art: Artefacts
) -> NDArray[np.float64]:
    """The servo's analog position output as recorded, rad at the platform."""
    if not art.quantisation:
        return np.array(angle_rad, dtype=float)
    step = params.servo.analog_output_resolution_rad
    return daq_quantize(
        np.round(angle_rad / step) * step, params.daq.motor_angle_range_rad, params.daq.bits
    )


def goniometer_reading(
    angle_rad: NDArray[np.float64],
    params: PerturberatorParameters,
    art: Artefacts,
    seed: int | np.random.Generator,
) -> NDArray[np.float64]:
    """The electrogoniometer's ankle angle as recorded, rad."""
    rng = np.random.default_rng(seed)
    g = params.goniometer
    reading = np.asarray(angle_rad, dtype=float) * (1 + g.sensitivity_error_fraction)
    if art.noise:
        fraction = np.clip(np.abs(angle_rad) / g.full_scale_rad, 0, 1)
        sd = g.precision_small_rad + (g.precision_full_scale_rad - g.precision_small_rad) * fraction
        reading = reading + sd * rng.standard_normal(reading.shape)
    if art.quantisation:
        full = g.sensitivity_rad_per_v * params.daq.input_range_v
        reading = daq_quantize(reading, full, params.daq.bits)
    return reading


def load_cell_reading(
    force_n: NDArray[np.float64],
    params: PerturberatorParameters,
    art: Artefacts,
    seed: int | np.random.Generator,
) -> NDArray[np.float64]:
    """The testing machine's load cell, N."""
    rng = np.random.default_rng(seed)
    force = np.asarray(force_n, dtype=float)
    if art.noise:
        force = force + params.bench.load_cell_noise_n * rng.standard_normal(force.shape)
    return force
