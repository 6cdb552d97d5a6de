"""The position-controlled hinge: servo loop, compliant transmission, moving platform.

Two inertias referred to the platform output (rad, N·m, kg·m²): the motor side ``J_m`` at angle
``ψ`` (what the servodrive's analog output reports as ``motor_angle``) and the platform side
``J`` at angle ``φ`` (the plate, and the foot standing on it), joined by the gearbox and
coupler spring ``K_t`` with damping ``c_t``. The drive closes a PID position loop on ``ψ``
(derivative on the measurement) tuned as if the motor were alone::

    J_m ψ'' = K_p (r - ψ) - K_d ψ' + K_i ∫(r - ψ) dt - K_t (ψ - φ) - c_t (ψ' - φ')
    J   φ'' = K_t (ψ - φ) + c_t (ψ' - φ') - k_s φ - c_s φ' + τ

with ``K_p = J_m ω_s²``, ``K_d = 2 ζ_s ω_s J_m``, ``K_i = K_p ω_i``. ``k_s`` is the gravity
stiffness of everything hanging below the hinge plus any extra stiffness acting on the plate
(the foot's reference stiffness), ``c_s`` bearing plus foot damping, ``τ`` the external torque
on the platform about the hinge (dorsiflexing positive). Angles are deviations from rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import DriveConfig, PlateConfig
from validation.cleanroom.lti import DiscreteSystem

__all__ = ["GRAVITY_M_S2", "Hinge", "platform_inertia"]

Array = NDArray[np.float64]
GRAVITY_M_S2 = 9.81
INPUTS = ("reference", "torque")
OUTPUTS = ("motor_angle", "angle", "velocity", "acceleration")


def platform_inertia(drive: DriveConfig, plate: PlateConfig) -> tuple[float, float]:
    """Inertia (kg·m²) and gravity stiffness (N·m/rad) of the moving platform about the hinge.

    The structure's values plus the top plate's: ``I_c + m (forward² + depth²)`` and
    ``m g depth`` (its centre of mass hangs ``depth`` below the hinge axis).
    """
    lever2 = plate.com_forward_m**2 + plate.com_depth_m**2
    inertia = drive.structure_inertia_kgm2 + plate.top_inertia_kgm2 + plate.top_mass_kg * lever2
    gravity = (
        drive.structure_gravity_nm_per_rad + plate.top_mass_kg * GRAVITY_M_S2 * plate.com_depth_m
    )
    return inertia, gravity


@dataclass(frozen=True)
class Hinge:
    """The hinge discretised at ``fs``: inputs ``reference`` (rad) and ``torque`` (N·m).

    Outputs ``motor_angle`` (ψ, rad), ``angle`` (φ, rad), ``velocity`` (φ', rad/s) and
    ``acceleration`` (φ'', rad/s²).
    """

    system: DiscreteSystem

    @classmethod
    def build(
        cls,
        drive: DriveConfig,
        plate: PlateConfig,
        fs: float,
        *,
        inertia_kgm2: float = 0.0,
        damping_nms_per_rad: float = 0.0,
        stiffness_nm_per_rad: float = 0.0,
    ) -> Hinge:
        """The hinge with an extra inertia, damping and stiffness rigidly on the platform.

        Parameters
        ----------
        drive, plate : DriveConfig, PlateConfig
            Servo, transmission and platform parameters.
        fs : float
            Simulation rate, Hz.
        inertia_kgm2, damping_nms_per_rad, stiffness_nm_per_rad : float
            A load moving with the platform (the foot's I, b and reference k), SI units.
        """
        j_platform, k_gravity = platform_inertia(drive, plate)
        jm = drive.motor_inertia_kgm2
        j = j_platform + inertia_kgm2
        omega = 2 * np.pi * drive.servo_frequency_hz
        kp = jm * omega**2
        kd = 2 * drive.servo_damping_ratio * omega * jm
        ki = kp * drive.servo_integral_ratio * omega
        kt = drive.transmission_stiffness_nm_per_rad
        ct = 2 * drive.transmission_damping_ratio * np.sqrt(kt * jm * j / (jm + j))
        ks = k_gravity + stiffness_nm_per_rad
        cs = drive.bearing_damping_nms_per_rad + damping_nms_per_rad
        # states: psi, psi', phi, phi', integral of (r - psi)
        a = np.array(
            [
                [0.0, 1.0, 0.0, 0.0, 0.0],
                [-(kp + kt) / jm, -(kd + ct) / jm, kt / jm, ct / jm, ki / jm],
                [0.0, 0.0, 0.0, 1.0, 0.0],
                [kt / j, ct / j, -(kt + ks) / j, -(ct + cs) / j, 0.0],
                [-1.0, 0.0, 0.0, 0.0, 0.0],
            ]
        )
        b = np.array([[0.0, 0.0], [kp / jm, 0.0], [0.0, 0.0], [0.0, 1 / j], [1.0, 0.0]])
        c = np.vstack([np.eye(5)[[0, 2, 3]], a[3]])
        d = np.vstack([np.zeros((3, 2)), b[3]])
        return cls(DiscreteSystem.from_continuous(a, b, c, d, fs, INPUTS, OUTPUTS))

    def response(
        self,
        reference: Array | None = None,
        torque: Array | None = None,
        outputs: tuple[str, ...] = OUTPUTS,
    ) -> dict[str, Array]:
        """Outputs for a reference angle and/or an external torque sampled at ``fs``.

        Both start at rest; inputs are sampled along the last axis (trials first).
        """
        inputs = {
            name: value
            for name, value in zip(INPUTS, (reference, torque), strict=True)
            if value is not None
        }
        return self.system.response(inputs, outputs)
