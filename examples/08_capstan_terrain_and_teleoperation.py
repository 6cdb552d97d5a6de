"""The capstan platform at work: what it can display, a terrain scene, teleoperation with delay.

1. The display envelope at a few frequencies, from the model and found on the twin.
2. The shipped hill-walk scene rendered to a standing person: the error by component and the
   soft patch's felt stiffness and damping.
3. Teleoperation of a remote robot's foot over a network with 200 ms delay and 50 ms jitter:
   wave variables stay stable, the direct scheme does not.

Writes into OUTPUT_DIR (default: a new temporary directory).

Usage: python examples/08_capstan_terrain_and_teleoperation.py [OUTPUT_DIR]
"""

import math
import sys
import tempfile
from pathlib import Path

from anklelab.control.scene import load_scene
from anklelab.experiments.capstan import CapstanSetup
from anklelab.experiments.capstan.config import Channel
from anklelab.experiments.capstan.envelope import check_envelope
from anklelab.experiments.capstan.scene import render_scene
from anklelab.experiments.capstan.teleop import teleoperate
from anklelab.report import envelope_figure, scene_figure

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-08-"))
out.mkdir(parents=True, exist_ok=True)

check = check_envelope(CapstanSetup(feedforward=True), [0.2, 2.0, 10.0], iterations=5)
for f, model, twin, limit in zip(
    check.analytic.frequency_hz,
    check.analytic.amplitude_rad,
    check.simulated_rad,
    check.analytic.limiting,
    strict=True,
):
    print(
        f"envelope at {f:4.1f} Hz: model {math.degrees(model):5.2f} deg ({limit}), "
        f"twin {math.degrees(twin):5.2f} deg"
    )
envelope_figure(check.analytic, check, out / "envelope.png")

scene = load_scene(Path(__file__).resolve().parent / "scenes" / "hill_walk.toml")
result, metrics, profile = render_scene(scene)
print(
    f"{scene.name}: slope {math.degrees(metrics.slope_rms_rad):.2f} deg rms, error "
    f"{math.degrees(metrics.slope_rms_error_rad):.3f} deg rms"
)
for patch in metrics.patches:
    print(
        f"  soft patch: felt {patch.felt_stiffness_nm_per_rad:.1f} N·m/rad "
        f"({patch.stiffness_error_percent:+.1f} %), {patch.felt_damping_nms_per_rad:.2f} "
        f"N·m·s/rad ({patch.damping_error_percent:+.1f} %)"
    )
scene_figure(result, profile, out / "scene.png", title=scene.name)

for scheme in ("wave", "direct"):
    _, m = teleoperate(CapstanSetup(), Channel(scheme, 0.2, 0.05), duration_s=10.0)
    print(
        f"teleoperation, {scheme:6s} at 200 ms: {'stable' if m.stable else 'UNSTABLE'}, angle "
        f"error {math.degrees(m.position_rms_error_rad):.2f} deg rms"
    )
print(f"figures in {out}")
