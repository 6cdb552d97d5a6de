"""Capstan twin in closed loop: compiled loop vs real time and vs a straightforward SciPy loop.

The task is paper 001's chirp (5 deg, 0.2 to 5 Hz) tracked by the PID with gravity
feed-forward, user on the platform. The SciPy baseline integrates the same plant (drive current
loop, motor, pinion with friction smoothed by ``tanh``, two-strand cable, platform, foot) with
``solve_ivp`` over every control period and runs the controller in Python, as one would write it
without a compiler.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from anklelab.control.pid import control_constants
from anklelab.experiments.capstan import CapstanSetup, chirp_reference, simulate_closed_loop
from anklelab.sim.capstan import CapstanTwin
from benchmarks._harness import Result, best_time, compare


def _ours(setup: CapstanSetup, reference: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    ref, speed = reference
    run = simulate_closed_loop(setup, ref.size, reference=ref, reference_speed=speed)
    return run["angle_rad"]


def _chirp(fs: float, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The reference (an input of the simulation, made once outside the timing)."""
    return chirp_reference(math.radians(5), 0.2, 5.0, duration_s, fs)[:2]


def _scipy(setup: CapstanSetup, reference: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Baseline: controller in Python, plant by solve_ivp over each control period."""
    twin = CapstanTwin(setup.params, setup.params.user)
    c, f = twin.constants, setup.params.friction
    k = control_constants(setup.params, setup.resolved_gains(), setup.fs)
    rc = c.pulley_radius / c.pinion_radius
    res = setup.params.encoder.resolution_rad
    dt = 1.0 / setup.fs

    def rhs(_t: float, x: np.ndarray, i_cmd: float) -> list[float]:
        i, qp, wp, q, w = x
        emf = c.back_emf * c.gear_ratio * wp
        v = c.resistance * i + c.inductance * c.current_bandwidth * (i_cmd - i) + emf
        v = min(max(v, -c.supply_voltage), c.supply_voltage)
        stretch = c.pinion_radius * qp - c.pulley_radius * q
        rate = 0.5 * c.cable_damping * (c.pinion_radius * wp - c.pulley_radius * w)
        diff = max(c.preload + c.k_cable * stretch + rate, 0.0) - max(
            c.preload - c.k_spring_strand * stretch - rate, 0.0
        )
        tc = f.coulomb_cw_nm if wp > 0 else f.coulomb_ccw_nm
        b = f.viscous_cw_nms_per_rad if wp > 0 else f.viscous_ccw_nms_per_rad
        stribeck = (f.static_friction_nm - tc) * math.exp(-((wp / f.stribeck_velocity_rad_s) ** 2))
        friction = math.tanh(wp / 0.01) * (tc + stribeck) + b * wp
        motor = c.gear_ratio * c.torque_constant * i
        ankle = -c.ankle_stiffness * q - c.ankle_damping * w
        plat = c.pulley_radius * diff - c.gravity_torque * math.sin(q + c.com_angle) + ankle
        return [
            (v - c.resistance * i - emf) / c.inductance,
            wp,
            (motor - c.pinion_radius * diff - friction) / c.pinion_inertia,
            w,
            plat / c.platform_inertia,
        ]

    ref, speed = reference
    x = twin.rest_state(0.0)
    integral, last, velocity = 0.0, 0.0, 0.0
    alpha = k.velocity_alpha
    angles = np.empty(ref.size)
    for n in range(ref.size):
        angle = math.floor(c.gear_ratio * x[1] / res) * res / c.gear_ratio / rc
        if n:
            velocity += alpha * ((angle - last) / dt - velocity)
        last = angle
        error = ref[n] - angle
        integral += min(max(error, -k.error_limit), k.error_limit) * dt
        torque = k.kp * error + k.kd * (speed[n] - velocity) + k.ki * integral
        torque += k.gravity_torque * math.sin(angle + k.com_angle)
        limit = c.current_limit
        current = min(max(torque / k.torque_per_amp, -limit), limit)
        x = solve_ivp(rhs, (0.0, dt), x, args=(current,), rtol=1e-6, atol=1e-9).y[:, -1]
        angles[n] = x[3]
    return angles


def _scene() -> float:
    """Render the shipped hill walk; returns the simulated time, s."""
    from anklelab.control.scene import load_scene
    from anklelab.experiments.capstan.scene import render_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "examples/scenes/hill_walk.toml")
    result, _, _ = render_scene(scene)
    return result.n_samples / result.fs


def _envelope_command() -> None:
    """The whole command as a user runs it, in a fresh process."""
    subprocess.run(
        [str(Path(sys.executable).with_name("anklelab")), "capstan", "envelope", "--points", "13"],
        check=True,
        capture_output=True,
    )


def _envelope_trial_seconds() -> float:
    """Simulated seconds of the envelope command's trials (counted, not timed)."""
    from anklelab.experiments.capstan import CapstanSetup as Setup
    from anklelab.experiments.capstan import envelope as module

    total = 0.0
    original = module.sine_trial

    def counting(setup: Setup, frequency_hz: float, amplitude_rad: float, **kw: object) -> str:
        nonlocal total
        period = 1.0 / frequency_hz
        total += 2 * max(period, 0.5) + max(2 * period, 1.0)
        return original(setup, frequency_hz, amplitude_rad, **kw)  # type: ignore[arg-type]

    module.sine_trial = counting  # type: ignore[assignment]
    try:
        module.check_envelope(Setup(feedforward=True), np.geomspace(0.1, 20.0, 13))
    finally:
        module.sine_trial = original
    return total


def run() -> list[Result]:
    rows = []
    for fs in (1000.0, 10000.0):
        setup, reference = CapstanSetup(fs=fs), _chirp(fs, 10.0)
        seconds = best_time(lambda s=setup, r=reference: _ours(s, r), repeat=9)
        rows.append(
            Result(f"capstan: 10 s closed loop at {fs / 1000:g} kHz", seconds, 10.0, "real time")
        )
    setup, reference = CapstanSetup(fs=1000.0), _chirp(1000.0, 2.0)
    rows.append(
        compare(
            "capstan: 2 s closed loop at 1 kHz",
            lambda: _ours(setup, reference),
            lambda: _scipy(setup, reference),
            "solve_ivp per control period",
            repeat=1,
        )
    )
    simulated = _scene()
    rows.append(
        Result("capstan: hill-walk scene", best_time(_scene, repeat=3), simulated, "real time")
    )
    from anklelab.experiments.capstan.config import Channel
    from anklelab.experiments.capstan.teleop import teleoperate

    rows.append(
        Result(
            "capstan: 20 s teleoperation, 200 ms",
            best_time(lambda: teleoperate(setup, Channel("wave", 0.2, 0.05)), repeat=3),
            20.0,
            "real time",
        )
    )
    # 13 frequencies x (bracketing + 8 bisection steps) sinusoid trials; baseline: the same
    # trials' simulated time in real time
    rows.append(
        Result(
            "capstan: `capstan envelope` command",
            best_time(_envelope_command, repeat=1),
            _envelope_trial_seconds(),
            "its trials in real time",
        )
    )
    gap = np.max(np.abs(_ours(setup, reference) - _scipy(setup, reference)))
    assert gap < math.radians(0.5), f"baseline and twin disagree by {math.degrees(gap):.2f} deg"
    return rows


if __name__ == "__main__":
    from benchmarks._harness import report

    report(run())
