"""Bilateral teleoperation over a delayed network with wave variables (Niemeyer & Slotine, IEEE
J. Oceanic Eng. 16:152, 1991), kept passive under a varying delay by bounding the energy each
receiver lets out.

At the platform (the master) the operator's speed ``w_m`` and the wave ``v`` returned by the
remote side give the torque to display and the wave to send::

    F_m = b w_m + sqrt(2 b) v,      u = sqrt(2 b) w_m + v      (the platform applies -F_m)

At the remote joint the wave ``u`` and the force ``F_s`` its local controller exerts give the
speed to follow and the wave to return::

    w_sd = (sqrt(2 b) u - F_s) / b,      v = (F_s - b w_sd) / sqrt(2 b)

The power into the channel is ``(u^2 - v^2) / 2`` at each end; with a constant delay the
channel stores what it receives and is passive for any delay. A varying delay (jitter, packets
overtaken, held) can let a receiver output more wave energy than was sent;
:func:`bounded_receive` prevents it: each packet carries the energy sent so far, and a receiver
shrinks the wave it uses whenever it would exceed that budget, so that the channel stays
passive whatever the network does.
"""

from __future__ import annotations

import math

from numba import njit

from anklelab.sim.capstan.remote import RemoteConstants

__all__ = ["bounded_receive", "wave_master", "wave_slave"]


@njit(cache=True, inline="always")
def bounded_receive(wave: float, budget: float, used: float, dt: float) -> float:
    """The wave to use this tick: ``wave`` unless that would let out more energy than the
    sender has put in (``budget``, J), given what this receiver has let out (``used``, J)."""
    room = budget - used
    if 0.5 * wave * wave * dt <= room:
        return wave
    return math.copysign(math.sqrt(max(room, 0.0) * 2.0 / dt), wave)


@njit(cache=True, inline="always")
def wave_master(impedance: float, speed: float, returned: float) -> tuple[float, float]:
    """Torque ``F_m`` the channel asks of the operator and the wave ``u`` to send."""
    root = math.sqrt(2.0 * impedance)
    return impedance * speed + root * returned, root * speed + returned


@njit(cache=True, inline="always")
def wave_slave(
    c: RemoteConstants, angle: float, speed: float, desired: float, wave: float, dt: float
) -> tuple[float, float, float]:
    """The remote joint's desired speed, its controller's force and the returned wave.

    The controller's force ``F_s = kd (w_sd - w) + kp (theta_d + dt w_sd - theta)`` and
    ``w_sd = (sqrt(2 b) u - F_s) / b`` are solved together (``desired`` is the joint's desired
    angle ``theta_d`` before this tick).
    """
    b = c.wave_impedance
    root = math.sqrt(2.0 * b)
    w_sd = (root * wave + c.kd * speed - c.kp * (desired - angle)) / (b + c.kd + c.kp * dt)
    force = c.kd * (w_sd - speed) + c.kp * (desired + dt * w_sd - angle)
    return w_sd, force, (force - b * w_sd) / root
