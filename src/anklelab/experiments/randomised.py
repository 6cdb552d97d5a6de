"""The randomised twin: Perturberator sessions drawn from broad families of platforms and feet.

An estimator tuned against one simulator learns that simulator. To validate against variation,
:func:`draw_twin` draws, per session, everything that differs between labs and subjects and that
paper 000 does not pin down, around the shipped parameter set:

- the force plate: sensor offsets ``a``, ``b``, ``az0``, its mounting (all four
  ``anterior_axis`` values), a yaw of up to 3° from the hinge's sagittal frame, the top plate's
  mass, inertia and centre of mass (up to 5 cm in front of the plate centre, 30–70 % of the way
  down to the sensors), its structural modes;
- the hinge (inertia, axis position, gravity stiffness) and the drivetrain (coupler stiffness);
- the servo: position and velocity gains, velocity integral and current-loop bandwidth (a
  closed loop from about 150 to 260 Hz, more or less damped);
- the subject: body mass, ankle height, heel-to-ankle distance, stance and loading times,
  stride-to-stride variability, the COP path after heel strike (a COP that rests at the heel or
  moves from the first instant of contact, starting up to 1 cm behind or ahead of where it
  rests, a faster or slower heel rocker);
- the foot: a prosthetic foot whose stiffness falls linearly with the lever arm (stiffness at
  6 cm 900–2200 N·m/rad, 5–40 % less at 11 cm) with its own damping and inertia, or a human-like
  ankle whose stiffness grows by 0–60 % per 150 ms through stance (exponentially), in half of
  the draws also falling with the lever arm, with human damping and foot inertia;
- noise: 1–3× the shipped channel noise, drift, goniometer precision and load-cell noise;
- the protocol: 40–100 perturbed trials per timing point and 2.5–4.5× as many unperturbed
  trials per point.

:func:`simulate_randomised` draws and simulates one session; its ``truth`` carries the draw
(``truth["draw"]``) besides the twin's usual reference values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from anklelab.data.session import Session
from anklelab.errors import ParameterError
from anklelab.experiments.perturberator import simulate_perturberator
from anklelab.platforms import load_platform
from anklelab.platforms.perturberator import PerturberatorParameters

__all__ = ["KINDS", "TwinDraw", "draw_twin", "simulate_randomised"]

Kind = Literal["prosthetic", "human", "random"]
KINDS: tuple[Kind, ...] = ("prosthetic", "human", "random")
"""Families :func:`draw_twin` draws from (``random``: either foot, with equal probability)."""
_AXES = ("+x", "-x", "+y", "-y")
_GROWTH_SPAN_S = 0.15  # the human stiffness grows by a drawn fraction over this span
_KNOTS_S = np.arange(0.0, 0.85, 0.025)  # knots of the human stiffness law (exact to ~0.1 %)
STANCE_RANGE_S = (0.78, 0.92)
"""The range the subject's mean stance time is drawn from, s."""


@dataclass(frozen=True)
class TwinDraw:
    """One draw of the randomised twin.

    Attributes
    ----------
    params : PerturberatorParameters
        The drawn parameter set.
    foot : {"prosthetic", "human"}
        What walks on the plate.
    trials_per_point, n_unperturbed : int
        Protocol size.
    noise_scale : float
        Factor applied to every noise source of the shipped set.
    human_growth_per_150ms : float
        Human foot: fractional stiffness growth per 150 ms (0 for the prosthetic foot).
    """

    params: PerturberatorParameters
    foot: Literal["prosthetic", "human"]
    trials_per_point: int
    n_unperturbed: int
    noise_scale: float
    human_growth_per_150ms: float

    def describe(self) -> dict[str, Any]:
        """The drawn scalars that are not parameters (for the session's truth)."""
        return {
            "foot": self.foot,
            "trials_per_point": self.trials_per_point,
            "n_unperturbed": self.n_unperturbed,
            "noise_scale": self.noise_scale,
            "human_growth_per_150ms": self.human_growth_per_150ms,
        }


