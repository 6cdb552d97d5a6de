"""The servo drive's position/velocity cascade: gains, PRBS excitation and loop measurements.

The drive (paper 000: Kollmorgen AKD) closes a proportional position loop (8 kHz) around a PI
velocity loop (16 kHz) around a current loop (1.5 MHz, modelled as a first-order torque lag of
``current_bandwidth_hz``); its autotune measures the loop with a small pseudorandom binary
sequence. The twin's compiled implementation of the cascade lives with the plant in
:mod:`anklelab.sim.drivetrain`; this module holds what is measured and reported about it:
maximum-length PRBS, periodic frequency-response estimates, the closed-loop fit
(natural frequency, damping, delay), the -3 dB bandwidth and gain/phase margins of a measured
loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize, signal

from anklelab.errors import ParameterError
from anklelab.platforms.perturberator import ServoParameters

__all__ = [
    "CascadeGains",
    "LoopMargins",
    "bandwidth_hz",
    "fit_second_order",
    "loop_margins",
    "periodic_frf",
    "phase_crossing_hz",
    "prbs",
    "second_order_response",
]


@dataclass(frozen=True)
class CascadeGains:
    """Gains of the cascade, referred to the platform output.

    ``velocity_command = position_gain_per_s * (reference - encoder)``;
    ``torque_command = velocity_gain * (e_v + 2 pi velocity_integral_hz * integral(e_v))``.
    """

    position_gain_per_s: float
    velocity_gain_nms_per_rad: float
    velocity_integral_hz: float

    @classmethod
    def from_params(cls, servo: ServoParameters) -> CascadeGains:
        """The gains stored in a parameter set."""
        return cls(
            servo.position_gain_per_s, servo.velocity_gain_nms_per_rad, servo.velocity_integral_hz
        )

    def as_changes(self) -> dict[str, float]:
        """Dotted-key changes for :meth:`anklelab.platforms.Parameters.replace`."""
        return {f"servo.{k}": float(v) for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class LoopMargins:
    """Stability margins of a measured open loop.

    Attributes
    ----------
    gain_margin_db : float
        ``-20 log10 |L|`` where the phase of ``L`` crosses -180 deg (inf if it never does).
    phase_margin_deg : float
        ``180 + angle(L)`` where ``|L|`` crosses 1.
    gain_crossover_hz, phase_crossover_hz : float
        Where those crossings happen (NaN if absent).
    """

    gain_margin_db: float
    phase_margin_deg: float
    gain_crossover_hz: float
    phase_crossover_hz: float


def prbs(n_bits: int = 13, *, periods: int = 1, amplitude: float = 1.0) -> NDArray[np.float64]:
    """Maximum-length pseudorandom binary sequence, ``±amplitude``, ``periods`` repetitions.

    Parameters
    ----------
    n_bits : int
        Register length (3 ... 16); one period has ``2**n_bits - 1`` samples.
    periods : int
        Number of repetitions.
    amplitude : float
        Level of the two values.

    Examples
    --------
    >>> x = prbs(4)
    >>> len(x), int(x.sum())        # 8 ones and 7 minus-ones per period
    (15, 1)
    """
    if not 3 <= n_bits <= 16:
        raise ParameterError(f"n_bits: expected 3 ... 16, got {n_bits}")
    seq = signal.max_len_seq(n_bits)[0].astype(float)
    return np.tile(amplitude * (2 * seq - 1), periods)


def periodic_frf(
    excitation: ArrayLike, response: ArrayLike, period: int, fs: float, *, skip: int = 1
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """Frequency response ``Y/X`` of a periodically excited system, periods averaged.

    Parameters
    ----------
    excitation, response : array_like, shape (..., n)
        Signals covering whole periods, time last.
    period : int
        Samples per excitation period.
    fs : float
        Sample rate, Hz.
    skip : int
        Leading periods discarded (transient).

    Returns
    -------
    freqs : ndarray
        Frequencies of the harmonics, Hz (DC excluded).
    frf : ndarray
        ``mean(FFT(y)) / mean(FFT(x))`` over the periods kept.
    """
    x = np.asarray(excitation, dtype=float)
    y = np.asarray(response, dtype=float)
    n_periods = x.shape[-1] // period
    if n_periods <= skip:
        raise ParameterError(
            f"need more than {skip} periods of {period} samples; got {x.shape[-1]}"
        )
    cut = slice(skip * period, n_periods * period)
    xs = x[..., cut].reshape(*x.shape[:-1], -1, period)
    ys = y[..., cut].reshape(*y.shape[:-1], -1, period)
    fx = np.fft.rfft(xs, axis=-1).mean(axis=-2)
    fy = np.fft.rfft(ys, axis=-1).mean(axis=-2)
    freqs = np.fft.rfftfreq(period, 1 / fs)
    excited = np.abs(fx) > 1e-9 * np.abs(fx).max()
    excited[0] = False
    return freqs[excited], fy[..., excited] / fx[excited]


def second_order_response(
    f: NDArray[np.float64], fn: float, zeta: float, delay: float
) -> NDArray[np.complex128]:
    """``wn²/(s² + 2 zeta wn s + wn²) e^(-s delay)`` at frequencies ``f`` (Hz), ``s = 2 pi j f``."""
    s = 2j * np.pi * f
    wn = 2 * np.pi * fn
    return wn**2 / (s**2 + 2 * zeta * wn * s + wn**2) * np.exp(-s * delay)


def fit_second_order(
    freqs: ArrayLike, frf: ArrayLike, *, f_max: float
) -> tuple[float, float, float]:
    """Fit ``wn²/(s² + 2 zeta wn s + wn²) e^(-s tau)`` to a closed-loop response up to ``f_max``.

    Returns
    -------
    natural_frequency_hz, damping_ratio, delay_s : float

    Examples
    --------
    >>> f = np.linspace(1.0, 600.0, 600)
    >>> h = second_order_response(f, 200.0, 0.4, 1e-4)
    >>> fn, zeta, tau = fit_second_order(f, h, f_max=600.0)
    >>> round(fn, 3), round(zeta, 3), round(tau * 1e6, 3)
    (200.0, 0.4, 100.0)
    """
    f = np.asarray(freqs, dtype=float)
    h = np.asarray(frf, dtype=complex)
    keep = (f > 0) & (f <= f_max)
    f, h = f[keep], h[keep]
    mag = np.abs(h)
    start = (float(f[np.argmax(mag)]) if mag.max() > 1.05 else float(f[np.argmin(abs(mag - 0.7))]),
             0.4, 1e-4)  # fmt: skip

    def residual(p: NDArray[np.float64]) -> NDArray[np.float64]:
        e = (second_order_response(f, *p) - h) / np.maximum(mag, 0.05)
        return np.concatenate([e.real, e.imag])

    fit = optimize.least_squares(residual, start, bounds=([1.0, 0.01, 0.0], [1e4, 3.0, 0.01]))
    return float(fit.x[0]), float(fit.x[1]), float(fit.x[2])


def bandwidth_hz(freqs: ArrayLike, frf: ArrayLike) -> float:
    """First frequency where ``|H|`` falls below ``1/sqrt(2)`` of its low-frequency value."""
    f = np.asarray(freqs, dtype=float)
    mag = np.abs(np.asarray(frf))
    level = mag[0] / np.sqrt(2)
    below = np.flatnonzero(mag < level)
    if below.size == 0:
        return float("nan")
    i = below[0]
    if i == 0:
        return float(f[0])
    # interpolate in dB between the bracketing harmonics
    a, b = 20 * np.log10(mag[i - 1]), 20 * np.log10(mag[i])
    target = 20 * np.log10(level)
    return float(f[i - 1] + (f[i] - f[i - 1]) * (a - target) / (a - b))


def phase_crossing_hz(freqs: ArrayLike, frf: ArrayLike, phase_deg: float = -90.0) -> float:
    """First frequency where the (unwrapped) phase of ``frf`` falls to ``phase_deg``, Hz.

    A second-order closed loop lags by 90 deg exactly at its natural frequency, whatever its
    damping, so this reads the natural frequency off a measured response without a model.

    Examples
    --------
    >>> f = np.linspace(1.0, 600.0, 600)
    >>> round(phase_crossing_hz(f, second_order_response(f, 200.0, 0.4, 0.0)), 3)
    200.0
    """
    f = np.asarray(freqs, dtype=float)
    phase = np.degrees(np.unwrap(np.angle(np.asarray(frf))))
    below = np.flatnonzero(phase <= phase_deg)
    if below.size == 0 or below[0] == 0:
        return float("nan")
    i = below[0]
    return float(
        f[i - 1] + (f[i] - f[i - 1]) * (phase_deg - phase[i - 1]) / (phase[i] - phase[i - 1])
    )


def loop_margins(freqs: ArrayLike, loop: ArrayLike) -> LoopMargins:
    """Gain and phase margins of a measured open-loop response (first crossings).

    Examples
    --------
    >>> f = np.linspace(1.0, 2000.0, 4000)
    >>> s = 2j * np.pi * f
    >>> m = loop_margins(f, 2 * np.pi * 100 / s * np.exp(-s * 1e-3))
    >>> round(m.phase_margin_deg, 1), round(m.gain_crossover_hz, 1)
    (54.0, 100.0)
    """
    f = np.asarray(freqs, dtype=float)
    loop = np.asarray(loop, dtype=complex)
    mag_db = 20 * np.log10(np.abs(loop))
    phase = np.degrees(np.unwrap(np.angle(loop)))
    phase -= 360 * np.round((phase[0] + 90) / 360)  # a type-1 loop starts near -90 deg

    def crossing(x: NDArray[np.float64], level: float) -> float:
        idx = np.flatnonzero((x[:-1] - level) * (x[1:] - level) <= 0)
        if idx.size == 0:
            return float("nan")
        i = idx[0]
        return float(i + (level - x[i]) / (x[i + 1] - x[i])) if x[i + 1] != x[i] else float(i)

    def at(x: NDArray[np.float64], pos: float) -> float:
        i = int(pos)
        return float(x[i] + (pos - i) * (x[min(i + 1, len(x) - 1)] - x[i]))

    gc = crossing(mag_db, 0.0)
    pc = crossing(phase, -180.0)
    return LoopMargins(
        gain_margin_db=-at(mag_db, pc) if np.isfinite(pc) else float("inf"),
        phase_margin_deg=180.0 + at(phase, gc) if np.isfinite(gc) else float("nan"),
        gain_crossover_hz=at(f, gc) if np.isfinite(gc) else float("nan"),
        phase_crossover_hz=at(f, pc) if np.isfinite(pc) else float("nan"),
    )
