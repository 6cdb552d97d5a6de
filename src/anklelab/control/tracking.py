"""Tracking beyond the feedback bandwidth: the closed loop's discrete model and the
zero-phase-error tracking controller (ZPETC, Tomizuka, ASME JDSMC 109:65, 1987).

The inverse-dynamics feed-forward itself runs inside the control loop
(``CapstanSetup.feedforward``: ``J a_ref + F(w_ref)``). For a trajectory known in advance, the
ZPETC goes further: :func:`closed_loop_model` builds the sampled closed loop from the reference
to the platform angle (rigid platform with the user's foot and ankle, the drive's current loop,
zero-order hold, the PID with its filtered speed estimate, the feed-forward from the
reference's backward differences), and :func:`zpetc_reference` passes the desired trajectory
through its inverse: exactly for the acceptable zeros, and for the unacceptable ones (on or
outside the unit circle, or on the left half of the plane beyond ``|z| = 0.5``, which an exact
inverse would make blow up or ring at the Nyquist frequency) by their zero-phase counterpart
``B_u(1/z) / B_u(1)^2``, so that the tracking error has no phase lag at any frequency
and only a small gain error near the Nyquist frequency. The inverse is applied to the whole
trajectory at once (non-causally) in the frequency domain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from anklelab.control.pid import PIDGains
from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters, UserParameters
from anklelab.sim.capstan import linear_platform

__all__ = ["ClosedLoopModel", "closed_loop_model", "reference_derivatives", "zpetc_reference"]

RINGING_ZERO_RADIUS = 0.5


@dataclass(frozen=True)
class ClosedLoopModel:
    """The sampled closed loop from reference to angle, ``G(z) = num(z) / den(z)``.

    Attributes
    ----------
    num, den : ndarray
        Polynomial coefficients in descending powers of ``z``.
    fs : float
        Sample rate, Hz.
    """

    num: NDArray[np.float64]
    den: NDArray[np.float64]
    fs: float

    def response(self, frequency_hz: ArrayLike) -> NDArray[np.complex128]:
        """``G(e^{j w T})`` at the given frequencies (Hz)."""
        z = np.exp(2j * np.pi * np.asarray(frequency_hz, dtype=float) / self.fs)
        return np.polyval(self.num, z) / np.polyval(self.den, z)


def reference_derivatives(
    reference: ArrayLike, fs: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Backward-difference speed and acceleration of a sampled reference (what the ZPETC's
    model assumes the loop's feed-forward receives), rad/s and rad/s²."""
    r = np.asarray(reference, dtype=float)
    speed = np.diff(r, prepend=r[0]) * fs
    return speed, np.diff(speed, prepend=speed[0]) * fs


