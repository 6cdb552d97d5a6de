"""Stance phase on the plate: ground reaction force and COP progression, trial by trial.

Within a stance of duration ``T`` starting at initial contact ``t_c`` (``s = t - t_c``,
``u = s / T``), with body weight ``W`` and a per-trial amplitude factor ``A``::

    envelope  E(s) = rise(s / loading) * fall((T - s) / unloading),  rise/fall = (1 - cos(pi x))/2
    vertical  GRF_z = A W E (base + hump [exp(-((u - .25)/.12)²) + exp(-((u - .75)/.12)²)])
    fore-aft  GRF_x = -A W E sin(2 pi u) (braking for u < 1/2, propulsion after)
    lateral   GRF_y = -A W E lateral sin(pi u)                 (right foot: medial = -y)
    COP       progression p(u) from the initial-contact point: shape-preserving cubic (PCHIP)
              through ``cop_knots``, scaled per trial (by default it stays at the heel for the
              first knot interval; knots may also move it from the first instant of contact).

All forces are the lab-frame GRF (plate on foot; x anterior, y right, z up), zero off stance.
Trial-to-trial variability scales stance time, loading time, GRF amplitude and COP progression
and shifts the foot placement and the lead time before contact.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import ParameterError
from anklelab.platforms.perturberator import GaitParameters
from anklelab.sim._pchip import pchip

__all__ = [
    "GaitTrials",
    "StanceSignals",
    "cop_progression_at",
    "heel_contact_times",
    "sample_gait",
    "stance_signals",
    "vertical_force",
]

GRAVITY = 9.81


@dataclass(frozen=True)
class GaitTrials:
    """Per-trial stance parameters, each an array of shape ``(n_trials,)``.

    Attributes
    ----------
    contact_s : initial foot contact, s from the start of the recording.
    stance_s : stance duration, s.
    loading_s : heel-strike loading time, s.
    amplitude : GRF scale factor (1 = nominal).
    cop_scale : COP progression scale factor.
    placement_m : fore-aft offset of the foot from its intended place on the plate, m.
    """

    contact_s: NDArray[np.float64]
    stance_s: NDArray[np.float64]
    loading_s: NDArray[np.float64]
    amplitude: NDArray[np.float64]
    cop_scale: NDArray[np.float64]
    placement_m: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.contact_s)

    def as_dict(self) -> dict[str, NDArray[np.float64]]:
        """The arrays by field name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class StanceSignals:
    """Lab GRF (N), COP progression from the heel point (m) and stance fraction, per sample.

    Each array has shape ``(n_trials, n_samples)``; ``fraction`` is NaN off stance.
    """

    grf_x: NDArray[np.float64]
    grf_y: NDArray[np.float64]
    grf_z: NDArray[np.float64]
    progression: NDArray[np.float64]
    fraction: NDArray[np.float64]

    @property
    def contact(self) -> NDArray[np.bool_]:
        """True while the foot is on the plate."""
        return ~np.isnan(self.fraction)


def sample_gait(
    params: GaitParameters,
    n_trials: int,
    seed: int | np.random.Generator,
    *,
    variability: bool = True,
) -> GaitTrials:
    """Draw ``n_trials`` stances (nominal ones when ``variability`` is False).

    ``seed`` is an int or a numpy.random.Generator (which then continues its stream).
    """
    g = params
    rng = np.random.default_rng(seed)

    def spread(sd: float) -> NDArray[np.float64]:
        if not variability:
            return np.ones(n_trials)
        return np.clip(1 + sd * rng.standard_normal(n_trials), 1 - 3 * sd, 1 + 3 * sd)

    lead = rng.uniform(0, g.pre_contact_jitter_s, n_trials) if variability else np.zeros(n_trials)
    placement = g.placement_sd_m * rng.standard_normal(n_trials) if variability else lead * 0
    trials = GaitTrials(
        contact_s=g.pre_contact_s + lead,
        stance_s=g.stance_s * spread(g.stance_sd_fraction),
        loading_s=g.loading_s * spread(g.loading_sd_fraction),
        amplitude=spread(g.force_sd_fraction),
        cop_scale=spread(g.cop_sd_fraction),
        placement_m=placement,
    )
    end = trials.contact_s + trials.stance_s
    if end.max() > g.trial_duration_s:
        raise ParameterError(
            f"gait.trial_duration_s: {g.trial_duration_s} s is shorter than a simulated stance "
            f"ending at {end.max():.3f} s; lengthen it"
        )
    return trials


