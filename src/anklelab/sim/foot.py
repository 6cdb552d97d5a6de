"""What stands on the plate: a prosthetic foot or a human ankle, coupled to the hinge.

**How the foot's torque reaches the plate.** Between foot flat and heel off
(``gait.foot_flat_fraction`` ... ``heel_off_fraction`` of stance) the sole rests flat on the
plate; before, the heel rocks on its contact point and after, the forefoot rolls, so the foot
is not coupled to the hinge and the plate sees the gait's load alone. The shank's motion is the
gait's (it does not respond to the 100 ms perturbation). When, with the foot flat, the hinge
rotates by ``th`` (counted from its angle at foot flat) the foot rotates with it about the
ankle centre (placed over the hinge axis, up to the
optional misalignment ``e``), so the ankle angle changes by ``phi = th + th e_z / L_shank`` (a
hinge axis below the ankle also translates the ankle and tilts the shank). The external
dorsiflexing moment on the foot about the ankle centre is::

    T_A = T_nominal(t) + I th'' + k(t) phi + b(t) phi'

(``I`` the foot with its coupled segments; with the optional compliant shell the foot is a
separate inertia joined to the plate by the shell's spring-damper, and ``T_A`` is the shell
torque). ``T_nominal = GRF_z dx_nom + GRF_x dz`` is the gait's own ankle moment. The perturbation
leaves the lab GRF vector unchanged (up to the leg-spring force ``k_leg e_x th`` that a misaligned
hinge adds through the ankle); so, at ~constant vertical load, the torque change appears as a
centre-of-pressure shift. In the tilted plate's frame the load is the lab GRF rotated by ``-th``
and the COP is placed where the moment about the ankle equals ``T_A``:
``cop_x = x_ankle + (T_A - GRF_x,plate dz) / GRF_z,plate``. Hence the plate signals satisfy the
DESIGN.md formula ``T_a = GRF_z dx + GRF_x dz`` *exactly* in the plate frame, with
``dx = cop_x - cop_x(heel contact) - heel_to_ankle``, heel contact being the 25 N threshold
crossing (the ankle is placed ``heel_to_ankle`` ahead of the COP at that instant, wherever the
COP path has moved to by then).

**Stiffness laws.** The prosthetic foot's stiffness is the bench law evaluated at the nominal
(unperturbed) lever arm ``dx_nom(t)`` (linear through ``bench.stiffness_nm_per_rad`` at
``bench.distances_m``, extrapolated linearly, 1300 -> 975 N·m/rad over 6-11 cm by default), so
the response stays linear in the perturbation; damping and inertia are constants. The human
ankle's stiffness follows published walking values through stance as a function of time after
heel contact (scaled by body mass), optionally times ``1 + g (dx_nom - dx_ref)`` (a stiffness
that also falls or rises with the lever arm); damping is proportional to body mass, inertia
constant. Both laws are floored at 5 % of their reference value.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from anklelab.errors import ParameterError
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim import _kernels as K
from anklelab.sim.drivetrain import FootLoad
from anklelab.sim.gait import GaitTrials, StanceSignals, cop_progression_at

__all__ = ["FootKind", "FootModel", "NominalStance", "foot_load", "foot_model"]

FootKind = Literal["prosthetic", "human"]
_FLOOR = 0.05  # laws never fall below this fraction of their reference stiffness


@dataclass(frozen=True)
class FootModel:
    """Impedance of the foot on the plate.

    Attributes
    ----------
    kind : {"prosthetic", "human"}
    params : PerturberatorParameters
        Where the laws come from (``bench``/``prosthetic`` or ``human``, ``gait`` body mass).
    """

    kind: FootKind
    params: PerturberatorParameters

    @property
    def inertia_kgm2(self) -> float:
        """Inertia of the foot and coupled segments about the ankle, kg·m²."""
        p = self.params
        return p.prosthetic.inertia_kgm2 if self.kind == "prosthetic" else p.human.inertia_kgm2

    def stiffness(self, lever_arm_m: NDArray, time_after_contact_s: NDArray) -> NDArray:
        """Ankle stiffness, N·m/rad, at the nominal lever arm and time after heel contact.

        Examples
        --------
        >>> from anklelab.platforms import load_platform
        >>> foot = foot_model("prosthetic", load_platform("perturberator"))
        >>> foot.stiffness(np.array([0.06, 0.085, 0.11]), np.zeros(3)).round(1).tolist()
        [1300.0, 1137.5, 975.0]
        """
        if self.kind == "prosthetic":
            return bench_law(self.params, lever_arm_m)
        h = self.params.human
        per_kg = np.interp(time_after_contact_s, h.knots_s, h.stiffness_nm_per_rad_per_kg)
        lever = 1.0 + h.stiffness_lever_arm_gain_per_m * (lever_arm_m - h.reference_lever_arm_m)
        return per_kg * self.params.gait.body_mass_kg * np.maximum(lever, _FLOOR)

    def damping(self, shape: tuple[int, ...]) -> NDArray:
        """Ankle damping, N·m·s/rad (constant through stance), broadcast to ``shape``."""
        p = self.params
        if self.kind == "prosthetic":
            value = p.prosthetic.damping_nms_per_rad
        else:
            value = p.human.damping_nms_per_rad_per_kg * p.gait.body_mass_kg
        return np.full(shape, value)

    def nominal_angle(self, torque: NDArray, stiffness: NDArray, fraction: NDArray) -> NDArray:
        """Unperturbed ankle angle, rad: the keel's static deflection (prosthetic) or the
        published stance pattern (human), held at its end values off stance."""
        if self.kind == "prosthetic":
            return np.where(np.isnan(fraction), 0.0, torque / stiffness)
        h = self.params.human
        curve = PchipInterpolator(h.angle_knots_fraction, h.angle_knots_rad)
        u = np.where(np.isnan(fraction), 0.0, fraction)
        return np.asarray(curve(np.clip(u, 0, 1)))

    def describe(self) -> dict[str, object]:
        """The foot's kind and parameters (for the session's truth tree)."""
        p = self.params
        table = p.prosthetic if self.kind == "prosthetic" else p.human
        out: dict[str, object] = {"kind": self.kind, **table.model_dump()}
        if self.kind == "prosthetic":
            out["law_distances_m"] = list(p.bench.distances_m)
            out["law_stiffness_nm_per_rad"] = list(p.bench.stiffness_nm_per_rad)
        else:
            out["body_mass_kg"] = p.gait.body_mass_kg
        return out


def foot_model(kind: str, params: PerturberatorParameters) -> FootModel:
    """The foot called ``kind`` ("prosthetic" or "human") with its laws from ``params``."""
    if kind not in ("prosthetic", "human"):
        raise ParameterError(f"foot: expected 'prosthetic' or 'human', got {kind!r}")
    return FootModel(kind, params)  # type: ignore[arg-type]


def bench_law(params: PerturberatorParameters, distance_m: NDArray) -> NDArray:
    """Prosthetic stiffness at a lever arm: piecewise linear through the bench points, ends
    extrapolated linearly, N·m/rad (floored at 5 % of the smallest bench value)."""
    d = np.asarray(params.bench.distances_m)
    k = np.asarray(params.bench.stiffness_nm_per_rad)
    x = np.asarray(distance_m, dtype=float)
    out = np.interp(x, d, k)
    if len(d) > 1:
        lo = k[0] + (x - d[0]) * (k[1] - k[0]) / (d[1] - d[0])
        hi = k[-1] + (x - d[-1]) * (k[-1] - k[-2]) / (d[-1] - d[-2])
        out = np.where(x < d[0], lo, np.where(x > d[-1], hi, out))
    return np.maximum(out, _FLOOR * k.min())


@dataclass(frozen=True)
class NominalStance:
    """The unperturbed ankle of each trial, ``(n_trials, n_samples)`` arrays.

    ``lever_arm_m`` is ``dx_nom`` (COP minus ankle, m; NaN off stance), ``torque_nm`` the gait's
    ankle moment, ``angle_rad`` the unperturbed ankle angle, ``stiffness``/``damping`` the foot's
    impedance while it is flat on the plate (0 otherwise); ``time_after_contact_s`` is measured
    from the true (25 N) heel contact.
    """

    lever_arm_m: NDArray[np.float64]
    torque_nm: NDArray[np.float64]
    angle_rad: NDArray[np.float64]
    stiffness_nm_per_rad: NDArray[np.float64]
    damping_nms_per_rad: NDArray[np.float64]
    time_after_contact_s: NDArray[np.float64]


def foot_load(
    foot: FootModel,
    trials: GaitTrials,
    stance: StanceSignals,
    heel_contact_s: NDArray[np.float64],
    time_s: NDArray[np.float64],
) -> tuple[FootLoad, NominalStance]:
    """The kernel's :class:`FootLoad` and the trials' nominal ankle from a batch of stances."""
    p = foot.params
    geo = p.geometry
    contact = stance.contact
    u = np.nan_to_num(stance.fraction, nan=-1.0)
    flat = (u >= p.gait.foot_flat_fraction) & (u <= p.gait.heel_off_fraction)
    # the ankle sits heel_to_ankle_m ahead of the COP at (25 N) heel contact, wherever the COP
    # path has moved to by then
    at_contact = cop_progression_at(trials, p.gait, heel_contact_s)[:, None]
    dx = np.where(contact, stance.progression - at_contact - geo.heel_to_ankle_m, np.nan)
    after = time_s[None, :] - heel_contact_s[:, None]
    law = foot.stiffness(np.nan_to_num(dx), after)
    k = np.where(flat, law, 0.0)
    b = np.where(flat, foot.damping(dx.shape), 0.0)
    torque = np.where(
        contact, stance.grf_z * np.nan_to_num(dx) + stance.grf_x * geo.ankle_height_m, 0.0
    )
    n = len(trials)
    channels = np.zeros((n, K.N_G, len(time_s)))
    channels[:, K.G_X] = stance.grf_x
    channels[:, K.G_Y] = stance.grf_y
    channels[:, K.G_Z] = stance.grf_z
    channels[:, K.G_TNOM] = torque
    channels[:, K.G_CY] = p.gait.lateral_position_m
    channels[:, K.G_K] = k
    channels[:, K.G_B] = b
    channels[:, K.G_CONTACT] = flat
    scalars = np.zeros((n, K.N_FP))
    scalars[:, K.F_IF] = foot.inertia_kgm2
    scalars[:, K.F_XA] = p.hinge.axis_anterior_m + geo.misalignment_anterior_m + trials.placement_m
    scalars[:, K.F_DZ] = geo.ankle_height_m
    scalars[:, K.F_MIS] = geo.misalignment_vertical_m / geo.shank_length_m
    scalars[:, K.F_KLEG] = geo.leg_stiffness_n_per_m
    compliance = p.prosthetic.shell_compliance_rad_per_nm if foot.kind == "prosthetic" else 0.0
    scalars[:, K.F_KSH] = 1.0 / compliance if compliance > 0 else 0.0
    scalars[:, K.F_BSH] = p.prosthetic.shell_damping_nms_per_rad
    fs = 1.0 / (time_s[1] - time_s[0])
    nominal = NominalStance(
        lever_arm_m=dx,
        torque_nm=torque,
        angle_rad=foot.nominal_angle(torque, law, stance.fraction),
        stiffness_nm_per_rad=k,
        damping_nms_per_rad=b,
        time_after_contact_s=after,
    )
    return FootLoad(channels, fs, scalars), nominal
