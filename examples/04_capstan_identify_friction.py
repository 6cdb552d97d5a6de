"""Identify the capstan pinion's inertia and friction (paper 001, section 3.3 and Table 2).

With the cable disconnected, the motor, gearhead and pinion are spun up and let coast to a stop
(spin-downs, both directions), and driven by an open-loop torque chirp. From those recordings
``FrictionIdentifier`` finds the inertia J, the viscous and Coulomb friction per direction, the
Stribeck velocity and the static friction. Here the capstan twin makes the recordings (its
true values are known); for a real rig, write the same identification directory
(DESIGN.md section 6, docs/guide/capstan.md) from your logs. Writes into OUTPUT_DIR (default: a
new temporary directory).

Usage: python examples/04_capstan_identify_friction.py [OUTPUT_DIR]
"""

import json
import sys
import tempfile
from pathlib import Path

from anklelab.experiments import (
    IdentProtocol,
    read_ident_directory,
    simulate_ident,
    write_ident_directory,
)
from anklelab.ident import FrictionIdentifier
from anklelab.report import friction_figures

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-04-"))
out.mkdir(parents=True, exist_ok=True)

# 1. Record: spin-downs from 15, 30, 45 and 60 rad/s each way and a 20 s torque chirp at
#    1 kHz, as `anklelab simulate capstan-ident --out ident` does. Velocities are encoder
#    differences, torques the commanded motor torque at the pinion.
data = simulate_ident(protocol=IdentProtocol(), seed=0)
ident_dir = write_ident_directory(data, out / "ident")
print(f"{len(data.spindown)} spin-downs and {len(data.chirp)} chirp -> {ident_dir}")

# 2. Identify from the files (`anklelab identify friction ident --out fit`).
data = read_ident_directory(ident_dir)
model = FrictionIdentifier().fit(data)
result = model.to_dict()

# 3. Compare with the twin's truth (absent for real data).
rows = [
    ("inertia J (kg·m²)", result["inertia_kgm2"], data.truth["inertia_kgm2"]),
    *(
        (f"{name} {d} ({unit})", result[key][d], data.truth[key][d])
        for key, name, unit in (
            ("viscous_nms_per_rad", "viscous b", "N·m·s/rad"),
            ("coulomb_nm", "Coulomb Tc", "N·m"),
        )
        for d in ("cw", "ccw")
    ),
    (
        "Stribeck velocity (rad/s)",
        result["stribeck_velocity_rad_s"],
        data.truth["stribeck_velocity_rad_s"],
    ),
    ("static friction Ts (N·m)", result["static_friction_nm"], data.truth["static_friction_nm"]),
]
print(f"{'parameter':28s} {'identified':>11s} {'truth':>11s}  error")
for name, value, truth in rows:
    print(f"{name:28s} {value:11.4g} {truth:11.4g}  {100 * (value - truth) / truth:+.2f} %")
print(
    f"spin-down fit VAF {model.spindown_vaf_percent_:.2f} %, "
    f"model through the chirp VAF {model.chirp_vaf_percent_:.2f} %"
)

# 4. friction.json (DESIGN.md section 6) feeds the controller's friction compensation and the
#    torque observer: `anklelab capstan observe --friction-model fit/friction.json`.
(out / "friction.json").write_text(json.dumps(result, indent=2) + "\n")
figures = friction_figures(model, data, out)
print(f"friction.json and {len(figures)} figures in {out}")
