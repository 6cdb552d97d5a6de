"""Plausibility checks of walking results: numbers that are physically implausible are flagged.

Each check returns a message naming the condition, the value and what was expected; the
analysis puts them in ``results.json`` (``warnings``), the command line prints them and the
report shows them. Nothing is silently corrected.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab.data.session import Session
from anklelab.ident.bench import EXTRAPOLATION_MARGIN_M, BenchStiffness, extrapolated
from anklelab.ident.irf import PlatformFilters
from anklelab.pipelines.walking.results import TimingPoint, sd

__all__ = [
    "ANGLE_GAIN_RANGE",
    "MAX_STIFFNESS_NM_PER_RAD",
    "MIN_STIFFNESS_NM_PER_RAD",
    "extrapolated_bench",
    "filter_summary",
    "plausibility",
    "walking_direction",
]

MAX_STIFFNESS_NM_PER_RAD = 20_000.0
"""Above this an ankle stiffness is implausible (the stiffest prosthetic feet and a human ankle
at push-off are well below 10 000 N·m/rad)."""
MIN_STIFFNESS_NM_PER_RAD = 20.0
"""Below this (yet positive) an ankle stiffness is implausible for a foot loaded in stance: a
human ankle's stiffness in walking is of the order of 1-10 N·m/rad per kg of body mass, so a few
hundred N·m/rad. A plate declared 90 degrees off reads a few N·m/rad (its ``dx`` is then the
COP across the foot)."""
LOADED_FRACTION = 0.5
""":func:`walking_direction` reads the COP where the vertical force exceeds this fraction of its
peak (the COP of a lightly loaded plate is noisy)."""
_DIRECTION_TRIALS = 50  # unperturbed trials read by walking_direction
_ACROSS_FACTOR = 2.0  # it warns when the COP travels this many times farther across than along
FOOT_LENGTH_M = 0.30
"""A lever arm farther than this from the heel-contact point lies beyond any foot's toes."""
_HEEL_MARGIN_M = 0.02  # a COP may sit slightly behind the heel-contact point
ANGLE_GAIN_RANGE = (0.5, 1.5)
"""The ankle angle's response over the plate's rotation (``angle_gain``) outside this range is
implausible for a foot standing on the plate: the shank's own motion and a hinge off the
ankle's axis move it by some percent, not by half; a goniometer recorded in degrees reads 57,
one of the wrong sign reads below 0."""


def plausibility(points: Sequence[TimingPoint], heel_to_ankle_m: float) -> list[str]:
    """Warnings about implausible estimates of the timing points.

    Parameters
    ----------
    points : sequence of TimingPoint
        The analysis' timing points.
    heel_to_ankle_m : float
        Anterior distance from the heel-contact COP to the ankle centre, m (the lever arm of
        the heel-contact point is minus this).

    Examples
    --------
    >>> from anklelab.pipelines.walking.results import Estimate
    >>> e = Estimate(40_018.0, 10.0, (39_000.0, 41_000.0))
    >>> tp = TimingPoint(100.0, "dorsi", 50, 200, 0.06, e, e, e, e, "constant", e, False)
    >>> plausibility([tp], 0.04)[0][:43]
    'dorsi/100: stiffness 40018 N·m/rad is above'
    """
    messages = []
    lowest, highest = -heel_to_ankle_m - _HEEL_MARGIN_M, FOOT_LENGTH_M - heel_to_ankle_m
    for tp in points:
        k = tp.stiffness.mean
        if not k > 0:
            messages.append(
                f"{tp.key}: stiffness {k:.0f} N·m/rad is not positive: check the plate's "
                "channel map and anterior_axis, the sign of the angles and the manifest's "
                "directions"
            )
        elif k > MAX_STIFFNESS_NM_PER_RAD:
            messages.append(
                f"{tp.key}: stiffness {k:.0f} N·m/rad is above {MAX_STIFFNESS_NM_PER_RAD:.0f}, "
                "implausible for an ankle: check the geometry's units (metres) and the "
                "channels for glitches"
            )
        elif k < MIN_STIFFNESS_NM_PER_RAD and not tp.stiffness.ci95[1] >= MIN_STIFFNESS_NM_PER_RAD:
            messages.append(
                f"{tp.key}: stiffness {k:.1f} N·m/rad is below {MIN_STIFFNESS_NM_PER_RAD:.0f}, "
                "implausible for an ankle loaded in stance: check anterior_axis (a plate "
                "declared 90 degrees off reads the COP across the foot), the plate's channel "
                "map and the angles' scale (radians)"
            )
        if not lowest <= tp.cop_m <= highest:
            messages.append(
                f"{tp.key}: the lever arm {100 * tp.cop_m:.1f} cm lies outside the foot (expected "
                f"{100 * lowest:.0f} to {100 * highest:.0f} cm from the ankle): check "
                "heel_to_ankle_m, the plate geometry and its channel map"
            )
        low, high = ANGLE_GAIN_RANGE
        if not low <= tp.angle_gain <= high and np.isfinite(tp.angle_gain):
            messages.append(
                f"{tp.key}: the ankle angle moves {tp.angle_gain:.2f} times the plate's rotation "
                f"under the perturbation (expected {low:g} to {high:g}: the foot stands on the "
                "plate): check the ankle angle's units (radians), sign and calibration"
            )
        if tp.vaf.mean < 0:
            messages.append(
                f"{tp.key}: the impedance model explains none of the torque (VAF "
                f"{tp.vaf.mean:.0f} %): the estimate is meaningless"
            )
    messages += _directions_disagree(points)
    return messages


