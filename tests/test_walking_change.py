"""The change of the stiffness within each window, from the neighbouring timing points."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from anklelab._student_t import t_quantile
from anklelab.pipelines.walking import WalkingSettings
from anklelab.pipelines.walking.change import change_warning, judge_change, pool_changes
from anklelab.pipelines.walking.results import Estimate, TimingPoint

W = 0.1  # the window, s
N = 41  # trials per point
T = t_quantile(N - 1, 0.975)
DELAYS = (100.0, 225.0, 350.0, 475.0)


def _point(direction, delay_ms, k, se_k, change, se_change, model="linear", n=N):
    """A timing point whose stiffness and window change have these standard errors (no
    intervals with one trial, as the analysis gives)."""
    t = t_quantile(n - 1, 0.975) if n > 1 else np.nan
    nothing = Estimate(1.0, 0.0, (0.5, 1.5))
    return TimingPoint(
        delay_ms=delay_ms, direction=direction, n_perturbed=n, n_unperturbed=100, cop_m=0.05,
        stiffness=Estimate(k, 0.0, (k - t * se_k, k + t * se_k)), damping=nothing,
        inertia=nothing, vaf=nothing, stiffness_model=model,
        stiffness_change=Estimate(change, 0.0, (change - t * se_change, change + t * se_change)),
        stiffness_changes=False,
    )  # fmt: skip


def _session(stiffness, change_error=0.0, se_change=0.05, se_k=10.0):
    """Both directions at :data:`DELAYS` with the stiffness ``stiffness(t)`` (t in s after heel
    contact), read at each window's middle (points without responses), and the window's own
    change off by ``change_error``."""
    points = []
    for direction in ("dorsi", "plantar"):
        for delay in DELAYS:
            t = delay / 1000
            true = (stiffness(t + W) - stiffness(t)) / stiffness(t + W / 2)
            k = stiffness(t + W / 2)
            points.append(_point(direction, delay, k, se_k, true + change_error, se_change))
    return points


def _half(point):
    return np.diff(point.stiffness_change.ci95)[0] / 2


def _half_without_curvature(stiffness, i):
    """The half-width from the neighbours' standard errors alone (point ``i`` of 4)."""
    low, high = max(i - 1, 0), min(i + 1, 3)
    span = (high - low) * 0.125
    k_low, k_high = stiffness(0.15 + 0.125 * low), stiffness(0.15 + 0.125 * high)
    rate = np.log(k_high / k_low) / span
    return T * W * np.cosh(rate * W / 2) / span * np.hypot(10.0 / k_low, 10.0 / k_high)


def test_a_stiffness_growing_in_proportion_gives_its_change_with_the_neighbours_errors():
    """``k = k₀ e^(r t)``: every point's change over the window is ``2 sinh(r W / 2)``, the
    interval ``t × W cosh(r W / 2) / span × sqrt(se₋² / k₋² + se₊² / k₊²)`` (the windows agree
    with it: no spread is added; ln k is straight: the ends add no curvature)."""
    rate = 2.7

    def stiffness(t):
        return 1000.0 * np.exp(rate * t)

    points = _session(stiffness)
    pooled = pool_changes(points, WalkingSettings(), W)
    for i, (before, after) in enumerate(zip(points, pooled, strict=True)):
        assert after.stiffness_change.mean == pytest.approx(2 * np.sinh(rate * W / 2))
        assert _half(after) == pytest.approx(_half_without_curvature(stiffness, i % 4))
        assert after.stiffness_change_in_window == before.stiffness_change
    assert pool_changes(pooled, WalkingSettings(), W) == pooled  # a second pass changes nothing


def test_the_ends_count_the_curvature_their_one_sided_difference_misses():
    """``ln k = ln 1000 + 2 t + 4 t²``: at the first point the parabola's slope is ``2 + 8 t``
    exactly, and the move from the one-sided difference to it is added in quadrature; the
    middle points' central differences get nothing."""

    def stiffness(t):
        return 1000.0 * np.exp(2.0 * t + 4.0 * t**2)

    # windows too imprecise to disagree with the ends' difference: no spread is added
    pooled = pool_changes(_session(stiffness, se_change=0.2), WalkingSettings(), W)
    first = pooled[0]
    one_sided = np.log(stiffness(0.275) / stiffness(0.15)) / 0.125
    assert first.stiffness_change.mean == pytest.approx(2 * np.sinh(one_sided * W / 2))
    move = 2 * np.sinh((2.0 + 8.0 * 0.15) * W / 2) - first.stiffness_change.mean
    expected = np.hypot(_half_without_curvature(stiffness, 0), move)
    assert _half(first) == pytest.approx(expected)
    for i in (1, 2):
        assert _half(pooled[i]) == pytest.approx(_half_without_curvature(stiffness, i))


def test_each_point_is_placed_where_its_stiffness_is_read():
    """Its mean finite onset plus the θ²-weighted time of its window: a point whose onsets were
    20 ms late, or whose perturbation peaks late in the window, moves; the change is taken
    relative to the stiffness at that weighted time."""
    rate = 2.7

    def stiffness(t):
        return 1000.0 * np.exp(rate * t)

    points = _session(stiffness)[:4]
    time = np.arange(100) / 1000.0
    late_angle = np.where(time >= 0.06, 1.0, 0.0)[None, :]  # θ² weighted time 0.0795 s
    moved = [
        dataclasses.replace(
            p,
            onset_ms=np.array([p.delay_ms + (20.0 if i == 2 else 0.0), np.nan]),
            time_s=time,
            angle=late_angle if i == 1 else np.full((1, 100), 1.0),  # middle: 0.0495 s
        )
        for i, p in enumerate(points)
    ]
    pooled = pool_changes(moved, WalkingSettings(), W)
    # point 1 is read at 225 + 79.5 ms; its neighbours at 100 + 49.5 and 370 + 49.5 ms
    span = (0.370 + 0.0495) - (0.100 + 0.0495)
    measured = np.log(points[2].stiffness.mean / points[0].stiffness.mean) / span
    expected = np.exp(measured * (W - 0.0795)) - np.exp(-measured * 0.0795)
    assert pooled[1].stiffness_change.mean == pytest.approx(expected)


