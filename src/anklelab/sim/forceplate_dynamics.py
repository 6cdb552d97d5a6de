"""Force-plate signal chain of the twin: structural modes, anti-alias filter, sensors, DAQ.

The compiled kernel (:mod:`anklelab.sim._kernels`) produces the load on the plate's sensors as a
wrench in the *sagittal plate frame* (Kistler axes of the tilted plate with x anterior, y right,
z down; moments about the centre of the sensor plane). It is the foot's load plus, while the
hinge moves, the top plate's own inertial and gravity-tilt loads, zeroed at rest as a charge
amplifier is. The plate's structural modes are second-order low-pass resonances applied to the
vertical group (Fz, Mx, My) and the horizontal group (Fx, Fy, Mz), followed by the amplifier's
anti-alias low-pass, all run at the position-loop rate and then sampled by the DAQ (the filters
are designed in closed form by :mod:`anklelab.iir`). This module maps the wrench to the
eight channels of the mounted plate (its ``anterior_axis``) and adds what the DAQ adds:
per-channel drift, noise and 16-bit quantisation.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.forceplate import PlateGeometry

__all__ = [
    "daq_quantize",
    "mounting_rotation",
    "sensor_channels",
]


def mounting_rotation(anterior_axis: str, yaw_rad: float = 0.0) -> NDArray[np.float64]:
    """3x3 rotation taking sagittal-frame vectors (x anterior, y right, z down) to plate axes.

    ``yaw_rad`` turns the plate about its vertical axis away from the hinge's sagittal frame:
    the plate's anterior axis then points ``yaw_rad`` to the right of the walking direction
    (a plate mounted slightly askew on the hinge).

    Examples
    --------
    >>> mounting_rotation("+y") @ [1.0, 0.0, 0.0]    # anterior is the plate's +y
    array([0., 1., 0.])
    >>> np.round(mounting_rotation("+x", 0.1) @ [1.0, 0.0, 0.0], 4)  # seen from a yawed plate
    array([ 0.995 , -0.0998,  0.    ])
    """
    x = {"+x": (1, 0), "-x": (-1, 0), "+y": (0, 1), "-y": (0, -1)}[anterior_axis]
    ex = np.array([x[0], x[1], 0.0])
    ey = np.cross([0.0, 0.0, 1.0], ex)  # right = down x anterior
    c, s = np.cos(yaw_rad), np.sin(yaw_rad)
    yaw = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # sagittal -> yawed plate
    return np.column_stack([ex, ey, [0.0, 0.0, 1.0]]) @ yaw


def sensor_channels(
    wrench: NDArray[np.float64], geometry: PlateGeometry, *, yaw_rad: float = 0.0
) -> NDArray[np.float64]:
    """The eight channels that carry a sagittal-frame wrench on a plate mounted as ``geometry``.

    Parameters
    ----------
    wrench : ndarray, shape (..., 6, n)
        (Fx, Fy, Fz, Mx, My, Mz) in the sagittal plate frame, N and N·m.
    geometry : PlateGeometry
        Sensor offsets and ``anterior_axis`` of the mounted plate.
    yaw_rad : float
        The plate's yaw from the sagittal frame about the vertical, rad (see
        :func:`mounting_rotation`).

    Returns
    -------
    ndarray, shape (..., 8, n)
        Channels in :data:`anklelab.forceplate.CHANNELS` order (minimum-norm split, so
        :func:`anklelab.forceplate.resultants` returns the wrench exactly).
    """
    r = mounting_rotation(geometry.anterior_axis, yaw_rad)
    rot = np.zeros((6, 6))
    rot[:3, :3] = r
    rot[3:, 3:] = r
    to_channels = np.linalg.pinv(geometry.matrix()) @ rot
    return np.einsum("cw,...wn->...cn", to_channels, wrench)


def daq_quantize(
    values: NDArray[np.float64], full_scale: float | NDArray[np.float64], bits: int
) -> NDArray[np.float64]:
    """Round to the steps of a ``bits``-bit converter spanning ``±full_scale`` (and clip).

    ``full_scale`` may be an array broadcasting against ``values`` (one range per channel).

    Examples
    --------
    >>> daq_quantize(np.array([0.3, 2.0]), full_scale=1.0, bits=2)
    array([0.5, 0.5])
    >>> float(daq_quantize(-0.3, full_scale=1.0, bits=2))
    -0.5
    """
    step = 2 * full_scale / 2**bits
    codes = np.asarray(values / step)  # one array, worked in place (a session's is ~100 MB)
    np.round(codes, out=codes)
    np.clip(codes, -(2 ** (bits - 1)), 2 ** (bits - 1) - 1, out=codes)
    codes *= step
    return codes if codes.ndim else codes[()]
