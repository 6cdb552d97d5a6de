"""Paper 001's friction and inertia identification tests, run on the capstan twin.

The data they produce and its directory format live in :mod:`anklelab.data.capstan_ident`.

:func:`simulate_ident` runs paper 001's two tests on the twin with the cable disconnected: for
each of four speeds in each direction, a speed-controlled ramp from rest (which breaks the shaft
away), a hold, then the current is cut and the shaft coasts to a stop; and an open-loop torque
chirp of rising frequency and amplitude. Velocities are what an encoder gives: whole counts of
the motor encoder, differenced at the sample rate; torques are the commanded motor torque at the
pinion, while the real torque also carries the drive's current-sensor noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from anklelab.control.pid import PIDGains
from anklelab.control.safety import SafetyLimits
from anklelab.data.capstan_ident import IdentData, IdentRun
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters

__all__ = ["IdentProtocol", "friction_truth", "simulate_ident"]


def friction_truth(params: CapstanParameters) -> dict[str, Any]:
    """The twin's pinion-shaft values, keyed like ``friction.json``."""
    f = params.friction
    return {
        "inertia_kgm2": f.inertia_kgm2,
        "viscous_nms_per_rad": {"cw": f.viscous_cw_nms_per_rad, "ccw": f.viscous_ccw_nms_per_rad},
        "coulomb_nm": {"cw": f.coulomb_cw_nm, "ccw": f.coulomb_ccw_nm},
        "stribeck_velocity_rad_s": f.stribeck_velocity_rad_s,
        "static_friction_nm": f.static_friction_nm,
        "stribeck_exponent": f.stribeck_exponent,
    }


@dataclass(frozen=True)
class IdentProtocol:
    """The identification tests (pinion speeds in rad/s, torques in N·m).

    Attributes
    ----------
    sample_rate_hz : float
        Sampling and control rate.
    speeds_rad_s : tuple of float
        Spin-down start speeds, run in both directions.
    ramp_s, hold_s, coast_s : float
        Speed ramp from rest, hold, and coast after the cut.
    chirp_s : float
        Chirp length.
    chirp_hz : (float, float)
        Start and end frequency (linear sweep).
    chirp_torque_nm : (float, float)
        Start and end amplitude (linear ramp).
    """

    sample_rate_hz: float = 1000.0
    speeds_rad_s: tuple[float, ...] = (15.0, 30.0, 45.0, 60.0)
    ramp_s: float = 0.5
    hold_s: float = 0.5
    coast_s: float = 2.0
    chirp_s: float = 20.0
    chirp_hz: tuple[float, float] = (0.5, 5.0)
    chirp_torque_nm: tuple[float, float] = (0.03, 0.3)
    gains: PIDGains = field(
        default_factory=lambda: PIDGains(
            kp_nm_per_rad=270.0,
            ki_nm_per_rad_s=500.0,
            kd_nms_per_rad=18.0,
            integral_error_limit_rad=0.05,
            velocity_filter_hz=100.0,
        )
    )

    def __post_init__(self) -> None:
        checks = {
            "sample_rate_hz": (self.sample_rate_hz, 100.0, 20000.0),
            "ramp_s": (self.ramp_s, 0.01, 60.0),
            "hold_s": (self.hold_s, 0.0, 60.0),
            "coast_s": (self.coast_s, 0.1, 60.0),
            "chirp_s": (self.chirp_s, 0.1, 600.0),
        }
        for name, (value, low, high) in checks.items():
            if not (math.isfinite(value) and low <= value <= high):
                raise ParameterError(
                    f"identification protocol: {name} must be a finite number in "
                    f"[{low:g}, {high:g}]; got {value!r}"
                )
        speeds = self.speeds_rad_s
        if not speeds or not all(math.isfinite(v) and 0 < v <= 100 for v in speeds):
            raise ParameterError(
                f"identification protocol: speeds_rad_s must be finite in (0, 100]; got {speeds}"
            )


