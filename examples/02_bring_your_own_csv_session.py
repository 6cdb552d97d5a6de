"""Bring your own lab data: write a CSV session directory, validate it, import it, analyse it.

anklelab reads an experiment as a directory of CSV files (docs/guide/own-data.md). This script
writes one the way a lab's export script would, with nothing but the csv module:

    my_lab_session/
      session.toml              sample rate, force-plate geometry and mounting, subject geometry
      calibration/*.csv         platform moving, nobody on it
      walking/trials.csv        one row per walking trial: file, perturbed, direction, delay_ms
      walking/<file>.csv        one file per walking trial
      bench/tests.csv           one row per testing-machine test: file, distance_m
      bench/<file>.csv          one file per bench test

The signals come from the digital twin, standing in for your acquisition system: replace
``acquired()`` with your own reader. The script then does what ``anklelab session info``,
``anklelab import`` and ``anklelab analyze`` do, through the Python API, and shows what an error
in a file looks like. Writes into OUTPUT_DIR (default: a new temporary directory).

Usage: python examples/02_bring_your_own_csv_session.py [OUTPUT_DIR]
"""

import csv
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from anklelab.data import load_session, save_session
from anklelab.errors import SessionFormatError
from anklelab.experiments import simulate_perturberator
from anklelab.pipelines import WalkingSettings, analyze_walking

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-02-"))
out.mkdir(parents=True, exist_ok=True)


def acquired():
    """Stand-in for the lab's recordings: a small session from the twin (truth discarded)."""
    return simulate_perturberator(trials_per_point=16, n_unperturbed=40, n_calibration=2, seed=2)


def write_csv(path, columns):
    """One recording: a header line naming the columns, then one row per sample."""
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        writer.writerows(np.column_stack(list(columns.values())).tolist())


lab = acquired()
root = out / "my_lab_session"
for folder in ("calibration", "walking", "bench"):
    (root / folder).mkdir(parents=True, exist_ok=True)

# session.toml: the plate's sensor offsets and mounting come from its data sheet and the lab's
# installation; the ankle height and heel-to-ankle distance are measured on the subject.
plate = lab.info.force_plate
(root / "session.toml").write_text(
    f"""format = "anklelab-session/1"
platform = "perturberator"
sample_rate_hz = {lab.info.sample_rate_hz}
subject = "S01"

[force_plate]
a_m = {plate.a_m}
b_m = {plate.b_m}
az0_m = {plate.az0_m}
anterior_axis = "{plate.anterior_axis}"

[geometry]
ankle_height_m = {lab.info.ankle_height_m}
heel_to_ankle_m = {lab.info.heel_to_ankle_m}
"""
)

# Calibration: columns time_s, motor_angle, fx12, fx34, fy14, fy23, fz1, fz2, fz3, fz4.
for number, recording in enumerate(lab.calibration, start=1):
    write_csv(root / "calibration" / f"calibration_{number:02d}.csv", recording.columns)

# Walking: one file per trial (time_s, motor_angle, ankle_angle and the eight channels) and a
# manifest row per trial. The trial label is any text unique in the session (here the twin's
# numbers, but "d060_1" or "S03_T012" work as well). delay_ms is the intended timing point,
# empty when unperturbed; heel contact and the true onset are detected from the data.
with open(root / "walking" / "trials.csv", "w", newline="") as f:
    manifest = csv.writer(f)
    manifest.writerow(["trial", "file", "perturbed", "direction", "delay_ms"])
    for number, trial in enumerate(lab.walking, start=1):
        name = f"trial_{number:04d}.csv"
        write_csv(root / "walking" / name, trial.recording.columns)
        delay = "" if not trial.perturbed else f"{trial.delay_ms:g}"
        manifest.writerow([trial.trial, name, int(trial.perturbed), trial.direction, delay])

# Bench: displacement (m) and force (N) of the testing machine at a distance along the foot.
with open(root / "bench" / "tests.csv", "w", newline="") as f:
    manifest = csv.writer(f)
    manifest.writerow(["test", "file", "distance_m"])
    for number, test in enumerate(lab.bench, start=1):
        name = f"bench_{number:02d}.csv"
        write_csv(root / "bench" / name, test.recording.columns)
        manifest.writerow([test.test, name, test.distance_m])

print(f"wrote {root}")

# `anklelab session info my_lab_session`: read and validate everything.
session = load_session(root)
print(
    f"valid session: {len(session.calibration)} calibration, {len(session.walking)} walking, "
    f"{len(session.bench)} bench recordings; sha256 {session.provenance['source_sha256'][:12]}"
)

# `anklelab import my_lab_session --out my_lab_session.h5`: one native file, written atomically.
h5 = save_session(session, out / "my_lab_session.h5")
print(f"imported -> {h5}")

# `anklelab analyze my_lab_session.h5 --out results`.
results = analyze_walking(session, WalkingSettings(bootstrap_reps=30))
(out / "results.json").write_text(json.dumps(results.to_dict(session=h5.name), indent=2))
for tp in results.timing_points:
    print(
        f"{tp.key:12s} n = {tp.n_perturbed:2d}  lever arm {tp.cop_m * 100:5.2f} cm  "
        f"k = {tp.stiffness.mean:5.0f} N·m/rad  I = {tp.inertia.mean:.3f} kg·m²"
    )
dropped = [reasons for reasons in results.stance.drop_log if reasons]
print(f"{len(dropped)} of {len(session.walking)} walking trials dropped")

# A broken copy: an empty cell in one walking recording. The error names file, column and line.
broken = shutil.copytree(root, out / "broken_session", dirs_exist_ok=True)
bad = broken / "walking" / "trial_0003.csv"
lines = bad.read_text().splitlines()
fields = lines[10].split(",")
fields[2] = ""  # ankle_angle of the 10th sample: line 11 of the file (line 1 is the header)
lines[10] = ",".join(fields)
bad.write_text("\n".join(lines) + "\n")
try:
    load_session(broken)
except SessionFormatError as error:
    print(f"error: {error}")
