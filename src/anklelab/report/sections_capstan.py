"""Report sections for the results of the ``anklelab capstan`` commands.

Each command with ``--out DIR`` writes ``DIR/<name>.json`` (one object, ``results``), its figure
``DIR/<name>.png`` and the run manifest ``DIR/run.json`` (the command, version, settings and
inputs); :func:`capstan_sections` turns those the run wrote into report sections: a table of the
results and the figure.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import Any

from anklelab._runs import NotEmbeddable
from anklelab.errors import ResultsFormatError
from anklelab.report._documents import parse_document
from anklelab.report.html import Section, Table
from anklelab.report.sections import MAX_RESULT_BYTES, ResultFiles, read_figures

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


def capstan_sections(files: ResultFiles) -> tuple[list[Section], list[str]]:
    """Sections for the capstan results among ``files``, and notes on figures left out.

    Raises
    ------
    ResultsFormatError
        A result file is not one the run wrote, not valid JSON, or not the results of its
        command.
    """
    directory, manifest = files.directory, files.manifest
    sections, notes = [], []
    for stem, title, caption, renderer in CAPSTAN_RESULTS:
        name = f"{stem}.json"
        if not os.path.lexists(directory / name):
            continue
        command = f"capstan {stem.split('_')[0]}"
        try:
            document = parse_document(
                files.read(name, limit=MAX_RESULT_BYTES), directory / name, ("results",)
            )
            columns, rows = renderer(document["results"])
        except NotEmbeddable as exc:
            raise ResultsFormatError(str(exc)) from None
        except (KeyError, TypeError, IndexError, ValueError, AttributeError) as exc:
            raise ResultsFormatError(
                f"{directory / name}: not the results of `anklelab {command}` "
                f"({type(exc).__name__}: {exc})"
            ) from None
        found = read_figures(files, [(stem, title, caption)])
        notes += [f"figure not found in {directory}: {m}" for m in found.missing] + found.refused
        source = (
            f"From `anklelab {manifest.command}` (anklelab {manifest.anklelab_version})."
            if manifest is not None
            else f"From `anklelab {command}`."
        )
        sections.append(Section(title, source, [Table(title, columns, rows)], found.figures))
    return sections, notes
