"""The plate on the moving hinge: tilt gravity, inertia, structural modes, mounting, DAQ."""

import numpy as np
import pytest
from scipy import signal

from anklelab.forceplate import CHANNELS, resultants, sagittal_load
from anklelab.iir import butterworth_sos, resonance_sos
from anklelab.platforms import load_platform
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.drivetrain import GRAVITY, simulate_platform
from anklelab.sim.forceplate_dynamics import (
    daq_quantize,
    mounting_rotation,
    sensor_channels,
)
from anklelab.sim.sensors import force_channels

FS = 8000.0
INERTIA_ONLY = Artefacts(resonance=False, anti_alias=False, quantisation=False)


@pytest.fixture(scope="module")
def params():
    return load_platform("perturberator")


@pytest.fixture(scope="module")
def ramp():
    """A dorsiflexion ramp to 0.035 rad and hold, as a raw position command at 8 kHz."""
    t = np.arange(int(1.2 * FS)) / FS
    return np.clip((t - 0.1) / 0.075, 0, 1)[None] * 0.035


def test_tilted_top_plate_loads_the_sensors_with_its_weight(params, ramp):
    run = simulate_platform(params, ramp, artefacts=INERTIA_ONLY, record_fs=FS)
    th = run.hinge_angle[0, -10]
    fx, fy, fz, mx, my, mz = run.wrench[0, :, -10]
    fp = params.force_plate
    m = fp.top_plate_mass_kg
    assert fx == pytest.approx(-m * GRAVITY * np.sin(th), rel=1e-3)  # slides towards the heel
    assert fz == pytest.approx(m * GRAVITY * (np.cos(th) - 1), rel=1e-3)
    assert my == pytest.approx(fp.top_plate_com_z_m * fx, rel=1e-3)
    assert fy == mx == mz == 0.0


def test_accelerating_hinge_loads_the_sensors_with_the_top_plates_inertia(params, ramp):
    run = simulate_platform(params, ramp, artefacts=INERTIA_ONLY, record_fs=FS)
    th = run.hinge_angle[0]
    acc = np.gradient(np.gradient(th, 1 / FS), 1 / FS)
    fp = params.force_plate
    hinge_z = fp.az0_m - params.geometry.ankle_height_m  # axis above the surface (z down)
    r_z = fp.top_plate_com_z_m - hinge_z
    expected = fp.top_plate_mass_kg * (-GRAVITY * np.sin(th) - acc * r_z)
    busy = slice(int(0.09 * FS), int(0.3 * FS))
    error = run.wrench[0, 0, busy] - expected[busy]
    assert np.abs(expected[busy]).max() > 20  # the inertial load is large
    assert np.abs(error).max() < 0.02 * np.abs(expected[busy]).max()


def test_structural_modes_ring_at_300_and_500_hz(params, ramp):
    plain = simulate_platform(params, ramp, artefacts=INERTIA_ONLY, record_fs=FS)
    ringing = simulate_platform(
        params, ramp, artefacts=Artefacts(anti_alias=False, quantisation=False), record_fs=FS
    )
    for component, expected in ((4, 300.0), (0, 500.0)):  # My vertical group, Fx horizontal
        x, y = plain.wrench[0, component], ringing.wrench[0, component]
        f, sxy = signal.csd(x, y, fs=FS, nperseg=1024)
        _, sxx = signal.welch(x, fs=FS, nperseg=1024)
        gain = np.abs(sxy / sxx)
        band = (f > 100) & (f < 1000)
        assert f[band][np.argmax(gain[band])] == pytest.approx(expected, abs=8.0)
        assert gain[band].max() > 5  # lightly damped


def test_anti_alias_filter_attenuates_above_the_daq_nyquist(params):
    sos = butterworth_sos(params.daq.anti_alias_order, params.daq.anti_alias_hz, FS)
    _, h = signal.sosfreqz(sos, [10.0, 500.0, 1000.0], fs=FS)
    assert abs(h[0]) == pytest.approx(1.0, abs=1e-3)
    assert abs(h[1]) < 0.5 and abs(h[2]) < 0.03
    mode = resonance_sos(500.0, 0.05, FS)
    assert abs(signal.sosfreqz(mode, [500.0], fs=FS)[1][0]) == pytest.approx(10.0, rel=1e-3)


@pytest.mark.parametrize("axis", ["+x", "-x", "+y", "-y"])
def test_channels_carry_the_sagittal_load_for_every_mounting(params, axis):
    geometry = params.force_plate.model_copy(update={"anterior_axis": axis})
    fx, fz, cop, az0 = -40.0, 700.0, 0.07, geometry.az0_m  # load on plate; COP 7 cm anterior
    wrench = np.array([fx, 0.0, fz, 0.0, az0 * fx - cop * fz, 0.0])[:, None]
    load = sagittal_load(resultants(sensor_channels(wrench, geometry), geometry), axis)
    assert load.grf_x[0] == pytest.approx(-fx)  # GRF is the plate on the foot
    assert load.grf_z[0] == pytest.approx(fz)
    assert load.cop_x[0] == pytest.approx(cop)
    assert np.allclose(mounting_rotation(axis) @ mounting_rotation(axis).T, np.eye(3))


def test_daq_adds_drift_noise_and_quantisation(params):
    n_trials, n = 400, 2000
    zero = np.zeros((n_trials, 6, n))
    rng = np.random.default_rng(0)
    drift = force_channels(zero, params, Artefacts(noise=False, quantisation=False), rng)
    slopes = drift[..., -1] / ((n - 1) / params.daq.sample_rate_hz)
    assert slopes.std() == pytest.approx(params.force_plate.drift_n_per_s, rel=0.1)
    noisy = force_channels(zero, params, Artefacts(drift=False, quantisation=False), rng)
    assert noisy.std() == pytest.approx(params.force_plate.noise_n, rel=0.02)
    quantised = force_channels(zero + 1.234, params, Artefacts(noise=False, drift=False), rng)
    fz_step = 2 * params.force_plate.range_vertical_n / 2**params.daq.bits
    fz = quantised[:, CHANNELS.index("fz1")]
    assert np.allclose(fz / fz_step, np.round(fz / fz_step))
    assert daq_quantize(np.array([1e9]), 1.0, 16)[0] < 1.0  # clipped at full scale
