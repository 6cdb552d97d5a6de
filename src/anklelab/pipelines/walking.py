"""Walking impedance: from a recorded session to ankle stiffness with uncertainty (paper 000).

The steps follow paper 000 (sections 2.2, 2.3, 2.4.2, 3) and DESIGN.md section 5:

1. **Platform filters** from the calibration trials (nobody on the plate): fitted on one trial,
   scored on the others (VAF per trial, pooled over channels, and per channel).
2. **Walking trials**: channels and motor angle zeroed over an unloaded baseline at the start of
   each file; heel contact detected from the vertical force; the platform's own force transients
   predicted from the motor angle and subtracted from the low-passed channels; GRF, COP and
   ankle torque computed with the COP and the ankle angle zeroed at heel contact; derivatives
   of the angle by a local quadratic fit; the true perturbation onset detected from the motor
   angle. Trials that fail a check are dropped with the reason logged.
3. **Ensembles**: for each timing point (manifest ``delay_ms``) and direction, every perturbed
   trial is cut at its own detected onset and the mean unperturbed trial, cut at the same time
   after heel contact, is subtracted; angle and torque offsets (read before the low-pass has
   spread the perturbation backwards in time) are removed; bootstrap averages of random
   subsets of the perturbed trials are formed.
4. **Model**: ``T = I θ'' + b θ' + k θ`` fitted to each bootstrap average over the analysis
   window and the sensitivity windows (optionally with a stiffness that changes linearly
   within the window, ``stiffness_model = "linear"``); ``cop_m`` is the θ²-weighted nominal
   lever arm.
5. **Bench**: stiffness per actuator distance and the walking-vs-bench error at ``cop_m``.

Everything is read from the session (sample rate, plate geometry and mounting, subject geometry,
trial manifest); no number of the digital twin is assumed.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from anklelab._params import Parameters, load_parameters
from anklelab._version import __version__
from anklelab.data.session import Recording, Session, WalkingTrial
from anklelab.errors import AnklelabWarning, ParameterError, SessionFormatError
from anklelab.forceplate import (
    CHANNELS,
    PlateGeometry,
    SagittalLoad,
    ankle_torque,
    resultants,
    sagittal_load,
)
from anklelab.ident.bench import BenchStiffness, bench_stiffness, interpolate_stiffness
from anklelab.ident.impedance import (
    ImpedanceFit,
    StiffnessModel,
    fit_impedance,
    impedance_torque,
)
from anklelab.ident.irf import PlatformFilters
from anklelab.signals import (
    Trials,
    epoch,
    heel_contact,
    kinematics,
    lowpass,
    lowpass_min_samples,
    perturbation_onset,
    stack_recordings,
)

__all__ = [
    "STANCE_CHANNELS",
    "STEPS",
    "TimingPoint",
    "WalkingResults",
    "WalkingSettings",
    "analyze_walking",
    "fit_platform_filters",
    "load_walking_settings",
]

STEPS = ("platform filters", "walking trials", "ensembles and bootstrap", "bench")
"""Names of the pipeline's steps, in order (reported to the ``progress`` callback)."""

STANCE_CHANNELS = ("angle", "velocity", "acceleration", "torque", "dx", "grf_z", "motor_angle")
"""Channels of the heel-contact-aligned stance trials (rad, rad/s, rad/s², N·m, m, N, rad)."""
_KIN = [0, 1, 2]
_ANGLE, _TORQUE, _DX = 0, 3, 4
_DIRECTIONS = ("dorsi", "plantar")
_MIN_FZ_N = 1.0  # below this vertical force the COP is undefined (forceplate.resultants' default)
_MISMATCH = "onset differs from the manifest's delay_ms"
_SLOPE_WARNING_FRACTION = 0.2  # stiffness change over the window / stiffness: warn above
_SLOPE_WARNING_SDS = 3.0  # ... if the slope also exceeds this many bootstrap sd
_OFFSET_REFERENCE_MS, _PAPER_CUTOFF_HZ = 80.0, 20.0  # offsets read 80 ms early at 20 Hz, order 4


