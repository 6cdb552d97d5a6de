"""The 8-channel Kistler plate: resultants to channels and back, and the mounting rotation.

Written from DESIGN §3 alone. Channels are the forces applied by the load to the plate, plate
frame x, y, z (down); sensor 1 at (+a, +b), 2 at (-a, +b), 3 at (-a, -b), 4 at (+a, -b):

``Fx = fx12 + fx34``, ``Fy = fy14 + fy23``, ``Fz = fz1 + fz2 + fz3 + fz4``,
``Mx = b (fz1 + fz2 - fz3 - fz4)``, ``My = a (-fz1 + fz2 + fz3 - fz4)``,
``Mz = b (-fx12 + fx34) + a (fy14 - fy23)``, moments about the centre of the sensor plane.

Six resultants do not fix eight channels. :func:`channels_from_resultants` splits them as equal
sensors on a rigid plate would: the vertical forces carry no "twist" (fz1 - fz2 + fz3 - fz4 =
0) and the shear sensors share Mz in proportion to their distance from the centre. This is the
minimum-norm solution.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CHANNELS",
    "channels_from_resultants",
    "cop_from_resultants",
    "resultants_from_channels",
    "rotate_about_z",
]

Array = NDArray[np.float64]

CHANNELS = ("fx12", "fx34", "fy14", "fy23", "fz1", "fz2", "fz3", "fz4")


def channels_from_resultants(force: Array, moment: Array, a_m: float, b_m: float) -> Array:
    """The eight channels that carry plate-frame resultants.

    Parameters
    ----------
    force, moment : ndarray, shape (3, ...)
        (Fx, Fy, Fz) in N and (Mx, My, Mz) in N·m about the sensor-plane centre, plate frame,
        load on the plate.
    a_m, b_m : float
        Sensor offsets along the plate's x and y, m.

    Returns
    -------
    ndarray, shape (8, ...)
        Channels in :data:`CHANNELS` order, N.

    Examples
    --------
    A 400 N vertical load 0.1 m in front of the centre (My = -0.1 · 400) loads sensors 1 and
    4 more:

    >>> ch = channels_from_resultants(np.array([0.0, 0.0, 400.0]),
    ...                               np.array([0.0, -40.0, 0.0]), 0.2, 0.1)
    >>> ch[4:].round(6).tolist()
    [150.0, 50.0, 50.0, 150.0]
    """
    fx, fy, fz = force
    mx, my, mz = moment
    shear = mz / (2 * (a_m**2 + b_m**2))
    return np.stack(
        [
            fx / 2 - b_m * shear,
            fx / 2 + b_m * shear,
            fy / 2 + a_m * shear,
            fy / 2 - a_m * shear,
            fz / 4 + mx / (4 * b_m) - my / (4 * a_m),
            fz / 4 + mx / (4 * b_m) + my / (4 * a_m),
            fz / 4 - mx / (4 * b_m) + my / (4 * a_m),
            fz / 4 - mx / (4 * b_m) - my / (4 * a_m),
        ]
    )


def resultants_from_channels(channels: Array, a_m: float, b_m: float) -> tuple[Array, Array]:
    """Force and moment about the sensor-plane centre from the eight channels (DESIGN §3).

    Parameters
    ----------
    channels : ndarray, shape (8, ...)
        Channels in :data:`CHANNELS` order, N.
    a_m, b_m : float
        Sensor offsets, m.

    Returns
    -------
    force, moment : ndarray, shape (3, ...)
        (Fx, Fy, Fz) in N and (Mx, My, Mz) in N·m.
    """
    fx12, fx34, fy14, fy23, fz1, fz2, fz3, fz4 = channels
    force = np.stack([fx12 + fx34, fy14 + fy23, fz1 + fz2 + fz3 + fz4])
    moment = np.stack(
        [
            b_m * (fz1 + fz2 - fz3 - fz4),
            a_m * (-fz1 + fz2 + fz3 - fz4),
            b_m * (-fx12 + fx34) + a_m * (fy14 - fy23),
        ]
    )
    return force, moment


def cop_from_resultants(force: Array, moment: Array, az0_m: float) -> tuple[Array, Array]:
    """Centre of pressure on the plate surface, plate frame (DESIGN §3).

    ``ax = (Fx az0 - My) / Fz`` and ``ay = (Fy az0 + Mx) / Fz``, m.
    """
    fx, fy, fz = force
    mx, my, _ = moment
    return (fx * az0_m - my) / fz, (fy * az0_m + mx) / fz


def rotate_about_z(vector: Array, angle_rad: float) -> Array:
    """Components in a frame turned by ``angle_rad`` about z of the frame ``vector`` is in.

    The new frame's x axis is ``(cos angle, sin angle, 0)`` in the old frame; the result is
    ``Rz(angle)^T @ vector`` along the first axis.

    Examples
    --------
    The plate mounted with walking along its +y axis is turned by -90°: a forward unit vector
    of the hinge frame has plate components (0, 1, 0).

    >>> rotate_about_z(np.array([1.0, 0.0, 0.0]), -np.pi / 2).round(12).tolist()
    [0.0, 1.0, 0.0]
    """
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    x, y, z = vector
    return np.stack([c * x + s * y, -s * x + c * y, z])