def _rig(params: CapstanParameters, protocol: IdentProtocol) -> CapstanSetup:
    """The motor, gearhead and pinion alone under speed control (angles referred / r_c)."""
    rc = params.capstan.ratio
    wide = 1e6
    limits = SafetyLimits(
        position_min=-wide,
        position_max=wide,
        velocity_max=100.0 / rc,
        output_max=params.drive.current_limit_a,
        output_trip=params.safety.current_trip_a,
        sensor_min=-wide,
        sensor_max=wide,
    )
    return CapstanSetup(
        params=params,
        gains=protocol.gains,
        fs=protocol.sample_rate_hz,
        with_user=False,
        gravity_compensation=False,
        coupled=False,
        safety=limits,
    )


def _measured(result: Any, params: CapstanParameters, name: str) -> IdentRun:
    fs = result.fs
    angle = result["measured_pinion_angle_rad"]
    velocity = np.concatenate([[0.0], np.diff(angle) * fs])
    torque = (
        result["current_command_a"] * params.motor.torque_constant_nm_per_a * params.gearhead.ratio
    )
    return IdentRun(name, result.time_s, velocity, torque)


def simulate_ident(
    params: CapstanParameters | None = None,
    protocol: IdentProtocol | None = None,
    *,
    seed: int | np.random.Generator = 0,
) -> IdentData:
    """Run the spin-down and chirp tests on the twin (see the module docstring).

    Examples
    --------
    >>> data = simulate_ident(protocol=IdentProtocol(speeds_rad_s=(20.0,), chirp_s=2.0))
    >>> [run.name for run in data.spindown], data.chirp[0].name
    (['cw_20.csv', 'ccw_20.csv'], 'chirp.csv')
    """
    params = load_platform("capstan") if params is None else params
    protocol = IdentProtocol() if protocol is None else protocol
    rng = np.random.default_rng(seed)
    setup = _rig(params, protocol)
    fs, rc = protocol.sample_rate_hz, params.capstan.ratio
    spindown = []
    for speed in protocol.speeds_rad_s:
        for sign, label in ((1.0, "cw"), (-1.0, "ccw")):
            t = np.arange(round((protocol.ramp_s + protocol.hold_s + protocol.coast_s) * fs)) / fs
            ramp = np.clip(t / protocol.ramp_s, 0.0, 1.0)
            # smooth ramp (raised cosine) of the speed; the reference angle is its integral
            profile = 0.5 * (1 - np.cos(np.pi * ramp))
            w_ref = sign * speed * profile / rc
            angle_ref = np.cumsum(w_ref) / fs
            driven = t < protocol.ramp_s + protocol.hold_s  # then the current is cut: it coasts
            # the shaft rests anywhere within an encoder count
            offset = rng.uniform(0.0, params.encoder.resolution_rad / params.gearhead.ratio) / rc
            result = simulate_closed_loop(
                setup,
                t.size,
                reference=angle_ref + offset,
                reference_speed=w_ref,
                enabled=driven,
                angle0=offset,
                seed=rng,
            )
            spindown.append(_measured(result, params, f"{label}_{speed:g}.csv"))
    n = round(protocol.chirp_s * fs)
    t = np.arange(n) / fs
    (f0, f1), (a0, a1) = protocol.chirp_hz, protocol.chirp_torque_nm
    phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / protocol.chirp_s * t**2)
    torque = (a0 + (a1 - a0) * t / protocol.chirp_s) * np.sin(phase)
    current = torque / (params.motor.torque_constant_nm_per_a * params.gearhead.ratio)
    offset = rng.uniform(0.0, params.encoder.resolution_rad / params.gearhead.ratio) / rc
    result = simulate_closed_loop(
        setup, n, mode="open-loop", command=current, angle0=offset, seed=rng
    )
    chirp = _measured(result, params, "chirp.csv")
    return IdentData(fs, tuple(spindown), (chirp,), friction_truth(params))
