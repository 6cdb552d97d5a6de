"""Platform filters from the calibration trials: fitted on one, scored on the others."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from anklelab.data.session import Recording, Session
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import ForcePlate, GrfCopPlate
from anklelab.ident.irf import PlatformFilters
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.signals import advance, lowpass_min_samples

__all__ = [
    "check_calibration_lengths",
    "fit_platform_filters",
    "load_signals",
    "score_filters",
    "uncorrected_moment",
]


def fit_platform_filters(
    session: Session, settings: WalkingSettings | None = None
) -> tuple[PlatformFilters, NDArray[np.float64], NDArray[np.float64]]:
    """Fit platform filters on one calibration trial and score them on the others.

    Parameters
    ----------
    session : Session
        Needs at least one calibration recording.
    settings : WalkingSettings, optional
        Filter settings (``filter_inputs``, ``n_lags``, ``angle_lags``, ``filter_method``,
        ``calibration_fit_trial``, ``cutoff_hz``, ``filter_order``, ``derivative_window``).

    Returns
    -------
    filters : PlatformFilters
    vaf : ndarray, shape (n_held_out,)
        Pooled VAF per held-out trial, %. With a single calibration trial it is scored on
        itself (in-sample).
    vaf_by_channel : ndarray, shape (n_held_out, n_channels)
    """
    settings = settings or WalkingSettings()
    calibration = session.calibration
    if not calibration:
        raise SessionFormatError("calibration/: the session has no calibration trials")
    fit_index = settings.calibration_fit_trial
    if fit_index >= len(calibration):
        raise ParameterError(
            f"calibration_fit_trial: expected an index below {len(calibration)} "
            f"(calibration trials in the session), got {fit_index}"
        )
    fs = session.info.sample_rate_hz
    filters = PlatformFilters(
        inputs=settings.filter_inputs,
        n_lags=settings.n_lags,
        angle_lags=settings.angle_lags,
        method=settings.filter_method,
        cutoff_hz=settings.cutoff_hz,
        filter_order=settings.filter_order,
        derivative_window=settings.derivative_window,
        channels=session.info.force_plate.signals,
    )
    check_calibration_lengths(filters, calibration, fs)
    fit_rec = calibration[fit_index]
    plate = session.info.force_plate
    lead = settings.force_delay_samples(session.info)
    filters.fit(fit_rec["motor_angle"], load_signals(fit_rec, plate, lead), fs=fs)
    held_out = [rec for i, rec in enumerate(calibration) if i != fit_index] or [fit_rec]
    return (filters, *score_filters(filters, held_out, plate, lead))


def load_signals(recording: Recording, plate: ForcePlate, lead: float = 0.0) -> NDArray[np.float64]:
    """The signals the platform filters model: the plate's channels, or for GRF/COP data the
    sagittal signals (``plate.signals``), shape ``(n_signals, n_samples)``; moved ``lead``
    samples earlier when they were recorded that late (``force_delay_ms``)."""
    return advance(plate.load_signals(recording.stack(plate.channels)), lead)


def check_calibration_lengths(
    filters: PlatformFilters, recordings: Sequence[Recording], fs: float
) -> None:
    """Every calibration file must be long enough to fit and score ``filters`` (else name it).

    Fitting needs more samples than the filters have weights per channel, and the zero-phase
    low-pass needs more samples than its edge padding.
    """
    weights = sum(filters.lags)
    filtered = lowpass_min_samples(fs, filters.cutoff_hz, order=filters.filter_order)
    need = max(weights + 1, filtered, filters.derivative_window)
    for rec in recordings:
        if rec.n_samples < need:
            raise SessionFormatError(
                f"calibration/{rec.name}: {rec.n_samples} samples is too short for the "
                f"platform filters: every calibration trial needs at least {need} (more than "
                f"the filters' {weights} weights per channel, and at least {filtered} for the "
                f"order-{filters.filter_order} {filters.cutoff_hz:g} Hz zero-phase low-pass)"
            )


def score_filters(
    filters: PlatformFilters,
    recordings: Sequence[Recording],
    plate: ForcePlate,
    lead: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Held-out VAF of ``filters`` per recording: pooled ``(n,)`` and per channel
    ``(n, n_signals)``, % (the signals moved ``lead`` samples earlier, see
    :func:`load_signals`)."""
    scores = [filters.vaf(rec["motor_angle"], load_signals(rec, plate, lead)) for rec in recordings]
    pooled = np.array([s[0] for s in scores])
    return pooled, np.array([s[1] for s in scores]).reshape(len(scores), len(filters.channels))


def uncorrected_moment(session: Session) -> list[str]:
    """A warning when the platform filters cannot remove the plate's own moment.

    A ``grf_cop`` plate's moment signal ``grf_z * cop_x`` is 0 wherever the COP is empty, and
    processed exports leave it empty on an unloaded plate, so calibration trials with an empty
    COP teach the filters no moment: the platform's inertial and gravitational moment then stays
    in the ankle torque, a bias the intervals cannot bound (the measured effect is in the 'Lab
    data formats' guide).
    """
    plate = session.info.force_plate
    column = "cop_x_m" if plate.anterior_axis[1] == "x" else "cop_y_m"
    cop = [rec[column] for rec in session.calibration if column in rec.columns]
    if not isinstance(plate, GrfCopPlate) or not cop:
        return []
    empty = float(np.mean(np.isnan(np.concatenate(cop))))
    if empty <= 0.1:
        return []
    return [
        f"calibration/: the centre of pressure ({column}) is empty in {empty:.0%} of the "
        "calibration samples of this grf_cop session, so the platform filters cannot remove the "
        "platform's own moment from the ankle torque (it is taken as zero about "
        f"plate_centre_m = {list(plate.plate_centre_m)}): stiffness, damping and inertia carry "
        "a bias their intervals cannot bound, and are flagged as poorly determined (on "
        "simulated platforms the stiffness moved by up to 4.5 % and the inertia by a factor of "
        "0.65 to 3.6, depending on how the export blanks the COP; export the calibration "
        "trials' COP at every sample (import c3d: leave [plate] min_force_n at 0); see the "
        "guide 'Lab data formats')"
    ]
