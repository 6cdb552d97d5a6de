"""Closed-form IIR designs and the zero-phase filter equal SciPy's, and the analysis of a
recorded session never imports ``scipy.signal``."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import signal

from anklelab.data import save_session
from anklelab.experiments import simulate_perturberator
from anklelab.iir import butterworth_sos, edge_padding, resonance_sos, sosfiltfilt


@pytest.mark.parametrize("order", [1, 2, 3, 4, 5, 8])
def test_butterworth_sections_filter_as_scipys(order):
    x = np.random.default_rng(order).standard_normal(4000)
    ours = signal.sosfilt(butterworth_sos(order, 400.0, 8000.0), x)
    theirs = signal.sosfilt(signal.butter(order, 400.0, fs=8000.0, output="sos"), x)
    assert np.abs(ours - theirs).max() < 1e-12 * np.abs(theirs).max()


@pytest.mark.parametrize(("f0", "zeta"), [(300.0, 0.05), (500.0, 0.1), (2500.0, 0.7)])
def test_resonance_section_equals_the_prewarped_bilinear_transform(f0, zeta):
    fs = 8000.0
    wa = 2 * fs * np.tan(np.pi * f0 / fs)
    z, p, k = signal.bilinear_zpk([], np.roots([1.0, 2 * zeta * wa, wa * wa]), wa * wa, fs)
    np.testing.assert_allclose(resonance_sos(f0, zeta, fs), signal.zpk2sos(z, p, k), atol=1e-12)


@pytest.mark.parametrize("order", [1, 2, 3, 4, 8])
@pytest.mark.parametrize("cutoff_hz", [5.0, 20.0, 200.0])
def test_zero_phase_filter_equals_scipys_sosfiltfilt(order, cutoff_hz):
    # drifting signals (a random walk): the odd extension and the initial states matter
    x = np.random.default_rng(order).standard_normal((70, 3, 900)).cumsum(axis=-1)
    sos = butterworth_sos(order, cutoff_hz, 1000.0)
    theirs = signal.sosfiltfilt(signal.butter(order, cutoff_hz, fs=1000.0, output="sos"), x)
    tol = 1e-11 * np.abs(theirs).max()
    np.testing.assert_allclose(sosfiltfilt(sos, x), theirs, rtol=0, atol=tol)
    along_0 = sosfiltfilt(sos, np.moveaxis(x, -1, 0), axis=0)  # more signals than one block
    np.testing.assert_allclose(np.moveaxis(along_0, 0, -1), theirs, rtol=0, atol=tol)
    assert edge_padding(sos) == 3 * (order + 1)


def test_a_constant_passes_unchanged_to_its_last_sample():
    y = sosfiltfilt(butterworth_sos(4, 20.0, 1000.0), np.full((2, 40), 3.25))
    np.testing.assert_allclose(y, 3.25, rtol=1e-13)


def test_analysing_a_recorded_session_never_imports_scipy_signal_or_linalg(tmp_path):
    """Nor the platforms' parameter models: reading a session needs only their names."""
    session = simulate_perturberator(
        trials_per_point=4, n_unperturbed=12, n_calibration=2, bench=False, seed=2
    )
    path = tmp_path / "session.h5"
    save_session(session, path)
    code = (
        "import sys\n"
        "from anklelab.data import load_session\n"
        "from anklelab.pipelines import WalkingSettings, analyze_walking\n"
        f"analyze_walking(load_session({str(path)!r}), WalkingSettings(bootstrap_reps=5))\n"
        "heavy = ('scipy.signal', 'scipy.linalg', 'anklelab.platforms.perturberator')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
