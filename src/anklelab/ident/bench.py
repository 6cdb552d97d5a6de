"""Testing-machine stiffness of a prosthetic foot (paper 000, section 2.3).

The actuator pushes the foot at a distance ``d`` from the ankle's centre of rotation. With the
setup geometry, a displacement ``x`` is a rotation ``θ = x / d`` and a force ``F`` a torque
``T = F d``; a straight line through torque against angle gives the stiffness at that distance.
The tests at one distance share the slope and each keeps its own offset (a preload or a sensor
zero differs between tests).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError

if TYPE_CHECKING:
    from anklelab.data.session import BenchTest

__all__ = [
    "EXTRAPOLATION_MARGIN_M",
    "BenchStiffness",
    "bench_stiffness",
    "extrapolated",
    "interpolate_stiffness",
]

EXTRAPOLATION_MARGIN_M = 0.005
"""A lever arm more than this beyond the tested distances, m, is :func:`extrapolated` (closer,
the bench line there is as good as a measurement; a walking lever arm itself is known only to
several millimetres, see the walking guide)."""


class BenchStiffness(NamedTuple):
    """Stiffness at one actuator distance.

    Attributes
    ----------
    distance_m : float
        Actuator distance from the centre of rotation, m.
    stiffness_nm_per_rad : float
        Slope of torque against angle, N·m/rad.
    r2 : float
        Coefficient of determination of the fit (offsets removed per test).
    n_tests : int
        Tests pooled at this distance.
    """

    distance_m: float
    stiffness_nm_per_rad: float
    r2: float
    n_tests: int


def _fit_distance(distance: float, tests: Sequence[BenchTest]) -> BenchStiffness:
    angles, torques = [], []
    for test in tests:
        angle = test.recording["displacement_m"] / distance
        torque = test.recording["force_n"] * distance
        angles.append(angle - angle.mean())
        torques.append(torque - torque.mean())
    a, t = np.concatenate(angles), np.concatenate(torques)
    if not np.any(a):
        raise ParameterError(f"bench: tests at distance {distance:g} m have no displacement")
    k = float(a @ t / (a @ a))
    r2 = float(1.0 - np.sum((t - k * a) ** 2) / np.sum(t**2))
    return BenchStiffness(float(distance), k, r2, len(tests))


def bench_stiffness(tests: Sequence[BenchTest], *, decimals: int = 6) -> list[BenchStiffness]:
    """Stiffness per actuator distance from testing-machine tests.

    Parameters
    ----------
    tests : sequence of BenchTest
        Each with a recording holding ``displacement_m`` (m) and ``force_n`` (N), and its
        ``distance_m`` (m, > 0).
    decimals : int
        Distances equal after rounding to this many decimals (of a metre) are pooled.

    Returns
    -------
    list of BenchStiffness
        One per distance, in increasing distance.

    Examples
    --------
    >>> import numpy as np
    >>> from anklelab.data import BenchTest, Recording
    >>> x = np.linspace(0.0, 0.015, 50)
    >>> rec = Recording("b.csv", {"time_s": x, "displacement_m": x, "force_n": 1200 * x / 0.06**2})
    >>> round(bench_stiffness([BenchTest(1, rec, 0.06)])[0].stiffness_nm_per_rad, 9)
    1200.0
    """
    if not tests:
        return []
    distances = np.round([test.distance_m for test in tests], decimals)
    if np.any(distances <= 0):
        raise ParameterError(f"bench: distance_m must be > 0 m, got {distances.min():g}")
    return [
        _fit_distance(float(d), [t for t, dt in zip(tests, distances, strict=True) if dt == d])
        for d in np.unique(distances)
    ]


def interpolate_stiffness(
    rows: Sequence[BenchStiffness], distance_m: ArrayLike
) -> NDArray[np.float64]:
    """Bench stiffness at other distances by piecewise-linear interpolation.

    Beyond the measured distances the nearest segment's line is extended (a single distance
    gives a constant).

    Parameters
    ----------
    rows : sequence of BenchStiffness
        Output of :func:`bench_stiffness`.
    distance_m : array_like
        Where to evaluate (e.g. a timing point's lever arm ``cop_m``), m.

    Returns
    -------
    ndarray
        Stiffness, N·m/rad.

    Examples
    --------
    >>> rows = [BenchStiffness(0.06, 1300.0, 1.0, 5), BenchStiffness(0.11, 975.0, 1.0, 5)]
    >>> interpolate_stiffness(rows, [0.085, 0.12]).round(6).tolist()
    [1137.5, 910.0]
    """
    if not rows:
        raise ParameterError("bench: no bench tests to interpolate")
    d = np.array([row.distance_m for row in rows])
    k = np.array([row.stiffness_nm_per_rad for row in rows])
    x = np.asarray(distance_m, dtype=float)
    if d.size == 1:
        return np.full_like(x, k[0])
    segment = np.clip(np.searchsorted(d, x) - 1, 0, d.size - 2)
    slope = (k[segment + 1] - k[segment]) / (d[segment + 1] - d[segment])
    return k[segment] + slope * (x - d[segment])


def extrapolated(
    rows: Sequence[BenchStiffness], distance_m: float, margin_m: float = EXTRAPOLATION_MARGIN_M
) -> bool:
    """Whether ``distance_m`` lies more than ``margin_m`` outside the tested distances, where
    :func:`interpolate_stiffness` extends the bench line instead of interpolating measurements
    (False without bench tests or with an unknown distance).

    Examples
    --------
    >>> rows = [BenchStiffness(0.06, 1300.0, 1.0, 5), BenchStiffness(0.11, 975.0, 1.0, 5)]
    >>> [extrapolated(rows, d) for d in (0.0599, 0.054, 0.11, 0.12, float("nan"))]
    [False, True, False, True, False]
    """
    tested = [row.distance_m for row in rows]
    if not tested or not np.isfinite(distance_m):
        return False
    return not min(tested) - margin_m <= distance_m <= max(tested) + margin_m
