"""The change of the stiffness within each window, from the neighbouring timing points."""

import dataclasses

import numpy as np
import pytest

from anklelab._student_t import t_quantile
from anklelab.pipelines.walking import WalkingSettings
from anklelab.pipelines.walking.change import pool_changes
from anklelab.pipelines.walking.results import Estimate, TimingPoint

W = 0.1  # the window, s
N = 41  # trials per point
T = t_quantile(N - 1, 0.975)


def _point(direction, delay_ms, k, se_k, change, se_change, model="linear"):
    """A timing point whose stiffness and window change have these standard errors."""
    nothing = Estimate(1.0, 0.0, (0.5, 1.5))
    return TimingPoint(
        delay_ms=delay_ms, direction=direction, n_perturbed=N, n_unperturbed=100, cop_m=0.05,
        stiffness=Estimate(k, 0.0, (k - T * se_k, k + T * se_k)), damping=nothing,
        inertia=nothing, vaf=nothing, stiffness_model=model,
        stiffness_change=Estimate(change, 0.0, (change - T * se_change, change + T * se_change)),
        stiffness_changes=False,
    )  # fmt: skip


def _session(stiffness, change_error=0.0, se_change=0.05, se_k=10.0):
    """Both directions at 100, 225, 350 and 475 ms with the stiffness ``stiffness(t)`` (t in s),
    the window's change off by ``change_error``."""
    points = []
    for direction in ("dorsi", "plantar"):
        for delay in (100.0, 225.0, 350.0, 475.0):
            t = delay / 1000
            true = (stiffness(t + W) - stiffness(t)) / stiffness(t + W / 2)
            points.append(
                _point(direction, delay, stiffness(t), se_k, true + change_error, se_change)
            )
    return points


def test_a_stiffness_growing_in_proportion_gives_its_change_with_the_neighbours_errors():
    """``k = k₀ e^(r t)``: every point's change over the window is ``2 sinh(r W / 2)``, the
    interval ``t × W cosh(r W / 2) / span × sqrt(se₋² / k₋² + se₊² / k₊²)`` (the windows agree
    with it: no spread is added; ln k is straight: the ends add no curvature)."""
    rate = 2.7

    def stiffness(t):
        return 1000.0 * np.exp(rate * t)

    points = _session(stiffness)
    pooled = pool_changes(points, WalkingSettings(), W)
    change = 2 * np.sinh(rate * W / 2)
    for i, (before, after) in enumerate(zip(points, pooled, strict=True)):
        assert after.stiffness_change.mean == pytest.approx(change)
        half = _half_without_curvature(stiffness, i % 4)
        assert np.diff(after.stiffness_change.ci95)[0] / 2 == pytest.approx(half)
        assert after.stiffness_change_in_window == before.stiffness_change


def _half_without_curvature(stiffness, i):
    """The half-width from the neighbours' standard errors alone (point ``i`` of 4)."""
    low, high = max(i - 1, 0), min(i + 1, 3)
    span = (high - low) * 0.125
    k_low, k_high = stiffness(0.1 + 0.125 * low), stiffness(0.1 + 0.125 * high)
    rate = np.log(k_high / k_low) / span
    return T * W * np.cosh(rate * W / 2) / span * np.hypot(10.0 / k_low, 10.0 / k_high)


def test_the_ends_count_the_curvature_their_one_sided_difference_misses():
    def stiffness(t):
        return 1000.0 * np.exp(2.0 * t + 4.0 * t**2)

    # windows too imprecise to disagree with the ends' difference: no spread is added
    pooled = pool_changes(_session(stiffness, se_change=0.2), WalkingSettings(), W)
    for i, p in enumerate(pooled[:4]):
        ratio = np.diff(p.stiffness_change.ci95)[0] / 2 / _half_without_curvature(stiffness, i)
        if p.delay_ms in (100.0, 475.0):
            assert ratio > 1.05, p.key
        else:
            assert ratio == pytest.approx(1.0), p.key


def test_a_window_that_disagrees_with_its_neighbours_widens_every_interval():
    agree = pool_changes(_session(lambda t: 1000.0 + 2000.0 * t), WalkingSettings(), W)
    off = pool_changes(
        _session(lambda t: 1000.0 + 2000.0 * t, change_error=0.3), WalkingSettings(), W
    )
    for a, b in zip(agree, off, strict=True):
        assert b.stiffness_change.mean == pytest.approx(a.stiffness_change.mean)
        width = np.diff(b.stiffness_change.ci95)[0] / np.diff(a.stiffness_change.ci95)[0]
        assert width > 3.0  # 0.3 of disagreement against standard errors of 0.05


def test_a_lone_timing_point_and_the_window_setting_keep_the_windows_change():
    points = _session(lambda t: 1000.0 + 2000.0 * t)
    lone = [points[0], *points[4:]]  # one dorsiflexion point
    pooled = pool_changes(lone, WalkingSettings(), W)
    assert pooled[0] == lone[0]
    assert all(p.stiffness_change_in_window is not None for p in pooled[1:])
    assert pool_changes(points, WalkingSettings(change_basis="window"), W) == points


def test_the_verdict_and_the_warning_follow_the_neighbours_change():
    """A stiffness rising 3x over the stance, fitted as constant: each window alone sees its
    change (+29 to +31 %) too imprecisely to say so, the neighbours say it at every point."""

    def stiffness(t):
        return 1000.0 * 3 ** (t / 0.375)

    points = [
        _point("dorsi", d, stiffness(d / 1000), 10.0, 0.3, 0.15, model="constant")
        for d in (100.0, 225.0, 350.0, 475.0)
    ]
    alone = pool_changes(points, WalkingSettings(change_basis="window"), W)
    assert not any(p.warnings for p in alone)
    for p in pool_changes(points, WalkingSettings(), W):
        assert p.stiffness_changes and p.stiffness_change_verdict == "changes", p.key
        assert p.stiffness_change_probability > 0.95
        (warning,) = p.warnings
        assert warning.startswith(f"{p.key}: the stiffness changes within the 100 ms window by +")


def test_the_points_are_placed_at_their_mean_detected_onsets():
    """Onsets detected 20 ms late at one point make its neighbours' span 20 ms shorter; a point
    without detected onsets sits at its manifest delay."""

    def stiffness(t):
        return 1000.0 * np.exp(2.7 * t)

    points = _session(stiffness)[:4]
    late = [
        dataclasses.replace(p, onset_ms=np.array([p.delay_ms + (20.0 if i == 2 else 0.0), np.nan]))
        for i, p in enumerate(points)
    ]
    pooled = pool_changes(late, WalkingSettings(), W)
    rate = np.log(stiffness(0.35) / stiffness(0.1)) / 0.27  # from 100 to 350 + 20 ms
    assert pooled[1].stiffness_change.mean == pytest.approx(2 * np.sinh(rate * W / 2))
    plain = pool_changes(points, WalkingSettings(), W)
    assert plain[1].stiffness_change.mean == pytest.approx(2 * np.sinh(2.7 * W / 2))