class WalkingSettings(Parameters):
    """Every setting of the walking analysis, validated (defaults from paper 000).

    Attributes
    ----------
    cutoff_hz, filter_order
        Zero-phase Butterworth low-pass for all signals (paper 000: 20 Hz, 4th order).
    derivative_window
        Samples per local quadratic fit for derivatives (paper 000: the point and 4 around it).
    heel_contact_threshold_n, heel_contact_hold_ms
        Vertical force that marks heel contact (paper 000: 25 N) and how long it must hold.
    contact_cop_ms
        The COP at heel contact (where the COP is zeroed) is the intercept of a line fitted to
        the unfiltered COP over this span after contact.
    baseline_ms
        Unloaded span at the start of each walking file used to zero channels and motor angle.
    onset_min_amplitude_rad
        Smallest motor-angle excursion that counts as a perturbation.
    onset_tolerance_ms
        A perturbed trial whose detected onset (after the detected heel contact) differs from
        its manifest ``delay_ms`` by more than this is dropped as mislabelled. The onset jitters
        by 3-5 ms sd around the intended delay (paper 000); on default twin sessions (seeds
        0-2, 1200 perturbed trials) onset minus delay_ms is -0.4 ± 4.2 ms, at most 15.9 ms
        away. 50 ms is three times that, and less than half the 125 ms between paper 000's
        timing points, so a trial filed under a neighbouring timing point is caught.
    filter_inputs, n_lags, angle_lags, filter_method, calibration_fit_trial
        Platform filters: input pathways, length of the velocity/acceleration filters and of
        the angle filter (samples; 1 = a static gain, see
        :class:`~anklelab.ident.irf.PlatformFilters`), estimator, calibration trial (index)
        they are fitted on; the other calibration trials score them.
    window_ms, sensitivity_windows_ms
        Impedance analysis window after the onset and the alternative windows checked.
    offset_reference_ms
        How long before each detected onset the angle and torque offsets are read. Paper 000
        zeroes both at the window start, but the zero-phase low-pass spreads the perturbation
        about 1.5/cutoff_hz s backwards in time, so at the onset the filtered acceleration is at
        its peak and the torque offset removed there contains ``I θ'' + b θ'`` that the angle
        offset does not: on data with known K, B, I this biases stiffness by about -15 % and
        inertia by -60 %. Reading the offsets before the spread removes the bias; 0 reproduces
        the paper literally. Unset (``None``, the default), it follows the low-pass (see
        :meth:`offset_reference`): 80 ms at paper 000's 20 Hz, order 4.
    stiffness_model
        ``"constant"`` (paper 000): one stiffness over the window. ``"linear"`` (expert
        option): ``k + k₁ (t - t_c)``, ``t_c`` the θ²-weighted mean time of the window, so ``k``
        is the θ²-weighted stiffness that ``cop_m`` refers to, and ``k₁`` is reported as
        ``stiffness_slope_nm_per_rad_per_s`` (see :mod:`anklelab.ident.impedance`). Use it
        when the stiffness changes markedly within the window (a human ankle in early and mid
        stance): a constant fit then lets damping and inertia absorb the change, and
        overestimates a rising stiffness. Measured on the twin's default sessions (10 seeds;
        error = mean over seeds of estimate vs the truth reference, sd = bootstrap sd, both in
        % of the reference; constant -> linear). Human ankle (stiffness rising 1.5 -> 6.5
        N·m/rad/kg over 150-525 ms): 225 ms +8 -> -2, 350 ms +4 -> -2, 475 ms +1 -> +1, sd
        1.3-3.0 -> 0.9-2.2; damping at 225/350 ms 0.2-0.3 -> 2.1-2.4 N·m·s/rad (true 2.25),
        inertia 0.027-0.029 -> 0.015 kg·m² (true 0.020). At 100 ms the twin's stiffness is flat
        until 150 ms and then rises, which neither model describes: +12/+21 -> -9/-4
        (dorsi/plantar), sd 11 -> 6. Prosthetic foot (stiffness changing only through the
        lever arm): errors within ±1.2 for both, sd 0.4-1.6 -> 0.7-1.6 (median ratio 1.38),
        mean |error| 0.78 -> 0.96: where the stiffness hardly changes the extra parameter
        costs precision, so the default stays ``"constant"``.
    bootstrap_reps, bootstrap_fraction, seed
        Bootstrap: repetitions, fraction of the perturbed trials per repetition, seed.
    """

    cutoff_hz: float = Field(20.0, gt=0)
    filter_order: int = Field(4, ge=1, le=12)
    derivative_window: int = Field(5, ge=3)
    heel_contact_threshold_n: float = Field(25.0, gt=0)
    heel_contact_hold_ms: float = Field(5.0, ge=0)
    contact_cop_ms: float = Field(20.0, gt=0)
    baseline_ms: float = Field(50.0, gt=0)
    onset_min_amplitude_rad: float = Field(0.005, gt=0)
    onset_tolerance_ms: float = Field(50.0, gt=0)
    filter_inputs: tuple[Literal["angle", "velocity", "acceleration"], ...] = Field(
        ("angle", "acceleration"), min_length=1
    )
    n_lags: int = Field(100, ge=1)
    angle_lags: int = Field(1, ge=1)
    filter_method: Literal["pinv", "toeplitz"] = "pinv"
    calibration_fit_trial: int = Field(0, ge=0)
    window_ms: float = Field(100.0, gt=0)
    offset_reference_ms: float | None = Field(None, ge=0)
    sensitivity_windows_ms: tuple[float, ...] = (75.0, 125.0)
    stiffness_model: StiffnessModel = "constant"
    bootstrap_reps: int = Field(100, ge=1)
    bootstrap_fraction: float = Field(0.6, gt=0, le=1)
    seed: int = Field(0, ge=0)

    @model_validator(mode="after")
    def _consistent(self) -> WalkingSettings:
        if self.derivative_window % 2 == 0:
            raise ValueError(
                f"derivative_window: expected an odd number, got {self.derivative_window}"
            )
        if len(set(self.filter_inputs)) != len(self.filter_inputs):
            raise ValueError(f"filter_inputs: expected distinct names, got {self.filter_inputs}")
        if any(w <= 0 for w in self.sensitivity_windows_ms):
            raise ValueError(
                f"sensitivity_windows_ms: expected > 0, got {self.sensitivity_windows_ms}"
            )
        return self

    def windows_ms(self) -> tuple[float, ...]:
        """The analysis window followed by the sensitivity windows, ms."""
        return (self.window_ms, *(w for w in self.sensitivity_windows_ms if w != self.window_ms))

    def offset_reference(self) -> float:
        """How long before each onset the offsets are read, ms: ``offset_reference_ms`` if set,
        else scaled to the low-pass.

        The zero-phase low-pass spreads the perturbation backwards in time by its impulse
        response mirrored; the envelope of a Butterworth response decays with the time
        constant of its least damped pole pair, ``τ = 1 / (2π f_c sin(π / 2n))`` (``f_c`` the
        cut-off, ``n`` the order). 80 ms (3.85 τ, where that envelope is down to 2 %) removes
        the bias at paper 000's 20 Hz, order 4; other filters get the same number of time
        constants: ``80 ms × (20 Hz / f_c) × sin(π/8) / sin(π / 2n)``. Measured on the
        hand-made session of known impedance (tests/test_pipeline_walking.py; order 4 at 10,
        20 and 40 Hz, orders 2 and 8 at 20 Hz), the largest stiffness error over its four
        conditions is 0.4-0.8 % with 3.85 τ for every filter, 0.8-7.8 % with 1 τ, and the mean
        error -12 % to -23 % with 0. A longer reference gains nothing and lets the walking
        profile's trial-to-trial drift in: the bootstrap sd grows (at 20 Hz 4.2 N·m/rad with
        3.85 τ, 4.7 with 5 τ), and at 40 Hz 80 ms (7.7 τ) gives -1.1 % at 150 ms, 40 ms -0.5 %.

        Examples
        --------
        >>> WalkingSettings().offset_reference()
        80.0
        >>> WalkingSettings(cutoff_hz=40.0).offset_reference()
        40.0
        >>> round(WalkingSettings(filter_order=2).offset_reference(), 1)
        43.3
        """
        if self.offset_reference_ms is not None:
            return self.offset_reference_ms
        slowest = np.sin(np.pi / 8) / np.sin(np.pi / (2 * self.filter_order))
        return float(_OFFSET_REFERENCE_MS * _PAPER_CUTOFF_HZ / self.cutoff_hz * slowest)