def draw_twin(
    seed: int | np.random.Generator,
    *,
    kind: Kind = "random",
    noise_scale: float | None = None,
    trials_per_point: int | None = None,
    params: PerturberatorParameters | None = None,
) -> TwinDraw:
    """Draw one randomised twin (see the module docstring for the distributions).

    Parameters
    ----------
    seed : int or numpy.random.Generator
        The same seed gives the same draw.
    kind : {"prosthetic", "human", "random"}
        Family of feet.
    noise_scale : float, optional
        Fix the noise factor instead of drawing it (1–3).
    trials_per_point : int, optional
        Fix the perturbed trials per timing point instead of drawing them (40–100).
    params : PerturberatorParameters, optional
        The set to draw around (the shipped one by default).

    Returns
    -------
    TwinDraw

    Examples
    --------
    >>> draw = draw_twin(3, kind="human")
    >>> draw.foot, 40 <= draw.trials_per_point <= 100, 1 <= draw.noise_scale <= 3
    ('human', True, True)
    """
    if kind not in KINDS:
        raise ParameterError(f"kind: expected one of {', '.join(KINDS)}; got {kind!r}")
    rng = np.random.default_rng(seed)
    base = load_platform("perturberator") if params is None else params
    foot: Literal["prosthetic", "human"]
    if kind == "random":
        foot = "human" if rng.random() < 0.5 else "prosthetic"
    else:
        foot = kind
    noise = float(rng.uniform(1.0, 3.0)) if noise_scale is None else float(noise_scale)
    per_point = int(rng.integers(40, 101)) if trials_per_point is None else trials_per_point
    unperturbed = round(per_point * rng.uniform(2.5, 4.5))
    growth = float(rng.uniform(0.0, 0.6)) if foot == "human" else 0.0
    changes = (
        _platform(rng, base)
        | _servo(rng, base)
        | _subject(rng, base)
        | _noise(noise, base)
        | (_human(rng, growth) if foot == "human" else _prosthetic(rng))
    )
    return TwinDraw(base.replace(changes), foot, per_point, unperturbed, noise, growth)


def simulate_randomised(
    seed: int | np.random.Generator,
    *,
    kind: Kind = "random",
    noise_scale: float | None = None,
    trials_per_point: int | None = None,
    **options: Any,
) -> Session:
    """Draw a randomised twin and simulate its session (the same seed gives the same bytes).

    ``options`` go to :func:`~anklelab.experiments.simulate_perturberator` (``n_calibration``,
    ``time_courses``, ``progress``...); the session's ``truth["draw"]`` describes the draw.

    Examples
    --------
    >>> s = simulate_randomised(1, kind="prosthetic", trials_per_point=2, n_unperturbed=4,
    ...                         n_calibration=1, time_courses=False)
    >>> s.truth["draw"]["foot"], len(s.walking)
    ('prosthetic', 12)
    """
    rng = np.random.default_rng(seed)
    draw = draw_twin(rng, kind=kind, noise_scale=noise_scale, trials_per_point=trials_per_point)
    options.setdefault("n_unperturbed", draw.n_unperturbed)
    session = simulate_perturberator(
        draw.params, seed=rng, foot=draw.foot, trials_per_point=draw.trials_per_point, **options
    )
    label = seed if isinstance(seed, int) else "generator"
    truth = dict(session.truth or {}) | {"draw": {"kind": kind, "seed": label} | draw.describe()}
    provenance = dict(session.provenance) | {"created_by": "randomised twin"}
    return Session(
        session.info, session.calibration, session.walking, session.bench, truth, provenance
    )


def _scaled(rng: np.random.Generator, value: float, low: float, high: float) -> float:
    return float(value * rng.uniform(low, high))


def _platform(rng: np.random.Generator, p: PerturberatorParameters) -> dict[str, Any]:
    """Force plate, hinge and drivetrain."""
    fp, hinge = p.force_plate, p.hinge
    az0 = float(rng.uniform(-0.06, -0.03))
    return {
        "force_plate.a_m": float(rng.uniform(0.10, 0.22)),
        "force_plate.b_m": float(rng.uniform(0.10, 0.25)),
        "force_plate.az0_m": az0,
        "force_plate.anterior_axis": str(rng.choice(_AXES)),
        "force_plate.yaw_rad": float(np.deg2rad(rng.uniform(-3.0, 3.0))),
        "force_plate.top_plate_mass_kg": float(rng.uniform(5.0, 14.0)),
        "force_plate.top_plate_inertia_kgm2": _scaled(rng, fp.top_plate_inertia_kgm2, 0.5, 2.0),
        "force_plate.top_plate_com_x_m": float(rng.uniform(-0.01, 0.05)),
        "force_plate.top_plate_com_z_m": float(az0 * rng.uniform(0.3, 0.7)),
        "force_plate.vertical_natural_frequency_hz": float(rng.uniform(220.0, 400.0)),
        "force_plate.horizontal_natural_frequency_hz": float(rng.uniform(350.0, 600.0)),
        "force_plate.damping_ratio": float(rng.uniform(0.03, 0.10)),
        "hinge.inertia_kgm2": _scaled(rng, hinge.inertia_kgm2, 0.7, 1.5),
        "hinge.axis_anterior_m": float(rng.uniform(-0.04, 0.0)),
        "hinge.gravity_stiffness_nm_per_rad": _scaled(
            rng, hinge.gravity_stiffness_nm_per_rad, 0.5, 1.8
        ),
        "transmission.series_stiffness_nm_per_rad": _scaled(
            rng, p.transmission.series_stiffness_nm_per_rad, 0.7, 1.3
        ),
    }


