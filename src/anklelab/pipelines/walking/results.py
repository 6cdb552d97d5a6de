"""What the walking analysis produced, and its one schema (``results.json``, CSV, summaries).

The quantities of a timing point and their keys, units and printed formats are declared once,
in :data:`QUANTITIES`; :meth:`WalkingResults.to_dict` (the ``results.json`` document of
DESIGN §5, extended additively), :meth:`WalkingResults.from_dict` (reading it back, for reports
and studies), :meth:`WalkingResults.table` (``results.csv``) and the command line's summary all
follow it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from anklelab._json import json_ready
from anklelab._version import __version__
from anklelab.errors import ResultsFormatError
from anklelab.ident.bench import BenchStiffness, extrapolated, interpolate_stiffness
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.signals import Trials

if TYPE_CHECKING:
    from anklelab.ident.irf import PlatformFilters

__all__ = ["QUANTITIES", "Estimate", "Quantity", "TimingPoint", "WalkingResults", "sd"]

POORLY_DETERMINED_FRACTION = 0.5
"""A quantity whose 95 % interval's half-width exceeds this fraction of its value is poorly
determined (as is one whose interval spans zero)."""


def _empty() -> NDArray[np.float64]:
    return np.zeros(0)


class Quantity(NamedTuple):
    """One estimated quantity of a timing point: attribute, ``results.json`` key, unit, symbol
    and number format."""

    name: str
    key: str
    unit: str
    symbol: str
    format: str


QUANTITIES = (
    Quantity("stiffness", "stiffness_nm_per_rad", "N·m/rad", "k", ".0f"),
    Quantity("damping", "damping_nms_per_rad", "N·m·s/rad", "b", ".2f"),
    Quantity("inertia", "inertia_kgm2", "kg·m²", "I", ".3f"),
    Quantity("vaf", "vaf_percent", "%", "VAF", ".1f"),
)
"""The quantities every timing point reports, in order."""
SLOPE = Quantity("stiffness_slope", "stiffness_slope_nm_per_rad_per_s", "N·m/rad/s", "k₁", ".0f")
CHANGE = Quantity("stiffness_change", "stiffness_change_fraction", "", "Δk/k", ".2f")


def sd(values: Sequence[float] | NDArray[np.float64]) -> float:
    """Sample standard deviation (0 for fewer than two values)."""
    return float(np.std(values, ddof=1)) if np.size(values) > 1 else 0.0


@dataclass(frozen=True)
class Estimate:
    """An estimated quantity.

    Attributes
    ----------
    mean : float
        The estimate from all the condition's trials (the ``mean`` key of ``results.json``).
    sd : float
        Paper 000's spread: sd over averages of random 60 % subsets of the perturbed trials
        (``bootstrap_reps``, ``bootstrap_fraction``), for comparison with the paper. It covers
        random error only and understates the estimate's standard error (~0.8×).
    ci95 : (float, float)
        95 % interval from the resampling of :mod:`.impedance` (NaN if not computed).
    samples : ndarray
        The subset values ``sd`` is taken over (in memory only).
    bias_unknown : bool
        (Keyword only.) The estimate carries a bias that the interval cannot bound (the
        session's warnings say why, e.g. a platform moment the filters could not learn); it is
        then poorly determined.
    """

    mean: float
    sd: float
    ci95: tuple[float, float] = (np.nan, np.nan)
    samples: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)
    bias_unknown: bool = field(default=False, kw_only=True)

    @property
    def poorly_determined(self) -> bool:
        """True when the interval spans zero or is wider than ±50 % of the estimate, or the
        estimate carries a bias the interval cannot bound."""
        if self.bias_unknown:
            return True
        low, high = self.ci95
        if not (np.isfinite(low) and np.isfinite(high)):
            return False
        half = (high - low) / 2
        return bool(low <= 0 <= high or half > POORLY_DETERMINED_FRACTION * abs(self.mean))

    def to_dict(self) -> dict[str, Any]:
        """``{"mean", "sd", "ci95", "poorly_determined"}``, and ``"bias_unknown": true`` when
        it is."""
        return {
            "mean": self.mean,
            "sd": self.sd,
            "ci95": list(self.ci95),
            "poorly_determined": self.poorly_determined,
        } | ({"bias_unknown": True} if self.bias_unknown else {})

    @classmethod
    def from_dict(cls, node: Any, where: str) -> Estimate:
        """Read :meth:`to_dict`'s form (``ci95`` optional, as older files lack it)."""
        if not isinstance(node, dict) or "mean" not in node:
            raise ResultsFormatError(
                f"{where}: expected {{'mean': ..., 'sd': ...}}, got {node!r:.60}"
            )
        low, high = node.get("ci95") or (None, None)
        return cls(
            _float(node["mean"]),
            _float(node.get("sd")),
            (_float(low), _float(high)),
            bias_unknown=bool(node.get("bias_unknown", False)),
        )


def _float(value: Any) -> float:
    return np.nan if value is None else float(value)


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
    stiffness, damping, inertia, vaf : Estimate
        N·m/rad (θ²-weighted over the window), N·m·s/rad, kg·m², %.
    stiffness_model : {"constant", "linear"}
        The stiffness model the stiffness and VAF come from (chosen per timing point when the
        setting is ``"auto"``, and then damping and inertia come from the linear model; a model
        set by hand gives all three).
    stiffness_change : Estimate
        Change of the stiffness over the analysis window as a fraction of it: from the
        neighbouring timing points' stiffnesses where the direction has more than one
        (:mod:`.change`), else ``k₁ W / k`` from the window's linear model (always fitted).
    stiffness_change_in_window : Estimate or None
        ``k₁ W / k`` from the window's linear model, when ``stiffness_change`` came from the
        neighbouring timing points (None otherwise, and in files written before it existed).
    stiffness_changes : bool
        The diagnostic: the stiffness changes within the window by more than
        ``change_threshold``, with a probability of at least ``change_confidence``.
    stiffness_slope : Estimate or None
        ``k₁``, N·m/rad/s, when the linear model is used.
    stiffness_change_probability : float
        The diagnostic's probability that the change lies beyond ``change_threshold`` on its
        estimate's side (NaN without an interval, e.g. with one trial, and
        in files written before it existed).
    stiffness_change_verdict : {"changes", "constant", "undetermined"} or None
        What the data say of the change: ``"changes"`` as ``stiffness_changes``; ``"constant"``
        when its 95 % interval lies within ±``change_threshold``; ``"undetermined"`` otherwise
        (the data can tell neither). None in files written before it existed.
    window_stiffness : dict of str to float
        Stiffness for each sensitivity window (key: window in ms, ``"75"``), N·m/rad.
    adjustment_explained : float
        Fraction of the trial-to-trial variance the covariate adjustment removed.
    angle_gain, angle_gain_pooled : float
        The ankle angle's response over the plate's rotation in the analysis window, all trials
        (``g_c``), and the gain the estimates use (pooled over the conditions, ``g*_c``;
        :mod:`.gain`); NaN in files written before they existed.
    warnings : tuple of str
        Doubts about the estimate (plausibility checks, poorly determined quantities, a
        stiffness that changes within the window).
    onset_ms, time_s, angle, torque, model_torque : ndarray
        In memory only (for figures): onsets after heel contact (ms), time over the window (s),
        averages of 60 % subsets of the perturbation angle (rad) and torque and the model torque
        (N·m), shape ``(bootstrap_reps, n_window)``.
    """

    delay_ms: float
    direction: str
    n_perturbed: int
    n_unperturbed: int
    cop_m: float
    stiffness: Estimate
    damping: Estimate
    inertia: Estimate
    vaf: Estimate
    stiffness_model: str
    stiffness_change: Estimate
    stiffness_changes: bool
    stiffness_slope: Estimate | None = None
    stiffness_change_probability: float = np.nan
    stiffness_change_verdict: str | None = None
    stiffness_change_in_window: Estimate | None = None
    window_stiffness: dict[str, float] = field(default_factory=dict)
    adjustment_explained: float = 0.0
    angle_gain: float = np.nan
    angle_gain_pooled: float = np.nan
    warnings: tuple[str, ...] = ()
    onset_ms: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)
    time_s: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)
    angle: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)
    torque: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)
    model_torque: NDArray[np.float64] = field(default_factory=_empty, repr=False, compare=False)

    @property
    def key(self) -> str:
        """Condition key, e.g. ``"dorsi/225"``."""
        return f"{self.direction}/{self.delay_ms:g}"

    def estimates(self) -> dict[Quantity, Estimate]:
        """Every reported quantity with its estimate, in schema order."""
        out = {q: getattr(self, q.name) for q in QUANTITIES}
        if self.stiffness_slope is not None:
            out[SLOPE] = self.stiffness_slope
        out[CHANGE] = self.stiffness_change
        return out

    def to_dict(self) -> dict[str, Any]:
        """This timing point's entry of ``results.json``."""
        entry: dict[str, Any] = {
            "delay_ms": self.delay_ms,
            "direction": self.direction,
            "n_perturbed": self.n_perturbed,
            "n_unperturbed": self.n_unperturbed,
            "cop_m": self.cop_m,
            **{q.key: e.to_dict() for q, e in self.estimates().items()},
            "stiffness_model": self.stiffness_model,
            "stiffness_changes": self.stiffness_changes,
            "stiffness_change_probability": self.stiffness_change_probability,
            "stiffness_change_verdict": self.stiffness_change_verdict,
            **(
                {"stiffness_change_in_window": self.stiffness_change_in_window.to_dict()}
                if self.stiffness_change_in_window is not None
                else {}
            ),
            "window_sensitivity": {
                key: {"stiffness_nm_per_rad": value} for key, value in self.window_stiffness.items()
            },
            "adjustment_explained": self.adjustment_explained,
            "angle_gain": self.angle_gain,
            "angle_gain_pooled": self.angle_gain_pooled,
        }
        return entry | ({"warnings": list(self.warnings)} if self.warnings else {})

    @classmethod
    def from_dict(cls, node: dict[str, Any], where: str) -> TimingPoint:
        """Read one ``timing_points[]`` entry (older files without the additive keys too)."""
        try:
            estimates = {
                q.name: Estimate.from_dict(node[q.key], f"{where}.{q.key}") for q in QUANTITIES
            }
            slope = node.get(SLOPE.key)
            change = node.get(CHANGE.key)
            in_window = node.get("stiffness_change_in_window")
            return cls(
                delay_ms=float(node["delay_ms"]),
                direction=str(node["direction"]),
                n_perturbed=int(node.get("n_perturbed", 0)),
                n_unperturbed=int(node.get("n_unperturbed", 0)),
                cop_m=_float(node.get("cop_m")),
                stiffness=estimates["stiffness"],
                damping=estimates["damping"],
                inertia=estimates["inertia"],
                vaf=estimates["vaf"],
                stiffness_model=str(node.get("stiffness_model", "constant")),
                stiffness_change=Estimate.from_dict(change, f"{where}.{CHANGE.key}")
                if change
                else Estimate(np.nan, np.nan),
                stiffness_changes=bool(node.get("stiffness_changes", False)),
                stiffness_slope=Estimate.from_dict(slope, f"{where}.{SLOPE.key}")
                if slope
                else None,
                stiffness_change_probability=_float(node.get("stiffness_change_probability")),
                stiffness_change_verdict=node.get("stiffness_change_verdict"),
                stiffness_change_in_window=Estimate.from_dict(
                    in_window, f"{where}.stiffness_change_in_window"
                )
                if in_window
                else None,
                window_stiffness={
                    key: float(value["stiffness_nm_per_rad"])
                    for key, value in node.get("window_sensitivity", {}).items()
                },
                adjustment_explained=float(node.get("adjustment_explained", 0.0)),
                angle_gain=_float(node.get("angle_gain")),
                angle_gain_pooled=_float(node.get("angle_gain_pooled")),
                warnings=tuple(node.get("warnings", ())),
            )
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, ResultsFormatError):
                raise
            raise ResultsFormatError(f"{where}: {exc!s:.80}") from None