def load_walking_settings(path: str | Path | None = None, **overrides: Any) -> WalkingSettings:
    """Settings from a TOML file of :class:`WalkingSettings` keys (defaults if no file).

    Keyword arguments that are not ``None`` override the file; every value is validated and an
    error names the file and the key.
    """
    settings = load_parameters(WalkingSettings, path) if path else WalkingSettings()
    changes = {key: value for key, value in overrides.items() if value is not None}
    return settings.replace(changes) if changes else settings


@dataclass(frozen=True)
class TimingPoint:
    """Impedance at one timing point and direction.

    Attributes
    ----------
    delay_ms : float
        Intended timing point after heel contact (the manifest's grouping key), ms.
    direction : {"dorsi", "plantar"}
    n_perturbed, n_unperturbed : int
        Trials used.
    cop_m : float
        Lever arm of the estimate: nominal ``dx`` weighted by θ² over the window, m.
    stiffness, damping, inertia, vaf : ndarray, shape (n_reps,)
        Bootstrap values: N·m/rad, N·m·s/rad, kg·m², %.
    stiffness_slope : ndarray, shape (n_reps,)
        Bootstrap rate of change of the stiffness within the window, N·m/rad/s (0 unless
        ``stiffness_model`` is ``"linear"``).
    window_stiffness : dict of str to float
        Mean stiffness for each sensitivity window (key: window in ms, ``"75"``), N·m/rad.
    onset_ms : ndarray
        Detected onset of each perturbed trial after its heel contact, ms.
    time_s : ndarray
        Time after the onset over the analysis window, s.
    angle, torque, model_torque : ndarray, shape (n_reps, n_window)
        Bootstrap perturbation angle (rad), measured and model torque (N·m).
    warnings : tuple of str
        Doubts about the estimate: with the constant stiffness model, a stiffness that the
        linear model, fitted as a diagnostic, finds changing within the window by more than
        20 % of the stiffness (by a slope of more than three bootstrap sd).
    """

    delay_ms: float
    direction: str
    n_perturbed: int
    n_unperturbed: int
    cop_m: float
    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    inertia: NDArray[np.float64]
    vaf: NDArray[np.float64]
    stiffness_slope: NDArray[np.float64]
    window_stiffness: dict[str, float]
    onset_ms: NDArray[np.float64]
    time_s: NDArray[np.float64]
    angle: NDArray[np.float64]
    torque: NDArray[np.float64]
    model_torque: NDArray[np.float64]
    warnings: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        """Condition key, e.g. ``"dorsi/225"``."""
        return f"{self.direction}/{self.delay_ms:g}"


