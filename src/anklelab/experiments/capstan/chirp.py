"""Chirp tracking on the capstan twin and the measured closed-loop response (paper 001, Fig. 5),
by the PID alone, with the inverse-dynamics feed-forward, or with the zero-phase-error tracking
controller (:mod:`anklelab.control.tracking`) on top."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.tracking import reference_derivatives, zpetc_reference
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.sim.capstan import SimulationResult

__all__ = ["ChirpMetrics", "chirp_metrics", "chirp_reference", "chirp_tracking"]


@dataclass(frozen=True)
class ChirpMetrics:
    """Chirp-tracking figures.

    Attributes
    ----------
    rms_error_rad, max_error_rad : float
        Tracking error (reference minus measured angle).
    rms_error_to_3hz_rad : float
        RMS error while the chirp is below 3 Hz.
    frequency_hz, gain, phase_deg : ndarray
        Measured closed-loop frequency response, band-averaged.
    bandwidth_3db_hz : float
        First frequency where the gain falls below -3 dB (inf if it does not in the sweep).
    bandwidth_45deg_hz : float
        First frequency where the phase lag exceeds 45 degrees (inf if it does not).
    tracking_limit_hz : float
        The frequency from which on the response stays outside 1 dB in gain or 20 degrees in
        phase to the sweep's end (inf if it is within at the end). Friction makes slow,
        small motions stick and slip: the response may stray outside at the low end and come
        back; this limit is the one that lasts.
    """

    rms_error_rad: float
    max_error_rad: float
    rms_error_to_3hz_rad: float
    frequency_hz: NDArray[np.float64]
    gain: NDArray[np.float64]
    phase_deg: NDArray[np.float64]
    bandwidth_3db_hz: float
    bandwidth_45deg_hz: float
    tracking_limit_hz: float


def chirp_reference(
    amplitude_rad: float, f0_hz: float, f1_hz: float, duration_s: float, fs: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Linear chirp ``A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))``, its speed and acceleration.

    Examples
    --------
    >>> angle, speed, acceleration = chirp_reference(0.1, 0.2, 5.0, 10.0, 1000.0)
    >>> angle.shape, round(float(speed[0]), 4)            # A 2 pi f0 at t = 0
    ((10000,), 0.1257)
    """
    if not (amplitude_rad > 0 and 0 < f0_hz < f1_hz < fs / 2 and duration_s > 0):
        raise ParameterError(
            "chirp: expected amplitude > 0, 0 < start < end frequency < fs/2 and duration > 0; "
            f"got {amplitude_rad}, {f0_hz}, {f1_hz} Hz, {duration_s} s at {fs} Hz"
        )
    t = np.arange(round(duration_s * fs)) / fs
    rate = (f1_hz - f0_hz) / duration_s
    phase = 2 * np.pi * (f0_hz * t + 0.5 * rate * t**2)
    omega = 2 * np.pi * (f0_hz + rate * t)
    speed = amplitude_rad * np.cos(phase) * omega
    acceleration = amplitude_rad * (-np.sin(phase) * omega**2 + np.cos(phase) * 2 * np.pi * rate)
    return amplitude_rad * np.sin(phase), speed, acceleration


def _first_below(f: NDArray[np.float64], value: NDArray[np.float64], level: float) -> float:
    """First frequency where ``value`` drops below ``level`` (log-frequency interpolation)."""
    below = np.flatnonzero(value < level)
    if below.size == 0:
        return math.inf
    k = below[0]
    if k == 0:
        return float(f[0])
    frac = (value[k - 1] - level) / (value[k - 1] - value[k])
    return float(f[k - 1] * (f[k] / f[k - 1]) ** frac)


def _lasting_departure(f: NDArray[np.float64], departure: NDArray[np.float64]) -> float:
    """Frequency from which ``departure`` stays above 1 to the end (log interpolation)."""
    within = np.flatnonzero(departure <= 1.0)
    if within.size == 0:
        return float(f[0])
    k = within[-1]
    if k == f.size - 1:
        return math.inf
    frac = (1.0 - departure[k]) / (departure[k + 1] - departure[k])
    return float(f[k] * (f[k + 1] / f[k]) ** frac)


