"""Impedance of every timing point and direction, with honest 95 % intervals.

From the condition's adjusted responses (:mod:`.responses`), ``T = I θ'' + b θ' + k(t) θ`` is
fitted to the average over all perturbed trials, with a constant stiffness and with one that
changes linearly within the window (``k + k₁ (t - t_c)``, ``t_c`` the θ²-weighted mean time, so
``k`` is the θ²-weighted stiffness in both; see :mod:`anklelab.ident.impedance`).

**Intervals.** The averages are resampled: perturbed trials drawn with replacement, and the
unperturbed trials' residual departures too (the nominal stance they were subtracted from is
itself an average with sampling error). The refitted values' spread over ``interval_reps``
resamples, scaled by Student's t, gives the random half-width (:func:`_estimate`); what the
data cannot pin down is added in quadrature (:func:`_systematic`: the timing between angle and
plate, the window, the coupler's twist correction and its damping). Paper 000's spread — the sd
over 60 % subsets drawn without replacement — is kept beside it as ``sd``, for comparison with
the paper; it covers random error only and is about 0.8 × the estimate's standard error.

**Which stiffness model** (``stiffness_model = "auto"``): the one with the smaller estimated
mean squared error of the headline stiffness (a focused information criterion, Claeskens &
Hjort 2003, JASA 98:900). The linear model is taken as nearly unbiased; the constant model's
squared bias is estimated as ``(k_const - k_lin)² - var(k_const - k_lin)`` and its variances
from the resamples. A constant stiffness wins where the stiffness hardly changes (it is more
precise); the linear one wherever the change biases the constant fit by more than that gain.

**Damping and inertia come from the linear model** with the automatic choice, whichever model
gives the stiffness (a model set by hand gives all three, as paper 000's constant one). A
stiffness that changes within the window, fitted as constant, puts its ``k' θ`` into them: the
prosthetic foot's stiffness falls as the COP moves forward, and on the twin with every artefact
off the constant model's damping read +1.41 N·m·s/rad high (true 3.0), the linear model's
+0.08. Where the stiffness is constant the linear model's damping and inertia are as unbiased
and only less precise, which their intervals show.

**One inertia for the session** (``inertia_model = "session"``). The foot and what moves with
it weigh the same at every timing point, and over a 100 ms window ``I θ''`` and ``k θ`` are
hard to tell apart: each point's own inertia takes up part of the acceleration's noise and
hands the stiffness the opposite part. The inertia is therefore the least-squares inertia of
one joint fit over the conditions, each with its own stiffness, damping (and slope), taken
from the model damping and inertia come from and weighted by its trials
(:func:`~anklelab.ident.inertia_terms`, summed over the conditions of two trials or more:
:class:`_SharedInertia`), and each condition is fitted around it. Each resample (the
conditions resampled independently), each sensitivity window and each systematic variant gets
its own joint inertia. The conditions' resamples are drawn independently also of the
unperturbed trials they share, which overstates those trials' part of the joint inertia's
spread a little (on one twin session its sd was 0.0125 against 0.0115 kg·m² with one shared
draw). ``"point"`` keeps paper 000's fit per point. How it does: docs/guide/walking-analysis.md.

**The angle's gain** (``angle_gain = "pooled"``). Each condition's angle is scaled to the gain
against the plate's rotation that the conditions share, as far as their gains differ by no
more than their noise explains (:mod:`.gain`): an electrogoniometer's gain changes from step to
step, and a condition's average keeps a few tenths of a percent of it, which the plate's
rotation, read by the encoder, does not have. Each resample and subset is scaled with its own
gain, before anything is fitted.

**The change within the window.** The linear model is always fitted; ``k₁ W / k`` is the
change of the stiffness over the window ``W`` as a fraction of it, with its interval, and the
diagnostic is judged on it (:func:`~.change.judge_change`). The analysis then takes the change
from the neighbouring timing points' stiffnesses where there are any, which is far more precise,
and judges it again (:mod:`.change`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from anklelab._student_t import t_quantile
from anklelab.ident.impedance import (
    ImpedanceFit,
    StiffnessModel,
    fit_impedance,
    impedance_torque,
    inertia_terms,
)
from anklelab.pipelines.walking.change import change_warning, judge_change
from anklelab.pipelines.walking.gain import angle_gains
from anklelab.pipelines.walking.responses import RESPONSE, Responses
from anklelab.pipelines.walking.results import Estimate, TimingPoint, sd
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import samples
from anklelab.signals import Trials, advance, bootstrap_weights

__all__ = ["DIRECTIONS", "condition_order", "estimate_timing_points"]

DIRECTIONS = ("dorsi", "plantar")
KINEMATICS = ("angle", "velocity", "acceleration")
_KIN = [RESPONSE.index(name) for name in KINEMATICS]
_TORQUE = RESPONSE.index("torque")
_TIME_ANGLE = RESPONSE.index("time_angle")
_ANGLES = [*_KIN, _TIME_ANGLE]  # the channels the angle's gain scales
_PLATE = RESPONSE.index("plate_angle")
_FULL = 0  # row of the all-trial average among the stacked averages
_SYSTEMATIC = ("stiffness", "damping", "inertia")  # quantities whose intervals are widened


def condition_order(stance: Trials) -> list[str]:
    """The perturbed conditions (``"dorsi/225"``), dorsiflexion first, by timing point."""
    keys = [c for c in stance.conditions() if c != "none"]
    delay = dict(zip(stance.metadata["condition"], stance.metadata["delay_ms"], strict=True))
    return sorted(keys, key=lambda c: (DIRECTIONS.index(c.split("/")[0]), delay[c]))


def _resampled(responses: Responses, n_reps: int, rng: np.random.Generator) -> NDArray[np.float64]:
    """Averages over ``n_reps`` resamples (with replacement) of perturbed and unperturbed
    trials, shape ``(n_reps, len(RESPONSE), n_window)``."""
    data, baseline = responses.perturbed.data, responses.unperturbed
    n_p, n_u = len(data), len(baseline)
    counts_p = _draw_counts(n_p, n_reps, rng) / n_p
    counts_u = _draw_counts(n_u, n_reps, rng) / n_u - 1.0 / n_u
    return np.tensordot(counts_p, data, axes=1) - np.tensordot(counts_u, baseline, axes=1)


def _draw_counts(n: int, n_reps: int, rng: np.random.Generator) -> NDArray[np.int64]:
    """How often each of ``n`` items is drawn in each of ``n_reps`` draws of ``n`` with
    replacement, shape ``(n_reps, n)`` (a multinomial draw, ten times faster than
    ``Generator.multinomial``)."""
    draws = rng.integers(0, n, (n_reps, n)) + n * np.arange(n_reps)[:, None]
    return np.bincount(draws.ravel(), minlength=n_reps * n).reshape(n_reps, n)


def _fit(
    averages: NDArray[np.float64],
    lengths: list[int] | None,
    model: StiffnessModel,
    fs: float,
    inertia: NDArray[np.float64] | None = None,
) -> ImpedanceFit:
    """The impedance of stacked response averages (channels :data:`RESPONSE`), around a known
    ``inertia`` (shaped like the fit's fields) if given."""
    return fit_impedance(
        averages[:, _KIN],
        averages[:, _TORQUE],
        lengths=lengths,
        stiffness_model=model,
        fs=fs,
        time_angle=averages[:, _TIME_ANGLE],
        inertia=inertia,
    )


def _focused_choice(constant: NDArray[np.float64], linear: NDArray[np.float64]) -> StiffnessModel:
    """The model whose stiffness has the smaller estimated mean squared error.

    ``constant`` and ``linear`` hold the all-trial estimate first, then the resampled ones.
    """
    bias2 = (constant[_FULL] - linear[_FULL]) ** 2 - np.var(constant[1:] - linear[1:], ddof=1)
    mse_constant = max(float(bias2), 0.0) + np.var(constant[1:], ddof=1)
    return "linear" if np.var(linear[1:], ddof=1) < mse_constant else "constant"


@dataclass(frozen=True)
class _Condition:
    """One condition's responses, their stacked averages (over all perturbed trials
    (:data:`_FULL`), then ``interval_reps`` resamples, then paper 000's subsets; the angle's
    gain pooled, :mod:`.gain`), the angle's ``gain`` (measured, pooled) and the all-trial
    average's ``variants`` behind the systematic half-width (:func:`_variants`; the first
    ``timing`` of them shift the timing)."""

    key: str
    responses: Responses
    averages: NDArray[np.float64]
    gain: tuple[float, float]
    variants: NDArray[np.float64]
    timing: int


def _variants(
    full: NDArray[np.float64], twist: NDArray[np.float64], n: int, shift: int, lag: float, fs: float
) -> tuple[NDArray[np.float64], int]:
    """The all-trial average ``full`` (channels :data:`RESPONSE`) over the first ``n`` samples
    under what the data cannot pin down (see :func:`_systematic`), stacked: the torque ``shift``
    samples later and earlier than the kinematics (when the average is long enough), without
    the coupler's twist correction (``twist``, :class:`~.responses.Responses`), and with it
    taken ``lag`` samples earlier and later. Also returns how many come first for the timing
    (0 or 2)."""
    out = []
    if shift and full.shape[-1] >= n + shift:
        for lead in (shift, -shift):  # torque later / earlier than the kinematics
            k0, t0 = (0, lead) if lead > 0 else (-lead, 0)
            shifted = full[:, k0 : k0 + n].copy()
            shifted[_TORQUE] = full[_TORQUE, t0 : t0 + n]
            shifted[_TIME_ANGLE] -= k0 / fs * shifted[_KIN[0]]  # time from the window start
            out.append(shifted)
    timing = len(out)
    untwisted = full[:, :n].copy()
    untwisted[_TORQUE] += twist[:n]
    out.append(untwisted)
    for early in (lag, -lag):  # the correction taken `lag` samples earlier and later
        moved = full[:, :n].copy()
        moved[_TORQUE] += (twist - advance(twist, early))[:n]
        out.append(moved)
    return np.stack(out), timing


@dataclass(frozen=True)
class _SharedInertia:
    """The session's one inertia (kg·m²), fitted jointly over the conditions, each with its own
    stiffness and damping: for each stacked average (``rows``), for the all-trial averages over
    each sensitivity window (``windows``) and under each of the conditions' ``variants``;
    ``scale``, the factor of its resamples' sd in its interval (NaN: none)."""

    rows: NDArray[np.float64]
    windows: NDArray[np.float64]
    variants: NDArray[np.float64]
    scale: float

    @classmethod
    def fit(
        cls,
        conditions: list[_Condition],
        model: StiffnessModel,
        lengths: list[int],
        fs: float,
        reps: int,
    ) -> _SharedInertia:
        """Sum the conditions' shares (:func:`~anklelab.ident.inertia_terms`, with ``model``),
        each weighted by its perturbed trials (its average's noise falls as 1 / n).

        Only conditions of two trials or more, with finite averages, take part: a single
        trial's resamples do not spread at all, and one bad condition must not spoil every
        point. Each one's ``reps`` interval resamples are widened about its all-trial average by
        ``sqrt(n / (n - 1))`` before the pooling (a resample of ``n`` trials underestimates the
        spread of their mean by ``(n - 1) / n`` in variance, see :func:`_estimate`), and the
        interval takes Student's t with the trials less the conditions as degrees of freedom.
        With no such condition the inertia comes from all of them, without an interval.
        """
        n = lengths[0]
        counts = [len(c.responses.perturbed) for c in conditions]
        members = [
            (c, k) for c, k in zip(conditions, counts, strict=True)
            if k >= 2 and np.isfinite(c.averages).all()
        ]  # fmt: skip
        pooled = members or list(zip(conditions, counts, strict=True))

        def shared(stacks: list[NDArray[np.float64]], windows: list[int] | None = None) -> NDArray:
            terms = [
                inertia_terms(
                    stack[:, _KIN],
                    stack[:, _TORQUE],
                    windows,
                    stiffness_model=model,
                    fs=fs,
                    time_angle=stack[:, _TIME_ANGLE],
                )
                for stack in stacks
            ]
            weights = [k for _, k in pooled]
            numerator = sum(w * t.numerator for w, t in zip(weights, terms, strict=True))
            denominator = sum(w * t.denominator for w, t in zip(weights, terms, strict=True))
            return np.asarray(numerator / denominator)

        def widened(condition: _Condition, k: int) -> NDArray[np.float64]:
            stack = condition.averages[..., :n].copy()
            if k >= 2:
                resamples = stack[1 : 1 + reps]
                resamples += (resamples - stack[_FULL]) * (np.sqrt(k / (k - 1)) - 1)
            return stack

        fulls = [c.averages[_FULL : _FULL + 1] for c, _ in pooled]
        dof = sum(k for _, k in members) - len(members)
        return cls(
            rows=shared([widened(c, k) for c, k in pooled]),
            windows=shared(fulls, lengths[1:])[:, 0] if len(lengths) > 1 else np.zeros(0),
            variants=shared([c.variants for c, _ in pooled]),
            scale=t_quantile(dof, 0.975) if members and dof >= 1 else np.nan,
        )


def _systematic(
    variants: ImpedanceFit, timing: int, centre: dict[str, float], by_window: ImpedanceFit | None
) -> dict[str, float]:
    """How far each all-trial estimate (``centre``) moves under what the data cannot pin down.

    ``variants`` is the fit of :func:`_variants` (``timing`` timing variants first).
    Three independent sources, added in quadrature:

    - *Timing and window*: the largest move when the torque of the all-trial average is
      shifted by ``±timing_uncertainty_ms`` against the kinematics (the timing between the
      encoder and the plate's channels, anti-alias filters and converter skew included, is
      known only to about a sample: ``θ(t - δ) ≈ θ - δ θ'`` moves damping by ``k δ`` and
      inertia by ``b δ``), and, for damping and inertia, across the sensitivity windows' fits
      ``by_window`` (a stiffness that changes within the window leaks into them). The
      stiffness's change between windows is a real change over time, not an error, and is left
      out.
    - *The coupler's twist*: the move when the torque is taken without the twist correction
      (``twist_torque`` added, :class:`~.responses.Responses`).
      The correction is quasi-static, with the paper's coupler stiffness; the coupler's own
      damping and the plate's resonance on it are left out. On the clean-room generator, whose
      couplers are 0.75-1.3 times as stiff and damped, the error left after it was 0.8 times
      (stiffness) to 1.3-1.8 times (damping) the correction's own size (medians), so its whole
      size counts.
    - *The coupler's damping*: the larger move when the twist correction is taken
      ``coupler_lag_ms`` earlier or later. A coupler of damping ``c`` twists as
      ``T / (K + c s)``, behind ``T / K`` by ``c / K``, which the correction takes as
      ``coupler_lag_ms``; no lab knows ``c``, and on a stiff foot the damping estimate is most
      sensitive to it.

    With the session's shared inertia each variant's fit takes that variant's shared inertia,
    so the inertia's own moves are the shared one's. Returns the systematic half-width per
    quantity (``stiffness``, ``damping``, ``inertia``).
    """
    moves = {}
    for name, value in centre.items():
        moved = np.ravel(getattr(variants, name)) - value
        timing_moves = [np.zeros(1), moved[:timing]]
        if name != "stiffness" and by_window is not None:
            timing_moves.append(np.ravel(getattr(by_window, name)) - value)
        largest = np.abs(np.concatenate(timing_moves)).max()
        twist_size = moved[timing]
        twist_lag = np.abs(moved[timing + 1 :]).max()
        moves[name] = float(np.linalg.norm([largest, twist_size, twist_lag]))
    return moves


def _interval_scale(n_trials: int) -> float:
    """The factor of the resamples' sd in an interval over ``n_trials`` perturbed trials:
    ``t(n-1, 0.975) × sqrt(n / (n-1))`` (NaN below two trials). A resample of few trials
    underestimates the spread of their mean (by ``(n-1)/n`` in variance), and the tails are
    Student's, not normal (1.58× the normal interval for 5 trials, 1.04× for 50)."""
    if n_trials < 2:
        return np.nan
    return t_quantile(n_trials - 1, 0.975) * float(np.sqrt(n_trials / (n_trials - 1)))


def _estimate(
    values: NDArray[np.float64],
    n_reps: int,
    paper: slice,
    scale: float,
    systematic: float = 0.0,
    bias_unknown: bool = False,
    moved: float = 0.0,
) -> Estimate:
    """An :class:`Estimate` from stacked values: all-trial, ``n_reps`` resamples, paper subsets.

    The interval is the all-trial value ± ``scale × s`` (:func:`_interval_scale`), ``s`` the
    resamples' sd; an sd settles with far fewer resamples than the 2.5 and 97.5 percentiles do.
    A ``systematic`` half-width (what the data cannot pin down, :func:`_systematic`) is added in
    quadrature, and what a correction ``moved`` the estimate and may have got wrong, in full
    (:func:`_timing_point`: the pooled angle gain); a bias that nothing bounds is flagged
    (``bias_unknown``). No interval with a NaN ``scale`` or fewer than two resamples.
    """
    centre, resampled, subsets = float(values[_FULL]), values[1 : 1 + n_reps], values[paper]
    interval = (np.nan, np.nan)
    if n_reps >= 2 and np.isfinite(scale):
        half = float(np.hypot(scale * sd(resampled), systematic)) + moved
        interval = (centre - half, centre + half)
    return Estimate(centre, sd(subsets), interval, subsets, bias_unknown=bias_unknown)


def estimate_timing_points(
    responses: Mapping[str, Responses],
    n_unperturbed: int,
    settings: WalkingSettings,
    seed: int | np.random.Generator,
    *,
    bias_unknown: bool = False,
) -> list[TimingPoint]:
    """Impedance of every condition, in the order given.

    Parameters
    ----------
    responses : mapping of str to Responses
        Each condition's (``"dorsi/225"``) responses (:func:`~.responses.condition_responses`).
    n_unperturbed : int
        Unperturbed trials behind the nominal stance.
    settings : WalkingSettings
        Windows, stiffness and inertia models, resampling and diagnostic settings.
    seed : int or numpy.random.Generator
        Draws the resamples and subsets, condition by condition (a Generator continues its
        stream).
    bias_unknown : bool
        The torque carries a bias the intervals cannot bound (the platform's own moment left in
        it, :func:`~.calibration.uncorrected_moment`): the impedance, its slope and its change
        are flagged (poorly determined), before the change is judged.
    """
    if not responses:
        return []
    rng = np.random.default_rng(seed)
    fs = next(iter(responses.values())).perturbed.fs
    lengths = [samples(w, fs) for w in settings.windows_ms()]
    shift = round(settings.timing_uncertainty_ms * fs / 1000.0)
    lag = settings.coupler_lag_ms * fs / 1000.0
    stacks = [_stacked(condition, settings, rng) for condition in responses.values()]
    gains, factors = angle_gains(
        np.stack([stack[:, _KIN[0], : lengths[0]] for stack in stacks]),
        np.stack([stack[:, _PLATE, : lengths[0]] for stack in stacks]),
        np.array([len(condition.perturbed) for condition in responses.values()]),
        settings.interval_reps,
        pool=settings.angle_gain == "pooled",
    )
    conditions = []
    for c, (key, condition) in enumerate(responses.items()):
        averages = stacks[c]
        averages[:, _ANGLES] *= factors[c][:, None, None]
        variants = _variants(averages[_FULL], condition.twist_torque, lengths[0], shift, lag, fs)
        gain = (float(gains.measured[c]), float(gains.pooled[c]))
        conditions.append(_Condition(key, condition, averages, gain, *variants))
    shared = None
    if settings.inertia_model == "session":
        model = _rest_model(settings)
        shared = _SharedInertia.fit(conditions, model, lengths, fs, settings.interval_reps)
    return [
        _timing_point(condition, n_unperturbed, settings, lengths, shared, bias_unknown)
        for condition in conditions
    ]


def _stacked(
    responses: Responses, settings: WalkingSettings, rng: np.random.Generator
) -> NDArray[np.float64]:
    """The condition's averages: over all perturbed trials, over ``interval_reps`` resamples
    (:func:`_resampled`) and over paper 000's subsets."""
    trials = responses.perturbed
    subsets = bootstrap_weights(
        len(trials), settings.bootstrap_reps, settings.bootstrap_fraction, random_state=rng
    )
    return np.concatenate(
        [
            trials.average()[None],
            _resampled(responses, settings.interval_reps, rng),
            np.tensordot(subsets, trials.data, axes=1),
        ]
    )


def _rest_model(settings: WalkingSettings) -> StiffnessModel:
    """The model damping and inertia come from: the linear one with the automatic choice,
    whichever gives the stiffness (a stiffness that changes within the window, fitted as
    constant, puts its ``k' θ`` into them; module docstring); a model set by hand gives all
    three, as paper 000's constant model does."""
    return "linear" if settings.stiffness_model == "auto" else settings.stiffness_model


def _timing_point(
    condition: _Condition,
    n_unperturbed: int,
    settings: WalkingSettings,
    lengths: list[int],
    shared: _SharedInertia | None,
    bias_unknown: bool,
) -> TimingPoint:
    """One condition's :class:`TimingPoint` (arguments as :func:`estimate_timing_points`;
    ``lengths``: the windows' lengths, samples; ``shared``: the session's inertia, or None for
    the point's own)."""
    key, responses, averages = condition.key, condition.responses, condition.averages
    trials = responses.perturbed
    fs = trials.fs
    windows = settings.windows_ms()
    n = lengths[0]
    reps = settings.interval_reps
    paper = slice(1 + reps, None)
    main = averages[..., :n]  # every resample fits the analysis window only
    rows = None if shared is None else shared.rows[None]
    constant = _fit(main, [n], "constant", fs, rows)
    linear = _fit(main, [n], "linear", fs, rows)
    model: StiffnessModel = (
        _focused_choice(constant.stiffness[0][: 1 + reps], linear.stiffness[0][: 1 + reps])
        if settings.stiffness_model == "auto"
        else settings.stiffness_model
    )
    window_s = n / fs
    change = linear.stiffness_slope[0] * window_s / linear.stiffness[0]
    scale = _interval_scale(len(trials))
    change_estimate = _estimate(change, reps, paper, scale, bias_unknown=bias_unknown)
    full = averages[_FULL : _FULL + 1]
    rest = _rest_model(settings)
    source: dict[str, StiffnessModel] = {
        "stiffness": model,
        "damping": rest,
        "inertia": rest,
        "vaf": model,
    }
    fitted = {"constant": constant, "linear": linear}
    at_windows = None if shared is None else shared.windows[:, None]
    window_fits = {  # each model's fits over the sensitivity windows
        name: _fit(full, lengths[1:], name, fs, at_windows) if len(lengths) > 1 else None
        for name in dict.fromkeys(source.values())
    }
    at_variants = None if shared is None else shared.variants
    systematic: dict[str, float] = {}
    for name, windows_fit in window_fits.items():
        centre = {
            q: float(getattr(fitted[name], q)[0][_FULL]) for q in _SYSTEMATIC if source[q] == name
        }
        variant_fits = _fit(condition.variants, None, name, fs, at_variants)
        systematic |= _systematic(variant_fits, condition.timing, centre, windows_fit)
    # the pooled angle gain's move (:mod:`.gain`), in full: the data cannot tell how much of it
    # was noise and how much a true difference between the conditions; the session's inertia
    # pools every condition's angle, so its own spread carries theirs
    measured, pooled = condition.gain
    moved = abs(1.0 - pooled / measured) if np.isfinite(measured) and pooled != measured else 0.0
    scaled = ("stiffness", "damping") if shared is not None else _SYSTEMATIC
    pooling = {q: moved * abs(float(getattr(fitted[source[q]], q)[0][_FULL])) for q in scaled}
    scales = {q: scale for q in source}
    if shared is not None:  # the session's trials behind it
        scales["inertia"] = shared.scale
    estimates = {
        q: _estimate(
            getattr(fitted[name], q)[0],
            reps,
            paper,
            scales[q],
            systematic.get(q, 0.0),
            bias_unknown and q in _SYSTEMATIC,
            pooling.get(q, 0.0),
        )
        for q, name in source.items()
    }
    vaf = estimates["vaf"]  # a VAF cannot exceed 100 %
    estimates["vaf"] = replace(vaf, ci95=(vaf.ci95[0], min(vaf.ci95[1], 100.0)))
    analysis = ImpedanceFit(*(values[0][paper] for values in fitted[model]))
    subset_avg = averages[paper]
    weight = averages[_FULL, RESPONSE.index("angle"), :n] ** 2
    determined = not estimates["stiffness"].poorly_determined
    probability, changes, verdict = judge_change(change_estimate, len(trials), determined, settings)
    model_windows = window_fits[model]
    point = TimingPoint(
        delay_ms=float(key.split("/")[1]),
        direction=key.split("/")[0],
        n_perturbed=len(trials),
        n_unperturbed=n_unperturbed,
        cop_m=float(weight @ responses.nominal_dx[:n] / weight.sum()),
        **estimates,
        stiffness_model=model,
        stiffness_change=change_estimate,
        stiffness_changes=changes,
        stiffness_change_probability=probability,
        stiffness_change_verdict=verdict,
        stiffness_slope=(
            _estimate(
                linear.stiffness_slope[0],
                reps,
                paper,
                scale,
                bias_unknown=bias_unknown,
                moved=moved * abs(float(linear.stiffness_slope[0][_FULL])),
            )
            if model == "linear"
            else None
        ),
        window_stiffness={}
        if model_windows is None
        else {
            f"{w:g}": float(k)
            for w, k in zip(windows[1:], model_windows.stiffness[:, 0], strict=True)
        },
        adjustment_explained=responses.explained,
        angle_gain=condition.gain[0],
        angle_gain_pooled=condition.gain[1],
        warnings=_stiffness_warning(key, estimates["stiffness"]),
        onset_ms=trials.metadata["onset_ms"],
        time_s=np.arange(n) / fs,
        angle=subset_avg[:, RESPONSE.index("angle"), :n],
        torque=subset_avg[:, _TORQUE, :n],
        model_torque=impedance_torque(
            analysis, subset_avg[:, _KIN, :n], fs, time_angle=subset_avg[:, _TIME_ANGLE, :n]
        ),
    )
    warning = change_warning(point, settings.change_threshold, window_s)
    return replace(point, warnings=(*point.warnings, warning)) if warning else point


def _stiffness_warning(key: str, stiffness: Estimate) -> tuple[str, ...]:
    """The warning a poorly determined stiffness needs (damping and inertia that the data
    determine poorly are flagged by their ``poorly_determined`` key, not warned about: they
    often are, and the headline is the stiffness)."""
    if not stiffness.poorly_determined:
        return ()
    return (
        f"{key}: stiffness is poorly determined by these data: 95 % interval "
        f"[{stiffness.ci95[0]:.3g}, {stiffness.ci95[1]:.3g}] around {stiffness.mean:.3g}; do not "
        "read it as a precise number",
    )