def walking_direction(session: Session) -> list[str]:
    """A warning when the COP travels across the declared walking direction, not along it.

    Heel to toe, the COP of a loaded foot moves 10-20 cm along the walking direction and a few
    centimetres across it. In up to 50 unperturbed trials, the COP's range along and across the
    plate's ``anterior_axis`` is read where the vertical force exceeds
    :data:`LOADED_FRACTION` of the trial's peak (and the COP is defined); when the medians say
    it moves more than twice as far across, ``anterior_axis`` names the wrong plate axis (the
    sign is checked by the lever arms). On 72 clean-room and 60 twin sessions of every mounting
    the ratio was at most 0.18.
    """
    plate = session.info.force_plate
    trials = [t.recording for t in session.walking if not t.perturbed][:_DIRECTION_TRIALS]
    along, across = [], []
    with np.errstate(invalid="ignore"):  # NaN (no COP) is never loaded
        for recording in trials:
            load = plate.lab_load(recording.stack(plate.channels))
            peak = np.nanmax(load.grf_z, initial=0.0)
            loaded = (load.grf_z > LOADED_FRACTION * peak) & np.isfinite(load.cop_x + load.cop_y)
            if loaded.sum() < 2:
                continue
            along.append(np.ptp(load.cop_x[loaded]))
            across.append(np.ptp(load.cop_y[loaded]))
    if not along or np.median(across) <= _ACROSS_FACTOR * np.median(along):
        return []
    axis = plate.anterior_axis
    other = "y" if axis[1] == "x" else "x"
    return [
        f"walking/: the centre of pressure of the loaded foot travels "
        f"{100 * np.median(across):.1f} cm across the declared walking direction "
        f"(anterior_axis = {axis!r}) and {100 * np.median(along):.1f} cm along it (medians of "
        f"{len(along)} unperturbed trials): the walking direction is probably the plate's "
        f"{other} axis (anterior_axis '+{other}' or '-{other}'), and every lever arm and "
        "stiffness is then wrong"
    ]


def extrapolated_bench(points: Sequence[TimingPoint], bench: Sequence[BenchStiffness]) -> list[str]:
    """A warning when a dorsiflexion point's lever arm lies outside the bench tests' distances
    (:func:`~anklelab.ident.bench.extrapolated`): its bench stiffness (``validation``) is then
    the bench line extended, not a measurement."""
    if not bench:
        return []
    outside = [tp for tp in points if tp.direction == "dorsi" and extrapolated(bench, tp.cop_m)]
    if not outside:
        return []
    low, high = min(b.distance_m for b in bench), max(b.distance_m for b in bench)
    named = ", ".join(f"{tp.key} ({100 * tp.cop_m:.1f} cm)" for tp in outside)
    tested, read = (
        (f"distances ({100 * low:.1f} to {100 * high:.1f} cm)", "the bench line extended")
        if high > low
        else (f"single distance ({100 * low:.1f} cm)", "that distance's")
    )
    return [
        f"validation: the lever arms of {named} lie more than {1000 * EXTRAPOLATION_MARGIN_M:g} "
        f"mm outside the bench tests' actuator {tested}, so their bench stiffness is {read}, "
        "not measured there (bench_extrapolated in results.json); the lever arm itself rests "
        "on the COP at heel contact (see the walking guide)"
    ]


def _directions_disagree(points: Sequence[TimingPoint]) -> list[str]:
    """Dorsi- and plantarflexion stiffness at one timing point whose intervals do not overlap."""
    by_key = {tp.key: tp for tp in points}
    messages = []
    for tp in points:
        other = by_key.get(f"plantar/{tp.delay_ms:g}") if tp.direction == "dorsi" else None
        if other is None:
            continue
        (a_low, a_high), (b_low, b_high) = tp.stiffness.ci95, other.stiffness.ci95
        if a_high < b_low or b_high < a_low:
            messages.append(
                f"{tp.delay_ms:g} ms: dorsiflexion and plantarflexion stiffness disagree by more "
                f"than their 95 % intervals ({tp.stiffness.mean:.0f} [{a_low:.0f}, {a_high:.0f}] "
                f"vs {other.stiffness.mean:.0f} [{b_low:.0f}, {b_high:.0f}] N·m/rad): the ankle "
                "responds differently in the two directions, or a direction is mislabelled"
            )
    return messages


def filter_summary(
    filters: PlatformFilters,
    vaf: NDArray[np.float64],
    vaf_by_channel: NDArray[np.float64],
    held_out: bool,
) -> dict[str, Any]:
    """The ``platform_filters`` entry of ``results.json``: filter length and scores (VAF, %)."""
    scored = vaf.size > 0
    by_channel = vaf_by_channel.mean(axis=0) if scored else []
    return {
        "n_lags": int(filters.n_lags),
        "vaf_percent_mean": float(np.mean(vaf)) if scored else None,
        "vaf_percent_sd": sd(vaf) if scored else None,
        "vaf_percent_by_channel": dict(zip(filters.channels, map(float, by_channel), strict=False)),
        "held_out": held_out,
    }
