"""Report sections for the results of the ``anklelab capstan`` commands.

Each command writes ``OUT/<name>.json`` (``anklelab_version``, ``command``, ``settings``,
``inputs``, ``results``) and ``OUT/<name>.png``; :func:`capstan_sections` turns those found in a
directory into report sections: a table of the results and the figure.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from anklelab.errors import ResultsFormatError
from anklelab.report.html import Figure, Section, Table

__all__ = ["CAPSTAN_RESULTS", "capstan_sections"]


def _deg(value: Any) -> str:
    return "-" if value is None else f"{math.degrees(value):.3g} deg"


def _num(value: Any, unit: str = "", fmt: str = ".3g") -> str:
    return "-" if value is None else f"{value:{fmt}}{' ' + unit if unit else ''}"


def _hz(value: Any) -> str:
    return "beyond the sweep" if value is None else f"{value:.2f} Hz"


def _steps(r: Any) -> tuple[list[str], list[list[str]]]:
    columns = ["set-point", "rise 10-90 %", "within 5 %", "within 2 %", "overshoot", "fault"]
    rows = [
        [
            f"{s['set_point_deg']:g} deg",
            _num(s["rise_time_s"] and s["rise_time_s"] * 1e3, "ms", ".0f"),
            _num(s["settling_time_5_s"] and s["settling_time_5_s"] * 1e3, "ms", ".0f"),
            _num(s["settling_time_s"] and s["settling_time_s"] * 1e3, "ms", ".0f"),
            _num(s["overshoot_percent"], "%", ".1f"),
            s["fault"],
        ]
        for s in r
    ]
    return columns, rows


def _chirp(r: Any) -> tuple[list[str], list[list[str]]]:
    return ["quantity", "value"], [
        ["rms tracking error", _deg(r["rms_error_rad"])],
        ["max error", _deg(r["max_error_rad"])],
        ["tracks within 1 dB and 20 deg up to", _hz(r["tracking_limit_hz"])],
        ["-3 dB bandwidth", _hz(r["bandwidth_3db_hz"])],
    ]


def _envelope(r: Any) -> tuple[list[str], list[list[str]]]:
    twin = r.get("twin_amplitude_rad")
    columns = ["frequency", "model", "limited by", *(["twin", "twin - model"] if twin else [])]
    rows = []
    for k, f in enumerate(r["frequency_hz"]):
        row = [f"{f:.3g} Hz", _deg(r["amplitude_rad"][k]), r["limiting"][k]]
        if twin:
            row += [_deg(twin[k]), _num(r["twin_minus_model_percent"][k], "%", "+.1f")]
        rows.append(row)
    return columns, rows


def _observer(r: Any) -> tuple[list[str], list[list[str]]]:
    return ["quantity", "value"], [
        ["VAF", _num(r["vaf_percent"], "%", ".1f")],
        ["delay", _num(r["delay_s"] * 1e3, "ms", ".0f")],
        ["VAF, delay removed", _num(r["vaf_delay_compensated_percent"], "%", ".1f")],
        ["rms error", _num(r["rms_error_nm"], "N·m")],
    ]


def _render(r: Any) -> tuple[list[str], list[list[str]]]:
    return ["felt by the foot", "value", "error"], [
        [
            "stiffness",
            _num(r["stiffness_nm_per_rad"], "N·m/rad"),
            _num(r["stiffness_error_percent"], "%", "+.1f"),
        ],
        [
            "damping",
            _num(r["damping_nms_per_rad"], "N·m·s/rad"),
            _num(r["damping_error_percent"], "%", "+.1f"),
        ],
        ["inertia", _num(r["inertia_kgm2"], "kg·m²"), ""],
    ]


def _scene(r: Any) -> tuple[list[str], list[list[str]]]:
    rows = [
        ["slope", _deg(r["slope_rms_rad"]), _deg(r["slope_rms_error_rad"])],
        ["bumps", _deg(r["bumps_rms_rad"]), _deg(r["bumps_rms_error_rad"])],
    ]
    for k, p in enumerate(r["patches"]):
        rows.append(
            [
                f"patch {k + 1}",
                f"K {p['stiffness_nm_per_rad']:g}, B {p['damping_nms_per_rad']:g}",
                f"K {_num(p['stiffness_error_percent'], '%', '+.1f')}, "
                f"B {_num(p['damping_error_percent'], '%', '+.1f')}",
            ]
        )
    return ["component", "rms (patches: commanded)", "error"], rows


def _zwidth(r: Any) -> tuple[list[str], list[list[str]]]:
    a, m = r["analytic"], r["measured_nm_per_rad"]
    rows = [
        [
            f"{b:g}",
            _num(a["viscous_nm_per_rad"][k], "", ".0f"),
            _num(m.get("stomp", [None] * (k + 1))[k], "", ".0f"),
            _num(a["quantization_nm_per_rad"], "", ".0f"),
            _num(m.get("nudge", [None] * (k + 1))[k], "", ".0f"),
        ]
        for k, b in enumerate(r["damping_nms_per_rad"])
    ]
    columns = ["damping (N·m·s/rad)", "viscous mode", "stomp (twin)", "quantisation", "nudge"]
    return columns, rows


def _teleop(r: Any) -> tuple[list[str], list[list[str]]]:
    rows = [
        [
            f"{t['delay_ms']:g} ms",
            "yes" if t["stable"] else "no",
            _deg(t["position_rms_error_rad"]),
            _num(t["force_rms_error_nm"], "N·m"),
        ]
        for t in r
    ]
    return ["delay", "stable", "angle error (rms)", "torque error (rms)"], rows


def _gains(r: Any) -> tuple[list[str], list[list[str]]]:
    return ["gain", "value"], [[key, _num(value)] for key, value in r.items()]


Renderer = Callable[[Any], tuple[list[str], list[list[str]]]]
CAPSTAN_RESULTS: tuple[tuple[str, str, str, Renderer], ...] = (
    (
        "gains",
        "Capstan: PID gains",
        "Critically damped PID designed from the platform model.",
        _gains,
    ),
    (
        "steps",
        "Capstan: set-point steps",
        "Encoder angle (solid) and reference (dashed) after each set-point change; the dotted line "
        "is paper 001's 300 ms.",
        _steps,
    ),
    (
        "chirp",
        "Capstan: chirp tracking",
        "The chirp in time and the measured closed-loop response; shaded: within 1 dB and "
        "20 degrees.",
        _chirp,
    ),
    (
        "envelope",
        "Capstan: display envelope",
        "The largest sinusoid the platform renders: each limit (dotted), their minimum (black), "
        "the amplitudes found on the twin (circles), paper 001's 5 degrees at 3 Hz (star) and the "
        "slope of ISO 8608 class B ground walked at 1 m/s (green, per octave).",
        _envelope,
    ),
    (
        "observer_hold",
        "Capstan: torque observer, holding",
        "The user's torque on the platform: the twin's truth and the observer's estimate.",
        _observer,
    ),
    (
        "observer_track",
        "Capstan: torque observer, tracking",
        "The user's torque on the platform: the twin's truth and the observer's estimate.",
        _observer,
    ),
    (
        "render",
        "Capstan: haptic rendering",
        "The rendered angle against the equilibrium, and the user's torque (true and estimated).",
        _render,
    ),
    (
        "scene",
        "Capstan: terrain scene",
        "The terrain and the platform's angle (compliant patches shaded), the difference, and the "
        "person's torque.",
        _scene,
    ),
    (
        "zwidth",
        "Capstan: Z-width",
        "Largest stable virtual stiffness per virtual damping: the analytic sampled-data passivity "
        "boundaries (lines) and the twin's, a human-like ankle on the platform (markers).",
        _zwidth,
    ),
    (
        "teleop",
        "Capstan: teleoperation",
        "Tracking error against the network delay, and the longest delay's run.",
        _teleop,
    ),
)
"""(file stem, section title, figure caption, table renderer) of each capstan result."""


def capstan_sections(directory: Path) -> tuple[list[Section], list[str]]:
    """Sections for the capstan results found in ``directory``, and figures that are missing.

    Raises
    ------
    ResultsFormatError
        A result file is not valid JSON or lacks its ``results``.
    """
    sections, missing = [], []
    for stem, title, caption, renderer in CAPSTAN_RESULTS:
        path = directory / f"{stem}.json"
        if not path.is_file():
            continue
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
            results = document["results"]
            columns, rows = renderer(results)
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ResultsFormatError(f"{path}: not valid JSON: {exc}") from None
        except (KeyError, TypeError, IndexError, ValueError) as exc:
            raise ResultsFormatError(
                f"{path}: not the results of `anklelab capstan {stem.split('_')[0]}` "
                f"({type(exc).__name__}: {exc})"
            ) from None
        figure = directory / f"{stem}.png"
        figures = [Figure(title, figure.read_bytes(), caption)] if figure.is_file() else []
        if not figures:
            missing.append(figure.name)
        command = document.get("command", f"anklelab capstan {stem}")
        text = f"From `{command}` (anklelab {document.get('anklelab_version', '?')})."
        sections.append(Section(title, text, [Table(title, columns, rows)], figures))
    return sections, missing
