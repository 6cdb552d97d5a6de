"""Walking trials to heel-contact-aligned stance trials, every dropped trial logged with why.

Each walking file is zeroed over its unloaded start; heel contact is detected from the vertical
force; the platform's own force transients (predicted by the platform filters from the motor
angle, and for the coupler's twist under the foot's torque by their memoryless gains) are
subtracted from the low-passed sagittal load; the COP, the lever arm ``dx`` and the ankle torque
are computed with the COP zeroed at heel contact (where it is read from the unfiltered load, less
the own forces of the coupler's twist under the heel's strike); the ankle angle's derivatives
come from a local quadratic fit; and the perturbation onset is detected from the motor angle.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from anklelab.data.session import Session, SessionInfo, WalkingTrial
from anklelab.errors import SessionFormatError
from anklelab.forceplate import (
    SagittalLoad,
    ankle_torque,
    cop_from_moment,
    sagittal_matrix,
)
from anklelab.ident.irf import PlatformFilters
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.signals import (
    Trials,
    advance,
    epoch,
    heel_contact,
    kinematics,
    lowpass,
    lowpass_min_samples,
    perturbation_onset,
    stack_recordings,
)

__all__ = ["STANCE_CHANNELS", "drop_summary", "reason_kind", "samples", "stance_trials"]

STANCE_CHANNELS = (
    "angle",
    "velocity",
    "acceleration",
    "torque",
    "dx",
    "grf_z",
    "motor_angle",
    "torque_raw",
    "grf_z_raw",
    "angle_raw",
    "time_angle",
    "torque_untwisted",
    "plate_angle",
)
"""Channels of the heel-contact-aligned stance trials (rad, rad/s, rad/s², N·m, m, N, rad; the
``_raw`` ones unfiltered and uncorrected for the platform, N·m, N, rad; ``time_angle``, rad·s,
is the time since heel contact times the unfiltered angle, low-passed like the angle: the
regressor of a stiffness that changes in time, see :func:`anklelab.ident.fit_impedance`;
``torque_untwisted``, N·m, is ``torque`` without the coupler's twist, the plate's own forces
predicted from the motor angle alone; ``plate_angle``, rad, is the plate's rotation, the motor
angle low-passed like the angle less the coupler's twist: the reference the ankle angle's gain
is measured against, see :mod:`anklelab.pipelines.walking.gain`)."""
_MISMATCH = "onset differs from the manifest's delay_ms"


def condition(trial: WalkingTrial) -> str:
    return f"{trial.direction}/{trial.delay_ms:g}" if trial.perturbed else "none"


def _first_reasons(
    checks: Sequence[tuple[NDArray[np.bool_], str | Sequence[str]]], n: int
) -> list[tuple[str, ...]]:
    """Per trial, the first failing check's reason (later checks assume the earlier passed).

    A check's reason is one text for every trial, or one per trial.
    """
    log: list[tuple[str, ...]] = [()] * n
    for mask, reason in checks:
        for i in np.flatnonzero(mask).tolist():
            log[i] = log[i] or (reason if isinstance(reason, str) else reason[i],)
    return log


def reason_kind(reason: str) -> str:
    """A drop reason without its per-trial details (the part in square brackets at its end)."""
    return reason.split(" [", 1)[0]


def _mismatch_reasons(
    walking: Sequence[WalkingTrial], onset_ms: NDArray[np.float64], tolerance_ms: float
) -> list[str]:
    """Per trial, the drop reason for an onset that disagrees with the manifest's delay_ms."""
    return [
        f"{_MISMATCH} by more than {tolerance_ms:g} ms [trial {w.trial}: detected "
        f"{t:.1f} ms after heel contact, manifest delay_ms {w.delay_ms:g}]"
        for w, t in zip(walking, onset_ms, strict=True)
    ]


