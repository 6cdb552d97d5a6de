"""The 16-bit DAQ and the sensors' own errors: noise, drift, offsets, hum, quantisation.

Every amplitude of :class:`~validation.cleanroom.config.NoiseConfig` is multiplied by its
``scale``; with ``scale = 0`` the signals pass unchanged. Arrays hold trials first and time
last; each function draws from the generator it is given.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import NoiseConfig

__all__ = ["acquire_forces", "acquire_goniometer", "acquire_motor_angle"]

Array = NDArray[np.float64]


def _quantise(x: Array, lsb: float | Array) -> Array:
    return np.round(x / lsb) * lsb


def acquire_forces(
    channels: Array, t: Array, noise: NoiseConfig, rng: np.random.Generator
) -> Array:
    """Plate channels (shape ``(8, n_trials, n_times)``, N) as the DAQ records them.

    Per channel and trial: a constant offset (uniform within ±``force_offset_n``), a linear
    drift (normal, sd ``force_drift_n_per_s``; paper 000: about 10 mN/s), mains hum of random
    amplitude up to ``hum_n`` and random phase, white noise (sd ``force_noise_n``), then
    quantisation to the channel's DAQ step (shear channels ``fxy_lsb_n``, vertical
    ``fz_lsb_n``).
    """
    s = noise.scale
    if s == 0:
        return channels
    shape = (*channels.shape[:2], 1)
    offset = s * noise.force_offset_n * rng.uniform(-1, 1, shape)
    drift = s * noise.force_drift_n_per_s * rng.standard_normal(shape) * t
    amplitude = s * noise.hum_n * rng.uniform(0, 1, shape)
    phase = rng.uniform(0, 2 * np.pi, shape)
    carrier = 2 * np.pi * noise.hum_hz * t  # sin(ωt + p) = sin ωt cos p + cos ωt sin p
    hum = amplitude * np.cos(phase) * np.sin(carrier) + amplitude * np.sin(phase) * np.cos(carrier)
    white = s * noise.force_noise_n * rng.standard_normal(channels.shape)
    lsb = s * np.repeat([noise.fxy_lsb_n, noise.fz_lsb_n], 4)[:, None, None]
    white += channels + offset + drift + hum
    return _quantise(white, lsb)


def acquire_motor_angle(angle: Array, noise: NoiseConfig, rng: np.random.Generator) -> Array:
    """The servodrive's analog position output as recorded, rad at the platform output."""
    s = noise.scale
    if s == 0:
        return angle
    white = s * noise.motor_angle_noise_rad * rng.standard_normal(angle.shape)
    return _quantise(angle + white, s * noise.motor_angle_lsb_rad)


def acquire_goniometer(angle: Array, noise: NoiseConfig, rng: np.random.Generator) -> Array:
    """The electrogoniometer's ankle angle as recorded, rad.

    Paper 000 §2.4.1 gives the goniometer's precision as 2.6e-3 rad over a 0.09 rad test
    displacement; it is modelled as a per-trial gain error (sd ``goniometer_gain_sd``), plus a
    per-trial offset (how it sits after each step), white noise and the DAQ step.
    """
    s = noise.scale
    if s == 0:
        return angle
    n = (*angle.shape[:-1], 1)
    gain = 1 + s * noise.goniometer_gain_sd * rng.standard_normal(n)
    offset = s * noise.goniometer_offset_sd_rad * rng.standard_normal(n)
    white = s * noise.goniometer_noise_rad * rng.standard_normal(angle.shape)
    return _quantise(gain * angle + offset + white, s * noise.goniometer_lsb_rad)
