"""What the report needs from ``results.json`` and ``friction.json``, checked before it is shown.

A result file may be damaged or edited by hand. Its values are checked against these models
(strict types: a number must be a JSON number, not text) before any of them is formatted, and
a problem is one :class:`~anklelab.errors.ResultsFormatError` naming the file and the key.
Keys the report does not show are allowed and ignored.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError

from anklelab.errors import ResultsFormatError

__all__ = ["FRICTION_KEYS", "WALKING_KEYS", "check_friction", "check_walking", "parse_document"]

WALKING_KEYS = ("platform_filters", "timing_points")
FRICTION_KEYS = ("inertia_kgm2", "coulomb_nm", "viscous_nms_per_rad")


class _Model(BaseModel):
    model_config = ConfigDict(strict=True, extra="allow")


class _MeanSd(_Model):
    mean: float | None = None
    sd: float | None = None


class _Filters(_Model):
    n_lags: int | None = None
    vaf_percent_mean: float | None = None
    vaf_percent_sd: float | None = None
    vaf_percent_by_channel: dict[str, float] = {}


class _TimingPoint(_Model):
    delay_ms: float
    direction: str
    n_perturbed: int | None = None
    n_unperturbed: int | None = None
    cop_m: float | None = None
    stiffness_nm_per_rad: _MeanSd
    damping_nms_per_rad: _MeanSd | None = None
    inertia_kgm2: _MeanSd | None = None
    vaf_percent: _MeanSd | None = None
    window_sensitivity: dict[str, dict[str, float | None]] = {}


class _Bench(_Model):
    distance_m: float
    stiffness_nm_per_rad: float
    r2: float
    n_tests: int | None = None


class _Validation(_Model):
    delay_ms: float
    cop_m: float
    bench_stiffness_nm_per_rad: float
    error_percent: float


class _Walking(_Model):
    platform_filters: _Filters
    timing_points: list[_TimingPoint]
    settings: dict[str, Any] = {}
    bench: list[_Bench] | None = None
    validation: list[_Validation] | None = None


class _Directions(_Model):
    cw: float
    ccw: float


class _Fit(_Model):
    spindown_vaf_percent: float | None = None
    chirp_vaf_percent: float | None = None


class _Friction(_Model):
    inertia_kgm2: float
    viscous_nms_per_rad: _Directions
    coulomb_nm: _Directions
    stribeck_velocity_rad_s: float
    static_friction_nm: float
    fit: _Fit = _Fit()


def _where(loc: Sequence[Any]) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else f".{part}" if text else str(part)
    return text


def _check(model: type[_Model], document: dict[str, Any], path: Path) -> dict[str, Any]:
    try:
        model.model_validate(document)
    except ValidationError as exc:
        error = exc.errors()[0]
        loc = error["loc"]
        if error["type"] == "missing":
            raise ResultsFormatError(f"{path}: {_where(loc)}: required key is missing") from None
        expected = error["msg"].removeprefix("Input should be ").replace("a valid ", "a ")
        raise ResultsFormatError(
            f"{path}: {_where(loc)}: expected {expected}, got {error.get('input')!r:.40}"
        ) from None
    return document


def parse_document(data: bytes, path: Path, required: Sequence[str]) -> dict[str, Any]:
    """A result file's JSON object, with its top-level ``required`` keys present.

    Raises
    ------
    ResultsFormatError
        Naming the file: not UTF-8, not valid JSON, not an object, or a key missing.
    """
    try:
        document = json.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ResultsFormatError(f"{path}: not UTF-8 text (offset {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise ResultsFormatError(f"{path}: not valid JSON: {exc}") from None
    except RecursionError:
        raise ResultsFormatError(f"{path}: not valid JSON: nested too deeply") from None
    if not isinstance(document, dict):
        raise ResultsFormatError(f"{path}: expected a JSON object, got {type(document).__name__}")
    missing = [key for key in required if key not in document]
    if missing:
        raise ResultsFormatError(
            f"{path}: missing key(s) {', '.join(missing)}; is this an anklelab result file?"
        )
    return document


def check_walking(document: dict[str, Any], path: Path) -> dict[str, Any]:
    """``document`` if it holds what the walking section shows (see the module docstring)."""
    return _check(_Walking, document, path)


def check_friction(document: dict[str, Any], path: Path) -> dict[str, Any]:
    """``document`` if it holds what the friction section shows (see the module docstring)."""
    return _check(_Friction, document, path)
