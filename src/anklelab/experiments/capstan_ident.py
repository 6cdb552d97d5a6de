"""Friction and inertia identification data of the capstan platform (DESIGN.md section 6).

The directory format::

    ident_dir/
      session.toml          format = "anklelab-session/1", platform = "capstan", sample_rate_hz
      spindown/runs.csv     columns: run, file
      spindown/<file>.csv   columns: time_s, velocity_rad_s, torque_nm (torque 0 from the coast on)
      chirp/<file>.csv      columns: time_s, torque_nm, velocity_rad_s (open-loop torque chirp)
      truth.json            optional: the twin's friction and inertia (simulated data only)

Everything is at the gearhead output (the capstan pinion), positive clockwise. The CSV files are
read and checked by the session reader's :func:`~anklelab.data.directory.read_csv_recording`
(finite values, time strictly increasing at ``sample_rate_hz``; messages name file, column and
line).

:func:`simulate_ident` runs paper 001's two tests on the twin with the cable disconnected: for
each of four speeds in each direction, a speed-controlled ramp from rest (which breaks the shaft
away), a hold, then the current is cut and the shaft coasts to a stop; and an open-loop torque
chirp of rising frequency and amplitude. Velocities are what an encoder gives: whole counts of
the motor encoder, differenced at the sample rate; torques are the commanded motor torque at the
pinion, while the real torque also carries the drive's current-sensor noise.
"""

from __future__ import annotations

import csv
import io
import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab._atomic import atomic_directory
from anklelab.control.pid import PIDGains
from anklelab.control.safety import SafetyLimits
from anklelab.data.directory import read_csv_recording, write_csv_recording
from anklelab.data.session import SESSION_FORMAT, Recording
from anklelab.errors import SessionFormatError
from anklelab.experiments.capstan import CapstanSetup, simulate_closed_loop
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters

__all__ = [
    "CHIRP_COLUMNS",
    "SPINDOWN_COLUMNS",
    "IdentData",
    "IdentProtocol",
    "IdentRun",
    "friction_truth",
    "read_ident_directory",
    "simulate_ident",
    "write_ident_directory",
]

SPINDOWN_COLUMNS = ("time_s", "velocity_rad_s", "torque_nm")
CHIRP_COLUMNS = ("time_s", "torque_nm", "velocity_rad_s")
RUNS_COLUMNS = ("run", "file")


@dataclass(frozen=True)
class IdentRun:
    """One recording at the pinion: time (s), velocity (rad/s, cw positive), torque (N·m)."""

    name: str
    time_s: NDArray[np.float64]
    velocity_rad_s: NDArray[np.float64]
    torque_nm: NDArray[np.float64]


@dataclass(frozen=True)
class IdentData:
    """An identification session: spin-down runs and torque chirps.

    Attributes
    ----------
    sample_rate_hz : float
        Sample rate of every file, Hz.
    spindown : tuple of IdentRun
        Spin-down runs in ``runs.csv`` order.
    chirp : tuple of IdentRun
        Open-loop torque chirps (file-name order).
    truth : mapping or None
        Simulated sessions: the twin's values, keyed like ``friction.json``.
    """

    sample_rate_hz: float
    spindown: tuple[IdentRun, ...]
    chirp: tuple[IdentRun, ...]
    truth: dict[str, Any] | None = None


def friction_truth(params: CapstanParameters) -> dict[str, Any]:
    """The twin's pinion-shaft values, keyed like ``friction.json``."""
    f = params.friction
    return {
        "inertia_kgm2": f.inertia_kgm2,
        "viscous_nms_per_rad": {"cw": f.viscous_cw_nms_per_rad, "ccw": f.viscous_ccw_nms_per_rad},
        "coulomb_nm": {"cw": f.coulomb_cw_nm, "ccw": f.coulomb_ccw_nm},
        "stribeck_velocity_rad_s": f.stribeck_velocity_rad_s,
        "static_friction_nm": f.static_friction_nm,
        "stribeck_exponent": f.stribeck_exponent,
    }


# ----------------------------------------------------------------------------------- reading


def _session_toml(path: Path) -> float:
    file = path / "session.toml"
    try:
        meta = tomllib.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SessionFormatError(f"{file}: file not found; expected session metadata") from None
    except tomllib.TOMLDecodeError as exc:
        raise SessionFormatError(f"{file}: not valid TOML: {exc}") from None
    expected = {"format": SESSION_FORMAT, "platform": "capstan"}
    for key, value in expected.items():
        if meta.get(key) != value:
            raise SessionFormatError(f"{file}: {key} = {meta.get(key)!r}; expected {value!r}")
    fs = meta.get("sample_rate_hz")
    if isinstance(fs, bool) or not isinstance(fs, int | float) or not fs > 0:
        raise SessionFormatError(f"{file}: sample_rate_hz = {fs!r}; expected a number > 0")
    return float(fs)