@dataclass(frozen=True)
class WalkingResults:
    """Everything the walking analysis produced.

    Attributes
    ----------
    settings : WalkingSettings
    platform_filters : dict
        Summary of the platform filters: ``n_lags``, held-out VAF mean and sd and per channel.
    timing_points : list of TimingPoint
    bench : list of BenchStiffness
    drops : dict of str to int
        Dropped walking trials per kind of reason.
    warnings : tuple of str
        Session-level doubts: manifest conditions that lost every trial, a ``grf_cop`` session
        whose calibration COP is empty (the platform's own moment is then not removed),
        implausible results.
    filters, filter_vaf, filter_vaf_by_channel, stance
        In memory only (None when read from ``results.json``): the platform filters used, their
        held-out VAF per calibration trial, pooled ``(n_held,)`` and per channel
        ``(n_held, n_channels)``, %, and the kept stance trials aligned at heel contact with a
        drop log naming why each other trial was dropped.
    """

    settings: WalkingSettings
    platform_filters: dict[str, Any]
    timing_points: list[TimingPoint]
    bench: list[BenchStiffness]
    drops: dict[str, int] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    filters: PlatformFilters | None = None
    filter_vaf: NDArray[np.float64] | None = None
    filter_vaf_by_channel: NDArray[np.float64] | None = None
    stance: Trials | None = None

    def drop_counts(self) -> dict[str, int]:
        """Number of dropped walking trials per kind of reason."""
        return dict(self.drops)

    def validation(self) -> list[dict[str, float | bool]]:
        """Dorsiflexion estimates against the bench stiffness interpolated at ``cop_m``
        (``bench_extrapolated`` where ``cop_m`` lies outside the tested distances, see
        :func:`~anklelab.ident.bench.extrapolated`)."""
        if not self.bench:
            return []
        rows = []
        for tp in self.timing_points:
            if tp.direction != "dorsi":
                continue
            bench = float(interpolate_stiffness(self.bench, tp.cop_m))
            rows.append(
                {
                    "delay_ms": tp.delay_ms,
                    "cop_m": tp.cop_m,
                    "bench_stiffness_nm_per_rad": bench,
                    "error_percent": (tp.stiffness.mean - bench) / bench * 100.0,
                    "bench_extrapolated": extrapolated(self.bench, tp.cop_m),
                }
            )
        return rows

    def to_dict(
        self, session: str, session_sha256: str | None = None, subject: str = ""
    ) -> dict[str, Any]:
        """The ``results.json`` document (DESIGN §5, extended additively).

        Parameters
        ----------
        session : str
            Name of the analysed input (its file or directory name).
        session_sha256 : str, optional
            SHA-256 of the input (:func:`anklelab.data.session_hash`), recorded when given.
        subject : str
            The session's subject (``session.toml``'s ``subject``), recorded when not empty.
        """
        return json_ready(
            {
                "anklelab_version": __version__,
                "session": session,
                **({"session_sha256": session_sha256} if session_sha256 else {}),
                **({"subject": subject} if subject else {}),
                "settings": self.settings.model_dump(mode="json")
                | {"offset_reference_ms": self.settings.offset_reference()},
                "platform_filters": self.platform_filters,
                "timing_points": [tp.to_dict() for tp in self.timing_points],
                "bench": [row._asdict() for row in self.bench],
                "validation": self.validation(),
                "dropped_trials": self.drops,
                **({"warnings": list(self.warnings)} if self.warnings else {}),
            }
        )

    @classmethod
    def from_dict(cls, document: Any, where: str = "results.json") -> WalkingResults:
        """Results read back from a ``results.json`` document (summaries only, no arrays)."""
        if not isinstance(document, dict):
            raise ResultsFormatError(f"{where}: expected a JSON object")
        try:
            points = document["timing_points"]
            settings = {
                k: v
                for k, v in document.get("settings", {}).items()
                if k in WalkingSettings.model_fields
            }
            # written before these settings existed: what the analysis did then
            settings.setdefault("inertia_model", "point")
            settings.setdefault("angle_gain", "measured")
            return cls(
                settings=WalkingSettings.model_validate(settings, strict=False),
                platform_filters=dict(document.get("platform_filters", {})),
                timing_points=[
                    TimingPoint.from_dict(tp, f"{where}: timing_points[{i}]")
                    for i, tp in enumerate(points)
                ],
                bench=[BenchStiffness(**row) for row in document.get("bench", [])],
                drops={k: int(v) for k, v in document.get("dropped_trials", {}).items()},
                warnings=tuple(document.get("warnings", ())),
            )
        except ResultsFormatError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise ResultsFormatError(f"{where}: {exc!s:.100}") from None

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
                "onset_ms_mean": float(np.mean(tp.onset_ms)) if tp.onset_ms.size else None,
                "onset_ms_sd": sd(tp.onset_ms),
                "cop_m": tp.cop_m,
                "stiffness_model": tp.stiffness_model,
            }
            for quantity, estimate in tp.estimates().items():
                row[f"{quantity.key}_mean"] = estimate.mean
                row[f"{quantity.key}_sd"] = estimate.sd
                row[f"{quantity.key}_ci95_low"], row[f"{quantity.key}_ci95_high"] = estimate.ci95
                row[f"{quantity.key}_poorly_determined"] = int(estimate.poorly_determined)
            row["stiffness_changes"] = int(tp.stiffness_changes)
            row["stiffness_change_probability"] = tp.stiffness_change_probability
            row["stiffness_change_verdict"] = tp.stiffness_change_verdict
            for key, value in tp.window_stiffness.items():
                row[f"stiffness_nm_per_rad_{key}ms"] = value
            match = check.get(tp.delay_ms) if tp.direction == "dorsi" else None
            row["bench_stiffness_nm_per_rad"] = match and match["bench_stiffness_nm_per_rad"]
            row["error_percent"] = match and match["error_percent"]
            row["bench_extrapolated"] = match and int(match["bench_extrapolated"])
            rows.append(json_ready(row))
        columns = dict.fromkeys(key for row in rows for key in row)  # the slope is per point
        return [{key: row.get(key) for key in columns} for row in rows]
