"""Impedance fits over bootstrap repetitions and windows vs one ``np.linalg.lstsq`` per fit.

The data are bootstrap averages shaped like the walking analysis's (100 repetitions, a 125-sample
record, windows of 100, 75 and 125 samples) with a stiffness that rises within the window; both
stiffness models are timed, and the baseline's numbers are checked against ours.
"""

from __future__ import annotations

import numpy as np

from anklelab.ident import fit_impedance
from anklelab.signals import kinematics
from benchmarks._harness import Result, compare

FS = 1000.0
LENGTHS = [100, 75, 125]


def _data(n_reps: int = 100, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(LENGTHS[-1]) / FS
    ramp = np.clip(t / 0.075, 0, 1) * 0.035
    theta = ramp * rng.uniform(0.9, 1.1, (n_reps, 1)) + rng.normal(0, 2e-4, (n_reps, t.size))
    kin = kinematics(theta, FS, 5)
    torque = (300.0 + 1000.0 * t) * kin[:, 0] + 2.25 * kin[:, 1] + 0.02 * kin[:, 2]
    return kin, torque + rng.normal(0, 0.05, torque.shape)


def per_fit_loop(kin: np.ndarray, torque: np.ndarray, linear: bool) -> np.ndarray:
    """Stiffness (at the θ²-weighted time when ``linear``), one least squares per fit."""
    t = np.arange(torque.shape[-1]) / FS
    out = np.empty((len(LENGTHS), len(torque)))
    for w, n in enumerate(LENGTHS):
        for r in range(len(torque)):
            theta = kin[r, 0, :n]
            columns = [theta, kin[r, 1, :n], kin[r, 2, :n]]
            if linear:
                centre = theta**2 @ t[:n] / (theta @ theta)
                columns.append((t[:n] - centre) * theta)
            out[w, r] = np.linalg.lstsq(np.column_stack(columns), torque[r, :n], rcond=None)[0][0]
    return out


def run() -> list[Result]:
    kin, torque = _data()
    results = []
    for model in ("constant", "linear"):
        linear = model == "linear"
        ours = fit_impedance(kin, torque, lengths=LENGTHS, stiffness_model=model, fs=FS)
        assert np.allclose(ours.stiffness, per_fit_loop(kin, torque, linear), rtol=1e-8)
        results.append(
            compare(
                f"impedance fit, {model} k: 100 reps x 3 win",
                lambda m=model: fit_impedance(
                    kin, torque, lengths=LENGTHS, stiffness_model=m, fs=FS
                ),
                lambda lin=linear: per_fit_loop(kin, torque, lin),
                "np.linalg.lstsq per rep and window",
                repeat=5,
            )
        )
    return results
