"""The ankle angle's gain against the plate's rotation, pooled over the conditions.

The stiffness is the torque over the angle, so the angle's gain error is the stiffness's. The
angle comes from the ankle's own sensor, an electrogoniometer in paper 000, whose gain is not
steady: paper 000 gives its precision as 2.6 mrad at 0.09 rad (2.9 %), and how the sensor bends
out of its plane changes from step to step. Averaged over a condition's 40-100 trials such
errors still leave a few tenths of a percent in its angle, independently in each condition.

The plate's rotation (the motor angle less the coupler's twist, ``plate_angle`` of
:data:`~.stance.STANCE_CHANNELS`) sees the same perturbation with an encoder's precision. The
ratio of the two over the analysis window, ``g_c = <θ, φ> / <φ, φ>`` of condition ``c``'s
average responses, is the angle's gain there, times whatever truly separates the ankle's angle
from the plate's (a hinge off the ankle's axis, the shank's own motion, an error of the twist).
The conditions' gains spread by their own noise (``v_c``, their variance over the resamples)
and by a real spread between conditions, ``τ²``, estimated with DerSimonian & Laird's moment
estimator (1986, Controlled Clinical Trials 7:177). Each condition's gain is replaced by its
best linear unbiased prediction ``g*_c = ḡ + τ² / (τ² + v_c) (g_c - ḡ)``, ``ḡ`` the mean
weighted by ``1 / (v_c + τ²)``: where the gains differ no more than their noise explains, the
conditions share one; where they differ by more, each keeps nearly its own. The session's own
gain is kept (the ankle's angle is not the plate's); only the noise between conditions is
pooled. The angle's channels are scaled by ``g*_c / g_c``, each resample and subset with its
own ``g_c`` and ``ḡ`` (the weights kept), so the intervals carry what is left of the noise.
What the resamples cannot see is the part of a true difference between conditions that the
pooling took away; with eight conditions ``τ`` is too uncertain to bound it, so the analysis
adds the pooling's whole move of each point's stiffness, damping and slope (and inertia, when
each point has its own) to its interval's half-width (:mod:`.impedance`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["AngleGains", "angle_gains"]

_NOISELESS = 1e-12  # relative variance floor of a gain: noise-free data


@dataclass(frozen=True)
class AngleGains:
    """Each condition's angle gain against the plate, measured and pooled.

    Attributes
    ----------
    measured : ndarray, shape (n_conditions,)
        ``g_c`` of the all-trial averages (NaN where the plate did not move).
    pooled : ndarray, shape (n_conditions,)
        ``g*_c`` (``measured`` where nothing was pooled).
    own_weight : ndarray, shape (n_conditions,)
        ``τ² / (τ² + v_c)``: 1 keeps the condition's own gain, 0 takes the shared one.
    between_sd : float
        ``τ``, the spread of the gains between conditions beyond their noise (NaN where nothing
        was pooled).
    """

    measured: NDArray[np.float64]
    pooled: NDArray[np.float64]
    own_weight: NDArray[np.float64]
    between_sd: float


def angle_gains(
    angle: NDArray[np.float64],
    plate: NDArray[np.float64],
    counts: NDArray[np.int64],
    n_reps: int,
    pool: bool = True,
) -> tuple[AngleGains, NDArray[np.float64]]:
    """The conditions' angle gains, and the factors that pool them.

    Parameters
    ----------
    angle, plate : ndarray, shape (n_conditions, n_rows, n_window)
        The ankle's and the plate's angle (rad) in each condition's stacked averages over the
        analysis window: row 0 over all trials, rows ``1 ... n_reps`` resamples (their spread
        gives ``v_c``), then any others (subsets), each scaled with its own gain.
    counts : ndarray of int, shape (n_conditions,)
        Each condition's perturbed trials. Only conditions of two trials or more, whose gain is
        positive and finite in every row, are pooled; each one's resamples are widened by
        ``n / (n - 1)`` in variance (a resample of ``n`` trials underestimates the spread of
        their mean by that much).
    n_reps : int
        Resamples among the rows.
    pool : bool
        Pool the gains (False: only measure them; the factors are then 1).

    Returns
    -------
    AngleGains
    ndarray, shape (n_conditions, n_rows)
        The factor ``g*_c / g_c`` of each row's angle channels (1 where nothing is pooled).

    Examples
    --------
    Two conditions whose gains differ by no more than their noise share one:

    >>> rng = np.random.default_rng(0)
    >>> plate = np.tile(np.linspace(0.0, 0.035, 50), (2, 41, 1))
    >>> noise = 1 + 0.01 * rng.standard_normal((2, 41, 1))
    >>> noise[:, 0] = [[1.004], [0.996]]
    >>> gains, factor = angle_gains(plate * noise, plate, np.array([40, 40]), 40)
    >>> gains.between_sd, bool(gains.pooled[0] == gains.pooled[1])
    (0.0, True)
    >>> np.round(gains.measured, 3).tolist(), round(float(gains.pooled[0]), 2)
    ([1.004, 0.996], 1.0)
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (angle * plate).sum(axis=-1) / (plate * plate).sum(axis=-1)
    factor = np.ones_like(ratio)
    own = np.ones(len(ratio))
    pooled = ratio[:, 0].copy()
    members = (np.asarray(counts) >= 2) & np.isfinite(ratio).all(axis=1) & (ratio > 0).all(axis=1)
    if not pool or members.sum() < 2 or n_reps < 2:
        return AngleGains(ratio[:, 0], pooled, own, np.nan), factor
    gains = ratio[members]
    k = np.asarray(counts)[members]
    noise = gains[:, 1 : 1 + n_reps].var(axis=1, ddof=1) * k / (k - 1)
    noise = np.maximum(noise, _NOISELESS * gains[:, 0] ** 2)
    weight = 1.0 / noise
    fixed = weight @ gains[:, 0] / weight.sum()
    q = weight @ (gains[:, 0] - fixed) ** 2
    spread = weight.sum() - (weight**2).sum() / weight.sum()
    between = max(0.0, float(q - (len(gains) - 1)) / spread)
    shared = 1.0 / (noise + between)
    centre = shared @ gains / shared.sum()  # ḡ of every row
    own[members] = between / (between + noise)
    star = own[members, None] * gains + (1 - own[members, None]) * centre
    factor[members] = star / gains
    pooled[members] = star[:, 0]
    return AngleGains(ratio[:, 0], pooled, own, float(np.sqrt(between))), factor
