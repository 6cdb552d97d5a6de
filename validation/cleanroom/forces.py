"""What the plate's sensors feel: the foot's load, the top plate's own inertia and weight.

Everything here is in the hinge frame W (moves with the plate: x anterior, y right, z down,
origin at the centre of the sensor plane) as the force and moment (about the origin) applied
*to the sensors*, then passed through the sensor dynamics, turned into the plate frame P and
split into the eight channels. Arrays carry components first: ``(3, n_trials, n_times)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from validation.cleanroom.config import PlateConfig
from validation.cleanroom.drive import GRAVITY_M_S2
from validation.cleanroom.lti import DiscreteSystem, second_order_lowpass
from validation.cleanroom.plate import channels_from_resultants, rotate_about_z

__all__ = ["PlateSensors", "foot_load", "plate_load", "tilt"]

Array = NDArray[np.float64]


def tilt(grf: Array, angle: Array) -> tuple[Array, Array]:
    """Anterior and normal GRF components in the frame of a plate tilted by ``angle`` (rad).

    ``grf`` holds the lab-frame (anterior, rightward, upward) GRF, N; a dorsiflexed plate
    (toes up, ``angle > 0``) sees part of the body weight as a forward push.
    """
    c, s = np.cos(angle), np.sin(angle)
    return grf[0] * c + grf[2] * s, -grf[0] * s + grf[2] * c


def foot_load(
    grf: Array,
    angle: Array,
    ankle_torque: Array,
    ankle_x_m: Array,
    cop_lateral_m: Array,
    free_moment: Array,
    contact: NDArray[np.bool_],
    plate: PlateConfig,
    ankle_height_m: float,
) -> tuple[Array, Array]:
    """Force and moment of the foot on the plate, hinge frame, about the sensor-plane centre.

    The foot stands on the plate surface (``z = az0``); the plate pushes it with the GRF at the
    COP, whose moment about the ankle centre (``ankle_height_m`` above the surface,
    ``ankle_x_m`` in front of the plate centre) is ``ankle_torque`` (dorsiflexing positive):
    ``T = G_n dx + G_a dz`` with the GRF components ``G_a`` (anterior) and ``G_n`` (normal) in
    the tilted plate's frame. The sagittal moment needs no COP:
    ``My = -T - x_ankle G_n + G_a (dz - az0)``.

    Returns
    -------
    force, moment : ndarray, shape (3, n_trials, n_times)
        N and N·m, zero where ``contact`` is false.
    """
    g_a, g_n = tilt(grf, angle)
    g_r = grf[1]
    dz, az0 = ankle_height_m, plate.az0_m
    lever = np.divide(
        ankle_torque - g_a * dz, g_n, out=np.zeros_like(g_n), where=np.abs(g_n) > 1e-9
    )
    cop_x = ankle_x_m + lever
    force = np.stack([-g_a, -g_r, g_n])
    moment = np.stack(
        [
            cop_lateral_m * g_n + az0 * g_r,
            -ankle_torque - ankle_x_m * g_n + g_a * (dz - az0),
            -cop_x * g_r + cop_lateral_m * g_a + free_moment,
        ]
    )
    return force * contact, moment * contact


def plate_load(
    plate: PlateConfig, angle: Array, velocity: Array, acceleration: Array
) -> tuple[Array, Array]:
    """Inertial and gravity load of the top plate on the sensors, tared at rest.

    The top plate (mass ``m``, centre of mass ``r`` from the hinge axis, inertia ``I_c``)
    rotates about the hinge (``y``) by ``φ``: its centre accelerates by
    ``a = φ'' (r_z, 0, -r_x) - φ'² (r_x, 0, r_z)`` and gravity turns to ``g (-sin φ, 0, cos φ)``
    in the plate's frame. The sensors carry ``F = m (g(φ) - g(0) - a)`` and
    ``M = q_c × F - I_c φ'' e_y`` (``q_c``: centre of mass from the sensor-plane centre).
    """
    hinge_z = plate.az0_m - plate.hinge_height_m
    r = np.array([plate.com_forward_m, plate.com_lateral_m, plate.com_depth_m])
    q = r + np.array([plate.hinge_x_m, 0.0, hinge_z])
    m = plate.top_mass_kg
    g = GRAVITY_M_S2
    force = m * np.stack(
        [
            -g * np.sin(angle) - acceleration * r[2] + velocity**2 * r[0],
            np.zeros_like(angle),
            g * (np.cos(angle) - 1) + acceleration * r[0] + velocity**2 * r[2],
        ]
    )
    moment = np.stack(
        [
            q[1] * force[2] - q[2] * force[1],
            q[2] * force[0] - q[0] * force[2] - plate.top_inertia_kgm2 * acceleration,
            q[0] * force[1] - q[1] * force[0],
        ]
    )
    return force, moment


@dataclass(frozen=True)
class PlateSensors:
    """Sensor dynamics, plate orientation and channel split of one plate at rate ``fs``.

    The vertical group (Fz, Mx, My, carried by the vertical sensors) rings at
    ``vertical_frequency_hz``, the horizontal group (Fx, Fy, Mz) at
    ``horizontal_frequency_hz`` (README.md, "Force plate"); both groups are unchanged by turns
    about z, so the dynamics act before the hinge-to-plate rotation.
    """

    plate: PlateConfig
    vertical: DiscreteSystem | None
    horizontal: DiscreteSystem | None

    @classmethod
    def build(cls, plate: PlateConfig, fs: float) -> PlateSensors:
        """Discretise the sensor modes at ``fs`` Hz (a frequency of 0 means rigid)."""

        def mode(frequency_hz: float) -> DiscreteSystem | None:
            if frequency_hz == 0:
                return None
            return second_order_lowpass(frequency_hz, plate.sensor_damping_ratio, fs)

        return cls(plate, mode(plate.vertical_frequency_hz), mode(plate.horizontal_frequency_hz))

    def channels(self, force: Array, moment: Array) -> Array:
        """The eight channels (N) for a load on the sensors in the hinge frame.

        Parameters
        ----------
        force, moment : ndarray, shape (3, ...)
            Load on the sensors, hinge frame, N and N·m about the sensor-plane centre.

        Returns
        -------
        ndarray, shape (8, ...)
            Channels in the plate's Kistler convention.
        """
        force, moment = force.copy(), moment.copy()
        groups = (
            (self.vertical, ((force, 2), (moment, 0), (moment, 1))),
            (self.horizontal, ((force, 0), (force, 1), (moment, 2))),
        )
        for system, members in groups:
            if system is not None:
                for array, row in members:
                    array[row] = system.filter(array[row])
        angle = self.plate.plate_angle_rad
        return channels_from_resultants(
            rotate_about_z(force, angle),
            rotate_about_z(moment, angle),
            self.plate.a_m,
            self.plate.b_m,
        )