def closed_loop_model(
    params: CapstanParameters,
    gains: PIDGains,
    fs: float,
    *,
    feedforward: bool,
    user: UserParameters | None = None,
    model_friction: FrictionParameters | None = None,
) -> ClosedLoopModel:
    """The linear sampled model of the position loop, reference to platform angle.

    Parameters
    ----------
    params : CapstanParameters
        The platform (inertia, viscous friction referred to the platform, torque constant,
        current-loop bandwidth).
    gains : PIDGains
        The PID and its speed filter.
    fs : float
        Control rate, Hz.
    feedforward : bool
        Include the inverse-dynamics feed-forward of the controller's model (inertia and
        viscous friction of ``model_friction``, else of ``params``, plus the user's nominal
        foot inertia and ankle stiffness and damping), as the loop adds it.
    user : UserParameters, optional
        The foot and relaxed ankle on the platform (its stiffness and damping load the plant).
    model_friction : FrictionParameters, optional
        The controller's model (e.g. identified).

    Examples
    --------
    >>> from anklelab.control.pid import design_critically_damped
    >>> from anklelab.platforms import load_platform
    >>> p = load_platform("capstan")
    >>> g = closed_loop_model(p, design_critically_damped(p), 1000.0, feedforward=False)
    >>> round(abs(complex(g.response(0.01))), 4)      # unit gain at low frequency
    1.0
    """
    if not fs > 0:
        raise ParameterError(f"fs must be > 0 Hz; got {fs}")
    dt = 1.0 / fs
    lin = linear_platform(params, user)
    wc = 2.0 * math.pi * params.drive.current_bandwidth_hz
    # continuous plant, states [angle, speed, motor torque]; input: commanded torque
    a = np.array(
        [
            [0.0, 1.0, 0.0],
            [
                -lin.stiffness_nm_per_rad / lin.inertia_kgm2,
                -lin.damping_nms_per_rad / lin.inertia_kgm2,
                1.0 / lin.inertia_kgm2,
            ],
            [0.0, 0.0, -wc],
        ]
    )
    b = np.array([0.0, 0.0, wc])
    block = np.zeros((4, 4))
    block[:3, :3], block[:3, 3] = a * dt, b * dt
    discrete = expm(block)
    ad, bd = discrete[:3, :3], discrete[:3, 3]
    model = params.friction if model_friction is None else model_friction
    rc = params.capstan.ratio
    foot = (user.foot_inertia_kgm2, user.ankle_damping_nms_per_rad) if user else (0.0, 0.0)
    ff_inertia = model.inertia_kgm2 * rc**2 + params.platform.inertia_kgm2 + foot[0]
    viscous = 0.5 * (model.viscous_cw_nms_per_rad + model.viscous_ccw_nms_per_rad) * rc**2
    ff_damping, ff_stiffness = viscous + foot[1], lin.stiffness_nm_per_rad
    alpha = -math.expm1(-2.0 * math.pi * gains.velocity_filter_hz / fs)
    kp, ki, kd = gains.kp_nm_per_rad, gains.ki_nm_per_rad_s, gains.kd_nms_per_rad
    on = 1.0 if feedforward else 0.0
    # closed-loop state z_k = [x_k (3), angle_{k-1}, speed estimate_{k-1}, integral_{k-1},
    # r_{k-1}, r_{k-2}]; the torque command is linear in z_k and r_k:
    #   v_k = (1 - alpha) v_{k-1} + alpha (angle_k - angle_{k-1}) / dt
    #   I_k = I_{k-1} + (r_k - angle_k) dt
    #   w_ref = (r_k - r_{k-1}) / dt,  a_ref = (r_k - 2 r_{k-1} + r_{k-2}) / dt^2
    #   u_k = kp (r_k - angle_k) + ki I_k + kd (w_ref - v_k) + on (J a_ref + b w_ref + K r_k)
    v_z = np.array([alpha / dt, 0, 0, -alpha / dt, 1 - alpha, 0, 0, 0])
    i_z, i_r = np.array([-dt, 0, 0, 0, 0, 1, 0, 0]), dt
    w_z, w_r = np.array([0, 0, 0, 0, 0, 0, -1 / dt, 0]), 1 / dt
    acc_z, acc_r = np.array([0, 0, 0, 0, 0, 0, -2 / dt**2, 1 / dt**2]), 1 / dt**2
    u_z = np.array([-kp, 0, 0, 0, 0, 0, 0, 0]) + ki * i_z + kd * (w_z - v_z)
    u_z = u_z + on * (ff_inertia * acc_z + ff_damping * w_z)
    u_r = kp + ki * i_r + kd * w_r + on * (ff_inertia * acc_r + ff_damping * w_r + ff_stiffness)
    big_a = np.zeros((8, 8))
    big_b = np.zeros(8)
    big_a[:3, :3] = ad
    big_a[:3, :] += np.outer(bd, u_z)
    big_b[:3] = bd * u_r
    big_a[3, 0] = 1.0
    big_a[4, :] = v_z
    big_a[5, :], big_b[5] = i_z, i_r
    big_b[6] = 1.0
    big_a[7, 6] = 1.0
    c = np.zeros((1, 8))
    c[0, 0] = 1.0
    from scipy.signal import ss2tf  # here: importing scipy.signal costs a simulation ~1 s

    num, den = ss2tf(big_a, big_b[:, None], c, np.zeros((1, 1)))
    num = np.trim_zeros(np.atleast_1d(num[0]), "f")
    num[np.abs(num) < 1e-14 * np.abs(num).max()] = 0.0
    return ClosedLoopModel(np.trim_zeros(num, "f"), den, fs)


def zpetc_reference(
    desired: ArrayLike, model: ClosedLoopModel, *, pad_s: float = 1.0
) -> NDArray[np.float64]:
    """The reference that makes ``model`` follow ``desired`` with zero phase error.

    Parameters
    ----------
    desired : array_like, shape (n,)
        The trajectory the platform should follow, rad, sampled at ``model.fs``.
    model : ClosedLoopModel
        From :func:`closed_loop_model`.
    pad_s : float
        Rest (the first and last values held) added at both ends while filtering, s, so that
        the non-causal inverse has room before the start and after the end.

    Returns
    -------
    ndarray, shape (n,)
        The prefiltered reference.
    """
    y = np.asarray(desired, dtype=float)
    if y.ndim != 1 or not np.all(np.isfinite(y)):
        raise ParameterError("desired must be a 1-D array of finite angles")
    pad = round(pad_s * model.fs)
    padded = np.concatenate([np.full(pad, y[0]), y, np.full(pad, y[-1])])
    zeros = np.roots(model.num)
    bad = (np.abs(zeros) >= 1.0) | ((zeros.real < 0) & (np.abs(zeros) > RINGING_ZERO_RADIUS))
    unacceptable, acceptable = zeros[bad], zeros[~bad]
    f = np.fft.rfftfreq(padded.size, 1.0 / model.fs)
    z = np.exp(2j * np.pi * f / model.fs)
    b_u = np.prod(z[:, None] - unacceptable[None, :], axis=1)
    b_u1 = np.prod(1.0 - unacceptable).real
    b_s = model.num[0] * np.prod(z[:, None] - acceptable[None, :], axis=1)
    inverse = np.polyval(model.den, z) / b_s * np.conj(b_u) / b_u1**2
    offset = padded[0]  # filter the motion about the start (the DC gain is one)
    out = np.fft.irfft(np.fft.rfft(padded - offset) * inverse, n=padded.size) + offset
    return out[pad : pad + y.size]
