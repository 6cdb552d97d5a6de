"""Platform filters: remove the plate's own forces (paper 000, section 2.2).

When the hinge moves, the top plate's inertia and its tilt in gravity load the force sensors
even with nobody on the plate. Calibration trials (platform moving, plate empty) give causal
filters from the motor angle to each of the eight channels; the walking analysis subtracts their
prediction. Paper 000 drives the filters with the angle's acceleration alone; anklelab uses the
angle and the acceleration by default, because a tilt held still loads the sensors through
gravity, which no acceleration filter can represent.

This script fits both on the twin's calibration trials, scores them on held-out trials, shows
what each predicts during a held tilt, and what the choice does to the stiffness estimate.
Writes into OUTPUT_DIR (default: a new temporary directory).

Usage: python examples/03_platform_filters.py [OUTPUT_DIR]
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from anklelab.experiments import simulate_perturberator
from anklelab.pipelines import WalkingSettings, analyze_walking, fit_platform_filters
from anklelab.report import figure_png, filters_figure

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-03-"))
out.mkdir(parents=True, exist_ok=True)

session = simulate_perturberator(trials_per_point=12, n_unperturbed=24, n_calibration=3, seed=3)

# A held tilt of 0.035 rad, reached by a 75 ms ramp (a calibration move without the return).
fs = session.info.sample_rate_hz
hold = np.minimum(np.arange(600) / (0.075 * fs), 1.0) * 0.035

for inputs in (("angle", "acceleration"), ("acceleration",)):
    settings = WalkingSettings(filter_inputs=inputs, bootstrap_reps=30)
    # fitted on calibration trial 0, scored on trials 1 and 2 (VAF %, all channels pooled)
    filters, vaf, by_channel = fit_platform_filters(session, settings)
    held = filters.predict(hold)[:, -1]  # the eight channels, N, after 0.5 s of hold
    results = analyze_walking(session, settings, filters=filters)
    stiffness = {tp.key: tp.stiffness.mean for tp in results.timing_points}
    print(f"inputs {' + '.join(inputs)}:")
    print(f"  held-out VAF {np.mean(vaf):.2f} % (all channels pooled); per channel:")
    # channels that carry almost nothing but noise (here the lateral fy) score near 0 %
    channels = zip(filters.channels, by_channel.mean(axis=0), strict=True)
    print("  " + ", ".join(f"{name} {value:.1f}" for name, value in channels))
    print(f"  predicted load during the hold: fx12 {held[0]:+.2f} N, fz1 {held[4]:+.2f} N")
    print("  stiffness (N·m/rad): " + ", ".join(f"{k} {v:.0f}" for k, v in stiffness.items()))
    name = "filters_" + "_".join(inputs) + ".png"
    (out / name).write_bytes(figure_png(filters_figure(filters)))

# Filters fitted once can be saved and reused for later sessions of the same platform
# (`anklelab identify platform-filters SESSION --out filters.json`, then
# `anklelab analyze SESSION --filters filters.json`).
path = filters.save(out / "filters.json", calibration_vaf_percent=vaf.tolist())
print(f"filter figures and {path.name} in {out}")