def _mislabelled_conditions(
    walking: Sequence[WalkingTrial],
    log: Sequence[tuple[str, ...]],
    onset_ms: NDArray[np.float64],
    tolerance_ms: float,
) -> list[str]:
    """A message for each manifest condition that lost every trial, some to the onset check.

    Says how many trials the check dropped, where their onsets were (median), and which of the
    manifest's timing points of the same direction that median is nearest to.
    """
    conditions = np.array([condition(w) for w in walking])
    delay = np.array([w.delay_ms for w in walking], dtype=float)
    mismatch = np.array([bool(r) and reason_kind(r[0]).startswith(_MISMATCH) for r in log])
    kept = np.array([not r for r in log])
    messages = []
    for key in dict.fromkeys(conditions[mismatch]):
        members = conditions == key
        if kept[members].any():
            continue
        direction, labelled = key.split("/")[0], delay[members][0]
        timing = np.unique(delay[np.char.startswith(conditions, f"{direction}/")])
        timing = timing[timing != labelled]
        median = float(np.median(onset_ms[members & mismatch]))
        nearest = timing[np.argmin(np.abs(timing - median))] if timing.size else np.inf
        hint = (
            f"they fit {direction}/{nearest:g}: are the delay_ms labels swapped?"
            if abs(nearest - median) <= tolerance_ms
            else "are the delay_ms labels wrong?"
        )
        messages.append(
            f"walking/trials.csv: {key}: all {members.sum()} perturbed trials were dropped, "
            f"{(members & mismatch).sum()} of them because the onset detected in the motor angle "
            f"(median {median:.0f} ms after heel contact) differs from the manifest's "
            f"delay_ms = {labelled:g} by more than onset_tolerance_ms = "
            f"{tolerance_ms:g} ms; {hint}"
        )
    return messages


_BLOCK_BYTES = 8 * 2**20
"""Trials are filtered in blocks of at most about this many bytes of stacked raw samples, so
that the temporaries stay bounded however many trials a session holds (only the stance is
kept)."""
_THREADS = 2
"""Blocks processed at once, in threads (NumPy releases the lock for its array work): at least
this many blocks, whatever the machine, so that the results never depend on its cores. On the
paper-size session two threads over blocks of 8 MiB took the analysis from 1.27 to 1.05 s; on
3 200 trials the analysis's peak memory stayed where one thread over blocks of 64 MiB left it
(1.12 against 1.13 GiB; 32 MiB blocks took 1.27 GiB)."""


