"""What the walking analysis produced, and its ``results.json`` / CSV forms (DESIGN §5)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab._version import __version__
from anklelab.ident.bench import BenchStiffness, interpolate_stiffness
from anklelab.ident.irf import PlatformFilters
from anklelab.pipelines.walking.settings import WalkingSettings
from anklelab.pipelines.walking.stance import reason_kind
from anklelab.signals import Trials

__all__ = ["TimingPoint", "WalkingResults", "sd"]


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
        with their ``delay_ms``, and a ``grf_cop`` session whose calibration COP is empty (the
        platform's own moment is then not removed); each is also issued as an
        :class:`~anklelab.errors.AnklelabWarning`.
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
        kinds = [reason_kind(reasons[0]) for reasons in self.stance.drop_log if reasons]
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
                    "vaf_percent_sd": sd(self.filter_vaf) if scored else None,
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
                "onset_ms_sd": sd(tp.onset_ms),
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
                row[f"{name}_mean"], row[f"{name}_sd"] = float(np.mean(values)), sd(values)
            for key, value in tp.window_stiffness.items():
                row[f"stiffness_nm_per_rad_{key}ms"] = value
            match = check.get(tp.delay_ms) if tp.direction == "dorsi" else None
            row["bench_stiffness_nm_per_rad"] = match and match["bench_stiffness_nm_per_rad"]
            row["error_percent"] = match and match["error_percent"]
            rows.append(row)
        return rows


def sd(values: NDArray[np.float64]) -> float:
    return float(np.std(values, ddof=1)) if np.size(values) > 1 else 0.0


def _summary(values: NDArray[np.float64]) -> dict[str, float]:
    return {"mean": float(np.mean(values)), "sd": sd(values)}


def _finite(node: Any) -> Any:
    """JSON has no NaN: non-finite floats become ``None``."""
    if isinstance(node, dict):
        return {key: _finite(value) for key, value in node.items()}
    if isinstance(node, list | tuple):
        return [_finite(value) for value in node]
    if isinstance(node, float) and not np.isfinite(node):
        return None
    return node
