"""A person standing or stepping on the platform: the human ankle's impedance, the load of the
body's weight, sway, a stretch reflex, and posture re-alignment to slow tilts.

The person's torque on the platform (dorsiflexing positive) is, while the foot is in contact,

``T = -K(t) (theta - theta_rest) - B(t) theta' + L(t) - G_r y(t)``

- ``K(t)``, ``B(t)``: the twin's human ankle (``perturberator.toml [human]``, per kilogram, times
  ``[gait] body_mass_kg``): quiet standing takes the stiffness at
  ``person.standing_stiffness_time_s``; a step's stance follows the stiffness knots through
  stance (held beyond the first and last knot), weighted by how far the foot has loaded the
  platform (the vertical force over its mid-stance level, at most 1);
- ``theta_rest`` follows the platform angle with ``person.posture_time_constant_s``: the person
  re-aligns the shank to a slow tilt, while a fast one loads the ankle's stiffness;
- ``L(t)``: the body weight on the platform times the centre of pressure's lever arm (anterior
  COP pushes the front down: negative), standing with a sway of the COP, stepping with paper
  000's stance GRF and COP progression (:mod:`anklelab.sim.gait`);
- ``y``: the stretch reflex of the plantarflexors, the dorsiflexion speed delayed by
  ``person.reflex_delay_s``, half-wave rectified and low-passed (second order, damping ratio
  0.7, ``person.reflex_cutoff_hz``); it plantarflexes (pushes the front down).

During a step's swing the foot is off the platform: no torque (its inertia stays in the plant,
a small approximation). :func:`person_profile` builds the per-sample arrays,
:func:`person_torque` is the compiled per-tick model the closed loop calls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, UserParameters
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim.capstan.user import voluntary_torque
from anklelab.sim.gait import GRAVITY, GaitTrials, stance_signals

__all__ = [
    "ACTIVITIES",
    "PersonConstants",
    "PersonProfile",
    "new_person_state",
    "person_constants",
    "person_foot",
    "person_profile",
    "person_torque",
]

Activity = Literal["standing", "walking"]
ACTIVITIES: tuple[str, ...] = ("standing", "walking")
REFLEX_DAMPING_RATIO = 0.7
LOAD_FADE_S = 0.5  # the person steps onto the platform: the standing load fades in


@dataclass(frozen=True)
class PersonProfile:
    """The person's time courses, one value per control tick.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad : ndarray
        Ankle stiffness and damping (0 off contact).
    load_torque_nm : ndarray
        Body weight times the centre-of-pressure lever arm, N·m (dorsiflexing positive).
    contact : ndarray
        1.0 while the foot is on the platform, else 0.0.
    """

    stiffness_nm_per_rad: NDArray[np.float64]
    damping_nms_per_rad: NDArray[np.float64]
    load_torque_nm: NDArray[np.float64]
    contact: NDArray[np.float64]


class PersonConstants(NamedTuple):
    """What the compiled person model needs (built by :func:`person_constants`)."""

    reflex_gain: float
    delay_ticks: int
    reflex_w: float
    reflex_zeta: float
    posture_rate: float
    dt: float


def person_foot(human: PerturberatorParameters) -> UserParameters:
    """The person's foot for the plant: its inertia; stiffness and damping come per tick."""
    return UserParameters(
        foot_inertia_kgm2=human.human.inertia_kgm2,
        ankle_stiffness_nm_per_rad=0.0,
        ankle_damping_nms_per_rad=0.0,
        rest_angle_rad=0.0,
    )


def person_constants(params: CapstanParameters, fs: float) -> PersonConstants:
    """Reflex and posture constants at the control rate ``fs`` (Hz)."""
    p = params.person
    return PersonConstants(
        reflex_gain=p.reflex_gain_nms_per_rad,
        delay_ticks=round(p.reflex_delay_s * fs),
        reflex_w=2.0 * math.pi * p.reflex_cutoff_hz,
        reflex_zeta=REFLEX_DAMPING_RATIO,
        posture_rate=1.0 / (p.posture_time_constant_s * fs),
        dt=1.0 / fs,
    )