def stance_trials(
    session: Session, settings: WalkingSettings, filters: PlatformFilters
) -> tuple[Trials, list[str]]:
    """Walking trials to heel-contact-aligned stance trials, every drop logged with its reason.

    Also returns a message for each manifest condition whose trials were all dropped, some
    because their detected onsets disagree with the manifest's ``delay_ms``.
    """
    info, walking = session.info, session.walking
    fs = info.sample_rate_hz
    if not walking:
        raise SessionFormatError("walking/trials.csv: the session has no walking trials")
    lengths = np.array([w.recording.n_samples for w in walking], dtype=np.int64)
    n_base = max(1, round(settings.baseline_ms * fs / 1000.0))
    n_filter = lowpass_min_samples(fs, settings.cutoff_hz, order=settings.filter_order)
    base, thr = f"{settings.baseline_ms:g} ms", f"{settings.heel_contact_threshold_n:g} N"
    too_short = [
        (lengths <= n_base, f"recording shorter than the {base} baseline"),
        (lengths < n_filter, f"recording shorter than the {n_filter} samples the low-pass needs"),
    ]
    if all(_first_reasons(too_short, len(walking))):
        raise SessionFormatError(
            "walking/trials.csv: no walking trial is long enough to analyse: "
            + drop_summary(_first_reasons(too_short, len(walking)), walking)
        )
    perturbed = np.array([w.perturbed for w in walking])
    delay = np.array([w.delay_ms for w in walking], dtype=float)
    sign = np.array([{"dorsi": 1.0, "plantar": -1.0}.get(w.direction, 0.0) for w in walking])
    tolerance = settings.onset_tolerance_ms
    # a kept trial's onset lies within the tolerance of its delay, so no stance is longer
    latest = np.max(delay[perturbed & np.isfinite(delay)], initial=0.0) + tolerance
    n_stance = math.ceil(latest * fs / 1000.0) + 1 + samples(max(settings.windows_ms()), fs)
    width = int(lengths.max())  # every block padded alike: the filtering sees the same rows
    trial_bytes = 8 * (2 + len(info.force_plate.channels)) * width
    n_blocks = max(_THREADS, math.ceil(len(walking) * trial_bytes / _BLOCK_BYTES))
    per_block = math.ceil(len(walking) / n_blocks)

    def block_from(start: int) -> _StanceBlock:
        trials = slice(start, start + per_block)
        return _stance_block(session, trials, settings, filters, width, n_stance)

    with ThreadPoolExecutor(min(_THREADS, os.cpu_count() or 1)) as pool:
        blocks = list(pool.map(block_from, range(0, len(walking), per_block)))
    block = _StanceBlock(*(np.concatenate(parts) for parts in zip(*blocks, strict=True)))
    found = np.isfinite(block.onset)
    onset = np.where(found, block.onset, block.event)
    offset = np.round(onset).astype(np.int64) - block.event
    onset_ms = (onset - block.event) / fs * 1000.0
    log = _first_reasons(
        [
            *too_short,
            (block.contact < 0, f"no heel contact: vertical force never held {thr}"),
            (
                block.contact <= n_base,
                f"heel contact within the first {base} (no unloaded baseline)",
            ),
            (~np.isfinite(block.cop0), "centre of pressure undefined at heel contact"),
            (perturbed & np.isnan(delay), "perturbed trial without delay_ms"),
            (perturbed & (sign == 0), "perturbed trial without a direction (dorsi or plantar)"),
            (perturbed & ~found, "no perturbation found in the motor angle"),
            (
                perturbed & (np.sign(block.amplitude) != sign),
                "motor moved against the manifest direction",
            ),
            (perturbed & (onset < block.event), "perturbation began before heel contact"),
            (
                perturbed & (np.abs(onset_ms - delay) > tolerance),
                _mismatch_reasons(walking, onset_ms, tolerance),
            ),
            (~perturbed & found, "motor angle moved in an unperturbed trial"),
        ],
        len(walking),
    )
    mislabelled = _mislabelled_conditions(walking, log, onset_ms, tolerance)
    usable = perturbed & np.array([not r for r in log])
    span = int(np.max(offset[usable], initial=0)) + samples(max(settings.windows_ms()), fs)
    time0 = np.array([w.recording.time_s[0] for w in walking])
    metadata = {
        "condition": np.array([condition(w) for w in walking]),
        "trial": np.array([w.trial for w in walking]),
        "delay_ms": delay,
        "heel_contact_s": time0 + block.event / fs,
        "onset_s": np.where(perturbed & found, time0 + onset / fs, np.nan),
        "onset_ms": np.where(perturbed & found, onset_ms, np.nan),
        "offset": offset,
    }
    stance = epoch(
        block.stance[..., : max(span, 1)],
        fs,
        np.zeros_like(block.event),
        0.0,
        (span - 1) / fs,
        ch_names=STANCE_CHANNELS,
        metadata=metadata,
        lengths=lengths - block.event,
        drop_log=log,
    )
    # a plate cannot pull: a low-passed vertical force far below zero is a corrupted channel (a
    # one-sample glitch rings through the low-pass), whether or not a sample lands near zero
    grf_z = stance.data[:, STANCE_CHANNELS.index("grf_z")]
    with warnings.catch_warnings():  # a trial without a defined sample: no bound, not dropped
        warnings.simplefilter("ignore", RuntimeWarning)
        load = np.nanpercentile(grf_z, 75, axis=-1)
        lowest = np.nanmin(grf_z, axis=-1)
    pulling = lowest < -_PULL_FRACTION * load
    if pulling.any():
        stance = stance.drop(
            pulling,
            [
                "the low-passed vertical force falls far below zero within the analysed stance: "
                f"a plate cannot pull (a glitch in a force channel?) [trial {trial}: {force:.0f} N]"
                for trial, force in zip(
                    stance.metadata["trial"][pulling], lowest[pulling], strict=True
                )
            ],
        )
    undefined = ~np.isfinite(stance.data).all(axis=(1, 2))
    if undefined.any():
        stance = stance.drop(
            undefined, "vertical force below 1 N within the analysed stance (COP undefined)"
        )
    return stance, mislabelled


