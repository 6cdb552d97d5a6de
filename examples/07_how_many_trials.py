"""Plan an experiment on the twin: how many perturbed trials per timing point do you need?

Paper 000 collected 100 perturbed trials per timing point and ~400 unperturbed ones: about 800
walking passes. Fewer trials save a subject's time but widen the uncertainty. This script
simulates sessions of increasing size and prints, per size, the half-width of the stiffness's
95 % interval and the actual error against the twin's truth. Every parameter of
the experiment can be changed the same way (``load_platform("perturberator").replace({...})``).

Usage: python examples/07_how_many_trials.py [OUTPUT_DIR]   (writes nothing; accepted for
uniformity with the other examples)
"""

import numpy as np

from anklelab.experiments import simulate_perturberator
from anklelab.pipelines import WalkingSettings, analyze_walking

print("perturbed trials   mean 95 % half-width   mean |error| vs truth")
print("per timing point      (N·m/rad)              (N·m/rad)")
for per_point in (10, 20, 40):
    session = simulate_perturberator(
        trials_per_point=per_point,
        n_unperturbed=2 * per_point,
        n_calibration=2,
        bench=False,
        seed=per_point,
    )
    results = analyze_walking(session, WalkingSettings(bootstrap_reps=40))
    se, error = [], []
    for tp in results.timing_points:
        low, high = tp.stiffness.ci95
        se.append((high - low) / 2)
        truth = session.truth["reference"][tp.direction][f"{tp.delay_ms:g}"]
        error.append(abs(tp.stiffness.mean - truth["stiffness_nm_per_rad"]))
    # each trial is dorsi or plantar at random: about half of per_point in each condition
    print(f"{per_point:10d}          {np.mean(se):10.1f}            {np.mean(error):10.1f}")