def test_the_interval_takes_the_neighbours_degrees_of_freedom():
    """A middle point of 3 trials between points of 41: its change rests on the neighbours, so
    its interval is as wide as with 41 trials of its own, not 3."""

    def stiffness(t):
        return 1000.0 * np.exp(2.7 * t)

    points = _session(stiffness)[:4]
    few = [dataclasses.replace(points[1], n_perturbed=3), *points[2:]]
    pooled = pool_changes([points[0], *few], WalkingSettings(), W)
    assert _half(pooled[1]) == pytest.approx(_half_without_curvature(stiffness, 1))


def test_a_window_that_disagrees_with_its_neighbours_widens_every_interval():
    agree = pool_changes(_session(lambda t: 1000.0 + 2000.0 * t), WalkingSettings(), W)
    off = pool_changes(
        _session(lambda t: 1000.0 + 2000.0 * t, change_error=0.3), WalkingSettings(), W
    )
    for a, b in zip(agree, off, strict=True):
        assert b.stiffness_change.mean == pytest.approx(a.stiffness_change.mean)
        assert _half(b) > 3.0 * _half(a)  # 0.3 of disagreement against standard errors of 0.05


def test_a_lone_timing_point_and_the_window_setting_keep_the_windows_change():
    points = _session(lambda t: 1000.0 + 2000.0 * t)
    lone = [points[0], *points[4:]]  # one dorsiflexion point
    pooled = pool_changes(lone, WalkingSettings(), W)
    assert pooled[0] == lone[0]
    assert all(p.stiffness_change_in_window is not None for p in pooled[1:])
    assert pool_changes(points, WalkingSettings(change_basis="window"), W) == points


def test_the_verdict_and_the_warning_follow_the_neighbours_change():
    """A stiffness rising 3x over the stance, fitted as constant: each window alone reads its
    change low and imprecisely (+15 ± 30 %) and cannot say it, the neighbours (+29 to +31 %)
    say it at every point, with the warning the constant model needs."""

    def stiffness(t):
        return 1000.0 * 3 ** (t / 0.375)

    points = [
        _point("dorsi", d, stiffness(d / 1000 + W / 2), 10.0, 0.15, 0.15, model="constant")
        for d in DELAYS
    ]
    for p in points:
        assert not judge_change(p.stiffness_change, N, True, WalkingSettings())[1]
    for p in pool_changes(points, WalkingSettings(), W):
        assert p.stiffness_changes and p.stiffness_change_verdict == "changes", p.key
        assert p.stiffness_change_probability > 0.95
        (warning,) = p.warnings
        assert warning.startswith(f"{p.key}: the stiffness changes within the 100 ms window by +")


def test_a_window_warning_the_neighbours_overrule_is_removed():
    """A window that read +30 % on a flat stiffness, and warned: the neighbours see no change,
    so the point is no longer said to change, and its warning goes; other warnings stay."""
    points = []
    for d in DELAYS:
        p = _point("dorsi", d, 1000.0, 10.0, 0.3, 0.05, model="constant")
        p = dataclasses.replace(p, stiffness_changes=True, stiffness_change_probability=1.0)
        warned = change_warning(p, 0.2, W)
        assert warned is not None
        points.append(dataclasses.replace(p, warnings=("another doubt", warned)))
    for p in pool_changes(points, WalkingSettings(), W):
        assert not p.stiffness_changes and p.stiffness_change.mean == pytest.approx(0.0)
        assert p.warnings == ("another doubt",)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["dorsi", "plantar"]),
            st.sampled_from(DELAYS),
            st.one_of(st.floats(-2000.0, 5000.0), st.just(np.nan)),  # stiffness
            st.one_of(st.floats(0.0, 500.0), st.just(np.nan)),  # its standard error
            st.floats(-1.0, 1.0),  # the window's change
            st.integers(1, 100),  # trials
        ),
        max_size=8,
        unique_by=lambda row: row[:2],
    )
)
def test_any_set_of_points_pools_without_error_into_valid_verdicts(rows):
    points = [
        _point(direction, delay, k, se, change, 0.05, n=n)
        for direction, delay, k, se, change, n in rows
    ]
    pooled = pool_changes(points, WalkingSettings(), W)
    assert [p.key for p in pooled] == [p.key for p in points]
    for before, p in zip(points, pooled, strict=True):
        assert p.stiffness_change_verdict in ("changes", "constant", "undetermined", None)
        probability = p.stiffness_change_probability
        assert np.isnan(probability) or 0.0 <= probability <= 1.0
        if p.stiffness_changes:  # never said of a stiffness the data leave open
            assert not p.stiffness.poorly_determined
        if p.stiffness_change_in_window is not None:  # replaced: a finite change from positives
            assert np.isfinite(p.stiffness_change.mean)
            assert p.stiffness_change_in_window == before.stiffness_change
