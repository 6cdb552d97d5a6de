"""Perturberator twin on a calibration trial: compiled kernel vs a straightforward SciPy loop.

The task is the first 2 s of a calibration trial (empty plate, a ramp-and-hold move through the
step/direction motion plan). Ours is :func:`anklelab.sim.drivetrain.simulate_platform` (numba).
The baseline writes the same model the way one would without a compiler: the drive's cascade
in Python at its 8/16 kHz rates, the plant (current lag, motor + gearhead, compliant coupler,
hinge with the plate, friction, gravity) integrated by ``scipy.integrate.solve_ivp`` over every
velocity-loop period, the top plate's inertial and tilt loads computed at each position-loop
tick and the plate's modes and anti-alias filter applied with ``scipy.signal.sosfilt``. Both
results are checked to agree before timing. A 20 s trial takes ten times as long for both.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import signal
from scipy.integrate import solve_ivp

from anklelab.control.motion_plan import StepDirectionPlan
from anklelab.control.perturbation import RampHold
from anklelab.iir import butterworth_sos, resonance_sos
from anklelab.platforms import load_platform
from anklelab.sim import _kernels as K
from anklelab.sim.artefacts import Artefacts
from anklelab.sim.drivetrain import platform_constants, simulate_platform
from benchmarks._harness import Result, best_time

DURATION_S = 2.0
ART = Artefacts(noise=False, drift=False)


def _reference(params) -> np.ndarray:
    plan = StepDirectionPlan.from_params(params)
    move = RampHold(0.035, ramp_s=0.075, hold_s=0.1, return_s=0.075)
    times = plan.update_times(DURATION_S)
    planned = move.sequence(times, [0.5, 1.2], [1.0, -1.0])[None]
    loop = params.servo.position_loop_rate_hz
    return plan.reference(planned, loop, int(DURATION_S * loop))


def _ours(params, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    run = simulate_platform(params, ref, artefacts=ART)
    return run.motor_angle[0], run.wrench[0, 0]


def _scipy(params, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Baseline: controller in Python, plant by solve_ivp over each velocity-loop period."""
    pc = platform_constants(params, hinge_height_m=params.geometry.ankle_height_m)
    dt = pc[K.DT]
    fp = params.force_plate
    r_x = -pc[K.X_H]
    r_z = fp.top_plate_com_z_m - (fp.az0_m - pc[K.H_H])

    def rhs(_t: float, x: np.ndarray, tau_cmd: float) -> list[float]:
        tau, thm, wm, thh, wh = x
        ts = pc[K.K_S] * (thm - thh) + pc[K.C_S] * (wm - wh)
        friction = pc[K.B_M] * wm + pc[K.T_COUL] * math.tanh(wm / pc[K.W_EPS])
        hinge = ts - pc[K.B_H] * wh - pc[K.K_G] * math.sin(thh)
        return [(tau_cmd - tau) * pc[K.INV_TC], wm, (tau - ts - friction) / pc[K.J_M], wh,
                hinge / pc[K.J_H]]  # fmt: skip

    n_steps = 2 * ref.shape[1]
    x = np.zeros(5)
    motor = np.empty(n_steps // 16)
    fx = np.empty(n_steps // 2)
    integ = vcmd = tau_next = enc_prev = 0.0
    for j in range(n_steps):
        enc = math.floor(x[1] / pc[K.ENC_Q] + 0.5) * pc[K.ENC_Q]
        if j % 2 == 0:
            vcmd = pc[K.KPP] * (ref[0, j // 2] - enc)
        vel = (enc - enc_prev) / dt if j else 0.0
        enc_prev = enc
        err = vcmd - vel
        raw = pc[K.KVP] * (err + integ)
        if abs(raw) < pc[K.TAU_MAX] or raw * err < 0:
            integ += pc[K.WI] * err * dt
        tau_cmd, tau_next = tau_next, min(max(raw, -pc[K.TAU_MAX]), pc[K.TAU_MAX])
        if j % 2 == 0:  # the top plate's load on the sensors at each position-loop tick
            ah = rhs(0.0, x, tau_cmd)[4]
            fx[j // 2] = fp.top_plate_mass_kg * (
                -9.81 * math.sin(x[3]) - (ah * r_z - x[4] ** 2 * r_x)
            )
        if j % 16 == 0:
            motor[j // 16] = x[1]
        x = solve_ivp(rhs, (0.0, dt), x, args=(tau_cmd,), method="RK45", rtol=1e-8,
                      atol=1e-12).y[:, -1]  # fmt: skip
    fs = params.servo.position_loop_rate_hz
    fx = signal.sosfilt(resonance_sos(fp.horizontal_natural_frequency_hz, fp.damping_ratio, fs), fx)
    fx = signal.sosfilt(
        butterworth_sos(params.daq.anti_alias_order, params.daq.anti_alias_hz, fs), fx
    )
    return motor, fx[::8]


def run() -> list[Result]:
    params = load_platform("perturberator")
    ref = _reference(params)
    ours_s = best_time(lambda: _ours(params, ref), repeat=3)
    motor, fx = _ours(params, ref)
    start = time.perf_counter()  # the baseline is slow and deterministic: one timed run
    base_motor, base_fx = _scipy(params, ref)
    base_s = time.perf_counter() - start
    assert np.abs(motor - base_motor).max() < 1e-3 * 0.035, "baseline and twin disagree (angle)"
    assert np.abs(fx - base_fx).max() < 0.02 * np.abs(fx).max(), "baseline and twin disagree (Fx)"
    return [
        Result(
            f"twin: {DURATION_S:g} s of a calibration trial (32k steps)",
            ours_s,
            base_s,
            "Python drive + solve_ivp per 16 kHz step",
        )
    ]


if __name__ == "__main__":
    from benchmarks._harness import report

    report(run())
