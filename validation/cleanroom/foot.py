"""The foot's impedance laws and the testing-machine (bench) measurements of a prosthetic foot.

The torque of the plate on the foot about the ankle, in response to a perturbation ``θ`` of the
ankle angle, is ``T_p = k(t) θ + b θ' + I θ''`` (paper 000, eq. 2). ``k(t)`` is evaluated on
the trial's *nominal* state (time since heel contact, nominal lever arm ``dx``): the foot is
linearised about the unperturbed step it takes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import HumanAnkle, ProstheticFoot, ProtocolConfig

__all__ = ["bench_tests", "stiffness"]

Array = NDArray[np.float64]


def stiffness(
    foot: ProstheticFoot | HumanAnkle, since_heel_contact_s: Array, lever_arm_m: Array
) -> Array:
    """The foot's stiffness k, N·m/rad, at a time after heel contact and a nominal lever arm.

    Parameters
    ----------
    foot : ProstheticFoot or HumanAnkle
        The foot model.
    since_heel_contact_s : ndarray
        Time after heel contact, s (before heel contact the value at heel contact is used).
    lever_arm_m : ndarray
        Nominal lever arm ``dx`` (COP anterior of the ankle centre), m.

    Examples
    --------
    >>> foot = ProstheticFoot(stiffness_nm_per_rad=(1300.0, 975.0))
    >>> stiffness(foot, np.zeros(3), np.array([0.06, 0.085, 0.11])).tolist()
    [1300.0, 1137.5, 975.0]
    >>> human = HumanAnkle(stiffness_100ms_nm_per_rad=200.0, rise_per_150ms=0.5)
    >>> stiffness(human, np.array([0.1, 0.25]), np.full(2, 0.08)).tolist()
    [200.0, 300.0]
    """
    dx = np.asarray(lever_arm_m, dtype=float)
    if isinstance(foot, ProstheticFoot):
        (d0, d1), (k0, k1) = foot.lever_arms_m, foot.stiffness_nm_per_rad
        d = np.clip(dx, *foot.lever_arm_range_m)
        return np.maximum(k0 + (k1 - k0) * (d - d0) / (d1 - d0), foot.min_fraction * k0)
    tau = np.maximum(np.asarray(since_heel_contact_s, dtype=float), 0.0)
    rise = (1 + foot.rise_per_150ms) ** ((tau - 0.1) / 0.15)
    lever = np.maximum(
        foot.min_factor, 1 + foot.lever_arm_slope_per_m * (dx - foot.lever_arm_ref_m)
    )
    return foot.stiffness_100ms_nm_per_rad * rise * lever


def bench_tests(
    foot: ProstheticFoot,
    protocol: ProtocolConfig,
    force_noise_n: float,
    rng: np.random.Generator,
) -> list[tuple[float, Array, Array, Array]]:
    """Testing-machine pushes at each of ``protocol.bench_distances_m`` (paper 000 §2.3).

    The actuator pushes the foot ``bench_displacement_m`` over ``bench_duration_s`` at distance
    ``d`` from the ankle's centre of rotation. With the small-angle conversion ``θ = x / d``,
    ``T = F d`` the foot's stiffness gives ``F = k(d) x / d²``; a cubic deviation orthogonal to
    that line (``bench_nonlinearity`` of the largest force) and white load-cell noise make the
    regression imperfect without biasing its slope.

    Returns
    -------
    list of (distance_m, time_s, displacement_m, force_n)
        One entry per test, distances in order, ``bench_tests_per_distance`` tests each.
    """
    n = round(protocol.bench_duration_s * protocol.sample_rate_hz) + 1
    time = np.arange(n) / protocol.sample_rate_hz
    displacement = protocol.bench_displacement_m * time / time[-1]
    u = 2 * displacement / protocol.bench_displacement_m - 1
    line = np.stack([np.ones(n), u])
    cubic = (5 * u**3 - 3 * u) / 2
    cubic -= line.T @ np.linalg.lstsq(line.T, cubic, rcond=None)[0]
    cubic /= np.max(np.abs(cubic))
    tests = []
    for distance in protocol.bench_distances_m:
        k = float(stiffness(foot, np.zeros(1), np.array([distance]))[0])
        force_line = k * displacement / distance**2
        for _ in range(protocol.bench_tests_per_distance):
            deviation = foot.bench_nonlinearity * force_line[-1] * cubic
            noise = force_noise_n * rng.standard_normal(n)
            tests.append((distance, time, displacement, force_line + deviation + noise))
    return tests