def _envelope(s: NDArray, trials: GaitTrials, params: GaitParameters) -> NDArray:
    stance = trials.stance_s[:, None]
    rise = np.clip(s / trials.loading_s[:, None], 0, 1)
    fall = np.clip((stance - s) / params.unloading_s, 0, 1)
    on = (s >= 0) & (s <= stance)
    return np.where(on, 0.25 * (1 - np.cos(np.pi * rise)) * (1 - np.cos(np.pi * fall)), 0.0)


def _vertical(
    s: NDArray, trials: GaitTrials, params: GaitParameters, envelope: NDArray | None = None
) -> NDArray:
    """Vertical GRF at times ``s`` after contact (``envelope``: :func:`_envelope` at ``s``, if
    the caller has it)."""
    u = s / trials.stance_s[:, None]
    humps = np.exp(-(((u - 0.25) / 0.12) ** 2)) + np.exp(-(((u - 0.75) / 0.12) ** 2))
    weight = params.body_mass_kg * GRAVITY * trials.amplitude[:, None]
    shape = params.vertical_base_bw + params.vertical_hump_bw * humps
    env = _envelope(s, trials, params) if envelope is None else envelope
    return weight * env * shape


def vertical_force(
    trials: GaitTrials, params: GaitParameters, time_s: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Vertical GRF of each trial at its own times ``time_s`` (shape (n_trials, n)), N."""
    return _vertical(np.asarray(time_s) - trials.contact_s[:, None], trials, params)


def stance_signals(
    trials: GaitTrials, params: GaitParameters, time_s: NDArray[np.float64]
) -> StanceSignals:
    """GRF and COP progression of each trial at the recording times ``time_s`` (s)."""
    s = np.asarray(time_s)[None, :] - trials.contact_s[:, None]
    u = s / trials.stance_s[:, None]
    on = (u >= 0) & (u <= 1)
    weight = params.body_mass_kg * GRAVITY * trials.amplitude[:, None]
    env = _envelope(s, trials, params)
    fore_aft = np.where(u < 0.5, params.braking_bw, params.propulsion_bw)
    progression = _progression(u, trials.cop_scale[:, None], params)
    return StanceSignals(
        grf_x=-weight * env * fore_aft * np.sin(2 * np.pi * u),
        grf_y=-weight * env * params.lateral_bw * np.sin(np.pi * np.clip(u, 0, 1)),
        grf_z=_vertical(s, trials, params, env),
        progression=np.where(on, progression, 0.0),
        fraction=np.where(on, u, np.nan),
    )


def _progression(u: NDArray, scale: NDArray, params: GaitParameters) -> NDArray:
    """COP progression from the initial-contact point at stance fractions ``u``, m."""
    cop = pchip(params.cop_knots_fraction, params.cop_knots_m, np.clip(u, 0, 1))
    return np.nan_to_num(cop) * scale


def cop_progression_at(
    trials: GaitTrials, params: GaitParameters, time_s: NDArray[np.float64]
) -> NDArray[np.float64]:
    """COP progression of each trial at its own time ``time_s[i]`` (shape (n_trials,)), m.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> g = load_platform("perturberator").gait
    >>> trials = sample_gait(g, 2, 0, variability=False)
    >>> cop_progression_at(trials, g, trials.contact_s + [0.0, g.stance_s]).round(3).tolist()
    [0.0, 0.215]
    """
    u = (np.asarray(time_s) - trials.contact_s) / trials.stance_s
    return _progression(u, trials.cop_scale, params)


def heel_contact_times(
    trials: GaitTrials, params: GaitParameters, threshold_n: float
) -> NDArray[np.float64]:
    """When the vertical GRF first exceeds ``threshold_n`` (the heel-contact definition), s.

    The vertical force rises monotonically during loading, so the crossing is found by
    bisection over the loading phase, to well below a nanosecond.
    """
    lo = np.zeros(len(trials))
    hi = trials.loading_s.copy()
    if np.any(_vertical(hi[:, None], trials, params)[:, 0] < threshold_n):
        raise ParameterError(
            f"heel contact: the vertical GRF does not reach {threshold_n} N in loading"
        )
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = _vertical(mid[:, None], trials, params)[:, 0] < threshold_n
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return trials.contact_s + 0.5 * (lo + hi)
