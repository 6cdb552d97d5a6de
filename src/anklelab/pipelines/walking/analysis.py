"""The walking analysis as one call: session in, :class:`WalkingResults` out."""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np

from anklelab.data.session import Session
from anklelab.errors import AnklelabWarning, ParameterError, SessionFormatError
from anklelab.ident.bench import bench_stiffness
from anklelab.ident.irf import PlatformFilters
from anklelab.pipelines.walking.calibration import (
    check_calibration_lengths,
    fit_platform_filters,
    score_filters,
    uncorrected_moment,
)
from anklelab.pipelines.walking.change import pool_changes
from anklelab.pipelines.walking.checks import (
    extrapolated_bench,
    filter_summary,
    plausibility,
    walking_direction,
)
from anklelab.pipelines.walking.impedance import condition_order, estimate_timing_points
from anklelab.pipelines.walking.responses import condition_responses, outliers
from anklelab.pipelines.walking.results import WalkingResults
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import drop_summary, reason_kind, samples, stance_trials
from anklelab.signals import Trials

__all__ = ["STEPS", "analyze_walking"]

_SCREENED = ("torque", "angle", "grf_z")  # unperturbed stance channels screened for outliers
STEPS = ("platform filters", "walking trials", "ensembles and bootstrap", "bench")
"""Names of the pipeline's steps, in order (reported to the ``progress`` callback)."""


def analyze_walking(
    session: Session,
    settings: WalkingSettings | None = None,
    *,
    filters: PlatformFilters | None = None,
    progress: Callable[[str], None] | None = None,
    filters_ready: Callable[[PlatformFilters], None] | None = None,
) -> WalkingResults:
    """Ankle stiffness, damping and inertia per timing point and direction, with bootstrap.

    Parameters
    ----------
    session : Session
        Calibration (unless ``filters`` is given), walking and optionally bench recordings.
    settings : WalkingSettings, optional
        Analysis settings; paper 000's defaults when omitted.
    filters : PlatformFilters, optional
        Previously fitted platform filters (``anklelab identify platform-filters``); they are
        then scored on every calibration trial of ``session`` (if it has any).
    progress : callable, optional
        Called with each name of :data:`STEPS` as that step starts.
    filters_ready : callable, optional
        Called with the platform filters once they are fitted (or checked, when given), before
        the walking trials are processed: ``anklelab analyze`` starts drawing them meanwhile.

    Returns
    -------
    WalkingResults
    """
    settings = settings or WalkingSettings()
    if all(trial.perturbed for trial in session.walking):
        raise SessionFormatError(
            "walking/trials.csv: no unperturbed trials (perturbed = 0): their average stance is "
            "what the analysis subtracts from the perturbed trials (paper 000 interleaves them); "
            "a session needs some"
        )
    report = progress or (lambda step: None)
    fs = session.info.sample_rate_hz
    report(STEPS[0])
    if filters is None:
        filters, filter_vaf, filter_vaf_by_channel = fit_platform_filters(session, settings)
    else:
        plate = session.info.force_plate
        if not np.isclose(filters.fs_, fs) or tuple(filters.channels) != plate.signals:
            raise ParameterError(
                f"filters: fitted at {filters.fs_:g} Hz on channels {filters.channels}; the "
                f"session is sampled at {fs:g} Hz with channels {plate.signals}"
            )
        check_calibration_lengths(filters, session.calibration, fs)
        filter_vaf, filter_vaf_by_channel = score_filters(
            filters, session.calibration, plate, settings.force_delay_samples(session.info)
        )
    if filters_ready is not None:
        filters_ready(filters)
    report(STEPS[1])
    stance, mislabelled = stance_trials(session, settings, filters)
    unperturbed = stance["none"]
    drops = "; ".join(
        [*mislabelled, f"drop reasons: {drop_summary(stance.drop_log, session.walking)}"]
    )
    if len(unperturbed) == 0:
        raise SessionFormatError(
            "walking/trials.csv: no usable unperturbed trials, so the walking profile cannot be "
            f"removed; {drops}"
        )
    if len(unperturbed) == len(stance):
        raise SessionFormatError(
            f"walking/trials.csv: no usable perturbed trials, so no impedance can be estimated; "
            f"{drops}"
        )
    uncorrected = uncorrected_moment(session)
    for message in (*mislabelled, *uncorrected):
        warnings.warn(message, AnklelabWarning, stacklevel=2)
    report(STEPS[2])
    stance = _drop_unperturbed_outliers(stance, settings.outlier_mads)
    unperturbed = stance["none"]
    responses = {}
    for key in condition_order(stance):
        responses[key] = condition_responses(stance, key, unperturbed, settings)
        if dropped := responses[key].dropped:
            wild = np.isin(stance.selection, list(dropped))
            stance = stance.drop(wild, [dropped[p] for p in stance.selection[wild]])
    points = estimate_timing_points(
        responses, len(unperturbed), settings, settings.seed, bias_unknown=bool(uncorrected)
    )
    points = pool_changes(points, settings, samples(settings.window_ms, stance.fs) / stance.fs)
    report(STEPS[3])
    held_out = len(session.calibration) > 1
    bench = bench_stiffness(session.bench)
    notes = [
        *walking_direction(session),
        *plausibility(points, session.info.heel_to_ankle_m),
        *extrapolated_bench(points, bench),
    ]
    if not held_out:
        notes.append(
            "platform filters: the session has one calibration trial, so their VAF is scored on "
            "the trial they were fitted on (in-sample), not held out"
        )
    return WalkingResults(
        settings=settings,
        platform_filters=filter_summary(filters, filter_vaf, filter_vaf_by_channel, held_out),
        timing_points=points,
        bench=bench,
        drops=_drop_counts(stance),
        warnings=(*mislabelled, *uncorrected, *notes),
        filters=filters,
        filter_vaf=filter_vaf,
        filter_vaf_by_channel=filter_vaf_by_channel,
        stance=stance,
    )


def _drop_unperturbed_outliers(stance: Trials, limit: float) -> Trials:
    """Drop unperturbed trials whose stance departs from the others' median beyond ``limit``
    robust sd anywhere (one such trial would shift the nominal stance of every condition)."""
    unperturbed = stance.metadata["condition"] == "none"
    picks = [stance.ch_names.index(name) for name in _SCREENED]
    wild = np.zeros(len(stance), dtype=bool)
    wild[unperturbed] = outliers(stance.data[unperturbed][:, picks], limit)
    return stance.drop(
        wild,
        [
            f"its stance departs from the other unperturbed trials' median by more than "
            f"{limit:g} robust sd (a glitch?) [trial {trial}]"
            for trial in stance.metadata["trial"][wild]
        ],
    )


def _drop_counts(stance: Trials) -> dict[str, int]:
    """Dropped walking trials per kind of reason (per-trial details left out)."""
    kinds = [reason_kind(reasons[0]) for reasons in stance.drop_log if reasons]
    return {kind: kinds.count(kind) for kind in dict.fromkeys(kinds)}
