"""Settings of the walking-impedance analysis, validated when loaded (paper 000's defaults)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import ConfigDict, Field, model_validator

from anklelab._params import Parameters, load_parameters

if TYPE_CHECKING:
    from anklelab.data.session import SessionInfo

__all__ = ["WalkingSettings", "load_walking_settings"]

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
    contact_cop_ms, contact_cop_degree
        The COP at heel contact (where the COP is zeroed) is a polynomial of this degree in time
        fitted to the unfiltered COP over this span from the contact sample, weighted by the
        squared vertical force, and read at the instant the force crosses the threshold. The
        early COP path's shape differs between feet and plates: no span and degree fits every
        one to 1 mm (see the walking-analysis guide for the measured spread).
    contact_twist_cutoff_hz
        With a ``transmission_stiffness_nm_per_rad``, the COP at heel contact is read from the
        unfiltered load less the plate's own forces of the coupler's twist under the heel's
        strike, the twist taken from the unfiltered ankle torque low-passed at this frequency
        (2nd order, zero phase; not filtered at or above the session's Nyquist frequency), Hz.
        At least the 20 Hz of paper 000's low-pass, below which the twist correction of the
        low-passed load already acts. A heavy top plate's own moment while the load is still
        small moved the contact COP by up to 4 cm on the independent generator. 60 Hz was
        chosen on 60 randomised-twin sessions: the lever arm's mean error was -1.68 mm without
        this correction, -0.76 mm with the twist unfiltered, -0.46, -0.41 and -0.43 mm at 30,
        60 and 150 Hz.
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
    transmission_stiffness_nm_per_rad
        Torsional stiffness between the motor's angle sensor and the plate (gearbox and coupler
        in series), N·m/rad; paper 000: 12 N·m/arcmin. The platform filters, fitted with nobody
        on the plate, predict the plate's own forces from the motor angle; under the foot's
        torque ``T`` the plate lags the motor by the coupler's twist ``T / K``, whose own forces
        (the filters' memoryless gains, :meth:`~anklelab.ident.PlatformFilters.predict_departure`)
        are taken off as well (see :func:`~.stance.stance_trials`). The correction's whole move
        of each estimate counts in its 95 % interval (it assumes this stiffness). 0: the motor
        angle is taken as the plate's angle, as in paper 000 (no correction, nothing added to
        the intervals).
    force_delay_ms
        How much later the plate's channels are recorded than the angles, ms: an amplifier's
        anti-alias low-pass (a 4th-order Butterworth at ``f`` Hz delays by about
        ``2.61 / (2π f)`` s, 1.04 ms at 400 Hz, as the twin's amplifier), converter skew. The
        plate's signals (calibration and walking) are moved that much earlier before anything
        else. A delay moves all three estimates (2 ms on the hand-made test session: the
        stiffness by about 1 %, the inertia by 4-11 %); the analysis does not estimate it.
        ``None`` (default): the session's own ``[force_plate] delay_ms``, which records the
        recording chain (0 when it says nothing, as paper 000's DAQ, which has no filter).
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
        ``"auto"`` (default): per timing point, the constant or the linearly changing stiffness
        ``k + k₁ (t - t_c)``, whichever estimates the θ²-weighted stiffness with the smaller
        mean squared error (see :mod:`anklelab.pipelines.walking.impedance`). ``"constant"``:
        paper 000's model. ``"linear"``: always the changing stiffness. How each does on the
        randomised twin and the independent generator: docs/guide/walking-analysis.md.
    inertia_model
        ``"session"`` (default): one inertia for every timing point and direction of the
        session (the foot and what moves with it do not change between them), fitted jointly
        with each point's own stiffness and damping (see
        :mod:`anklelab.pipelines.walking.impedance`), from the model damping and inertia come
        from (with ``stiffness_model = "auto"`` the linear one: the constant model's stiffness
        is then fitted around that inertia too); ``"point"``: each point's own, as paper 000
        fits it.
    angle_gain
        ``"pooled"`` (default): each condition's ankle angle is scaled to the gain against the
        plate's rotation that the conditions share, as far as their gains differ by no more
        than their noise explains (:mod:`anklelab.pipelines.walking.gain`); ``"measured"``:
        the angle as recorded, as paper 000 takes it. Either way ``results.json`` gives each
        condition's gain.
    covariate_adjustment, adjustment_span_ms, adjustment_guard_ms, adjustment_bins
        Remove each trial's own gait variation, predicted from its raw signals over the
        ``adjustment_span_ms`` before its onset (ending ``adjustment_guard_ms`` before it, in
        ``adjustment_bins`` bins) by a regression learned on the unperturbed trials (see
        :mod:`anklelab.pipelines.walking.adjustment`).
    outlier_mads
        A perturbed or unperturbed trial departing from its group's median by more than this
        many robust sd at any sample is dropped with a reason (a glitch would dominate the
        average).
    interval_reps
        Resamples behind each 95 % interval (``ci95``).
    timing_uncertainty_ms
        How well the timing between the angle and the plate's channels is known (anti-alias
        filters, converter skew); the estimates' moves when the torque is shifted by this much
        widen the intervals (damping moves by about ``k δ``, inertia by ``b δ``), ms.
    coupler_lag_ms
        How far the coupler's own damping ``c`` delays its twist behind ``T / K`` (``c / K``;
        ``2 ζ / ω`` for a damping ratio ``ζ`` at the plate's resonance ``ω`` on the coupler),
        ms. The twist correction is delayed by this much, and the estimates' moves when it is
        taken this much earlier or later widen the intervals. 2 ms is a damping ratio of 0.15
        with the resonance at 25 Hz, or 0.3 at 50 Hz.
    change_basis
        Where the change of the stiffness within each window is taken from: ``"neighbours"``,
        the slope of the stiffness across the neighbouring timing points of its direction (the
        window's own linear model where a direction has one point), or ``"window"``, the
        window's linear model everywhere (far less precise: root-mean-square error 0.080
        against 0.024 on 200 held-out randomised-twin sessions; see :mod:`.change`).
    change_threshold, change_confidence
        The stiffness is reported as changing within the window when the probability that its
        change over the window (a fraction of it) lies beyond ``change_threshold`` on its
        estimate's side is at least
        ``change_confidence`` (and the stiffness itself is not poorly determined). The
        probability is Student's t about the estimate with the standard error behind its 95 %
        interval; 0.5 says it when the estimated change itself lies beyond the threshold. 0.5
        was chosen on 200 randomised-twin sessions, as the value whose larger rate of false
        alarms and misses is smallest (0.975 would need the whole 95 % interval beyond the
        threshold, and misses half the large changes), and checked on 200 others and on the
        clean-room generator (walking-analysis guide).
    bootstrap_reps, bootstrap_fraction, seed
        Paper 000's bootstrap (its ``sd``): repetitions, fraction of the perturbed trials per
        repetition; the seed of every random draw.
    """

    model_config = ConfigDict(**Parameters.model_config, allow_inf_nan=False)

    cutoff_hz: float = Field(20.0, gt=0)
    filter_order: int = Field(4, ge=1, le=12)
    derivative_window: int = Field(5, ge=3)
    heel_contact_threshold_n: float = Field(25.0, gt=0)
    heel_contact_hold_ms: float = Field(5.0, ge=0)
    contact_cop_ms: float = Field(20.0, gt=0)
    contact_cop_degree: int = Field(1, ge=0, le=5)
    contact_twist_cutoff_hz: float = Field(60.0, ge=20)
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
    transmission_stiffness_nm_per_rad: float = Field(41252.96, ge=0)  # 12 N·m/arcmin
    force_delay_ms: float | None = Field(None, ge=0, le=50)
    window_ms: float = Field(100.0, gt=0)
    offset_reference_ms: float | None = Field(None, ge=0)
    sensitivity_windows_ms: tuple[float, ...] = (75.0, 125.0)
    stiffness_model: Literal["auto", "constant", "linear"] = "auto"
    inertia_model: Literal["session", "point"] = "session"
    angle_gain: Literal["pooled", "measured"] = "pooled"
    covariate_adjustment: bool = True
    adjustment_span_ms: float = Field(100.0, gt=0)
    adjustment_guard_ms: float = Field(5.0, ge=0)
    adjustment_bins: int = Field(5, ge=1, le=50)
    outlier_mads: float = Field(25.0, gt=3)
    interval_reps: int = Field(200, ge=20, le=20_000)
    timing_uncertainty_ms: float = Field(1.0, ge=0)
    coupler_lag_ms: float = Field(2.0, ge=0, le=50)
    change_basis: Literal["neighbours", "window"] = "neighbours"
    change_threshold: float = Field(0.2, gt=0)
    change_confidence: float = Field(0.5, ge=0.5, lt=1.0)
    bootstrap_reps: int = Field(100, ge=1, le=20_000)
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

    def force_delay_samples(self, info: SessionInfo) -> float:
        """The plate channels' delay in samples of the session ``info`` describes (a fraction
        of a sample allowed): ``force_delay_ms``, or the session's own when it is ``None``."""
        delay_ms = info.force_delay_ms if self.force_delay_ms is None else self.force_delay_ms
        return delay_ms * info.sample_rate_hz / 1000.0

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
