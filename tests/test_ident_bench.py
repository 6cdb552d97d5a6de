"""Testing-machine stiffness per actuator distance, and interpolation at a lever arm."""

import numpy as np
import pytest

from anklelab.data import BenchTest, Recording
from anklelab.errors import ParameterError
from anklelab.ident import BenchStiffness, bench_stiffness, interpolate_stiffness


def _test(number, distance, stiffness, rng, offset=0.0, noise=0.5):
    x = np.linspace(0.0, 0.015, 500)  # 1.5 cm over the test (paper 000, section 2.3)
    # geometry: angle = x / d, torque = F d  ->  F = k x / d^2
    force = stiffness * x / distance**2 + offset + rng.normal(0, noise, x.size)
    rec = Recording(
        f"b{number}.csv", {"time_s": np.linspace(0, 10, 500), "displacement_m": x, "force_n": force}
    )
    return BenchTest(number, rec, distance)


def test_stiffness_per_distance_with_per_test_offsets():
    rng = np.random.default_rng(0)
    law = {0.06: 1300.0, 0.085: 1137.5, 0.11: 975.0}
    tests = [
        _test(i, d, k, rng, offset=rng.normal(0, 20))
        for i, (d, k) in enumerate(list(law.items()) * 5)
    ]
    rows = bench_stiffness(tests[::-1])
    assert [r.distance_m for r in rows] == [0.06, 0.085, 0.11]
    for row in rows:
        assert row.n_tests == 5
        assert row.stiffness_nm_per_rad == pytest.approx(law[row.distance_m], rel=2e-3)
        assert 0.99 < row.r2 <= 1.0


def test_r2_reflects_noise():
    rng = np.random.default_rng(1)
    clean = bench_stiffness([_test(1, 0.06, 1300.0, rng, noise=1.0)])[0]
    noisy = bench_stiffness([_test(1, 0.06, 1300.0, rng, noise=60.0)])[0]
    assert noisy.r2 < clean.r2


def test_interpolation_and_linear_extrapolation():
    rows = [
        BenchStiffness(0.06, 1300.0, 1.0, 5),
        BenchStiffness(0.085, 1150.0, 1.0, 5),
        BenchStiffness(0.11, 975.0, 1.0, 5),
    ]
    got = interpolate_stiffness(rows, [0.06, 0.0725, 0.0975, 0.05, 0.12])
    assert np.allclose(got, [1300.0, 1225.0, 1062.5, 1360.0, 905.0])
    assert interpolate_stiffness(rows[:1], 0.2) == pytest.approx(1300.0)
    with pytest.raises(ParameterError, match="no bench tests"):
        interpolate_stiffness([], 0.1)
    assert bench_stiffness([]) == []


def test_bad_bench_data():
    rng = np.random.default_rng(2)
    test = _test(1, 0.06, 1300.0, rng)
    with pytest.raises(ParameterError, match="distance_m"):
        bench_stiffness([BenchTest(1, test.recording, -0.06)])
    flat = Recording(
        "f.csv", {"time_s": np.arange(3.0), "displacement_m": np.zeros(3), "force_n": np.ones(3)}
    )
    with pytest.raises(ParameterError, match="no displacement"):
        bench_stiffness([BenchTest(1, flat, 0.06)])