_PULL_FRACTION = 0.2
"""A trial whose low-passed vertical force falls below minus this fraction of its load (75th
percentile over the analysed stance) is dropped as corrupted: a sudden full unloading undershoots
by about 6 % through the 20 Hz low-pass, a 10⁶ N one-sample glitch by hundreds of newtons."""


class _StanceBlock(NamedTuple):
    """Per trial of a block: the first ``n_stance`` samples after heel contact of every stance
    channel, and what the drop checks need (samples; NaN where undefined)."""

    stance: NDArray[np.float64]  # (n_trials, len(STANCE_CHANNELS), n_stance)
    contact: NDArray[np.int64]  # heel contact's sample (-1: none)
    event: NDArray[np.int64]  # the sample the stance starts at
    cop0: NDArray[np.float64]  # COP at heel contact, m
    onset: NDArray[np.float64]  # perturbation onset, fractional sample
    amplitude: NDArray[np.float64]  # the motor's signed excursion, rad


def _stance_block(
    session: Session,
    trials: slice,
    settings: WalkingSettings,
    filters: PlatformFilters,
    width: int,
    n_stance: int,
) -> _StanceBlock:
    """The stance of the walking ``trials``, their raw samples padded to ``width``."""
    info, walking = session.info, session.walking[trials]
    fs = info.sample_rate_hz
    plate = info.force_plate
    raw, _ = stack_recordings(
        [w.recording for w in walking], ("motor_angle", "ankle_angle", *plate.channels), width
    )
    n_base = max(1, round(settings.baseline_ms * fs / 1000.0))
    # the plate's signals that are linear in the load (its channels, or for GRF/COP data the
    # sagittal signals); they, the motor and the ankle angle are zeroed over the baseline (the
    # ankle angle is re-zeroed later)
    load = advance(plate.load_signals(raw[:, 2:]), settings.force_delay_samples(info))
    signals = np.concatenate([raw[:, :2], load], axis=1)
    del raw, load
    signals -= signals[..., :n_base].mean(axis=-1, keepdims=True)
    motor, ankle_raw = signals[:, 0], signals[:, 1]
    sagittal = sagittal_matrix(plate)
    load_raw = sagittal @ signals[:, 2:]  # grf_x, grf_z, grf_z * cop_x
    contact = heel_contact(
        load_raw[:, 1],
        fs,
        settings.heel_contact_threshold_n,
        hold_ms=settings.heel_contact_hold_ms,
    )
    event = np.maximum(contact, n_base)
    rows = np.arange(len(walking))

    lp = {"fs": fs, "cutoff_hz": settings.cutoff_hz, "order": settings.filter_order}
    cop0 = _contact_cop(load_raw, event, settings, filters, sagittal, info)
    cop_defined = np.isfinite(cop0)
    load_lp = lowpass(load_raw, **lp)

    def foot_load(own: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
        """The foot's GRF, torque and lever arm: the low-passed load minus the plate's ``own``
        forces."""
        grf_x, grf_z, moment = np.moveaxis(load_lp - own, 1, 0)
        cop_x = cop_from_moment(moment, grf_z)
        cop_x[rows, event] = np.where(cop_defined, cop0, 0.0)  # ankle_torque zeroes it here
        torque, dx = ankle_torque(
            SagittalLoad(grf_x, grf_z, cop_x),
            event,
            heel_to_ankle_m=info.heel_to_ankle_m,
            ankle_height_m=info.ankle_height_m,
        )
        return grf_z, torque, dx

    plate_angle = lowpass(motor, **lp)
    own = (  # the filters' inputs are low-passed as the angles (unless fitted otherwise)
        filters.predict_low_passed(plate_angle, combine=sagittal)
        if (filters.cutoff_hz, filters.filter_order) == (settings.cutoff_hz, settings.filter_order)
        else filters.predict(motor, combine=sagittal)
    )
    grf_z, torque, dx = foot_load(own)
    untwisted = torque
    if stiffness := settings.transmission_stiffness_nm_per_rad:
        # the foot's torque twists the coupler: the plate's own forces follow the plate, which
        # departs from the motor by -T/(K + c s), T/K delayed by up to the coupler's lag c/K (the
        # hinge is on the ankle's axis, so T is the load about it); T is low-passed already
        twist = advance(np.nan_to_num(torque) / stiffness, -settings.coupler_lag_ms * fs / 1000.0)
        grf_z, torque, dx = foot_load(own + filters.predict_departure(-twist, combine=sagittal))
        plate_angle -= twist
    ankle = lowpass(ankle_raw, **lp)
    ankle_at_contact = ankle[rows, event][:, None]
    kin = kinematics(ankle - ankle_at_contact, fs, settings.derivative_window)
    since_contact = (np.arange(width) - event[:, None]) / fs
    time_angle = lowpass(since_contact * (ankle_raw - ankle_at_contact), **lp)
    onsets = perturbation_onset(
        motor, start=event, min_amplitude_rad=settings.onset_min_amplitude_rad
    )
    channels_by_name = {
        "angle": kin[:, 0],
        "velocity": kin[:, 1],
        "acceleration": kin[:, 2],
        "torque": torque,
        "dx": dx,
        "grf_z": grf_z,
        "motor_angle": motor,
        "torque_raw": _raw_torque(load_raw, cop0, info),
        "grf_z_raw": load_raw[:, 1],
        "angle_raw": ankle_raw - ankle_at_contact,
        "time_angle": time_angle,
        "torque_untwisted": untwisted,
        "plate_angle": plate_angle,
    }
    window = np.minimum(event[:, None] + np.arange(n_stance), width - 1)
    stance = np.empty((len(walking), len(STANCE_CHANNELS), n_stance))
    for i, name in enumerate(STANCE_CHANNELS):  # only the stance of each channel is copied
        stance[:, i] = channels_by_name[name][rows[:, None], window]
    return _StanceBlock(stance, contact, event, cop0, onsets.index, onsets.amplitude)


def _raw_torque(
    load: NDArray[np.float64], cop0: NDArray[np.float64], info: SessionInfo
) -> NDArray[np.float64]:
    """The unfiltered ankle torque (N·m) of the sagittal ``load`` (grf_x, grf_z, moment; trials
    first) for each trial's COP at contact ``cop0`` (m; 0 where it is undefined)."""
    lever = np.where(np.isfinite(cop0), cop0, 0.0)[:, None] + info.heel_to_ankle_m
    return load[:, 2] - lever * load[:, 1] + load[:, 0] * info.ankle_height_m


def _contact_cop(
    load: NDArray[np.float64],
    event: NDArray[np.int64],
    settings: WalkingSettings,
    filters: PlatformFilters,
    sagittal: NDArray[np.float64],
    info: SessionInfo,
) -> NDArray[np.float64]:
    """Each trial's COP at heel contact (sample ``event``) from the unfiltered sagittal ``load``,
    m (NaN where it is undefined: the trial is then dropped).

    The heel's strike twists the coupler faster than anything else in the stance, while the
    load is still small. With a ``transmission_stiffness_nm_per_rad``, the plate's own forces
    of that twist (the filters' memoryless gains, on the unfiltered ankle torque low-passed at
    ``contact_twist_cutoff_hz``; not filtered when that is at or above the Nyquist frequency)
    are taken off the load before the COP is read again. Only the samples near contact are
    needed, with 50 ms (or two periods of the cut-off, if longer) either side for the low-pass
    and the derivatives to settle.
    """
    fs = info.sample_rate_hz
    read = partial(
        _cop_at_contact,
        threshold_n=settings.heel_contact_threshold_n,
        fs=fs,
        span_ms=settings.contact_cop_ms,
        degree=settings.contact_cop_degree,
    )
    cop0 = read(load[:, 1], load[:, 2], event)
    stiffness = settings.transmission_stiffness_nm_per_rad
    if not stiffness:
        return cop0
    cutoff = settings.contact_twist_cutoff_hz
    pad = samples(max(50.0, 2000.0 / cutoff), fs)
    span = np.arange(-pad, samples(settings.contact_cop_ms, fs) + pad)
    index = np.clip(event[:, None] + span, 0, load.shape[-1] - 1)
    near = np.take_along_axis(load, index[:, None], axis=-1)
    torque = np.nan_to_num(_raw_torque(near, cop0, info))
    if cutoff < fs / 2:
        torque = lowpass(torque, fs, cutoff, order=2)
    twist = advance(torque / stiffness, -settings.coupler_lag_ms * fs / 1000.0)
    near = near - filters.predict_departure(-twist, combine=sagittal)
    return np.where(
        np.isfinite(cop0), read(near[:, 1], near[:, 2], np.full_like(event, pad)), np.nan
    )


def _cop_at_contact(
    grf_z: NDArray[np.float64],
    moment: NDArray[np.float64],
    event: NDArray[np.int64],
    threshold_n: float,
    fs: float,
    span_ms: float,
    degree: int,
) -> NDArray[np.float64]:
    """COP at heel contact: the raw COP's local polynomial at the instant the force crosses.

    The crossing is found to a fraction of a sample (linear interpolation of the vertical force
    between the last sample below ``threshold_n`` and the first above). A polynomial of
    ``degree`` in time is fitted to the raw COP (``moment / grf_z``) over the first ``span_ms``
    from the crossing sample, weighted by ``grf_z**2``, and evaluated at the crossing. The
    weight follows the COP's error, which falls as 1/Fz: channel noise, and the plate's own
    inertial and ringing loads when the foot's strike moves the compliant hinge, weigh most
    where the load is small. The low-pass is not used: it would smear the force's rise over the
    following samples. With the weight every term is a product of raw signals (no division).
    """
    n = max(degree + 1, round(span_ms * fs / 1000.0))
    last = grf_z.shape[-1] - 1
    index = np.minimum(event[:, None] + np.arange(n), last)
    before = np.take_along_axis(grf_z, np.maximum(event - 1, 0)[:, None], axis=-1)[:, 0]
    at = np.take_along_axis(grf_z, index[:, :1], axis=-1)[:, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        crossing = np.clip((threshold_n - at) / (at - before), -1.0, 0.0)  # samples from event
    fz = np.take_along_axis(grf_z, index, axis=-1)
    t = (np.arange(n) - np.nan_to_num(crossing)[:, None]) / n  # 0 at the crossing
    powers = t[..., None] ** np.arange(degree + 1)  # (n_trials, n, degree + 1)
    weighted = powers * fz[..., None]
    gram = np.einsum("tnp,tnq->tpq", weighted, weighted)
    rhs = np.einsum("tnp,tn->tp", weighted, np.take_along_axis(moment, index, axis=-1))
    with np.errstate(invalid="ignore", divide="ignore"):
        singular = np.abs(np.linalg.det(gram)) < np.finfo(float).tiny
        gram[singular] = np.eye(degree + 1)
        coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    return np.where(singular, np.nan, coef[:, 0])


def samples(ms: float, fs: float) -> int:
    """Samples in ``ms`` milliseconds at ``fs`` Hz (at least 3)."""
    return max(3, round(ms * fs / 1000.0))


def drop_summary(
    drop_log: Sequence[tuple[str, ...]], walking: Sequence[WalkingTrial], shown: int = 3
) -> str:
    """Each kind of drop reason with its count and the first ``shown`` files it applies to."""
    files: dict[str, list[str]] = {}
    for reasons, trial in zip(drop_log, walking, strict=True):
        for reason in reasons:
            files.setdefault(reason_kind(reason), []).append(trial.recording.name)
    parts = []
    for reason, names in files.items():
        more = ", ..." if len(names) > shown else ""
        parts.append(f"{reason} ({len(names)}: {', '.join(names[:shown])}{more})")
    return "; ".join(parts) or "none"
