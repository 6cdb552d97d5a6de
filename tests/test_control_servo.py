"""The Perturberator servo: PRBS/FRF tools on analytic loops, and the loop measured on the twin."""

import json

import numpy as np
import pytest
from scipy import signal
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.control.motion_plan import StepDirectionPlan
from anklelab.control.perturbation import RampHold
from anklelab.control.servo import (
    CascadeGains,
    bandwidth_hz,
    fit_second_order,
    loop_margins,
    periodic_frf,
    phase_crossing_hz,
    prbs,
)
from anklelab.experiments.perturberator_bode import measure_servo_bode
from anklelab.platforms import load_platform
from anklelab.sim.drivetrain import simulate_platform

FS = 8000.0


@pytest.fixture(scope="module")
def params():
    return load_platform("perturberator")


@pytest.fixture(scope="module")
def bode(params):
    return measure_servo_bode(params)


def test_prbs_is_a_maximum_length_sequence():
    x = prbs(7, periods=2, amplitude=0.5)
    one = x[:127]
    assert np.array_equal(x[127:], one)
    assert set(np.unique(one)) == {-0.5, 0.5}
    circular = np.array([np.dot(one, np.roll(one, k)) for k in range(1, 127)])
    assert np.allclose(circular, -0.25)  # flat spectrum: autocorrelation -1/N off the peak
    with pytest.raises(ValueError, match="n_bits"):
        prbs(20)


def test_periodic_frf_recovers_a_known_filter():
    b, a = signal.butter(2, 300.0, fs=FS)
    x = prbs(10, periods=3)
    y = signal.lfilter(b, a, x)
    f, h = periodic_frf(x, y, 1023, FS)
    _, expected = signal.freqz(b, a, worN=f, fs=FS)
    assert np.allclose(h, expected, rtol=1e-6, atol=1e-9)
    with pytest.raises(ValueError, match="periods"):
        periodic_frf(x[:1023], y[:1023], 1023, FS)


def test_margins_and_crossings_of_analytic_loops():
    f = np.linspace(1.0, 3000.0, 6000)
    s = 2j * np.pi * f
    tau = 2e-4
    loop = 2 * np.pi * 150.0 / s * np.exp(-s * tau) / (1 + s / (2 * np.pi * 600.0))
    m = loop_margins(f, loop)
    wc = 2 * np.pi * m.gain_crossover_hz
    assert abs(loop[np.argmin(abs(f - m.gain_crossover_hz))]) == pytest.approx(1.0, abs=2e-3)
    expected_pm = 90 - np.degrees(wc * tau) - np.degrees(np.arctan(wc / (2 * np.pi * 600)))
    assert m.phase_margin_deg == pytest.approx(expected_pm, abs=0.05)
    at_pc = loop[np.argmin(abs(f - m.phase_crossover_hz))]
    assert m.gain_margin_db == pytest.approx(-20 * np.log10(abs(at_pc)), abs=0.05)
    closed = loop / (1 + loop)
    assert bandwidth_hz(f, closed) > m.gain_crossover_hz
    assert phase_crossing_hz(f, closed) > 0
    fn, zeta, delay = fit_second_order(f, closed, f_max=600.0)
    assert 100 < fn < 400 and 0 < zeta < 1.5 and delay >= 0


def test_bode_measured_on_the_twin_matches_paper_000(bode):
    # paper 000, section 2.1: ~200 Hz natural frequency, 8 dB gain margin, pi/4 phase margin
    assert bode.natural_frequency_hz == pytest.approx(200.0, rel=0.10)
    assert bode.fit_natural_frequency_hz == pytest.approx(200.0, rel=0.10)
    assert bode.gain_margin_db == pytest.approx(8.0, abs=2.0)
    assert bode.phase_margin_deg == pytest.approx(45.0, abs=10.0)
    assert bode.bandwidth_hz > bode.natural_frequency_hz
    low = bode.freqs_hz < 20
    assert np.allclose(np.abs(bode.closed_loop[low]), 1.0, atol=0.01)


def test_closed_and_open_loop_measurements_agree(bode):
    # the directly measured T and the one implied by the injected loop L = T/(1-T) agree
    keep = bode.freqs_hz < 600
    implied = bode.open_loop[keep] / (1 + bode.open_loop[keep])
    db = 20 * np.log10(np.abs(bode.closed_loop[keep]) / np.abs(implied))
    assert np.abs(db).max() < 1.0


def test_measurement_responds_to_the_gains(params, bode):
    gains = CascadeGains.from_params(params.servo)
    stiffer = params.replace({"servo.position_gain_per_s": 1.5 * gains.position_gain_per_s})
    more = measure_servo_bode(stiffer)
    assert more.phase_margin_deg < bode.phase_margin_deg - 5
    assert more.gain_crossover_hz > bode.gain_crossover_hz


def test_ramp_is_tracked_as_the_measured_closed_loop_implies(params, bode):
    n = (2**11 - 1) * 4  # one PRBS period of the measurement, so T applies harmonic by harmonic
    plan = StepDirectionPlan.from_params(params)
    move = RampHold(0.035, ramp_s=0.075, hold_s=0.1, return_s=0.075)
    command = plan.reference(move(plan.update_times(n / FS), 0.5)[None], FS, n)[0]
    run = simulate_platform(params, command[None], plate=False, record_loop=True, record_fs=FS)
    response = run.loop["encoder"][0]
    transfer = np.zeros(n // 2 + 1, dtype=complex)
    transfer[0] = 1.0
    transfer[np.rint(bode.freqs_hz * n / FS).astype(int)] = bode.closed_loop
    predicted = np.fft.irfft(np.fft.rfft(command) * transfer, n)
    assert np.abs(response - predicted).max() < 0.005 * 0.035
    t = np.arange(n) / FS
    mid = np.searchsorted(t, 0.56)  # steady part of the ramp
    speed = 0.035 / 0.075
    lag_ms = (command[mid] - response[mid]) / speed * 1e3
    assert lag_ms == pytest.approx((command[mid] - predicted[mid]) / speed * 1e3, rel=0.02)
    assert 0.5 < lag_ms < 3.0
    hold = slice(np.searchsorted(t, 0.575), np.searchsorted(t, 0.67))
    overshoot = response[hold].max() - 0.035
    assert overshoot == pytest.approx(predicted[hold].max() - 0.035, abs=1e-5)


def test_bode_command_prints_the_figures(tmp_path):
    plot = tmp_path / "bode.png"
    result = CliRunner().invoke(app, ["platform", "bode", "--json", "--plot", str(plot)])
    assert result.exit_code == 0, result.output
    figures = json.loads(result.output)
    for key in ("natural_frequency_hz", "gain_margin_db", "phase_margin_deg", "bandwidth_hz"):
        assert np.isfinite(figures[key])
    assert plot.stat().st_size > 1000
