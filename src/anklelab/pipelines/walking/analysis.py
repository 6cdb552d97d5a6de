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
from anklelab.pipelines.walking.impedance import condition_order, timing_point
from anklelab.pipelines.walking.results import WalkingResults
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import drop_summary, stance_trials

__all__ = ["STEPS", "analyze_walking"]

STEPS = ("platform filters", "walking trials", "ensembles and bootstrap", "bench")
"""Names of the pipeline's steps, in order (reported to the ``progress`` callback)."""


def analyze_walking(
    session: Session,
    settings: WalkingSettings | None = None,
    *,
    filters: PlatformFilters | None = None,
    progress: Callable[[str], None] | None = None,
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

    Returns
    -------
    WalkingResults
    """
    settings = settings or WalkingSettings()
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
        filter_vaf, filter_vaf_by_channel = score_filters(filters, session.calibration, plate)
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
    notes = [*mislabelled, *uncorrected_moment(session)]
    for message in notes:
        warnings.warn(message, AnklelabWarning, stacklevel=2)
    report(STEPS[2])
    rng = np.random.default_rng(settings.seed)
    nominal = unperturbed.average()
    points = [
        timing_point(stance, key, nominal, len(unperturbed), settings, rng)
        for key in condition_order(stance)
    ]
    report(STEPS[3])
    return WalkingResults(
        settings=settings,
        filters=filters,
        filter_vaf=filter_vaf,
        filter_vaf_by_channel=filter_vaf_by_channel,
        timing_points=points,
        bench=bench_stiffness(session.bench),
        stance=stance,
        warnings=tuple(notes),
    )
