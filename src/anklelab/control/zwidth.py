"""The Z-width of impedance rendering: which virtual stiffness ``K`` and damping ``B`` the
platform renders passively, from the sampled-data passivity conditions.

The rendering ``tau_k = -K theta_k - B w_k`` is computed from the encoder (one count ``q``,
floored) at ``1/T`` Hz and held over the period; ``w_k`` is the controller's filtered backward
difference. Over one period in which the platform turns by ``d``, the held spring generates at
most ``K d (d/2 + q)`` of energy (the floor quantiser errs by up to one count, the hold by half
the step), while the platform dissipates at least ``b d^2 / T`` (viscous) and ``f_c |d|``
(Coulomb). Passivity for every ``d`` splits into two conditions (Abbott & Okamura, IEEE T-RO
21:952, 2005, who give ``2 f_c / q`` for a rounding quantiser):

- **sampled-viscous mode**, large, fast motions: ``K T / 2 < b + b_h - g B``: the sampled,
  held spring's energy leak must be covered by the platform's damping ``b`` and the attached
  ankle's ``b_h`` (for the device and the ankle together, as the person's voluntary torque sees
  them); ``g B`` is the virtual damper's own leak at its worst frequency (Colgate & Schenkel,
  J. Robotic Systems 14:37, 1997), ``g = max_w (T/2) Re{(1 - e^{-jwT}) D(e^{jwT})} / (1 - cos wT)``
  for the filtered difference ``D``;
- **quantisation mode**, the platform at rest against the spring: ``K q < f_c``: one count's
  torque step must not break the shaft loose, else the rendering buzzes.

:func:`zwidth_boundary` gives both boundaries over a range of damping.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, UserParameters
from anklelab.sim.capstan import linear_platform

__all__ = ["ZWidthBoundary", "damper_leak", "zwidth_boundary"]


def damper_leak(fs: float, velocity_filter_hz: float) -> float:
    """The worst-frequency energy leak ``g`` of a virtual damper on the filtered backward
    difference, per unit damping (1 for an unfiltered difference).

    Examples
    --------
    >>> round(damper_leak(1000.0, 1e9), 3)            # unfiltered: Colgate & Schenkel's |B|
    1.0
    >>> round(damper_leak(1000.0, 100.0), 3)          # the platform's 100 Hz speed filter
    0.304
    """
    if not fs > 0 or not velocity_filter_hz > 0:
        raise ParameterError("fs and velocity_filter_hz must be > 0")
    dt = 1.0 / fs
    alpha = -math.expm1(-2.0 * math.pi * velocity_filter_hz / fs)
    w = np.linspace(1e-3, math.pi, 20001) / dt
    z = np.exp(1j * w * dt)
    d = alpha * (1 - 1 / z) / dt / (1 - (1 - alpha) / z)
    g = (dt / 2) * np.real((1 - 1 / z) * d) / (1 - np.cos(w * dt))
    return float(g.max())


@dataclass(frozen=True)
class ZWidthBoundary:
    """Largest passively rendered stiffness at each virtual damping, by mode.

    Attributes
    ----------
    damping_nms_per_rad : ndarray
        Virtual damping ``B``.
    viscous_nm_per_rad : ndarray
        Sampled-viscous mode ``2 (b + b_h - g B) / T`` (0 where negative: no stiffness renders
        passively for fast motions).
    quantization_nm_per_rad : float
        Quantisation mode ``f_c / q``.
    leak : float
        ``g`` of the virtual damper.
    platform_damping_nms_per_rad, ankle_damping_nms_per_rad, coulomb_nm, count_rad : float
        The inputs: ``b``, ``b_h``, ``f_c`` (the smaller direction's) and ``q`` at the platform.
    fs : float
        Control rate, Hz.
    """

    damping_nms_per_rad: NDArray[np.float64]
    viscous_nm_per_rad: NDArray[np.float64]
    quantization_nm_per_rad: float
    leak: float
    platform_damping_nms_per_rad: float
    ankle_damping_nms_per_rad: float
    coulomb_nm: float
    count_rad: float
    fs: float

    def viscous_at(self, damping_nms_per_rad: ArrayLike) -> NDArray[np.float64]:
        """The sampled-viscous boundary at any virtual damping, N·m/rad (0 where none)."""
        b = np.asarray(damping_nms_per_rad, dtype=float)
        total = self.platform_damping_nms_per_rad + self.ankle_damping_nms_per_rad
        return np.maximum(2.0 * self.fs * (total - self.leak * b), 0.0)

    @property
    def stiffness_nm_per_rad(self) -> NDArray[np.float64]:
        """The Z-width boundary: both modes must hold."""
        return np.minimum(self.viscous_nm_per_rad, self.quantization_nm_per_rad)


def zwidth_boundary(
    damping_nms_per_rad: ArrayLike,
    params: CapstanParameters,
    fs: float,
    *,
    velocity_filter_hz: float,
    user: UserParameters | None = None,
    ankle_damping_nms_per_rad: float | None = None,
) -> ZWidthBoundary:
    """The analytic Z-width boundary (see the module notes).

    Parameters
    ----------
    damping_nms_per_rad : array_like
        Virtual damping values, N·m·s/rad.
    params : CapstanParameters
        Platform: viscous and Coulomb friction, encoder.
    fs : float
        Control rate, Hz.
    velocity_filter_hz : float
        The controller's speed filter.
    user : UserParameters, optional
        The attached foot and ankle (its damping is ``b_h``).
    ankle_damping_nms_per_rad : float, optional
        ``b_h`` directly (a standing person's ankle), overriding ``user``.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("capstan")
    >>> z = zwidth_boundary([0.0], p, 1000.0, velocity_filter_hz=100.0, user=p.user)
    >>> round(float(z.viscous_nm_per_rad[0])), round(z.quantization_nm_per_rad)
    (1693, 61497)
    """
    b_virtual = np.asarray(damping_nms_per_rad, dtype=float)
    if b_virtual.ndim != 1 or not np.all(np.isfinite(b_virtual) & (b_virtual >= 0)):
        raise ParameterError("damping_nms_per_rad must be a 1-D array of finite values >= 0")
    b = linear_platform(params).damping_nms_per_rad
    b_h = ankle_damping_nms_per_rad
    if b_h is None:
        b_h = user.ankle_damping_nms_per_rad if user else 0.0
    leak = damper_leak(fs, velocity_filter_hz)
    f = params.friction
    coulomb = min(f.coulomb_cw_nm, f.coulomb_ccw_nm) * params.capstan.ratio
    count = params.encoder.resolution_rad / params.total_ratio
    boundary = ZWidthBoundary(
        damping_nms_per_rad=b_virtual,
        viscous_nm_per_rad=np.zeros_like(b_virtual),
        quantization_nm_per_rad=coulomb / count,
        leak=leak,
        platform_damping_nms_per_rad=b,
        ankle_damping_nms_per_rad=float(b_h),
        coulomb_nm=coulomb,
        count_rad=count,
        fs=fs,
    )
    return dataclasses.replace(boundary, viscous_nm_per_rad=boundary.viscous_at(b_virtual))
