"""Render a virtual spring-damper, and a terrain's slope, to the foot (haptic ankle platform).

Two ways to make the platform feel like K = 50 N·m/rad and B = 5 N·m·s/rad:

- impedance: the motor applies ``-K (theta - theta_eq) - B w`` on top of gravity compensation.
  No force sensing, but the foot also feels the platform's own inertia and friction.
- admittance: the observer's estimate of the user's torque drives a virtual mass-spring-damper
  whose motion the position controller follows (with feed-forward, the estimated torque taken
  off the loop and the observer's lag compensated: ``CapstanSetup.for_rendering()``): the foot
  feels the virtual inertia instead of the platform's, and friction hides behind the loop.

The user pushes with a random voluntary torque; what the foot felt is fitted from the twin's
true platform angle and interaction torque. Then the equilibrium follows the slope of a hilly
virtual terrain walked at 1 m/s. Writes into OUTPUT_DIR (default: a new temporary directory).

Usage: python examples/06_capstan_haptic_rendering.py [OUTPUT_DIR]
"""

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from anklelab.control import TerrainProfile, VirtualEnvironment
from anklelab.experiments import CapstanSetup, render
from anklelab.report import render_figure

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-06-"))
out.mkdir(parents=True, exist_ok=True)

setup = CapstanSetup.for_rendering()  # shipped parameters, the user's foot on, 1 kHz
spring = VirtualEnvironment(stiffness_nm_per_rad=50.0, damping_nms_per_rad=5.0, inertia_kgm2=0.2)
print("rendered: K 50 N·m/rad, B 5 N·m·s/rad (admittance: virtual inertia 0.2 kg·m²)")
for mode in ("impedance", "admittance"):
    result, felt = render(setup, spring, mode=mode, duration_s=20.0, seed=0)
    print(
        f"{mode:10s} felt K {felt.stiffness_nm_per_rad:5.1f} N·m/rad "
        f"({felt.stiffness_error_percent:+.1f} %), B {felt.damping_nms_per_rad:4.2f} N·m·s/rad "
        f"({felt.damping_error_percent:+.1f} %), inertia {felt.inertia_kgm2:.3f} kg·m²"
    )

# A terrain: the equilibrium angle follows the ground's slope under the foot (uphill dorsiflexes).
duration, speed = 20.0, 1.0
hills = TerrainProfile.hills(speed * duration + 1.0, seed=0)
result, felt = render(setup, spring, terrain=hills, walking_speed_m_s=speed, duration_s=duration)
equilibrium = hills.equilibrium(duration, setup.fs, speed)
print(
    f"terrain: slope angles within ±{math.degrees(np.abs(equilibrium).max()):.1f} deg, "
    f"foot's rms deviation from them {math.degrees(felt.equilibrium_rms_error_rad):.2f} deg"
)
render_figure(result, equilibrium, out / "terrain.png", title="admittance rendering over hills")
print(f"figure in {out}")