@dataclass(frozen=True)
class WalkingResults:
    """Everything the walking analysis produced.

    Attributes
    ----------
    settings : WalkingSettings
    filters : PlatformFilters
        The platform filters used.
    filter_vaf, filter_vaf_by_channel : ndarray
        Held-out VAF per calibration trial, pooled (n_held,) and per channel (n_held, 8), %.
    timing_points : list of TimingPoint
    bench : list of BenchStiffness
    stance : Trials
        Kept walking trials aligned at heel contact (:data:`STANCE_CHANNELS`), with metadata
        ``condition``, ``trial``, ``heel_contact_s``, ``onset_s`` (detected, NaN if unperturbed),
        ``onset_ms`` (after heel contact) and a drop log naming why each other trial was dropped.
    warnings : tuple of str
        Conditions of the manifest that lost every trial because the detected onsets disagree
        with their ``delay_ms`` (each also issued as an :class:`~anklelab.errors.AnklelabWarning`).
    """

    settings: WalkingSettings
    filters: PlatformFilters
    filter_vaf: NDArray[np.float64]
    filter_vaf_by_channel: NDArray[np.float64]
    timing_points: list[TimingPoint]
    bench: list[BenchStiffness]
    stance: Trials
    warnings: tuple[str, ...] = ()

    def drop_counts(self) -> dict[str, int]:
        """Number of dropped walking trials per kind of reason (per-trial details left out)."""
        kinds = [_reason_kind(reasons[0]) for reasons in self.stance.drop_log if reasons]
        return {kind: kinds.count(kind) for kind in dict.fromkeys(kinds)}

    def validation(self) -> list[dict[str, float]]:
        """Dorsiflexion estimates against the bench stiffness interpolated at ``cop_m``."""
        if not self.bench:
            return []
        rows = []
        for tp in self.timing_points:
            if tp.direction != "dorsi":
                continue
            bench = float(interpolate_stiffness(self.bench, tp.cop_m))
            walking = float(np.mean(tp.stiffness))
            rows.append(
                {
                    "delay_ms": tp.delay_ms,
                    "cop_m": tp.cop_m,
                    "bench_stiffness_nm_per_rad": bench,
                    "error_percent": (walking - bench) / bench * 100.0,
                }
            )
        return rows

    def to_dict(self, session: str, session_sha256: str | None = None) -> dict[str, Any]:
        """The ``results.json`` document (DESIGN.md section 5).

        Parameters
        ----------
        session : str
            Name of the analysed input (its file or directory name).
        session_sha256 : str, optional
            SHA-256 of the input (:func:`anklelab.data.session_hash`), recorded when given.
        """
        scored = self.filter_vaf.size > 0
        by_channel = self.filter_vaf_by_channel.mean(axis=0) if scored else []
        linear = self.settings.stiffness_model == "linear"
        return _finite(
            {
                "anklelab_version": __version__,
                "session": session,
                **({"session_sha256": session_sha256} if session_sha256 else {}),
                "settings": self.settings.model_dump(mode="json")
                | {"offset_reference_ms": self.settings.offset_reference()},
                "platform_filters": {
                    "n_lags": int(self.filters.n_lags),
                    "vaf_percent_mean": float(np.mean(self.filter_vaf)) if scored else None,
                    "vaf_percent_sd": _sd(self.filter_vaf) if scored else None,
                    "vaf_percent_by_channel": dict(
                        zip(self.filters.channels, map(float, by_channel), strict=False)
                    ),
                },
                "timing_points": [
                    {
                        "delay_ms": tp.delay_ms,
                        "direction": tp.direction,
                        "n_perturbed": tp.n_perturbed,
                        "n_unperturbed": tp.n_unperturbed,
                        "cop_m": tp.cop_m,
                        "stiffness_nm_per_rad": _summary(tp.stiffness),
                        "damping_nms_per_rad": _summary(tp.damping),
                        "inertia_kgm2": _summary(tp.inertia),
                        "vaf_percent": _summary(tp.vaf),
                        "window_sensitivity": {
                            key: {"stiffness_nm_per_rad": value}
                            for key, value in tp.window_stiffness.items()
                        },
                    }
                    | (
                        {"stiffness_slope_nm_per_rad_per_s": _summary(tp.stiffness_slope)}
                        if linear
                        else {}
                    )
                    | ({"warnings": list(tp.warnings)} if tp.warnings else {})
                    for tp in self.timing_points
                ],
                "bench": [row._asdict() for row in self.bench],
                "validation": self.validation(),
                **({"warnings": list(self.warnings)} if self.warnings else {}),
            }
        )

    def table(self) -> list[dict[str, Any]]:
        """One row per timing point and direction, for a CSV file."""
        check = {row["delay_ms"]: row for row in self.validation()}
        rows = []
        for tp in self.timing_points:
            row: dict[str, Any] = {
                "delay_ms": tp.delay_ms,
                "direction": tp.direction,
                "n_perturbed": tp.n_perturbed,
                "n_unperturbed": tp.n_unperturbed,
                "onset_ms_mean": float(np.mean(tp.onset_ms)),
                "onset_ms_sd": _sd(tp.onset_ms),
                "cop_m": tp.cop_m,
            }
            series = [
                ("stiffness_nm_per_rad", tp.stiffness),
                ("damping_nms_per_rad", tp.damping),
                ("inertia_kgm2", tp.inertia),
                ("vaf_percent", tp.vaf),
            ]
            if self.settings.stiffness_model == "linear":
                series.append(("stiffness_slope_nm_per_rad_per_s", tp.stiffness_slope))
            for name, values in series:
                row[f"{name}_mean"], row[f"{name}_sd"] = float(np.mean(values)), _sd(values)
            for key, value in tp.window_stiffness.items():
                row[f"stiffness_nm_per_rad_{key}ms"] = value
            match = check.get(tp.delay_ms) if tp.direction == "dorsi" else None
            row["bench_stiffness_nm_per_rad"] = match and match["bench_stiffness_nm_per_rad"]
            row["error_percent"] = match and match["error_percent"]
            rows.append(row)
        return rows


