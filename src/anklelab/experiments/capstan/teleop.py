"""Teleoperation on the twin: a remote robot walks over hilly ground; its foot's pitch and its
ground contact reach the platform over a delayed (and jittery) network, and the person's foot
drives the robot's foot back. The person also pushes (a random voluntary torque).

Position tracking compares the platform's angle with the remote foot's; force tracking the
torque the platform puts on the person's foot (minus the person's torque on the platform) with
the torque the ground puts on the remote foot, each also after the best shift in time (the
delay shows as a lag). A run is *stable* when
no fault latched and the platform stayed inside its software limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from anklelab.control.haptics import TerrainProfile
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup, Channel
from anklelab.sim.capstan import SimulationResult, voluntary_torque

__all__ = ["TeleopMetrics", "teleoperate"]

MAX_LAG_S = 0.5


@dataclass(frozen=True)
class TeleopMetrics:
    """How well the platform and the remote robot tracked each other.

    Attributes
    ----------
    stable : bool
        No fault, and the platform inside its software limit.
    position_rms_error_rad : float
        RMS of the platform's angle minus the remote foot's.
    position_lag_s, position_rms_error_lagged_rad : float
        The shift that best aligns them, and the RMS error after it.
    force_rms_error_nm : float
        RMS of the platform's torque on the foot minus the ground's on the remote foot.
    force_lag_s, force_rms_error_lagged_nm : float
        Likewise after the best shift.
    remote_rms_rad, remote_torque_rms_nm : float
        RMS of the remote foot's angle and of the ground's torque (the scales of the errors).
    channel_energy_min_j : float
        Least energy held in the channel (negative would mean it produced energy).
    fault : int
        Latched fault code (0: none).
    """

    stable: bool
    position_rms_error_rad: float
    position_lag_s: float
    position_rms_error_lagged_rad: float
    force_rms_error_nm: float
    force_lag_s: float
    force_rms_error_lagged_nm: float
    remote_rms_rad: float
    remote_torque_rms_nm: float
    channel_energy_min_j: float
    fault: int


def _lagged(
    follower: NDArray[np.float64], leader: NDArray[np.float64], fs: float
) -> tuple[float, float]:
    """The lag (s, >= 0) of ``follower`` behind ``leader`` that minimises their RMS
    difference (or of ``leader`` behind ``follower``, negative), and that RMS."""
    best, best_lag = math.inf, 0
    for lag in range(-round(MAX_LAG_S * fs), round(MAX_LAG_S * fs) + 1, max(1, round(fs / 500))):
        if lag >= 0:
            d = follower[lag:] - leader[: leader.size - lag]
        else:
            d = follower[: follower.size + lag] - leader[-lag:]
        rms = float(np.sqrt(np.mean(d**2)))
        if rms < best:
            best, best_lag = rms, lag
    return best_lag / fs, best


def teleoperate(
    setup: CapstanSetup,
    channel: Channel,
    *,
    duration_s: float = 20.0,
    walking_speed_m_s: float = 0.5,
    torque_rms_nm: float = 2.0,
    settle_s: float = 2.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, TeleopMetrics]:
    """Teleoperate the remote robot over hills for ``duration_s`` (metrics after ``settle_s``).

    ``seed`` draws the hills, the person's pushes, the network's jitter and sensor noise.
    """
    rng = np.random.default_rng(seed)
    n = round(duration_s * setup.fs)
    hills = TerrainProfile.hills(walking_speed_m_s * duration_s + 1.0, seed=rng)
    ground = hills.equilibrium(duration_s, setup.fs, walking_speed_m_s)
    pushes = voluntary_torque(duration_s, setup.fs, rms_nm=torque_rms_nm, seed=rng)
    run = simulate_closed_loop(
        setup,
        n,
        mode="teleoperation",
        voluntary=pushes,
        remote_ground=ground,
        channel=channel,
        seed=rng,
    )
    keep = slice(round(settle_s * setup.fs), None)
    angle, remote = run["angle_rad"][keep], run["remote_angle_rad"][keep]
    torque, contact = -run["interaction_torque_nm"][keep], run["remote_contact_nm"][keep]
    fault = int(run["fault"].max())
    inside = np.max(np.abs(run["angle_rad"])) < setup.params.safety.angle_limit_rad
    position_lag, position_lagged = _lagged(angle, remote, setup.fs)
    force_lag, force_lagged = _lagged(torque, contact, setup.fs)
    metrics = TeleopMetrics(
        stable=bool(fault == 0 and inside),
        position_rms_error_rad=float(np.sqrt(np.mean((angle - remote) ** 2))),
        position_lag_s=position_lag,
        position_rms_error_lagged_rad=position_lagged,
        force_rms_error_nm=float(np.sqrt(np.mean((torque - contact) ** 2))),
        force_lag_s=force_lag,
        force_rms_error_lagged_nm=force_lagged,
        remote_rms_rad=float(np.sqrt(np.mean(remote**2))),
        remote_torque_rms_nm=float(np.sqrt(np.mean(contact**2))),
        channel_energy_min_j=float(np.min(run["channel_energy_j"])),
        fault=fault,
    )
    return run, metrics
