"""The display envelope: the largest sinusoidal amplitude the platform can render at each
frequency, from the model.

For ``theta = A sin(w t)`` about level, with the user's foot and ankle on the platform (lumped
with the platform: inertia ``J``, damping ``b``, stiffness ``K``, :func:`linear_platform`), the
amplitude is bounded by

- the **workspace**: ``A <= safety.angle_limit_rad`` (the software limit the monitor enforces);
- the **speed limit**: ``A w |F_v(w)| <= safety.velocity_limit_rad_s`` (``F_v`` the controller's
  speed filter, through which the monitor sees the speed);
- the **torque**: ``|K - J w^2 + j b w| A + T_c <= T_max``, with ``T_c`` the Coulomb friction
  referred to the platform and ``T_max`` the drive's peak torque less the gravity torque at
  the largest angle, or, with a person on the platform, the person guard's limit on the torque
  beyond gravity compensation;
- the **supply voltage**: ``|(R + j w L) (K - J w^2 + j b w) / k_t + j w K_b r| A + R T_c / k_t
  <= V`` (``k_t = K_i r``, ``r = r_g r_c``);

These bound the platform's motion whatever the controller; the controller decides how close a
commanded trajectory comes to it. :func:`display_envelope` also gives the **closed-loop
bandwidth** of the controller in use, the frequency where the loop's model
(:func:`~anklelab.control.tracking.closed_loop_model`) leaves 1 dB in gain or 20 degrees in
phase: beyond it the PID alone displays the amplitude late and off; with the inverse-dynamics
feed-forward (and for known trajectories the ZPETC) that frequency moves out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.control.pid import PIDGains
from anklelab.control.tracking import closed_loop_model
from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters, UserParameters
from anklelab.sim.capstan import linear_platform
from anklelab.sim.capstan.plant import GRAVITY_M_S2

__all__ = ["LIMITS", "DisplayEnvelope", "PersonLoad", "display_envelope", "fidelity_limit_hz"]

LIMITS = ("workspace", "speed", "torque", "voltage")


@dataclass(frozen=True)
class PersonLoad:
    """A standing or stepping person as the envelope sees them.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad : float
        The ankle's impedance; its rest angle follows a slow tilt with
        ``posture_time_constant_s``, so the stiffness acts as ``K j w tau / (1 + j w tau)``.
    posture_time_constant_s : float
        Posture re-alignment time constant, s.
    load_nm : float
        The largest torque of the body weight on the platform (it takes that much of the
        torque budget), N·m.
    """

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float
    posture_time_constant_s: float
    load_nm: float


@dataclass(frozen=True)
class DisplayEnvelope:
    """The amplitude bounds at each frequency (rad), and which one binds.

    Attributes
    ----------
    frequency_hz : ndarray, shape (n,)
        Frequencies.
    bounds : dict of str to ndarray
        Each limit's largest amplitude (keys :data:`LIMITS`).
    amplitude_rad : ndarray
        Their minimum: the envelope.
    limiting : list of str
        The binding limit at each frequency.
    torque_limit_nm : float
        The torque available for motion (``T_max``).
    fidelity_hz : float
        The closed-loop bandwidth: the model's 1 dB / 20 degree limit (inf if beyond 100 Hz).
    """

    frequency_hz: NDArray[np.float64]
    bounds: dict[str, NDArray[np.float64]]
    amplitude_rad: NDArray[np.float64]
    limiting: list[str]
    torque_limit_nm: float
    fidelity_hz: float


def fidelity_limit_hz(
    params: CapstanParameters,
    gains: PIDGains,
    fs: float,
    *,
    feedforward: bool,
    user: UserParameters | None,
    model_friction: FrictionParameters | None = None,
    top_hz: float = 100.0,
) -> float:
    """Lowest frequency where the loop's model leaves 1 dB in gain or 20 degrees in phase
    (``inf`` if it stays within up to ``top_hz``)."""
    model = closed_loop_model(
        params, gains, fs, feedforward=feedforward, user=user, model_friction=model_friction
    )
    f = np.geomspace(0.05, min(top_hz, 0.45 * fs), 2000)
    h = model.response(f)
    outside = (np.abs(20 * np.log10(np.abs(h))) > 1.0) | (np.abs(np.degrees(np.angle(h))) > 20)
    hits = np.flatnonzero(outside)
    return float(f[hits[0]]) if hits.size else math.inf


def display_envelope(
    frequency_hz: ArrayLike,
    params: CapstanParameters,
    gains: PIDGains,
    fs: float,
    *,
    feedforward: bool = True,
    user: UserParameters | None = None,
    person_guard: bool = True,
    model_friction: FrictionParameters | None = None,
    person: PersonLoad | None = None,
) -> DisplayEnvelope:
    """The display envelope of the platform under its controller (see the module notes).

    Parameters
    ----------
    frequency_hz : array_like
        Frequencies, Hz.
    params : CapstanParameters
        The platform and its limits.
    gains : PIDGains
        The position controller.
    fs : float
        Control rate, Hz.
    feedforward : bool
        The loop adds the inverse-dynamics feed-forward.
    user : UserParameters, optional
        The foot and ankle on the platform.
    person_guard : bool
        The person guard limits the torque beyond gravity compensation (with a user on).
    model_friction : FrictionParameters, optional
        The controller's friction and inertia model.
    person : PersonLoad, optional
        A standing or stepping person (``user`` then gives their foot's inertia).

    Examples
    --------
    >>> from anklelab.control.pid import design_critically_damped
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("capstan")
    >>> env = display_envelope([0.1, 3.0, 20.0], p, design_critically_damped(p), 1000.0,
    ...                        user=p.user)
    >>> env.limiting
    ['workspace', 'speed', 'torque']
    """
    f = np.asarray(frequency_hz, dtype=float)
    if f.ndim != 1 or not np.all((f > 0) & np.isfinite(f)):
        raise ParameterError("frequency_hz must be a 1-D array of positive frequencies")
    w = 2 * np.pi * f
    s = params.safety
    lin = linear_platform(params, user)
    ratio = params.total_ratio
    k_t = params.motor.torque_constant_nm_per_a * ratio
    friction = params.friction
    coulomb = 0.5 * (friction.coulomb_cw_nm + friction.coulomb_ccw_nm) * params.capstan.ratio
    plat = params.platform
    gravity = plat.mass_kg * GRAVITY_M_S2 * plat.com_distance_m
    if person_guard and user is not None:
        torque_limit = params.person_safety.torque_limit_nm
    else:
        torque_limit = params.peak_torque_nm - gravity
    z = lin.stiffness_nm_per_rad - lin.inertia_kgm2 * w**2 + 1j * lin.damping_nms_per_rad * w
    if person is not None:
        tau = person.posture_time_constant_s
        z = z + person.stiffness_nm_per_rad * (1j * w * tau) / (1 + 1j * w * tau)
        z = z + 1j * w * person.damping_nms_per_rad
        torque_limit -= person.load_nm
    filter_w = 2 * np.pi * gains.velocity_filter_hz
    speed_filter = np.abs(1.0 / (1.0 + 1j * w / filter_w))
    m = params.motor
    emf = m.back_emf_constant_v_s_per_rad * ratio
    volts = (m.resistance_ohm + 1j * w * m.inductance_h) * z / k_t + 1j * w * emf
    headroom = params.drive.supply_voltage_v - m.resistance_ohm * coulomb / k_t
    fidelity = fidelity_limit_hz(
        params, gains, fs, feedforward=feedforward, user=user, model_friction=model_friction
    )
    bounds = {
        "workspace": np.full(f.shape, s.angle_limit_rad),
        "speed": s.velocity_limit_rad_s / (w * speed_filter),
        "torque": (torque_limit - coulomb) / np.abs(z),
        "voltage": headroom / np.abs(volts),
    }
    stacked = np.vstack([bounds[name] for name in LIMITS])
    return DisplayEnvelope(
        frequency_hz=f,
        bounds=bounds,
        amplitude_rad=stacked.min(axis=0),
        limiting=[LIMITS[k] for k in stacked.argmin(axis=0)],
        torque_limit_nm=float(torque_limit),
        fidelity_hz=fidelity,
    )