def _sd(values: NDArray[np.float64]) -> float:
    return float(np.std(values, ddof=1)) if np.size(values) > 1 else 0.0


def _summary(values: NDArray[np.float64]) -> dict[str, float]:
    return {"mean": float(np.mean(values)), "sd": _sd(values)}


def _finite(node: Any) -> Any:
    """JSON has no NaN: non-finite floats become ``None``."""
    if isinstance(node, dict):
        return {key: _finite(value) for key, value in node.items()}
    if isinstance(node, list | tuple):
        return [_finite(value) for value in node]
    if isinstance(node, float) and not np.isfinite(node):
        return None
    return node


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
        settings.filter_inputs,
        n_lags=settings.n_lags,
        angle_lags=settings.angle_lags,
        method=settings.filter_method,
        cutoff_hz=settings.cutoff_hz,
        filter_order=settings.filter_order,
        derivative_window=settings.derivative_window,
    )
    _check_calibration_lengths(filters, calibration, fs)
    fit_rec = calibration[fit_index]
    filters.fit(fit_rec["motor_angle"], fit_rec.stack(CHANNELS), fs=fs)
    held_out = [rec for i, rec in enumerate(calibration) if i != fit_index] or [fit_rec]
    return (filters, *_score_filters(filters, held_out))


def _check_calibration_lengths(
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


def _score_filters(
    filters: PlatformFilters, recordings: Sequence[Recording]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    scores = [filters.vaf(rec["motor_angle"], rec.stack(CHANNELS)) for rec in recordings]
    pooled = np.array([s[0] for s in scores])
    return pooled, np.array([s[1] for s in scores]).reshape(len(scores), len(filters.channels))


def _condition(trial: WalkingTrial) -> str:
    return f"{trial.direction}/{trial.delay_ms:g}" if trial.perturbed else "none"


def _first_reasons(
    checks: Sequence[tuple[NDArray[np.bool_], str | Sequence[str]]], n: int
) -> list[tuple[str, ...]]:
    """Per trial, the first failing check's reason (later checks assume the earlier passed).

    A check's reason is one text for every trial, or one per trial.
    """
    log: list[tuple[str, ...]] = [()] * n
    for mask, reason in checks:
        for i in np.flatnonzero(mask):
            log[i] = log[i] or (reason if isinstance(reason, str) else reason[i],)
    return log


def _reason_kind(reason: str) -> str:
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
    condition = np.array([_condition(w) for w in walking])
    delay = np.array([w.delay_ms for w in walking], dtype=float)
    mismatch = np.array([bool(r) and _reason_kind(r[0]).startswith(_MISMATCH) for r in log])
    kept = np.array([not r for r in log])
    messages = []
    for key in dict.fromkeys(condition[mismatch]):
        members = condition == key
        if kept[members].any():
            continue
        direction, labelled = key.split("/")[0], delay[members][0]
        timing = np.unique(delay[np.char.startswith(condition, f"{direction}/")])
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


def _stance_trials(
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
    raw, lengths = stack_recordings(
        [w.recording for w in walking], ("motor_angle", "ankle_angle", *CHANNELS)
    )
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
            + _drop_summary(_first_reasons(too_short, len(walking)), walking)
        )
    raw -= raw[..., :n_base].mean(axis=-1, keepdims=True)  # the ankle angle is re-zeroed later
    motor = raw[:, 0]
    sagittal = _sagittal_matrix(info.force_plate)
    load_raw = np.einsum("sc,nct->nst", sagittal, raw[:, 2:])  # grf_x, grf_z, grf_z * cop_x
    contact = heel_contact(
        load_raw[:, 1],
        fs,
        settings.heel_contact_threshold_n,
        hold_ms=settings.heel_contact_hold_ms,
    )
    event = np.maximum(contact, n_base)
    rows = np.arange(len(walking))

    lp = {"fs": fs, "cutoff_hz": settings.cutoff_hz, "order": settings.filter_order}
    grf_x, grf_z, moment = np.moveaxis(
        lowpass(load_raw, **lp) - filters.predict(motor, combine=sagittal), 1, 0
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        cop_x = np.where(np.abs(grf_z) > _MIN_FZ_N, moment / grf_z, np.nan)
    cop0 = _cop_at_contact(load_raw[:, 1], load_raw[:, 2], event, fs, settings.contact_cop_ms)
    cop_defined = np.isfinite(cop0)
    cop_x[rows, event] = np.where(cop_defined, cop0, 0.0)  # ankle_torque zeroes the COP here
    torque, dx = ankle_torque(
        SagittalLoad(grf_x, grf_z, cop_x),
        event,
        heel_to_ankle_m=info.heel_to_ankle_m,
        ankle_height_m=info.ankle_height_m,
    )
    ankle = lowpass(raw[:, 1], **lp)
    kin = kinematics(ankle - ankle[rows, event][:, None], fs, settings.derivative_window)

    onsets = perturbation_onset(
        motor, start=event, min_amplitude_rad=settings.onset_min_amplitude_rad
    )
    found = np.isfinite(onsets.index)
    perturbed = np.array([w.perturbed for w in walking])
    delay = np.array([w.delay_ms for w in walking], dtype=float)
    sign = np.array([{"dorsi": 1.0, "plantar": -1.0}.get(w.direction, 0.0) for w in walking])
    onset = np.where(found, onsets.index, event)
    offset = np.round(onset).astype(np.int64) - event
    onset_ms = (onset - event) / fs * 1000.0
    tolerance = settings.onset_tolerance_ms
    log = _first_reasons(
        [
            *too_short,
            (contact < 0, f"no heel contact: vertical force never held {thr}"),
            (contact <= n_base, f"heel contact within the first {base} (no unloaded baseline)"),
            (~cop_defined, "centre of pressure undefined at heel contact"),
            (perturbed & np.isnan(delay), "perturbed trial without delay_ms"),
            (perturbed & (sign == 0), "perturbed trial without a direction (dorsi or plantar)"),
            (perturbed & ~found, "no perturbation found in the motor angle"),
            (
                perturbed & (np.sign(onsets.amplitude) != sign),
                "motor moved against the manifest direction",
            ),
            (perturbed & (onset < event), "perturbation began before heel contact"),
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
    span = int(np.max(offset[usable], initial=0)) + _samples(max(settings.windows_ms()), fs)
    data = np.concatenate(
        [kin, torque[:, None], dx[:, None], grf_z[:, None], motor[:, None]], axis=1
    )
    time0 = np.array([w.recording.time_s[0] for w in walking])
    metadata = {
        "condition": np.array([_condition(w) for w in walking]),
        "trial": np.array([w.trial for w in walking]),
        "delay_ms": delay,
        "heel_contact_s": time0 + event / fs,
        "onset_s": np.where(perturbed & found, time0 + onset / fs, np.nan),
        "onset_ms": np.where(perturbed & found, onset_ms, np.nan),
        "offset": offset,
    }
    stance = epoch(
        data,
        fs,
        event,
        0.0,
        (span - 1) / fs,
        ch_names=STANCE_CHANNELS,
        metadata=metadata,
        lengths=lengths,
        drop_log=log,
    )
    stance = stance.drop(
        ~np.isfinite(stance.data).all(axis=(1, 2)),
        "vertical force below 1 N within the analysed stance (COP undefined)",
    )
    return stance, mislabelled


def _sagittal_matrix(plate: PlateGeometry) -> NDArray[np.float64]:
    """The (3, 8) map from force channels to ``(grf_x, grf_z, grf_z * cop_x)``.

    All three are linear in the channels, so the walking trials are low-passed and corrected as
    three signals instead of eight. The matrix is read off :mod:`anklelab.forceplate`'s own
    functions by probing them with unit channel loads (on top of a vertical load, so the COP is
    defined), which keeps every sign and mounting convention in that one module.
    """
    base = np.zeros(len(CHANNELS))
    base[CHANNELS.index("fz1")] = 100.0
    probes = np.vstack([base, base + np.eye(len(CHANNELS))])
    load = sagittal_load(resultants(probes, plate, axis=-1), plate.anterior_axis)
    values = np.stack([load.grf_x, load.grf_z, load.grf_z * load.cop_x])
    return values[:, 1:] - values[:, :1]


def _cop_at_contact(
    grf_z: NDArray[np.float64],
    moment: NDArray[np.float64],
    event: NDArray[np.int64],
    fs: float,
    span_ms: float,
) -> NDArray[np.float64]:
    """COP at heel contact: a line fitted to the raw COP over the first ``span_ms`` of contact.

    The low-pass would smear the force's sudden rise at heel strike over the following samples
    and move the COP at contact forward; the raw COP (``moment / grf_z``) is unbiased but noisy
    at small loads, so the line is weighted by ``grf_z**2`` (the COP's noise falls as 1/Fz),
    which also makes every term a product of the raw signals (no division).
    """
    n = max(2, round(span_ms * fs / 1000.0))
    index = np.minimum(event[:, None] + np.arange(n), grf_z.shape[-1] - 1)
    fz = np.take_along_axis(grf_z, index, axis=-1)
    weight, weighted_cop = fz**2, fz * np.take_along_axis(moment, index, axis=-1)
    t = np.arange(n, dtype=float)
    s0, s1, s2 = weight.sum(-1), weight @ t, weight @ t**2
    c0, c1 = weighted_cop.sum(-1), weighted_cop @ t
    with np.errstate(invalid="ignore", divide="ignore"):
        return (s2 * c0 - s1 * c1) / (s0 * s2 - s1**2)


def _samples(ms: float, fs: float) -> int:
    return max(3, round(ms * fs / 1000.0))


def _timing_point(
    stance: Trials,
    key: str,
    unperturbed: NDArray[np.float64],
    n_unperturbed: int,
    settings: WalkingSettings,
    rng: np.random.Generator,
) -> TimingPoint:
    """Bootstrap impedance of one condition (``"dorsi/225"``) from the stance trials.

    ``unperturbed`` is the mean unperturbed stance trial, shape (n_channels, n_times).
    """
    group = stance[key]
    fs = stance.fs
    windows = settings.windows_ms()
    lengths = [_samples(w, fs) for w in windows]
    onset = group.metadata["offset"]
    reference = np.maximum(onset - round(settings.offset_reference() * fs / 1000.0), 0)
    index = np.concatenate([reference[:, None], onset[:, None] + np.arange(max(lengths))], axis=1)
    segment = np.take_along_axis(group.data, index[:, None, :], axis=-1)
    nominal = unperturbed[:, index].transpose(1, 0, 2)
    difference = segment[:, :4] - nominal[:, :4]  # angle, velocity, acceleration, torque
    difference[:, [_ANGLE, _TORQUE]] -= difference[:, [_ANGLE, _TORQUE], :1]
    response, nominal = difference[..., 1:], nominal[..., 1:]
    boot = Trials(response, fs, STANCE_CHANNELS[:4]).bootstrap(
        settings.bootstrap_reps, settings.bootstrap_fraction, random_state=rng
    )
    fit = fit_impedance(
        boot[:, _KIN],
        boot[:, _TORQUE],
        lengths=lengths,
        stiffness_model=settings.stiffness_model,
        fs=fs,
    )
    n = lengths[0]
    analysis = ImpedanceFit(*(field[0] for field in fit))
    angle = response[:, _ANGLE, :n].mean(axis=0)
    weight = angle**2
    return TimingPoint(
        delay_ms=float(group.metadata["delay_ms"][0]),
        direction=key.split("/")[0],
        n_perturbed=len(group),
        n_unperturbed=n_unperturbed,
        cop_m=float(weight @ nominal[:, _DX, :n].mean(axis=0) / weight.sum()),
        stiffness=analysis.stiffness,
        damping=analysis.damping,
        inertia=analysis.inertia,
        vaf=analysis.vaf,
        stiffness_slope=analysis.stiffness_slope,
        window_stiffness={
            f"{w:g}": float(np.mean(k)) for w, k in zip(windows[1:], fit.stiffness[1:], strict=True)
        },
        onset_ms=group.metadata["onset_ms"],
        time_s=np.arange(n) / fs,
        angle=boot[:, _ANGLE, :n],
        torque=boot[:, _TORQUE, :n],
        model_torque=impedance_torque(analysis, boot[:, _KIN, :n], fs),
        warnings=(
            ()
            if settings.stiffness_model == "linear"
            else _slope_warning(
                key, analysis.stiffness, boot[:, _KIN, :n], boot[:, _TORQUE, :n], fs
            )
        ),
    )


def _slope_warning(
    key: str,
    stiffness: NDArray[np.float64],
    kinematics: NDArray[np.float64],
    torque: NDArray[np.float64],
    fs: float,
) -> tuple[str, ...]:
    """A warning when a constant-stiffness estimate hides a stiffness that changes in its window.

    The linear stiffness model (:func:`~anklelab.ident.impedance.fit_impedance`,
    ``stiffness_model="linear"``) is fitted to the same bootstrap averages as a diagnostic. A
    warning is returned when the change it finds over the window, ``|k₁| × window``, exceeds
    ``_SLOPE_WARNING_FRACTION`` (20 %) of the constant model's stiffness and ``|k₁|``
    exceeds ``_SLOPE_WARNING_SDS`` (3) bootstrap sd (a slope that noise alone could produce is
    not reported).

    Parameters
    ----------
    key : str
        Condition named in the message (``"dorsi/225"``).
    stiffness : ndarray, shape (n_reps,)
        Bootstrap stiffness of the constant model, N·m/rad.
    kinematics : ndarray, shape (n_reps, 3, n_window)
        Bootstrap ``(θ, θ', θ'')`` over the analysis window, rad, rad/s, rad/s².
    torque : ndarray, shape (n_reps, n_window)
        Bootstrap torque over the window, N·m.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    tuple of str
        The warning, or nothing.
    """
    slope = fit_impedance(kinematics, torque, stiffness_model="linear", fs=fs).stiffness_slope
    mean, window_s, k = float(np.mean(slope)), torque.shape[-1] / fs, float(np.mean(stiffness))
    change = abs(mean) * window_s
    if change <= _SLOPE_WARNING_FRACTION * abs(k) or abs(mean) <= _SLOPE_WARNING_SDS * _sd(slope):
        return ()
    return (
        f"{key}: the stiffness changes within the {window_s * 1000:g} ms window: the linear "
        f"model finds {mean:+.0f} ± {_sd(slope):.0f} N·m/rad/s, {change / abs(k):.0%} of the "
        f"constant model's {k:.0f} N·m/rad over the window; a constant stiffness lets damping "
        'and inertia absorb the change and biases it: consider stiffness_model = "linear"',
    )


def _condition_order(stance: Trials) -> list[str]:
    keys = [c for c in stance.conditions() if c != "none"]
    delay = dict(zip(stance.metadata["condition"], stance.metadata["delay_ms"], strict=True))
    return sorted(keys, key=lambda c: (_DIRECTIONS.index(c.split("/")[0]), delay[c]))


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
        if not np.isclose(filters.fs_, fs) or tuple(filters.channels) != CHANNELS:
            raise ParameterError(
                f"filters: fitted at {filters.fs_:g} Hz on channels {filters.channels}; the "
                f"session is sampled at {fs:g} Hz with channels {CHANNELS}"
            )
        _check_calibration_lengths(filters, session.calibration, fs)
        filter_vaf, filter_vaf_by_channel = _score_filters(filters, session.calibration)
    report(STEPS[1])
    stance, mislabelled = _stance_trials(session, settings, filters)
    unperturbed = stance["none"]
    drops = "; ".join(
        [*mislabelled, f"drop reasons: {_drop_summary(stance.drop_log, session.walking)}"]
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
    for message in mislabelled:
        warnings.warn(message, AnklelabWarning, stacklevel=2)
    report(STEPS[2])
    rng = np.random.default_rng(settings.seed)
    nominal = unperturbed.average()
    points = [
        _timing_point(stance, key, nominal, len(unperturbed), settings, rng)
        for key in _condition_order(stance)
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
        warnings=tuple(mislabelled),
    )


def _drop_summary(
    drop_log: Sequence[tuple[str, ...]], walking: Sequence[WalkingTrial], shown: int = 3
) -> str:
    """Each kind of drop reason with its count and the first ``shown`` files it applies to."""
    files: dict[str, list[str]] = {}
    for reasons, trial in zip(drop_log, walking, strict=True):
        for reason in reasons:
            files.setdefault(_reason_kind(reason), []).append(trial.recording.name)
    parts = []
    for reason, names in files.items():
        more = ", ..." if len(names) > shown else ""
        parts.append(f"{reason} ({len(names)}: {', '.join(names[:shown])}{more})")
    return "; ".join(parts) or "none"