def person_profile(
    activity: Activity,
    duration_s: float,
    fs: float,
    params: CapstanParameters,
    human: PerturberatorParameters,
    *,
    seed: int | np.random.Generator = 0,
) -> PersonProfile:
    """The person's stiffness, damping, load and contact at each of ``duration_s * fs`` ticks.

    Parameters
    ----------
    activity : {"standing", "walking"}
        Quiet standing (with sway), or stepping in place (stance, then swing off the platform).
    duration_s, fs : float
        Length (s) and control rate (Hz).
    params : CapstanParameters
        ``params.person`` (load fractions, COP, sway, gait cycle).
    human : PerturberatorParameters
        The twin's human ankle (``human``), body mass, stance GRF and COP (``gait``) and the
        heel-to-ankle distance (``geometry``).
    seed : int or Generator
        The standing sway's random phases.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> cap, per = load_platform("capstan"), load_platform("perturberator")
    >>> stand = person_profile("standing", 2.0, 1000.0, cap, per)
    >>> round(float(stand.stiffness_nm_per_rad[0]))          # 3.2 N·m/rad/kg x 75 kg
    240
    """
    if activity not in ACTIVITIES:
        raise ParameterError(f"activity must be one of {list(ACTIVITIES)}; got {activity!r}")
    if not duration_s > 0 or not fs > 0:
        raise ParameterError(f"duration_s and fs must be > 0; got {duration_s}, {fs}")
    n = round(duration_s * fs)
    t = np.arange(n) / fs
    mass, ankle, person = human.gait.body_mass_kg, human.human, params.person
    knots, per_kg = np.asarray(ankle.knots_s), np.asarray(ankle.stiffness_nm_per_rad_per_kg)
    damping = ankle.damping_nms_per_rad_per_kg * mass
    if activity == "standing":
        weight = person.standing_load_fraction * mass * GRAVITY
        sway = voluntary_torque(
            duration_s, fs, rms_nm=person.sway_cop_rms_m, band_hz=person.sway_band_hz, seed=seed
        )
        fade = 0.5 * (1 - np.cos(np.pi * np.clip(t / LOAD_FADE_S, 0.0, 1.0)))
        stiffness = np.interp(person.standing_stiffness_time_s, knots, per_kg) * mass
        return PersonProfile(
            np.full(n, stiffness),
            np.full(n, damping),
            -weight * fade * (person.cop_offset_m + sway),
            np.ones(n),
        )
    gait = human.gait
    cycle = gait.stance_s / (1.0 - person.swing_fraction)
    steps = math.ceil(duration_s / cycle)
    ones = np.ones(steps)
    trials = GaitTrials(
        contact_s=cycle * np.arange(steps, dtype=np.float64),
        stance_s=gait.stance_s * ones,
        loading_s=gait.loading_s * ones,
        amplitude=ones,
        cop_scale=ones,
        placement_m=0 * ones,
    )
    stance = stance_signals(trials, gait, t)
    contact = stance.contact.any(axis=0)
    vertical = np.sum(stance.grf_z, axis=0)
    lever = np.sum(stance.progression, axis=0) - human.geometry.heel_to_ankle_m
    load = -person.walking_load_fraction * vertical * lever
    # the ankle's impedance reaches the platform as the foot loads it (no jump at toe-off)
    loaded = np.clip(vertical / (gait.vertical_base_bw * mass * GRAVITY), 0.0, 1.0)
    stiffness = np.interp(np.mod(t, cycle), knots, per_kg) * mass * loaded
    return PersonProfile(stiffness, damping * loaded, load, contact.astype(float))


@njit(cache=True)
def new_person_state(angle: float, delay_ticks: int) -> NDArray[np.float64]:
    """Fresh state ``[rest angle, reflex y, reflex y', ring index, speed ring...]``."""
    state = np.zeros(4 + delay_ticks + 1)
    state[0] = angle
    return state


@njit(cache=True, inline="always")
def person_torque(
    c: PersonConstants,
    state: NDArray[np.float64],
    stiffness: float,
    damping: float,
    load: float,
    contact: float,
    angle: float,
    speed: float,
) -> tuple[float, float]:
    """One tick of the person (compiled): their torque on the platform and its reflex part, N·m.

    ``angle`` and ``speed`` are the platform's true angle (rad) and speed (rad/s); ``state``
    (:func:`new_person_state`) is updated in place.
    """
    ring = state[4:]
    index = int(state[3])
    ring[index] = speed
    index = (index + 1) % ring.size
    state[3] = index
    stretch = max(ring[index], 0.0)  # the speed delay_ticks ago: dorsiflexion stretches
    w = c.reflex_w
    state[2] += c.dt * (w * w * (stretch - state[1]) - 2.0 * c.reflex_zeta * w * state[2])
    state[1] += c.dt * state[2]
    state[0] += c.posture_rate * (angle - state[0])
    reflex = -c.reflex_gain * state[1] * contact
    passive = -stiffness * (angle - state[0]) - damping * speed
    return contact * passive + load + reflex, reflex
