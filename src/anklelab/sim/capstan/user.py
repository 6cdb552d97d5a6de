"""The user's voluntary ankle torque: smooth random multisines within a frequency band."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import ParameterError

__all__ = ["voluntary_torque"]


def voluntary_torque(
    duration_s: float,
    fs: float,
    *,
    rms_nm: float = 2.0,
    band_hz: tuple[float, float] = (0.1, 3.0),
    fade_s: float = 0.5,
    seed: int | np.random.Generator = 0,
) -> NDArray[np.float64]:
    """A voluntary torque profile: equal-amplitude sines with random phases, faded in and out.

    Parameters
    ----------
    duration_s, fs : float
        Length (s) and sample rate (Hz).
    rms_nm : float
        RMS of the profile before fading, N·m.
    band_hz : (float, float)
        Lowest and highest frequency, Hz (the grid is ``1/duration_s``).
    fade_s : float
        Raised-cosine fade at both ends, s, so the torque starts and ends at zero.
    seed : int or Generator
        Random phases.

    Examples
    --------
    >>> tau = voluntary_torque(10.0, 1000.0, rms_nm=2.0, fade_s=0.0, seed=1)
    >>> tau.shape, round(float(np.sqrt(np.mean(tau**2))), 6)
    ((10000,), 2.0)
    >>> float(voluntary_torque(10.0, 1000.0, seed=1)[0])
    0.0
    """
    lo, hi = band_hz
    if not 0 < lo <= hi < fs / 2:
        raise ParameterError(f"band_hz must satisfy 0 < low <= high < fs/2; got {band_hz}")
    n = round(duration_s * fs)
    t = np.arange(n) / fs
    freqs = np.arange(np.ceil(lo * duration_s), np.floor(hi * duration_s) + 1) / duration_s
    if freqs.size == 0:
        raise ParameterError(f"band_hz {band_hz} holds no multiple of 1/duration_s")
    phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, freqs.size)
    tau = np.sin(2 * np.pi * freqs[:, None] * t + phases[:, None]).sum(axis=0)
    tau *= rms_nm / np.sqrt(freqs.size / 2)
    ramp = np.clip(np.minimum(t, t[-1] - t) / fade_s, 0.0, 1.0) if fade_s > 0 else 1.0
    return tau * 0.5 * (1 - np.cos(np.pi * ramp))
