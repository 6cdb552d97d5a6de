"""Derivatives by a local quadratic fit."""

import numpy as np
import pytest
from scipy.signal import savgol_filter

from anklelab.errors import ParameterError
from anklelab.signals import derivative, kinematics

FS = 1000.0
T = np.arange(300) / FS


def test_exact_on_quadratics_including_the_ends():
    x = 0.2 + 1.5 * T - 40.0 * T**2
    assert np.allclose(derivative(x, FS, deriv=1), 1.5 - 80.0 * T)
    assert np.allclose(derivative(x, FS, deriv=2), -80.0)


@pytest.mark.parametrize("window", [5, 11, 21])
def test_sinusoid_derivatives_in_the_interior(window):
    w = 2 * np.pi * 3.0
    x = np.sin(w * T)
    interior = slice(window, -window)
    tol = 1e-3 * window**2  # the quadratic-fit error grows with the window
    assert np.allclose(
        derivative(x, FS, window)[interior], w * np.cos(w * T)[interior], rtol=0, atol=tol * w
    )
    acc = derivative(x, FS, window, deriv=2)[interior]
    assert np.allclose(acc, -(w**2) * np.sin(w * T)[interior], atol=tol * w**2)


def test_kinematics_stacks_angle_velocity_acceleration_before_time():
    x = np.stack([T**2, 2 * T**2])
    kin = kinematics(x, FS)
    assert kin.shape == (2, 3, T.size)
    assert np.array_equal(kin[:, 0], x)
    assert np.allclose(kin[1, 1], 4 * T) and np.allclose(kin[1, 2], 4.0)
    assert np.allclose(kinematics(x.T, FS, axis=0), kin)


@pytest.mark.parametrize("window", [4, 2, 3.5])
def test_bad_window_is_rejected(window):
    with pytest.raises(ParameterError, match="window"):
        derivative(T, FS, window)


@pytest.mark.parametrize(
    ("window", "polyorder", "deriv"), [(5, 2, 0), (5, 2, 1), (5, 2, 2), (7, 3, 1), (11, 4, 3)]
)
def test_equals_scipys_savitzky_golay_filter_ends_included(window, polyorder, deriv):
    x = np.random.default_rng(window).standard_normal((3, 2, 200)).cumsum(axis=-1)
    ours = derivative(np.moveaxis(x, -1, 1), FS, window, deriv=deriv, polyorder=polyorder, axis=1)
    theirs = savgol_filter(x, window, polyorder, deriv=deriv, delta=1 / FS, mode="interp")
    tol = 1e-12 * abs(theirs).max()
    np.testing.assert_allclose(np.moveaxis(ours, 1, -1), theirs, rtol=0, atol=tol)


def test_a_signal_shorter_than_the_window_is_rejected():
    with pytest.raises(ParameterError, match=r"3 samples.*window=5"):
        derivative(T[:3], FS, 5)
