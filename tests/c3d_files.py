"""C3D files for the tests, written with ezc3d: force platforms of type 2, 3 and 4 in y-up or
z-up global frames, mm or m, built from a known load so both readers can be checked against it.

The load is made in the global frame (GRF of the plate on the foot, COP on the surface, free
moment) and turned into each plate type's channels by statics alone, independently of the
module under test.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import ezc3d
import numpy as np

from anklelab.forceplate import CHANNELS, PlateGeometry, channels_from_load

UNITS = {"mm": 1e-3, "m": 1.0}
UP = {"z": np.array([0.0, 0.0, 1.0]), "y": np.array([0.0, 1.0, 0.0])}
# walking direction in the global frame, for each vertical axis
FORWARD = {"z": np.array([0.0, 1.0, 0.0]), "y": np.array([-1.0, 0.0, 0.0])}


def _int_parameter(c3d, group, name, values):
    c3d.add_parameter(group, name, np.asarray(values, dtype=float))
    c3d["parameters"][group][name]["type"] = ezc3d.ezc3d.INT


def write_c3d(
    path,
    analogs,
    *,
    rate=1000.0,
    per_frame=10,
    units=None,
    length_unit="mm",
    plates=(),
    events=(),
    gen_scale=1.0,
    scale=None,
):
    """Write ``analogs`` ({label: values}) and force-platform parameters to ``path``.

    ``plates``: dicts with ``type``, ``labels`` (the plate's channel labels), ``origin`` and
    ``corners`` (4x3, file units) and ``cal`` (type 4). ``events``: (label, context, time_s).
    ``gen_scale``/``scale``: the file's ANALOG:GEN_SCALE and SCALE; ezc3d stores
    ``value / (SCALE * GEN_SCALE)``, so a reader that applies both gets ``analogs`` back.
    """
    labels = list(analogs)
    data = np.stack([np.asarray(analogs[k], dtype=float) for k in labels])
    n = data.shape[1] - data.shape[1] % per_frame
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [rate / per_frame]
    c["parameters"]["POINT"]["LABELS"]["value"] = []
    c["parameters"]["POINT"]["UNITS"]["value"] = [length_unit]
    c["parameters"]["ANALOG"]["RATE"]["value"] = [rate]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = labels
    units = units or {}
    c["parameters"]["ANALOG"]["UNITS"]["value"] = [units.get(k, "") for k in labels]
    c["parameters"]["ANALOG"]["GEN_SCALE"]["value"] = [gen_scale]
    if scale is not None:
        c["parameters"]["ANALOG"]["SCALE"]["value"] = [scale.get(k, 1.0) for k in labels]
    if plates:
        width = max(8 if p["type"] == 3 else 6 for p in plates)
        channel = np.zeros((width, len(plates)))
        for i, p in enumerate(plates):
            channel[: len(p["labels"]), i] = [labels.index(k) + 1 for k in p["labels"]]
        _int_parameter(c, "FORCE_PLATFORM", "USED", [len(plates)])
        _int_parameter(c, "FORCE_PLATFORM", "TYPE", [p["type"] for p in plates])
        _int_parameter(c, "FORCE_PLATFORM", "CHANNEL", channel)
        c.add_parameter("FORCE_PLATFORM", "ORIGIN", np.stack([p["origin"] for p in plates], axis=1))
        c.add_parameter(
            "FORCE_PLATFORM", "CORNERS", np.stack([np.asarray(p["corners"]).T for p in plates], 2)
        )
        cal = np.stack([p.get("cal", np.eye(6)) for p in plates], axis=2)
        c.add_parameter("FORCE_PLATFORM", "CAL_MATRIX", cal)
    for label, context, time_s in events:
        c.add_event([int(time_s // 60), float(time_s % 60)], context=context, label=label)
    c["data"]["points"] = np.zeros((4, 0, n // per_frame))
    c["data"]["analogs"] = data[None, :, :n]
    c.write(str(path))
    return Path(path)


def plate_rotation(up, forward_axis="+x"):
    """Columns: the plate's x, y, z (down) axes in the global frame, the plate axis
    ``forward_axis`` pointing in :data:`FORWARD` [up]."""
    down, forward = -UP[up], FORWARD[up]
    sign = 1.0 if forward_axis[0] == "+" else -1.0
    if forward_axis[1] == "x":
        x = sign * forward
        y = np.cross(down, x)
    else:
        y = sign * forward
        x = np.cross(y, down)
    return np.stack([x, y, down], axis=1)


@dataclass
class Stance:
    """A stance on the plate in the global frame: GRF (3, n) N, COP (3, n) m, free moment
    (about up, plate on foot) N·m."""

    grf: np.ndarray
    cop: np.ndarray
    free_moment: np.ndarray


def stance(up, centre_m, n=1200, rate=1000.0, seed=0):
    """A double-hump vertical force, braking then propulsive shear, a COP rolling 25 cm forward
    and a little sideways, unloaded at both ends, with sensor noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    s = np.clip((t - 0.2) / 0.7, 0, 1)
    on = (s > 0) & (s < 1)
    fz = on * (650 * np.sin(np.pi * s) + 180 * np.sin(3 * np.pi * s) ** 2)
    fx = on * (-120 * np.sin(2 * np.pi * s))
    fy = on * 25 * np.sin(np.pi * s)
    forward, up_v = FORWARD[up], UP[up]
    left = np.cross(up_v, forward)
    grf = np.outer(forward, fx) + np.outer(left, fy) + np.outer(up_v, fz)
    grf += rng.normal(0, 0.5, grf.shape)
    cop = centre_m[:, None] + np.outer(forward, -0.12 + 0.25 * s) + np.outer(left, 0.02 * s)
    free = on * 2.0 * np.sin(2 * np.pi * s)
    return Stance(grf, cop, free)


def plate_channels(kind, load, rotation, centre_m, to_surface_m, a_b=(0.12, 0.2)):
    """The plate's channels (SI: N, N·m) for ``load``: load on plate, plate frame z down,
    moments about the origin ``-to_surface_m`` below the surface centre."""
    force = -(rotation.T @ load.grf)
    cop = rotation.T @ (load.cop - centre_m[:, None])  # z = 0: on the surface
    # the plate's moment on the foot about up equals the foot's on the plate about down (z)
    tz = load.free_moment
    if kind == 3:
        geometry = PlateGeometry(a_m=a_b[0], b_m=a_b[1], az0_m=to_surface_m[2])
        return channels_from_load(force, cop[:2], geometry, free_moment_nm=tz, axis=0)
    lever = cop + to_surface_m[:, None]  # from the origin to the point of application
    moment = np.cross(lever, force, axis=0)
    moment[2] += tz
    return np.vstack([force, moment])


def write_plate_file(path, kind, up, length_unit, *, seed=0, origin_sign=1.0, extra=None):
    """A one-plate C3D file of ``kind`` (2, 3, 4) in a ``up``-up frame and ``length_unit``;
    returns (path, the stance in SI units)."""
    scale = UNITS[length_unit]
    rotation = plate_rotation(up, "+y" if kind == 3 else "-x")
    centre = np.array([0.3, 0.5, 0.02]) if up == "z" else np.array([0.3, 0.02, -0.5])
    load = stance(up, centre, seed=seed)
    to_surface = np.array([0.004, -0.002, -0.041]) if kind != 3 else np.array([0, 0, -0.045])
    channels = plate_channels(kind, load, rotation, centre, to_surface)
    if kind == 3:
        labels = [f"F{c}" for c in CHANNELS]
        units = dict.fromkeys(labels, "N")
        origin = np.array([0.12, 0.2, -0.045]) / scale
        values = channels
    else:
        labels = ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
        moment_unit = "Nmm" if length_unit == "mm" else "Nm"
        units = dict(zip(labels, ["N"] * 3 + [moment_unit] * 3, strict=True))
        origin = origin_sign * -to_surface / scale  # AMTI style: z positive (origin below)
        values = channels.copy()
        values[3:] /= scale  # moments in N·(file unit)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * [0.2, 0.3]
    corners = np.array([centre + rotation[:, :2] @ h for h in half]) / scale
    plate = {"type": kind, "labels": labels, "origin": origin, "corners": corners}
    if kind == 4:
        rng = np.random.default_rng(seed + 10)
        cal = np.diag(rng.uniform(50, 500, 6)) + rng.normal(0, 5, (6, 6))
        plate["cal"] = cal
        values = np.linalg.solve(cal, values)  # raw volts
        units = dict.fromkeys(labels, "V")
    analogs = dict(zip(labels, values, strict=True)) | (extra or {})
    write_c3d(path, analogs, units=units, length_unit=length_unit, plates=[plate])
    return Path(path), load
