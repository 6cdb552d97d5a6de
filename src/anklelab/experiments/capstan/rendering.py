"""Haptic rendering of a virtual spring-damper (level, or following a terrain's slope), and the
impedance the foot actually felt."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from anklelab.control.haptics import TerrainProfile, VirtualEnvironment
from anklelab.errors import ParameterError
from anklelab.experiments.capstan.closed_loop import simulate_closed_loop
from anklelab.experiments.capstan.config import CapstanSetup
from anklelab.sim.capstan import SimulationResult, voluntary_torque

__all__ = ["RenderMetrics", "render", "render_metrics"]


@dataclass(frozen=True)
class RenderMetrics:
    """The impedance the foot actually felt.

    The felt impedance ``Z(f) = S_theta,T(f) / S_theta,theta(f)`` (Welch cross- and
    auto-spectra of the twin's true platform angle and interaction torque, the angle measured
    from the equilibrium) is fitted by ``K - J w^2 + j B w`` over ``band_hz``; a spectral fit
    keeps the friction's stick-slip, which is not linear, from biasing the coefficients.

    Attributes
    ----------
    stiffness_nm_per_rad, damping_nms_per_rad, inertia_kgm2 : float
        Felt impedance.
    stiffness_error_percent, damping_error_percent : float
        Relative to the rendered environment's (NaN for a commanded 0, or an infinite, rigid
        stiffness: then the fit gives the stiffness of the position loop and the cable).
    equilibrium_rms_error_rad : float
        RMS of ``theta - theta_eq``.
    """

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float
    inertia_kgm2: float
    stiffness_error_percent: float
    damping_error_percent: float
    equilibrium_rms_error_rad: float


def render(
    setup: CapstanSetup,
    environment: VirtualEnvironment,
    *,
    mode: Literal["admittance", "impedance"] = "admittance",
    terrain: TerrainProfile | None = None,
    walking_speed_m_s: float = 1.0,
    duration_s: float = 30.0,
    torque_rms_nm: float = 2.0,
    seed: int | np.random.Generator = 0,
) -> tuple[SimulationResult, RenderMetrics]:
    """Render ``environment`` to a user pushing with a random voluntary torque.

    Without ``terrain`` the equilibrium is level (a plain virtual spring-damper); with it, the
    equilibrium follows the slope under a user walking at ``walking_speed_m_s``. ``seed`` (int
    or Generator) draws the voluntary torque and the current-sensor noise; the same seed gives
    the same run.
    """
    rng = np.random.default_rng(seed)
    n = round(duration_s * setup.fs)
    equilibrium = (
        np.zeros(n)
        if terrain is None
        else terrain.equilibrium(duration_s, setup.fs, walking_speed_m_s)
    )
    torque = voluntary_torque(duration_s, setup.fs, rms_nm=torque_rms_nm, seed=rng)
    result = simulate_closed_loop(
        setup,
        n,
        mode=mode,
        reference=equilibrium,
        voluntary=torque,
        environment=environment,
        seed=rng,
    )
    return result, render_metrics(result, equilibrium, environment)


def _percent(felt: float, commanded: float) -> float:
    """Relative error, %; NaN where the commanded value is 0 or infinite (rigid)."""
    if commanded == 0 or not math.isfinite(commanded):
        return math.nan
    return float(100 * (felt - commanded) / commanded)


def render_metrics(
    result: SimulationResult,
    equilibrium: ArrayLike,
    environment: VirtualEnvironment,
    *,
    band_hz: tuple[float, float] = (0.2, 3.0),
    segment_s: float = 5.0,
) -> RenderMetrics:
    """Fit the felt impedance (see :class:`RenderMetrics`)."""
    from scipy.signal import csd, welch

    fs = result.fs
    deflection = result["angle_rad"] - np.asarray(equilibrium, dtype=float)
    torque = result["interaction_torque_nm"]
    nperseg = min(deflection.size, round(segment_s * fs))
    f, s_xx = welch(deflection, fs, nperseg=nperseg)
    _, s_xt = csd(deflection, torque, fs, nperseg=nperseg)
    sel = (f >= band_hz[0]) & (f <= band_hz[1])
    if sel.sum() < 3:
        raise ParameterError(
            f"band_hz {band_hz} holds fewer than 3 frequencies at {segment_s} s segments"
        )
    z, w = s_xt[sel] / s_xx[sel], 2 * np.pi * f[sel]
    zero, one = np.zeros_like(w), np.ones_like(w)
    design = np.vstack([np.column_stack([one, zero, -(w**2)]), np.column_stack([zero, w, zero])])
    stiffness, damping, inertia = np.linalg.lstsq(
        design, np.concatenate([z.real, z.imag]), rcond=None
    )[0]
    k_env, b_env = environment.stiffness_nm_per_rad, environment.damping_nms_per_rad
    return RenderMetrics(
        stiffness_nm_per_rad=float(stiffness),
        damping_nms_per_rad=float(damping),
        inertia_kgm2=float(inertia),
        stiffness_error_percent=_percent(stiffness, k_env),
        damping_error_percent=_percent(damping, b_env),
        equilibrium_rms_error_rad=float(np.sqrt(np.mean(deflection**2))),
    )