def _run(path: Path, columns: tuple[str, ...], fs: float) -> IdentRun:
    rec = read_csv_recording(path, columns, fs)
    return IdentRun(path.name, rec["time_s"], rec["velocity_rad_s"], rec["torque_nm"])


def _manifest(folder: Path) -> list[Path]:
    file = folder / "runs.csv"
    try:
        text = file.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise SessionFormatError(f"{file}: file not found; expected columns run, file") from None
    reader = csv.DictReader(io.StringIO(text))
    names = [n.strip() for n in reader.fieldnames or []]
    missing = [c for c in RUNS_COLUMNS if c not in names]
    if missing:
        raise SessionFormatError(
            f"{file}: missing column(s) {', '.join(missing)} in the header (line 1); expected "
            f"columns {', '.join(RUNS_COLUMNS)}"
        )
    paths = []
    for row in reader:
        row = {k.strip(): (v or "").strip() for k, v in row.items() if k}
        where = f"{file}, line {reader.line_num}"
        if not row["run"]:
            raise SessionFormatError(f"{where}, column 'run': empty; expected a run label")
        name = row["file"]
        if not name or "/" in name or "\\" in name or not (folder / name).is_file():
            raise SessionFormatError(f"{where}, column 'file': {name!r} is not a file in {folder}")
        paths.append(folder / name)
    if not paths:
        raise SessionFormatError(f"{file}: no rows after the header; expected one row per run")
    return paths


def read_ident_directory(path: str | Path) -> IdentData:
    """Read and validate an identification directory (see the module docstring).

    Raises
    ------
    SessionFormatError
        Naming the file, column and line of the first problem.
    """
    path = Path(path)
    if not path.is_dir():
        raise SessionFormatError(f"{path}: not a directory; expected an identification session")
    fs = _session_toml(path)
    spindown = tuple(_run(p, SPINDOWN_COLUMNS, fs) for p in _manifest(path / "spindown"))
    chirp_dir = path / "chirp"
    chirps = sorted(chirp_dir.glob("*.csv")) if chirp_dir.is_dir() else []
    if not chirps:
        raise SessionFormatError(f"{chirp_dir}: no CSV files; expected at least one torque chirp")
    chirp = tuple(_run(p, CHIRP_COLUMNS, fs) for p in chirps)
    truth_file = path / "truth.json"
    truth = json.loads(truth_file.read_text()) if truth_file.is_file() else None
    return IdentData(fs, spindown, chirp, truth)


def write_ident_directory(data: IdentData, path: str | Path, *, overwrite: bool = True) -> Path:
    """Write ``data`` as an identification directory, atomically."""
    path = Path(path)
    with atomic_directory(path, overwrite=overwrite) as tmp:
        (tmp / "session.toml").write_text(
            f'format = "{SESSION_FORMAT}"\nplatform = "capstan"\n'
            f"sample_rate_hz = {data.sample_rate_hz!r}\n"
        )
        for folder, runs, columns in (
            ("spindown", data.spindown, SPINDOWN_COLUMNS),
            ("chirp", data.chirp, CHIRP_COLUMNS),
        ):
            (tmp / folder).mkdir()
            for run in runs:
                values = {
                    "time_s": run.time_s,
                    "velocity_rad_s": run.velocity_rad_s,
                    "torque_nm": run.torque_nm,
                }
                write_csv_recording(
                    tmp / folder / run.name, Recording(run.name, {c: values[c] for c in columns})
                )
        lines = ["run,file"] + [f"{k + 1},{run.name}" for k, run in enumerate(data.spindown)]
        (tmp / "spindown" / "runs.csv").write_text("\n".join(lines) + "\n")
        if data.truth is not None:
            (tmp / "truth.json").write_text(json.dumps(data.truth, indent=2) + "\n")
    return path


# -------------------------------------------------------------------------------- simulation