def _servo(rng: np.random.Generator, p: PerturberatorParameters) -> dict[str, Any]:
    """Drive gains: a faster or slower, more or less damped position loop."""
    sv = p.servo
    return {
        "servo.position_gain_per_s": _scaled(rng, sv.position_gain_per_s, 0.75, 1.25),
        "servo.velocity_gain_nms_per_rad": _scaled(rng, sv.velocity_gain_nms_per_rad, 0.8, 1.2),
        "servo.velocity_integral_hz": _scaled(rng, sv.velocity_integral_hz, 0.7, 1.3),
        "servo.current_bandwidth_hz": float(rng.uniform(1500.0, 4000.0)),
    }


def _subject(rng: np.random.Generator, p: PerturberatorParameters) -> dict[str, Any]:
    """Subject geometry, gait and its variability, and the COP path after heel strike."""
    g = p.gait
    scale = float(rng.uniform(0.85, 1.15))
    rest = float(rng.uniform(0.01, 0.05))  # stance fraction at which the heel rocker is under way
    start = float(rng.uniform(-0.01, 0.01))  # where the COP starts relative to its heel point
    heel = float(rng.uniform(-0.002, 0.02))  # how far it has moved by then
    fractions = (0.0, rest, *g.cop_knots_fraction[2:])
    metres = (start, heel, *(scale * m for m in g.cop_knots_m[2:]))
    variability = {
        "gait.stance_sd_fraction": _scaled(rng, g.stance_sd_fraction, 0.5, 1.5),
        **{
            f"gait.{name}": _scaled(rng, getattr(g, name), 0.5, 2.0)
            for name in ("force_sd_fraction", "cop_sd_fraction")
        },
    }
    # the last window (475 ms + 100 ms, plus the onset latency) ends before heel-off even in a
    # stance 2 sd short: 0.78 s x 0.88 x (1 - 2 x 0.03) = 0.645 s
    stance = float(rng.uniform(*STANCE_RANGE_S))
    longest = stance * (1 + 3 * variability["gait.stance_sd_fraction"])
    duration = g.pre_contact_s + g.pre_contact_jitter_s + longest + 0.05  # covers every stance
    return variability | {
        "gait.body_mass_kg": float(rng.uniform(55.0, 100.0)),
        "gait.stance_s": stance,
        "gait.trial_duration_s": max(g.trial_duration_s, float(np.ceil(duration * 20) / 20)),
        "gait.loading_s": float(rng.uniform(0.06, 0.14)),
        "gait.placement_sd_m": _scaled(rng, g.placement_sd_m, 0.5, 2.0),
        "gait.cop_knots_fraction": fractions,
        "gait.cop_knots_m": metres,
        "geometry.ankle_height_m": float(rng.uniform(0.06, 0.11)),
        "geometry.heel_to_ankle_m": float(rng.uniform(0.03, 0.07)),
        "trigger.input_offset_sd_n": _scaled(rng, p.trigger.input_offset_sd_n, 0.5, 1.5),
    }


def _noise(scale: float, p: PerturberatorParameters) -> dict[str, Any]:
    """Every noise source of the set times ``scale``."""
    return {
        "force_plate.noise_n": p.force_plate.noise_n * scale,
        "force_plate.drift_n_per_s": p.force_plate.drift_n_per_s * scale,
        "goniometer.precision_small_rad": p.goniometer.precision_small_rad * scale,
        "goniometer.precision_full_scale_rad": p.goniometer.precision_full_scale_rad * scale,
        "bench.load_cell_noise_n": p.bench.load_cell_noise_n * scale,
    }


def _prosthetic(rng: np.random.Generator) -> dict[str, Any]:
    """A prosthetic foot: bench law falling linearly with the lever arm, damping, inertia."""
    heel = float(rng.uniform(900.0, 2200.0))
    toe = heel * float(rng.uniform(0.60, 0.95))
    return {
        "bench.stiffness_nm_per_rad": (heel, (heel + toe) / 2, toe),
        "prosthetic.damping_nms_per_rad": float(rng.uniform(1.0, 6.0)),
        "prosthetic.inertia_kgm2": float(rng.uniform(0.15, 0.45)),
    }


def _human(rng: np.random.Generator, growth: float) -> dict[str, Any]:
    """A human-like ankle: stiffness growing by ``growth`` per 150 ms (exponentially)."""
    mid = float(rng.uniform(2.5, 5.0))  # N·m/rad/kg at 300 ms after heel contact
    per_kg = mid * (1.0 + growth) ** ((_KNOTS_S - 0.3) / _GROWTH_SPAN_S)
    lever = float(rng.uniform(-5.0, 0.0)) if rng.random() < 0.5 else 0.0
    return {
        "human.knots_s": tuple(float(t) for t in _KNOTS_S),
        "human.stiffness_nm_per_rad_per_kg": tuple(float(k) for k in per_kg),
        "human.stiffness_lever_arm_gain_per_m": lever,
        "human.damping_nms_per_rad_per_kg": float(rng.uniform(0.015, 0.06)),
        "human.inertia_kgm2": float(rng.uniform(0.015, 0.05)),
    }
