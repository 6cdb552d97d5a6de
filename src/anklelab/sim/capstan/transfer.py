"""Linear models of paper 001 (eqs. 1, 2, 8 and 9) as python-control transfer functions.

Inertia and viscous friction come from the same parameters the twin uses: the pinion-shaft
inertia ``J`` and viscous coefficient ``b`` of Table 2 (``b`` averaged over the two directions),
referred through the gearhead (``r_g``) and the capstan (``r_c``), plus the platform's inertia
and, optionally, the user's foot. Paper 001's Table 1 gives ``J_eq = 42.92 g·cm²`` at the motor,
which leaves out the pinion; with Table 2's ``J`` the motor-side inertia is 49.0 g·cm².

Angles follow anklelab's convention (motor angle referred positive in dorsiflexion), so the
ankle torque enters eq. 2 with a plus sign where paper 001 writes ``-1/(r_g r_c)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from anklelab.platforms.capstan import CapstanParameters, UserParameters

__all__ = [
    "LinearPlatform",
    "ankle_torque_to_motor_speed",
    "disturbance_to_angle",
    "linear_platform",
    "reference_to_angle",
    "voltage_to_motor_speed",
]


@dataclass(frozen=True)
class LinearPlatform:
    """Lumped linear model at the platform axis.

    Attributes
    ----------
    inertia_kgm2 : float
        Pinion side referred (``J r_c^2``) plus platform (plus foot), kg·m².
    damping_nms_per_rad : float
        Viscous friction referred (``b r_c^2``) plus the ankle's damping, N·m·s/rad.
    stiffness_nm_per_rad : float
        The ankle's passive stiffness (0 without a user), N·m/rad.
    torque_per_amp_nm_per_a : float
        Platform torque per motor ampere, ``K_i r_g r_c``.
    """

    inertia_kgm2: float
    damping_nms_per_rad: float
    stiffness_nm_per_rad: float
    torque_per_amp_nm_per_a: float


def linear_platform(
    params: CapstanParameters, user: UserParameters | None = None
) -> LinearPlatform:
    """Lump the platform (and the user, if given) into one inertia, damping and stiffness.

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> round(linear_platform(load_platform("capstan")).inertia_kgm2, 4)
    0.3733
    """
    rc = params.capstan.ratio
    f = params.friction
    b = 0.5 * (f.viscous_cw_nms_per_rad + f.viscous_ccw_nms_per_rad) * rc**2
    inertia = f.inertia_kgm2 * rc**2 + params.platform.inertia_kgm2
    if user is not None:
        inertia += user.foot_inertia_kgm2
        b += user.ankle_damping_nms_per_rad
    return LinearPlatform(
        inertia_kgm2=inertia,
        damping_nms_per_rad=b,
        stiffness_nm_per_rad=user.ankle_stiffness_nm_per_rad if user else 0.0,
        torque_per_amp_nm_per_a=params.motor.torque_constant_nm_per_a * params.total_ratio,
    )


def _motor_side(params: CapstanParameters, back_emf: bool) -> tuple[float, float]:
    lin = linear_platform(params)
    inertia = lin.inertia_kgm2 / params.total_ratio**2
    damping = lin.damping_nms_per_rad / params.total_ratio**2
    if back_emf:
        m = params.motor
        damping += m.torque_constant_nm_per_a * m.back_emf_constant_v_s_per_rad / m.resistance_ohm
    return inertia, damping


def voltage_to_motor_speed(params: CapstanParameters) -> Any:
    """Eq. 1: motor speed per volt, ``(K_i/R) / (J_eq s + b_eq)``, with back-EMF in ``b_eq``."""
    import control

    inertia, damping = _motor_side(params, back_emf=True)
    gain = params.motor.torque_constant_nm_per_a / params.motor.resistance_ohm
    return control.tf([gain], [inertia, damping], inputs="voltage_v", outputs="motor_speed_rad_s")


def ankle_torque_to_motor_speed(params: CapstanParameters, *, back_emf: bool = False) -> Any:
    """Eq. 2: motor speed per ankle torque, ``(1/(r_g r_c)) / (J s + b)`` (motor side).

    ``back_emf=False`` (default) models the current-controlled drive, whose current loop
    cancels the back-EMF damping; True gives the voltage-driven motor of eq. 1.
    """
    import control

    inertia, damping = _motor_side(params, back_emf=back_emf)
    return control.tf(
        [1.0 / params.total_ratio],
        [inertia, damping],
        inputs="ankle_torque_nm",
        outputs="motor_speed_rad_s",
    )


def _closed_loop_denominator(lin: LinearPlatform, kp: float, kd: float, ki: float) -> list[float]:
    den = [lin.inertia_kgm2, lin.damping_nms_per_rad + kd, kp + lin.stiffness_nm_per_rad]
    return [*den, ki] if ki else den


def reference_to_angle(
    params: CapstanParameters,
    kp: float,
    kd: float,
    ki: float = 0.0,
    user: UserParameters | None = None,
) -> Any:
    """Eq. 8: closed-loop platform angle per reference angle under PD (or PID) control.

    ``(Kd s + Kp) / (J s^2 + (b + Kd) s + Kp)``, gravity perfectly compensated; with ``ki``
    the integral adds ``Ki`` to the numerator and a pole (both multiplied through by ``s``).

    Examples
    --------
    >>> from anklelab.platforms import load_platform
    >>> g = reference_to_angle(load_platform("capstan"), kp=150.0, kd=15.0)
    >>> round(float(g.dcgain()), 6)
    1.0
    """
    import control

    lin = linear_platform(params, user)
    num = [kd, kp, ki] if ki else [kd, kp]
    den = _closed_loop_denominator(lin, kp, kd, ki)
    return control.tf(num, den, inputs="reference_rad", outputs="angle_rad")


def disturbance_to_angle(
    params: CapstanParameters,
    kp: float,
    kd: float,
    ki: float = 0.0,
    user: UserParameters | None = None,
) -> Any:
    """Eq. 9: closed-loop platform angle per external (ankle) torque, ``1 / (J s^2 + ...)``."""
    import control

    lin = linear_platform(params, user)
    num = [1.0, 0.0] if ki else [1.0]
    den = _closed_loop_denominator(lin, kp, kd, ki)
    return control.tf(num, den, inputs="ankle_torque_nm", outputs="angle_rad")
