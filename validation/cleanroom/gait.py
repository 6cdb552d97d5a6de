"""Nominal (unperturbed) walking over the plate: ground reaction force, COP path, ankle angle.

Every trial draws its own stance duration, force amplitude, COP speeds, foot placement and heel
transient around the session's :class:`~validation.cleanroom.config.GaitConfig`. Times are s
after the start of the file, forces N in the lab's sagittal frame (x anterior, y right, z up;
GRF = force of the plate on the foot), COP in m. ``s`` is the stance fraction
``(t - t_contact) / stance``.

- Vertical GRF: ``BW · peak · P(s) / max P`` with ``P = sin πs + a2 sin 2πs + a3 sin 3πs +
  a5 sin 5πs`` (a double hump), plus a heel-strike impact pulse.
- Anterior GRF: a braking lobe ``-sin^1.5`` up to ``braking_fraction``, then a propulsive lobe.
- COP along the walking direction from initial contact ``u = t - t_contact``: heel rocker
  ``v_h τ_h (1 - exp(-u/τ_h))``, mid-stance roll ``v_m u``, forefoot acceleration after heel
  rise, and an initial transient ``A (u/τ) exp(1 - u/τ)``, capped at the foot length; it is
  zeroed at heel contact (the instant the vertical GRF reaches the trigger threshold).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from validation.cleanroom.config import TRUNCATE_SD, GaitConfig

__all__ = ["Gait", "Steps"]

Array = NDArray[np.float64]

#: Human sagittal ankle angle over stance (rad, dorsiflexion positive, zero at initial contact):
#: loading-response plantarflexion, dorsiflexion as the shank rolls over the foot, push-off.
_HUMAN_ANKLE_S = (0.0, 0.1, 0.2, 0.5, 0.8, 0.92, 1.0)
_HUMAN_ANKLE_RAD = (0.0, -0.09, -0.05, 0.06, 0.16, 0.05, -0.2)


@dataclass(frozen=True)
class Gait:
    """Nominal walking of some trials on a common time grid (trials first, time last).

    Attributes
    ----------
    t : ndarray, shape (n_times,)
        Time in the file, s.
    grf : ndarray, shape (3, n_trials, n_times)
        Anterior, rightward and upward GRF in the lab frame, N.
    cop_rel : ndarray, shape (n_trials, n_times)
        COP along the walking direction minus its value at heel contact, m (0 off the plate).
    cop_lateral : ndarray, shape (n_trials, n_times)
        COP to the right of the plate centre, m.
    free_moment : ndarray, shape (n_trials, n_times)
        Torque of the foot on the plate about the plate's z (down) axis, N·m.
    in_contact : ndarray of bool, shape (n_trials, n_times)
        Samples with the foot on the plate.
    """

    t: Array
    grf: Array
    cop_rel: Array
    cop_lateral: Array
    free_moment: Array
    in_contact: NDArray[np.bool_]


def _normal(rng: np.random.Generator, n: int) -> Array:
    return np.clip(rng.standard_normal(n), -TRUNCATE_SD, TRUNCATE_SD)


def _pulse(u: Array, time_s: float) -> Array:
    """A smooth pulse that starts at zero with zero slope and peaks at 1 after ``time_s``."""
    x = np.maximum(u, 0.0) / time_s
    return x**2 * np.exp(2.0 * (1.0 - x))


def _lobe(x: Array) -> Array:
    """``sin(π x)^1.5`` on 0 < x < 1, zero elsewhere."""
    sine = np.sin(np.pi * np.clip(x, 0.0, 1.0))
    return sine * np.sqrt(sine)


def _vertical_shape(s: Array, gait: GaitConfig) -> Array:
    """``sin x + a2 sin 2x + a3 sin 3x + a5 sin 5x`` at ``x = π s``, by multiple angles."""
    a2, a3, a5 = gait.vertical_harmonics
    x = np.pi * np.clip(s, 0.0, 1.0)
    sin, cos = np.sin(x), np.cos(x)
    sin2 = sin * sin
    return sin * (1 + 2 * a2 * cos + a3 * (3 - 4 * sin2) + a5 * (5 - 20 * sin2 + 16 * sin2 * sin2))


def _vertical_grf(u: Array, stance: Array, weight: Array, gait: GaitConfig) -> Array:
    """Vertical GRF (N) at ``u`` s after initial contact for stance ``stance`` s."""
    peak = np.max(_vertical_shape(np.linspace(0, 1, 2001), gait))
    s = u / stance
    body = weight * gait.vertical_peak_bw * _vertical_shape(s, gait) / peak
    impact = weight * gait.impact_bw * _pulse(u, gait.impact_time_s)
    return np.where((s > 0) & (s < 1), body + impact, 0.0)


def _heel_contact(stance: Array, weight: Array, gait: GaitConfig, threshold_n: float) -> Array:
    """Time (s after initial contact) at which the vertical GRF first reaches the threshold."""
    u = np.linspace(0.0, 0.08, 1601)  # linear interpolation on a 50 µs grid: error < 1e-10 s
    force = _vertical_grf(u, stance[:, None], weight[:, None], gait)
    above = force >= threshold_n
    if not np.all(above.any(axis=1)):
        raise ValueError("gait: the vertical GRF never reaches the heel-contact threshold")
    first = np.argmax(above, axis=1)
    rows = np.arange(len(stance))
    f0, f1 = force[rows, first - 1], force[rows, first]
    return u[first - 1] + (threshold_n - f0) / (f1 - f0) * (u[1] - u[0])


def _cop_path(
    u: Array, stance: Array, heel: Array, mid: Array, transient: Array, gait: GaitConfig
) -> Array:
    """COP along the walking direction from the initial contact point, m."""
    uu = np.maximum(u, 0.0)
    rocker = heel * gait.heel_rocker_time_s * (1 - np.exp(-uu / gait.heel_rocker_time_s))
    forefoot = (
        0.5 * gait.forefoot_accel_m_s2 * np.maximum(uu - gait.heel_rise_fraction * stance, 0) ** 2
    )
    x = uu / gait.cop_transient_time_s
    early = transient * x * np.exp(1 - x)
    return np.minimum(rocker + mid * uu + forefoot + early, gait.foot_length_m)


@dataclass(frozen=True)
class Steps:
    """Per-trial draws of the nominal step: amplitudes, speeds, placement (arrays per trial).

    Attributes
    ----------
    gait : GaitConfig
        The session's walking.
    weight_n, stance_s, heel_rocker_m_s, midstance_m_s, transient_m : ndarray
        Body weight (N), stance duration (s), heel-rocker and mid-stance COP speeds (m/s) and
        COP transient amplitude (m) of each trial.
    lateral_m, ankle_offset_m, angle_scale : ndarray
        Foot placement right of the plate centre (m), ankle centre in front of the hinge axis
        (m) and scale of the human ankle-angle curve of each trial.
    contact_s, heel_contact_s : ndarray
        Initial contact and heel contact (vertical GRF reaches the threshold) in the file, s.
    """

    gait: GaitConfig
    weight_n: Array
    stance_s: Array
    heel_rocker_m_s: Array
    midstance_m_s: Array
    transient_m: Array
    lateral_m: Array
    ankle_offset_m: Array
    angle_scale: Array
    contact_s: Array
    heel_contact_s: Array

    @classmethod
    def draw(
        cls,
        gait: GaitConfig,
        n_trials: int,
        contact_range_s: tuple[float, float],
        threshold_n: float,
        rng: np.random.Generator,
    ) -> Steps:
        """Draw ``n_trials`` steps; heel contact is where the vertical GRF reaches
        ``threshold_n`` (N) and initial contact lies uniformly in ``contact_range_s`` (s)."""
        weight = gait.body_mass_kg * 9.81 * (1 + gait.force_cv * _normal(rng, n_trials))
        stance = gait.stance_s * (1 + gait.stance_cv * _normal(rng, n_trials))
        draws = {
            "heel_rocker_m_s": gait.heel_rocker_speed_m_s
            * (1 + gait.cop_cv * _normal(rng, n_trials)),
            "midstance_m_s": gait.midstance_cop_speed_m_s
            * (1 + gait.cop_cv * _normal(rng, n_trials)),
            "transient_m": gait.cop_transient_m + gait.cop_transient_sd_m * _normal(rng, n_trials),
            "lateral_m": gait.foot_lateral_m + gait.foot_lateral_sd_m * _normal(rng, n_trials),
            "ankle_offset_m": gait.ankle_hinge_offset_m
            + gait.ankle_hinge_offset_sd_m * _normal(rng, n_trials),
            "angle_scale": gait.ankle_angle_scale
            * (1 + gait.ankle_angle_cv * _normal(rng, n_trials)),
        }
        contact = rng.uniform(*contact_range_s, size=n_trials)
        heel = contact + _heel_contact(stance, weight, gait, threshold_n)
        return cls(gait, weight, stance, **draws, contact_s=contact, heel_contact_s=heel)

    def nominal(self, t: Array, rows: slice) -> Gait:
        """The nominal walking signals of trials ``rows`` on the time grid ``t`` (s)."""
        gait = self.gait
        stance, weight = self.stance_s[rows, None], self.weight_n[rows, None]
        contact = self.contact_s[rows, None]
        u = t - contact
        s = u / stance
        inside = (s > 0) & (s < 1)
        vertical = _vertical_grf(u, stance, weight, gait)
        brake = gait.braking_fraction
        anterior = weight * (
            gait.propulsion_bw * _lobe((s - brake) / (1 - brake))
            - gait.braking_bw * _lobe(s / brake)
            + gait.ap_impact_bw * _pulse(u, gait.impact_time_s) * inside
        )
        rightward = -weight * gait.lateral_bw * np.where(inside, np.sin(np.pi * s), 0.0)
        path = (
            stance,
            self.heel_rocker_m_s[rows, None],
            self.midstance_m_s[rows, None],
            self.transient_m[rows, None],
            gait,
        )
        cop = _cop_path(u, *path) - _cop_path(self.heel_contact_s[rows, None] - contact, *path)
        sc = np.clip(s, 0, 1)
        return Gait(
            t=t,
            grf=np.stack([anterior, rightward, vertical]),
            cop_rel=np.where(inside, cop, 0.0),
            cop_lateral=self.lateral_m[rows, None] - gait.lateral_cop_drift_m * sc,
            free_moment=vertical * gait.free_moment_arm_m * np.sin(2 * np.pi * sc),
            in_contact=inside,
        )

    def human_ankle_angle(self, t: Array, rows: slice) -> Array:
        """A human's nominal ankle angle over stance for trials ``rows``, rad."""
        s = np.clip((t - self.contact_s[rows, None]) / self.stance_s[rows, None], 0.0, 1.0)
        curve = PchipInterpolator(_HUMAN_ANKLE_S, _HUMAN_ANKLE_RAD)(s)
        return self.angle_scale[rows, None] * curve