@dataclass(frozen=True)
class IdentProtocol:
    """The identification tests (pinion speeds in rad/s, torques in N·m).

    Attributes
    ----------
    sample_rate_hz : float
        Sampling and control rate.
    speeds_rad_s : tuple of float
        Spin-down start speeds, run in both directions.
    ramp_s, hold_s, coast_s : float
        Speed ramp from rest, hold, and coast after the cut.
    chirp_s : float
        Chirp length.
    chirp_hz : (float, float)
        Start and end frequency (linear sweep).
    chirp_torque_nm : (float, float)
        Start and end amplitude (linear ramp).
    """

    sample_rate_hz: float = 1000.0
    speeds_rad_s: tuple[float, ...] = (15.0, 30.0, 45.0, 60.0)
    ramp_s: float = 0.5
    hold_s: float = 0.5
    coast_s: float = 2.0
    chirp_s: float = 20.0
    chirp_hz: tuple[float, float] = (0.5, 5.0)
    chirp_torque_nm: tuple[float, float] = (0.03, 0.3)
    gains: PIDGains = field(
        default_factory=lambda: PIDGains(
            kp_nm_per_rad=270.0,
            ki_nm_per_rad_s=500.0,
            kd_nms_per_rad=18.0,
            integral_error_limit_rad=0.05,
            velocity_filter_hz=100.0,
        )
    )


def _rig(params: CapstanParameters, protocol: IdentProtocol) -> CapstanSetup:
    """The motor, gearhead and pinion alone under speed control (angles referred / r_c)."""
    rc = params.capstan.ratio
    wide = 1e6
    limits = SafetyLimits(
        position_min=-wide,
        position_max=wide,
        velocity_max=100.0 / rc,
        output_max=params.drive.current_limit_a,
        output_trip=params.safety.current_trip_a,
        sensor_min=-wide,
        sensor_max=wide,
    )
    return CapstanSetup(
        params=params,
        gains=protocol.gains,
        fs=protocol.sample_rate_hz,
        with_user=False,
        gravity_compensation=False,
        coupled=False,
        safety=limits,
    )


def _measured(result: Any, params: CapstanParameters, name: str) -> IdentRun:
    fs = result.fs
    angle = result["measured_pinion_angle_rad"]
    velocity = np.concatenate([[0.0], np.diff(angle) * fs])
    torque = (
        result["current_command_a"] * params.motor.torque_constant_nm_per_a * params.gearhead.ratio
    )
    return IdentRun(name, result.time_s, velocity, torque)


def simulate_ident(
    params: CapstanParameters | None = None,
    protocol: IdentProtocol | None = None,
    *,
    seed: int | np.random.Generator = 0,
) -> IdentData:
    """Run the spin-down and chirp tests on the twin (see the module docstring).

    Examples
    --------
    >>> data = simulate_ident(protocol=IdentProtocol(speeds_rad_s=(20.0,), chirp_s=2.0))
    >>> [run.name for run in data.spindown], data.chirp[0].name
    (['cw_20.csv', 'ccw_20.csv'], 'chirp.csv')
    """
    params = load_platform("capstan") if params is None else params
    protocol = IdentProtocol() if protocol is None else protocol
    rng = np.random.default_rng(seed)
    setup = _rig(params, protocol)
    fs, rc = protocol.sample_rate_hz, params.capstan.ratio
    spindown = []
    for speed in protocol.speeds_rad_s:
        for sign, label in ((1.0, "cw"), (-1.0, "ccw")):
            t = np.arange(round((protocol.ramp_s + protocol.hold_s + protocol.coast_s) * fs)) / fs
            ramp = np.clip(t / protocol.ramp_s, 0.0, 1.0)
            # smooth ramp (raised cosine) of the speed; the reference angle is its integral
            profile = 0.5 * (1 - np.cos(np.pi * ramp))
            w_ref = sign * speed * profile / rc
            angle_ref = np.cumsum(w_ref) / fs
            angle_ref[t >= protocol.ramp_s + protocol.hold_s] = np.nan  # cut: the shaft coasts
            # the shaft rests anywhere within an encoder count
            offset = rng.uniform(0.0, params.encoder.resolution_rad / params.gearhead.ratio) / rc
            result = simulate_closed_loop(
                setup,
                t.size,
                reference=angle_ref + offset,
                reference_speed=w_ref,
                angle0=offset,
                seed=rng,
            )
            spindown.append(_measured(result, params, f"{label}_{speed:g}.csv"))
    n = round(protocol.chirp_s * fs)
    t = np.arange(n) / fs
    (f0, f1), (a0, a1) = protocol.chirp_hz, protocol.chirp_torque_nm
    phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / protocol.chirp_s * t**2)
    torque = (a0 + (a1 - a0) * t / protocol.chirp_s) * np.sin(phase)
    current = torque / (params.motor.torque_constant_nm_per_a * params.gearhead.ratio)
    offset = rng.uniform(0.0, params.encoder.resolution_rad / params.gearhead.ratio) / rc
    result = simulate_closed_loop(
        setup, n, mode="open-loop", command=current, angle0=offset, seed=rng
    )
    chirp = _measured(result, params, "chirp.csv")
    return IdentData(fs, tuple(spindown), (chirp,), friction_truth(params))
