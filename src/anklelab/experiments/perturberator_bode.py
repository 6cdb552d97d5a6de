"""Measure the Perturberator servo's position loop on the twin, as the drive's autotune does.

Two small pseudorandom-binary-sequence experiments on the empty platform (paper 000, section
2.1 and Fig. 2):

1. **Closed loop.** A PRBS position command (default ±20 µrad, clocked at 2 kHz) replaces the
   motion plan; the closed-loop response ``T = encoder / command`` is estimated from whole
   periods. Its *natural frequency* is read where the phase lag reaches 90 deg (model-free;
   a second-order response lags 90 deg at its natural frequency), its *bandwidth* where the
   magnitude falls 3 dB; a second-order-with-delay fit is reported too.
2. **Open loop.** A PRBS velocity command (default ±0.05 rad/s) is added at the position
   controller's output with the command held at zero; the loop is
   ``L = -controller output / (controller output + injection)``, and its gain and phase
   margins are read at the crossings.

Nothing here reads the gains: everything comes from the simulated signals.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from anklelab.control.servo import (
    bandwidth_hz,
    fit_second_order,
    loop_margins,
    periodic_frf,
    phase_crossing_hz,
    prbs,
    second_order_response,
)
from anklelab.errors import ParameterError
from anklelab.platforms import load_platform
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim.drivetrain import simulate_platform

__all__ = ["ServoBode", "measure_servo_bode"]


@dataclass(frozen=True)
class ServoBode:
    """Measured closed-loop and open-loop responses of the position loop and their figures.

    Attributes
    ----------
    freqs_hz : ndarray
        Harmonics of the PRBS period up to the analysis limit, Hz.
    closed_loop, open_loop : ndarray of complex
        ``T(j w)`` (encoder / command) and ``L(j w)`` at ``freqs_hz``.
    natural_frequency_hz, bandwidth_hz, peak_db : float
        Where ``T`` lags 90 deg; where ``|T|`` falls 3 dB; the largest ``|T|``.
    fit_natural_frequency_hz, fit_damping_ratio, fit_delay_s : float
        Second-order-with-delay fit to ``T`` up to 600 Hz.
    gain_margin_db, phase_margin_deg, gain_crossover_hz, phase_crossover_hz : float
        Margins of ``L``.
    """

    freqs_hz: NDArray[np.float64]
    closed_loop: NDArray[np.complex128]
    open_loop: NDArray[np.complex128]
    natural_frequency_hz: float
    bandwidth_hz: float
    peak_db: float
    fit_natural_frequency_hz: float
    fit_damping_ratio: float
    fit_delay_s: float
    gain_margin_db: float
    phase_margin_deg: float
    gain_crossover_hz: float
    phase_crossover_hz: float

    def summary(self) -> dict[str, float]:
        """The scalar figures, by name (what ``anklelab platform bode --json`` prints)."""
        return {
            name: float(getattr(self, name))
            for name in (
                "natural_frequency_hz", "gain_margin_db", "phase_margin_deg", "bandwidth_hz",
                "peak_db", "gain_crossover_hz", "phase_crossover_hz",
                "fit_natural_frequency_hz", "fit_damping_ratio", "fit_delay_s",
            )
        }  # fmt: skip

    def plot(self, path: str | Path) -> Path:
        """Bode plot of ``T`` (with its fit) and ``L``, written to ``path`` (PNG, SVG, PDF)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        f = self.freqs_hz
        fit = second_order_response(
            f, self.fit_natural_frequency_hz, self.fit_damping_ratio, self.fit_delay_s
        )
        fig, (mag, ph) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
        for h, label, style in (
            (self.closed_loop, "closed loop T (measured)", "-"),
            (fit, "second-order fit", "--"),
            (self.open_loop, "open loop L (measured)", "-"),
        ):
            mag.semilogx(f, 20 * np.log10(np.abs(h)), style, label=label)
            ph.semilogx(f, np.degrees(np.unwrap(np.angle(h))), style)
        mag.axhline(-3, color="0.6", lw=0.8)
        mag.axvline(self.natural_frequency_hz, color="0.6", lw=0.8)
        mag.set_ylabel("magnitude (dB)")
        mag.set_ylim(-40, 40)
        mag.legend(loc="lower left")
        mag.set_title(
            f"position loop: natural frequency {self.natural_frequency_hz:.0f} Hz, "
            f"GM {self.gain_margin_db:.1f} dB, PM {self.phase_margin_deg:.0f} deg"
        )
        ph.set_ylabel("phase (deg)")
        ph.set_xlabel("frequency (Hz)")
        ph.set_ylim(-360, 30)
        fig.tight_layout()
        path = Path(path)
        fig.savefig(path)
        plt.close(fig)
        return path


