"""Plan an experiment on the twin: how many perturbed trials per timing point do you need?

Paper 000 collected 100 perturbed trials per timing point and ~400 unperturbed ones: about 800
walking passes. Fewer trials save a subject's time but widen the uncertainty. This script
simulates sessions of increasing size and prints, per size, the stiffness's standard error
(from the bootstrap spread) and the actual error against the twin's truth. Every parameter of
the experiment can be changed the same way (``load_platform("perturberator").replace({...})``).

Usage: python examples/07_how_many_trials.py [OUTPUT_DIR]   (writes nothing; accepted for
uniformity with the other examples)
"""

import numpy as np

from anklelab.experiments import simulate_perturberator
from anklelab.pipelines import WalkingSettings, analyze_walking

FRACTION = 0.6  # bootstrap subsets hold 60 % of the trials (paper 000)

print("perturbed trials   mean standard error   mean |error| vs truth")
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
        # averages of 60 % subsets (without replacement) scatter sqrt((1 - f) / f) times less
        # than the full-sample average does: rescale the bootstrap sd to a standard error
        se.append(np.std(tp.stiffness, ddof=1) * np.sqrt(FRACTION / (1 - FRACTION)))
        truth = session.truth["reference"][tp.direction][f"{tp.delay_ms:g}"]
        error.append(abs(np.mean(tp.stiffness) - truth["stiffness_nm_per_rad"]))
    # each trial is dorsi or plantar at random: about half of per_point in each condition
    print(f"{per_point:10d}          {np.mean(se):10.1f}            {np.mean(error):10.1f}")