def chirp_metrics(
    reference: ArrayLike,
    angle: ArrayLike,
    fs: float,
    f0_hz: float,
    f1_hz: float,
    *,
    duration_s: float | None = None,
    n_bands: int = 24,
) -> ChirpMetrics:
    """Tracking error and closed-loop frequency response of a linear chirp.

    Parameters
    ----------
    reference, angle : array_like
        Reference and measured angle, rad: the sweep, optionally followed by a rest period
        (reference 0) that lets the response ring down, which makes ``Y(f) = H(f) R(f)`` hold
        for the record.
    fs : float
        Sample rate, Hz.
    f0_hz, f1_hz : float
        Sweep start and end frequencies.
    duration_s : float, optional
        Sweep length (default: the whole record); tracking errors are taken over the sweep.
    n_bands : int
        The response is the ratio of the Fourier transforms, averaged (weighted by the
        reference's power) over ``n_bands`` log-spaced bands in ``[f0, f1]``.
    """
    r = np.asarray(reference, dtype=float)
    y = np.asarray(angle, dtype=float)
    sweep = r.size if duration_s is None else round(duration_s * fs)
    err = (r - y)[:sweep]
    inst_f = f0_hz + (f1_hz - f0_hz) * np.arange(sweep) / sweep
    spec_r, spec_y = np.fft.rfft(r), np.fft.rfft(y)
    freqs = np.fft.rfftfreq(r.size, 1 / fs)
    power = np.abs(spec_r) ** 2
    cross = spec_y * spec_r.conj()
    band = np.digitize(freqs, np.geomspace(f0_hz, f1_hz, n_bands + 1))
    inside = (band >= 1) & (band <= n_bands)
    weight = np.bincount(band[inside], power[inside], n_bands + 1)[1:]
    used = weight > 0
    f = np.bincount(band[inside], (power * freqs)[inside], n_bands + 1)[1:][used] / weight[used]
    h = (
        np.bincount(band[inside], cross.real[inside], n_bands + 1)[1:][used]
        + 1j * np.bincount(band[inside], cross.imag[inside], n_bands + 1)[1:][used]
    ) / weight[used]
    gain = np.abs(h)
    phase = np.degrees(np.unwrap(np.angle(h)))
    off_db = np.abs(20 * np.log10(np.maximum(gain, 1e-12)))
    return ChirpMetrics(
        rms_error_rad=float(np.sqrt(np.mean(err**2))),
        max_error_rad=float(np.max(np.abs(err))),
        rms_error_to_3hz_rad=float(np.sqrt(np.mean(err[inst_f <= 3.0] ** 2))),
        frequency_hz=f,
        gain=gain,
        phase_deg=phase,
        bandwidth_3db_hz=_first_below(f, gain, 10 ** (-3 / 20)),
        bandwidth_45deg_hz=_first_below(f, phase, -45.0),
        tracking_limit_hz=_lasting_departure(f, np.maximum(off_db / 1.0, np.abs(phase) / 20.0)),
    )


def chirp_tracking(
    setup: CapstanSetup,
    *,
    amplitude_rad: float = math.radians(5.0),
    f0_hz: float = 0.2,
    f1_hz: float = 5.0,
    duration_s: float = 10.0,
    rest_s: float = 2.0,
    zpetc: bool = False,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, ChirpMetrics]:
    """Paper 001's chirp: 5 degrees, 0.2 to 5 Hz over 10 s (then ``rest_s`` at 0), with metrics.

    With ``setup.feedforward`` the loop adds the inverse dynamics of the chirp's exact speed and
    acceleration; with ``zpetc`` the reference is the chirp passed through the inverse of the
    closed loop's model (:func:`~anklelab.control.tracking.zpetc_reference`) and its
    derivatives are backward differences, as the model assumes. The metrics always compare the
    measured angle with the chirp itself.
    """
    desired, speed, acceleration = chirp_reference(
        amplitude_rad, f0_hz, f1_hz, duration_s, setup.fs
    )
    rest = np.zeros(round(rest_s * setup.fs))
    desired = np.concatenate([desired, rest])
    reference = desired
    speed, acceleration = np.concatenate([speed, rest]), np.concatenate([acceleration, rest])
    if zpetc:
        reference = zpetc_reference(desired, setup.loop_model())
        speed, acceleration = reference_derivatives(reference, setup.fs)
    result = simulate_closed_loop(
        setup,
        reference.size,
        reference=reference,
        reference_speed=speed,
        reference_acceleration=acceleration,
        seed=seed,
    )
    metrics = chirp_metrics(
        desired, result["measured_angle_rad"], setup.fs, f0_hz, f1_hz, duration_s=duration_s
    )
    return result, metrics