def measure_servo_bode(
    params: PerturberatorParameters | None = None,
    *,
    amplitude_rad: float = 2e-5,
    injection_rad_per_s: float = 0.05,
    n_bits: int = 11,
    clock_hz: float = 2000.0,
    periods: int = 3,
    f_max_hz: float = 1500.0,
) -> ServoBode:
    """PRBS measurement of the twin's position loop (closed loop and open loop).

    Parameters
    ----------
    params : PerturberatorParameters, optional
        The platform (gains, drivetrain); the shipped set by default.
    amplitude_rad : float
        PRBS level of the position command, rad at the platform.
    injection_rad_per_s : float
        PRBS level of the velocity command injected at the position controller's output.
    n_bits : int
        PRBS register length (period ``2**n_bits - 1`` bits).
    clock_hz : float
        PRBS bit rate; must divide the position-loop rate.
    periods : int
        Periods simulated; the first is discarded as transient.
    f_max_hz : float
        Highest frequency kept.

    Returns
    -------
    ServoBode
    """
    params = load_platform("perturberator") if params is None else params
    fs = params.servo.position_loop_rate_hz
    hold = round(fs / clock_hz)
    if hold < 1 or not np.isclose(hold * clock_hz, fs):
        raise ParameterError(f"clock_hz: {clock_hz} Hz must divide the position-loop rate {fs} Hz")
    period = (2**n_bits - 1) * hold
    command = np.repeat(prbs(n_bits, periods=periods, amplitude=amplitude_rad), hold)
    closed = simulate_platform(params, command[None], plate=False, record_loop=True, record_fs=fs)
    assert closed.loop is not None
    f, t_cl = periodic_frf(command, closed.loop["encoder"][0], period, fs)
    injection = np.repeat(prbs(n_bits, periods=periods, amplitude=injection_rad_per_s), hold)
    opened = simulate_platform(
        params,
        np.zeros((1, injection.size)),
        injection=injection[None],
        plate=False,
        record_loop=True,
        record_fs=fs,
    )
    assert opened.loop is not None
    _, ctrl = periodic_frf(injection, opened.loop["control"][0], period, fs)
    _, cmd = periodic_frf(injection, opened.loop["command"][0], period, fs)
    keep = f <= f_max_hz
    f, t_cl, loop = f[keep], t_cl[keep], (-ctrl / cmd)[keep]
    margins = loop_margins(f, loop)
    fn, zeta, delay = fit_second_order(f, t_cl, f_max=600.0)
    return ServoBode(
        freqs_hz=f,
        closed_loop=t_cl,
        open_loop=loop,
        natural_frequency_hz=phase_crossing_hz(f, t_cl, -90.0),
        bandwidth_hz=bandwidth_hz(f, t_cl),
        peak_db=float(20 * np.log10(np.abs(t_cl).max())),
        fit_natural_frequency_hz=fn,
        fit_damping_ratio=zeta,
        fit_delay_s=delay,
        gain_margin_db=margins.gain_margin_db,
        phase_margin_deg=margins.phase_margin_deg,
        gain_crossover_hz=margins.gain_crossover_hz,
        phase_crossover_hz=margins.phase_crossover_hz,
    )
