"""Heel contact from the vertical force; perturbation onset from the motor angle."""

import numpy as np
import pytest
from scipy.signal import lfilter

from anklelab.errors import ParameterError
from anklelab.signals import NOT_FOUND, heel_contact, perturbation_onset

FS = 1000.0


def _stance(contact, n=800):
    t = np.arange(n) - contact
    return np.where(t >= 0, 700.0 * np.sin(np.pi * np.clip(t, 0, 600) / 600) ** 0.5, 0.0)


def test_heel_contact_is_the_first_sustained_threshold_crossing():
    rng = np.random.default_rng(0)
    contacts = np.array([150, 173, 260])
    fz = np.stack([_stance(c) for c in contacts]) + rng.normal(0, 2.0, (3, 800))
    fz[0, 60] = 80.0  # a spike before contact is not a contact
    found = heel_contact(fz, FS)
    first_above = np.array([np.argmax(_stance(c) >= 25.0) for c in contacts])
    assert np.all(np.abs(found - first_above) <= 1)
    assert heel_contact(fz, FS, 300.0)[0] > found[0]


def test_heel_contact_not_found_and_hold_zero():
    fz = np.zeros((2, 100))
    fz[1, 40] = 30.0
    assert heel_contact(fz, FS).tolist() == [NOT_FOUND, NOT_FOUND]
    assert heel_contact(fz, FS, hold_ms=0.0).tolist() == [NOT_FOUND, 40]
    with pytest.raises(ParameterError, match="threshold_n"):
        heel_contact(fz, FS, -1.0)


def _servo_ramp(onset, amplitude, n=600, ramp=75, hold=25):
    """A ramp-and-hold command through a 200 Hz, zeta 0.4 servo (bilinear), at rest before."""
    k = np.arange(n) - onset
    cmd = amplitude * np.clip(k / ramp, 0, 1) - amplitude * np.clip((k - ramp - hold) / ramp, 0, 1)
    w, z, dt = 2 * np.pi * 200.0, 0.4, 1 / FS
    # discretised second-order low-pass, unit DC gain
    c = 2 / dt
    a0, a1, a2 = c * c + 2 * z * w * c + w * w, 2 * w * w - 2 * c * c, c * c - 2 * z * w * c + w * w
    return lfilter(np.array([1, 2, 1]) * w * w / a0, [1, a1 / a0, a2 / a0], cmd)


@pytest.mark.parametrize("onset", [212.0, 300.25, 333.7])
@pytest.mark.parametrize("amplitude", [0.035, -0.035, 0.02])
def test_onset_of_a_quantised_noisy_servo_ramp(onset, amplitude):
    rng = np.random.default_rng(int(onset))
    n = np.arange(600.0)
    angle = np.interp(n - (onset - np.floor(onset)), n, _servo_ramp(int(onset), amplitude))
    angle = np.round(angle + rng.normal(0, 5e-5, n.size), 4)  # 1e-4 rad analog resolution
    result = perturbation_onset(angle[None], start=[150])
    # the servo lags the command by 2*zeta/omega = 0.64 ms; detection is within 1.5 ms
    assert result.index[0] == pytest.approx(onset, abs=1.5)
    assert result.amplitude[0] == pytest.approx(amplitude, rel=0.05)


def test_no_perturbation_and_movement_before_start_are_ignored():
    quiet = np.round(np.random.default_rng(3).normal(0, 2e-4, (1, 500)), 4)
    assert np.isnan(perturbation_onset(quiet).index[0])
    moved_early = _servo_ramp(20, 0.03, n=500)  # over and back before sample 250
    late = _servo_ramp(300, 0.03, n=500)
    found = perturbation_onset(np.stack([moved_early + late, moved_early]), start=[250, 250])
    assert found.index[0] == pytest.approx(300, abs=1.5)
    assert np.isnan(found.index[1])


def test_onset_bad_levels():
    with pytest.raises(ParameterError, match="levels"):
        perturbation_onset(np.zeros(10), levels=(0.6, 0.5))
