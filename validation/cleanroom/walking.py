"""Walking trials: the foot on the moving plate, the servo's perturbation, the plate's channels.

For each trial (README.md, "Walking trials"):

1. The nominal step (:mod:`~validation.cleanroom.gait`) loads the platform with the moment of
   the GRF about the hinge; the compliant drive yields by ``φ_u`` (a few mrad). The nominal
   ankle torque is ``T_nom = G_n dx_u + G_a dz`` with the tilted plate's GRF components and
   the nominal lever arm ``dx_u = cop_rel - heel_to_ankle``.
2. A perturbed trial adds the motion plan ``r`` at its onset. The foot rides on the plate, so
   the ankle angle's perturbation is the platform's, ``θ = φ_p``, and the foot answers with
   ``T_p = k(t) θ + b θ' + I θ''``, which loads the platform back. The hinge with the foot's
   ``I``, ``b`` and a reference stiffness ``k_ref`` is linear and time-invariant; the rest,
   ``(k(t) - k_ref) θ`` and the change of the GRF's moment arms as the plate tilts, is solved
   by fixed-point iteration (it converges geometrically: the drive is ~40 times stiffer).
3. The plate's sensors carry the foot's load (total torque ``T_nom + T_p``) and the top plate's
   inertia and weight; the DAQ samples every ``oversample``-th value.

Trials are simulated in chunks so that memory stays bounded; all randomness is drawn up front.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import TRUNCATE_SD, Config, HumanAnkle, ProstheticFoot
from validation.cleanroom.drive import Hinge
from validation.cleanroom.foot import stiffness
from validation.cleanroom.forces import PlateSensors, foot_load, plate_load, tilt
from validation.cleanroom.gait import Gait, Steps
from validation.cleanroom.protocol import WalkingPlan, ramp_hold_ramp

__all__ = ["WalkingSimulation", "reference_stiffness", "simulate_walking"]

Array = NDArray[np.float64]
CHUNK = 100  # trials simulated together
_MAX_ITERATIONS = 20
_TOLERANCE_RAD = 1e-12


@dataclass(frozen=True)
class WalkingSimulation:
    """Clean walking signals at the DAQ rate and the true quantities behind them.

    Arrays hold trials first and time last (``n_times`` DAQ samples from ``time_s``).

    Attributes
    ----------
    time_s : ndarray, shape (n_times,)
        Sample times in each file, s.
    channels : ndarray, shape (8, n_trials, n_times)
        Plate channels before the DAQ's errors, N.
    motor_angle, ankle_angle : ndarray
        Motor-side hinge angle (what the drive reports) and true ankle angle, rad.
    perturbation, perturbation_velocity, perturbation_acceleration : ndarray
        True perturbation θ of the ankle angle (perturbed minus the same trial without the
        perturbation) and its derivatives, rad, rad/s, rad/s² (zero when unperturbed).
    ankle_torque, ankle_torque_nominal : ndarray
        True ankle torque of the trial and of the same trial without the perturbation, N·m.
    stiffness : ndarray
        The foot's true k(t), N·m/rad.
    lever_arm : ndarray
        Nominal lever arm ``dx = (cop_x - cop_x[heel contact]) - heel_to_ankle``, m.
    heel_contact_s, onset_s : ndarray, shape (n_trials,)
        True heel contact and perturbation onset (start of the motion plan; NaN when
        unperturbed), s in file time.
    channels_nominal : ndarray or None
        With ``nominal_channels=True``: the channels of each trial without its perturbation.
    """

    time_s: Array
    channels: Array
    motor_angle: Array
    ankle_angle: Array
    perturbation: Array
    perturbation_velocity: Array
    perturbation_acceleration: Array
    ankle_torque: Array
    ankle_torque_nominal: Array
    stiffness: Array
    lever_arm: Array
    heel_contact_s: Array
    onset_s: Array
    channels_nominal: Array | None = None


def reference_stiffness(foot: ProstheticFoot | HumanAnkle) -> float:
    """A stiffness typical of the perturbation windows, N·m/rad (the iteration's pivot)."""
    if isinstance(foot, HumanAnkle):
        return foot.stiffness_100ms_nm_per_rad * (1 + foot.rise_per_150ms)
    return float(np.mean(foot.stiffness_nm_per_rad))


def _draw_onsets(
    config: Config, plan: WalkingPlan, heel_contact_s: Array, rng: np.random.Generator
) -> Array:
    protocol = config.protocol
    sd = np.asarray(protocol.onset_jitter_sd_s)[np.maximum(plan.point, 0)]
    jitter = np.clip(rng.standard_normal(plan.n_trials), -TRUNCATE_SD, TRUNCATE_SD) * sd
    onset = heel_contact_s + plan.delay_ms / 1000 + protocol.trigger_latency_s + jitter
    return np.where(plan.perturbed, onset, np.nan)


class _Chunk:
    """The signals of one chunk of trials at the simulation rate."""

    def __init__(
        self, config: Config, gait: Gait, steps: Steps, rows: slice, hinges: tuple[Hinge, Hinge]
    ) -> None:
        foot, plate = config.foot, config.plate
        self.config, self.gait = config, gait
        self.contact = gait.in_contact
        self.dz = foot.ankle_height_m
        self.ex = steps.ankle_offset_m[rows, None]
        self.ez = plate.hinge_height_m - foot.ankle_height_m
        self.ankle_x = plate.hinge_x_m + self.ex
        self.lever = np.where(
            self.contact, gait.cop_rel - foot.heel_to_ankle_m, -foot.heel_to_ankle_m
        )
        self.since_hc = gait.t - steps.heel_contact_s[rows, None]
        self.k = stiffness(foot, self.since_hc, self.lever)
        self.nominal = self._nominal(hinges[0])

    def _loads(self, angle: Array, ankle_torque: Array | None = None) -> tuple[Array, Array]:
        """Nominal ankle torque (if not given) and the foot's moment about the hinge, N·m.

        ``T_nom = G_n dx_u + G_a dz`` on a plate tilted by ``angle``; the platform feels
        ``-(T + G_n e_x + G_a e_z)`` (``e``: hinge-to-ankle offset, forward and down).
        """
        g_a, g_n = tilt(self.gait.grf, angle)
        if ankle_torque is None:
            ankle_torque = (g_n * self.lever + g_a * self.dz) * self.contact
        return ankle_torque, -(ankle_torque + g_n * self.ex + g_a * self.ez) * self.contact

    def _nominal(self, hinge: Hinge) -> dict[str, Array]:
        angle = np.zeros_like(self.lever)
        for _ in range(2):  # the GRF's tilt changes the load by ~1e-4 of the drive's stiffness
            _, torque = self._loads(angle)
            angle = hinge.response(torque=torque, outputs=("angle",))["angle"]
        result = hinge.response(torque=torque)
        result["torque"], _ = self._loads(result["angle"])
        return result

    def perturb(
        self, rows: NDArray[np.int64], reference: Array, hinge: Hinge, k_ref: float
    ) -> dict[str, Array]:
        """Perturbation response of trials ``rows`` (indices within the chunk)."""
        base_angle = self.nominal["angle"][rows]
        k = self.k[rows]
        grf, ex, ez = self.gait.grf[:, rows], self.ex[rows], self.ez
        contact = self.contact[rows]
        g_a0, g_n0 = tilt(grf, base_angle)
        free = hinge.response(reference=reference, outputs=("angle",))["angle"]
        theta = free
        for _ in range(_MAX_ITERATIONS):
            g_a, g_n = tilt(grf, base_angle + theta)
            extra = -((k - k_ref) * theta + ((g_n - g_n0) * ex + (g_a - g_a0) * ez) * contact)
            updated = free + hinge.response(torque=extra, outputs=("angle",))["angle"]
            change = np.max(np.abs(updated - theta), initial=0.0)
            theta = updated
            if change < _TOLERANCE_RAD:
                break
        else:
            raise RuntimeError(
                f"walking: the foot-platform iteration did not converge ({change:.2e} rad)"
            )
        result = hinge.response(reference=reference, torque=extra)
        foot = self.config.foot
        result["torque"] = (
            k * result["angle"]
            + foot.damping_nms_per_rad * result["velocity"]
            + foot.inertia_kgm2 * result["acceleration"]
        )
        return result

    def channels(self, sensors: PlateSensors, motion: dict[str, Array], torque: Array) -> Array:
        """Plate channels for a platform motion and a total ankle torque."""
        gait, plate = self.gait, self.config.plate
        force, moment = foot_load(
            gait.grf,
            motion["angle"],
            torque,
            self.ankle_x,
            gait.cop_lateral,
            gait.free_moment,
            self.contact,
            plate,
            self.dz,
        )
        inertial_force, inertial_moment = plate_load(
            plate, motion["angle"], motion["velocity"], motion["acceleration"]
        )
        return sensors.channels(force + inertial_force, moment + inertial_moment)


def simulate_walking(
    config: Config, plan: WalkingPlan, rng: np.random.Generator, *, nominal_channels: bool = False
) -> WalkingSimulation:
    """Simulate every walking trial of ``plan`` (clean signals; the DAQ's errors come later).

    Parameters
    ----------
    config : Config
        The session.
    plan : WalkingPlan
        Condition of each trial, in recording order.
    rng : numpy.random.Generator
        Source of the trial-to-trial variation (steps and onset jitter).
    nominal_channels : bool
        Also return each trial's channels without its perturbation (for checks).
    """
    protocol, foot = config.protocol, config.foot
    fs, over = protocol.sample_rate_hz, protocol.oversample
    n_out = round(protocol.trial_duration_s * fs)
    t = np.arange(n_out * over) / (fs * over)
    steps = Steps.draw(
        config.gait, plan.n_trials, protocol.contact_time_s, protocol.heel_contact_threshold_n, rng
    )
    onset = _draw_onsets(config, plan, steps.heel_contact_s, rng)
    k_ref = reference_stiffness(foot)
    hinges = (
        Hinge.build(config.drive, config.plate, fs * over),
        Hinge.build(
            config.drive,
            config.plate,
            fs * over,
            inertia_kgm2=foot.inertia_kgm2,
            damping_nms_per_rad=foot.damping_nms_per_rad,
            stiffness_nm_per_rad=k_ref,
        ),
    )
    sensors = PlateSensors.build(config.plate, fs * over)
    pieces: dict[str, list[Array]] = {}
    for start in range(0, plan.n_trials, CHUNK):
        rows = slice(start, min(start + CHUNK, plan.n_trials))
        chunk = _Chunk(config, steps.nominal(t, rows), steps, rows, hinges)
        nominal = chunk.nominal
        motion = {key: value.copy() for key, value in nominal.items()}
        perturbation = {key: np.zeros_like(value) for key, value in nominal.items()}
        hit = np.flatnonzero(plan.perturbed[rows])
        if hit.size:
            reference = ramp_hold_ramp(
                t,
                onset[rows][hit, None],
                plan.sign[rows][hit, None],
                protocol,
                protocol.walking_hold_s,
            )
            response = chunk.perturb(hit, reference, hinges[1], k_ref)
            for key, value in response.items():
                perturbation[key][hit] = value
                motion[key][hit] += value
        if isinstance(foot, HumanAnkle):
            ankle = steps.human_ankle_angle(t, rows) + nominal["angle"]
        else:  # a solid-ankle prosthesis: the keel bends under the nominal torque
            ankle = nominal["torque"] / chunk.k
        keep = np.s_[..., ::over]
        out = {
            "channels": chunk.channels(sensors, motion, motion["torque"])[keep],
            "motor_angle": motion["motor_angle"][keep],
            "ankle_angle": (ankle + perturbation["angle"])[keep],
            "perturbation": perturbation["angle"][keep],
            "perturbation_velocity": perturbation["velocity"][keep],
            "perturbation_acceleration": perturbation["acceleration"][keep],
            "ankle_torque": motion["torque"][keep],
            "ankle_torque_nominal": nominal["torque"][keep],
            "stiffness": chunk.k[keep],
            "lever_arm": chunk.lever[keep],
        }
        if nominal_channels:
            out["channels_nominal"] = chunk.channels(sensors, nominal, nominal["torque"])[keep]
        for key, value in out.items():
            pieces.setdefault(key, []).append(value)
    arrays = {key: np.concatenate(value, axis=-2) for key, value in pieces.items()}
    return WalkingSimulation(
        time_s=t[::over], heel_contact_s=steps.heel_contact_s, onset_s=onset, **arrays
    )
