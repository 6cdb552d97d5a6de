"""Ground truth of a session: per condition, what an ideal analysis should report.

DESIGN §5 and the task's definitions. For each perturbed trial the window holds the DAQ samples
from the true onset (the start of the motion plan) for ``window`` seconds; the weights are
``θ²`` with ``θ`` the true perturbation of the ankle angle (the trial minus the same trial
without its perturbation):

- stiffness: ``Σ k θ² / Σ θ²`` (the foot's true ``k(t)``);
- ``cop_m``: ``Σ dx θ² / Σ θ²`` with the nominal lever arm ``dx``;
- ``stiffness_change_fraction``: ``(k(last) - k(first)) / weighted k``;

each then averaged over the trials of the condition (direction and intended delay).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import Config
from validation.cleanroom.protocol import WalkingPlan
from validation.cleanroom.walking import WalkingSimulation

__all__ = ["WINDOWS_MS", "reference_truth", "window_averages"]

Array = NDArray[np.float64]
WINDOWS_MS = (100.0, 75.0, 125.0)
DIRECTION_NAMES = {1.0: "dorsi", -1.0: "plantar"}


def window_averages(
    sim: WalkingSimulation, rows: NDArray[np.int64], window_s: float, fs: float
) -> dict[str, Array]:
    """θ²-weighted stiffness, lever arm and stiffness change of trials ``rows``.

    Parameters
    ----------
    sim : WalkingSimulation
        The simulated trials.
    rows : ndarray of int
        Perturbed trials to evaluate.
    window_s : float
        Window length after the true onset, s.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    dict of str to ndarray
        ``stiffness``, ``cop`` and ``change`` of each trial.
    """
    count = round(window_s * fs)
    first = np.ceil(sim.onset_s[rows] * fs - 1e-9).astype(int)
    index = first[:, None] + np.arange(count)
    pick = rows[:, None]
    weight = sim.perturbation[pick, index] ** 2
    k = sim.stiffness[pick, index]
    total = weight.sum(axis=1)
    stiffness = (k * weight).sum(axis=1) / total
    return {
        "stiffness": stiffness,
        "cop": (sim.lever_arm[pick, index] * weight).sum(axis=1) / total,
        "change": (k[:, -1] - k[:, 0]) / stiffness,
    }


def reference_truth(config: Config, plan: WalkingPlan, sim: WalkingSimulation) -> dict[str, Any]:
    """``truth["reference"]`` and ``truth["trials"]`` of a session (floats and arrays)."""
    fs = config.protocol.sample_rate_hz
    foot = config.foot
    perturbed = np.flatnonzero(plan.perturbed)
    per_window = {w: window_averages(sim, perturbed, w / 1000, fs) for w in WINDOWS_MS}
    main = per_window[100.0]
    reference: dict[str, dict[str, dict[str, float]]] = {}
    for sign, direction in DIRECTION_NAMES.items():
        for delay in config.protocol.timing_points_ms:
            members = (plan.sign[perturbed] == sign) & (plan.delay_ms[perturbed] == delay)
            if not members.any():
                continue
            entry = {
                "stiffness_nm_per_rad": float(np.mean(main["stiffness"][members])),
                "damping_nms_per_rad": float(foot.damping_nms_per_rad),
                "inertia_kgm2": float(foot.inertia_kgm2),
                "cop_m": float(np.mean(main["cop"][members])),
                "stiffness_change_fraction": float(np.mean(main["change"][members])),
                "n_trials": float(members.sum()),
            }
            for window in WINDOWS_MS[1:]:
                value = np.mean(per_window[window]["stiffness"][members])
                entry[f"stiffness_nm_per_rad_{window:g}"] = float(value)
            reference.setdefault(direction, {})[f"{delay:g}"] = entry
    n = plan.n_trials
    per_trial = {name: np.full(n, np.nan) for name in ("stiffness_nm_per_rad", "cop_m")}
    per_trial["stiffness_nm_per_rad"][perturbed] = main["stiffness"]
    per_trial["cop_m"][perturbed] = main["cop"]
    trials = {
        "trial": np.arange(1, n + 1, dtype=float),
        "heel_contact_s": sim.heel_contact_s.copy(),
        "onset_s": sim.onset_s.copy(),
        **per_trial,
    }
    return {"reference": reference, "trials": trials}
