"""Position control and the torque observer on the capstan platform (paper 001, sections 3.2-3.4).

1. Design critically damped PID gains from the platform model.
2. Set-point steps of 5, 10 and 15 degrees with the user's foot on the platform, with and without
   gravity compensation (paper 001: reached within 300 ms).
3. The paper's chirp: 5 degrees, 0.2 to 5 Hz over 10 s.
4. The disturbance observer: the user's ankle torque from motor current and encoder alone, with
   a friction model identified from a short spin-down/chirp session.
5. A sensor fault: the encoder reading turns NaN; the safety monitor cuts the current.

Writes into OUTPUT_DIR (default: a new temporary directory).

Usage: python examples/05_capstan_control_and_observer.py [OUTPUT_DIR]
"""

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from anklelab.control import Fault, design_critically_damped
from anklelab.experiments import (
    CapstanSetup,
    FaultInjection,
    IdentProtocol,
    chirp_tracking,
    observer_trial,
    simulate_closed_loop,
    simulate_ident,
    step_response,
)
from anklelab.ident import FrictionIdentifier
from anklelab.platforms import load_platform
from anklelab.report import chirp_tracking_figure, observer_figure, step_figure

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="anklelab-05-"))
out.mkdir(parents=True, exist_ok=True)
platform = load_platform("capstan")

# 1. Gains: both closed-loop poles at -5.83 / 0.2 s for the lumped platform (`capstan tune`).
gains = design_critically_damped(platform, settling_time_s=0.2)
print(
    f"Kp {gains.kp_nm_per_rad:.1f} N·m/rad, Kd {gains.kd_nms_per_rad:.2f} N·m·s/rad, "
    f"Ki {gains.ki_nm_per_rad_s:.0f} N·m/(rad·s)"
)

# 2. Steps (`capstan step`), 1 kHz control, the user's relaxed foot on the platform.
for gravity in (True, False):
    setup = CapstanSetup(params=platform, gains=gains, gravity_compensation=gravity)
    runs = [step_response(setup, math.radians(d), hold_s=1.0) for d in (5, 10, 15)]
    print(f"steps, gravity compensation {'on' if gravity else 'off'}:")
    for _, m in runs:
        print(
            f"  {math.degrees(m.amplitude_rad):4.0f} deg: rise {m.rise_time_s * 1e3:4.0f} ms, "
            f"within 5 % after {m.settling_time_5_s * 1e3:4.0f} ms, overshoot "
            f"{m.overshoot_percent:4.1f} %, error {math.degrees(m.steady_state_error_rad):+.3f} deg"
        )
step_figure(runs, out / "steps_without_gravity_compensation.png")

# 3. The chirp (`capstan chirp`).
setup = CapstanSetup(params=platform, gains=gains)
result, chirp = chirp_tracking(setup)
print(
    f"chirp: rms error {math.degrees(chirp.rms_error_rad):.2f} deg "
    f"({math.degrees(chirp.rms_error_to_3hz_rad):.2f} deg below 3 Hz), gain at 3 Hz "
    f"{np.interp(3.0, chirp.frequency_hz, chirp.gain):.2f}, -3 dB bandwidth "
    + (f"{chirp.bandwidth_3db_hz:.1f} Hz" if math.isfinite(chirp.bandwidth_3db_hz) else "> 5 Hz")
)
chirp_tracking_figure(result, chirp, out / "chirp.png")

# 4. The observer needs the pinion's inertia and friction: identify them (example 04) and give
#    the identified model to the controller and the observer (`--friction-model friction.json`).
ident = simulate_ident(protocol=IdentProtocol(speeds_rad_s=(20.0, 40.0), chirp_s=10.0), seed=1)
friction = FrictionIdentifier().fit(ident).to_parameters()
for cutoff in (10.0, 20.0):
    setup = CapstanSetup(
        params=platform, gains=gains, model_friction=friction, observer_cutoff_hz=cutoff
    )
    result, obs = observer_trial(setup, "hold", duration_s=10.0, seed=2)
    print(
        f"observer, Q cut-off {cutoff:g} Hz: VAF {obs.vaf_percent:.1f} %, delay "
        f"{obs.delay_s * 1e3:.0f} ms, VAF with the delay removed "
        f"{obs.vaf_delay_compensated_percent:.1f} %"
    )
observer_figure(result, out / "observer.png", title="estimated vs true ankle torque")

# 5. Fail safe: from t = 0.5 s the encoder reads NaN while the platform holds 10 degrees.
n = round(1.0 * setup.fs)
reference = np.full(n, math.radians(10.0))
fault = FaultInjection("encoder-nan", time_s=0.5)
run = simulate_closed_loop(setup, n, reference=reference, fault=fault)
tripped = int(np.argmax(run["fault"] > 0))
print(
    f"fault {Fault(int(run['fault'][tripped])).name} at {tripped / setup.fs:.3f} s; current "
    f"command after it: {np.abs(run['current_command_a'][tripped:]).max():g} A"
)
print(f"figures in {out}")
