"""Force-plate signal chain of the twin: structural modes, anti-alias filter, sensors, DAQ.

The compiled kernel (:mod:`anklelab.sim._kernels`) produces the load on the plate's sensors as a
wrench in the *sagittal plate frame* (Kistler axes of the tilted plate with x anterior, y right,
z down; moments about the centre of the sensor plane). It is the foot's load plus, while the
hinge moves, the top plate's own inertial and gravity-tilt loads, zeroed at rest as a charge
amplifier is. The plate's structural modes are second-order low-pass resonances applied to the
vertical group (Fz, Mx, My) and the horizontal group (Fx, Fy, Mz), followed by the amplifier's
anti-alias low-pass, all run at the position-loop rate and then sampled by the DAQ. This module
designs those filters, maps the wrench to the eight channels of the mounted plate (its
``anterior_axis``) and adds what the DAQ adds: per-channel drift, noise and 16-bit quantisation.

The filters are designed here in closed form (bilinear transform, pre-warped), with NumPy only:
importing ``scipy.signal`` would cost a simulation about a second of start-up.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from anklelab.forceplate import PlateGeometry

__all__ = [
    "anti_alias_sos",
    "daq_quantize",
    "mode_sos",
    "mounting_rotation",
    "sensor_channels",
]


def mode_sos(natural_frequency_hz: float, damping_ratio: float, fs: float) -> NDArray[np.float64]:
    """One second-order section of ``w²/(s² + 2 zeta w s + w²)`` (unit DC gain) at rate ``fs``.

    Bilinear transform pre-warped at the natural frequency, so the discrete resonance sits
    exactly at ``natural_frequency_hz``.

    Examples
    --------
    >>> sos = mode_sos(300.0, 0.05, 8000.0)
    >>> z = np.exp(2j * np.pi * np.array([0.0, 300.0]) / 8000.0)
    >>> h = np.polyval(sos[0, :3], z) / np.polyval(sos[0, 3:], z)
    >>> round(float(abs(h[0])), 9), round(float(abs(h[1])), 3)   # DC gain 1, peak 1/(2 zeta)
    (1.0, 10.0)
    """
    wa = _prewarp(natural_frequency_hz, fs)
    return _bilinear_section(wa * wa, 2 * damping_ratio * wa, fs)[None, :]


def anti_alias_sos(cutoff_hz: float, order: int, fs: float) -> NDArray[np.float64]:
    """Butterworth low-pass of the plate amplifier, as second-order sections at rate ``fs``.

    The analog Butterworth poles ``wa exp(i pi (2k + 1 + n) / 2n)`` (``wa`` the pre-warped
    cut-off) in conjugate pairs, each pair (and, for an odd order, the real pole) one section
    of unit DC gain, the section nearest the unit circle last (as ``scipy.signal.butter``).

    Examples
    --------
    >>> sos = anti_alias_sos(400.0, 4, 8000.0)
    >>> z = np.exp(2j * np.pi * 400.0 / 8000.0)
    >>> h = np.prod([np.polyval(s[:3], z) / np.polyval(s[3:], z) for s in sos])
    >>> sos.shape, round(float(abs(h)) ** 2, 6)   # half power at the cut-off
    ((2, 6), 0.5)
    """
    wa = _prewarp(cutoff_hz, fs)
    angles = np.pi * (2 * np.arange(order // 2) + 1 + order) / (2 * order)
    # pairs s² - 2 Re(p) s + |p|², the least damped (nearest the unit circle) last
    sections = [_bilinear_section(wa * wa, -2 * wa * np.cos(a), fs) for a in angles[::-1]]
    if order % 2:
        k = wa / (2 * fs + wa)
        sections.insert(0, np.array([k, k, 0.0, 1.0, (wa - 2 * fs) / (2 * fs + wa), 0.0]))
    return np.array(sections)


def _prewarp(frequency_hz: float, fs: float) -> float:
    """Analog frequency that the bilinear transform at ``fs`` maps onto ``frequency_hz``, rad/s."""
    return float(2 * fs * np.tan(np.pi * frequency_hz / fs))


def _bilinear_section(w2: float, c1: float, fs: float) -> NDArray[np.float64]:
    """``[b0, b1, b2, 1, a1, a2]`` of ``w2 / (s² + c1 s + w2)`` by ``s = 2 fs (z - 1)/(z + 1)``."""
    f2 = (2 * fs) ** 2
    a0 = f2 + 2 * fs * c1 + w2
    b = w2 / a0
    return np.array([b, 2 * b, b, 1.0, 2 * (w2 - f2) / a0, (f2 - 2 * fs * c1 + w2) / a0])


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
    """
    step = 2 * full_scale / 2**bits
    codes = np.clip(np.round(values / step), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1)
    return codes * step
