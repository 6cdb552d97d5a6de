"""The compiled closed loop of the capstan twin: sensors, faults, controller, feed-forward,
rendering, person guard, safety monitor, observer, the person and the plant, one tick at a time.

Every tick: the motor encoder is read (quantised to whole counts) and the current sensor (with
its noise); an injected fault may corrupt them; the reference is the input's (``position``), the
equilibrium plus the admittance's virtual deflection (``admittance``), or none (``impedance``:
the PID is off and the virtual spring-damper's torque, with the passivity controller, is the
command); the PID (with gravity and optional friction compensation) and the optional inverse
dynamics feed-forward compute a current request, plus the input's feed-forward current; a
disabled drive asks for nothing; the person guard limits what reaches the person and runs the
fall-safe stop; the safety monitor passes, clamps or (latched fault) zeroes the request; the
disturbance observer updates its estimate of the human torque; the person (if any) answers the
platform's true motion; finally the plant advances one period.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from anklelab.control._platform_model import friction_feedforward
from anklelab.control.haptics import admittance_update, impedance_torque, new_admittance_state
from anklelab.control.observer import new_observer_state, observer_update
from anklelab.control.passivity import new_passivity_state, passivity_update
from anklelab.control.person_guard import guard_update, new_guard_state
from anklelab.control.pid import new_control_state, position_control_update
from anklelab.control.safety import Fault, new_safety_state, safety_update
from anklelab.control.teleop import bounded_receive, wave_master, wave_slave
from anklelab.sim.capstan._jit import FAST
from anklelab.sim.capstan.person import new_person_state, person_torque
from anklelab.sim.capstan.plant import encoder_angle, plant_advance
from anklelab.sim.capstan.remote import new_remote_state, remote_step

MODES = {"position": 0, "admittance": 1, "impedance": 2, "teleoperation": 3}
SCHEMES = {"wave": 1, "direct": 0}
FAULTS = {
    "none": 0,
    "encoder-nan": 1,
    "encoder-stale": 2,
    "encoder-jump": 3,
    "encoder-reversed": 4,
    "current-nan": 5,
}
INPUTS = (
    "reference_rad",  # position: the reference; rendering: the equilibrium angle
    "reference_speed_rad_s",
    "reference_acceleration_rad_s2",
    "feedforward_current_a",
    "stiffness_nm_per_rad",  # rendering, per tick (inf: rigid ground in admittance)
    "damping_nms_per_rad",
    "enabled",  # 0: the drive's output stage is off this tick
    "voluntary_torque_nm",
    "person_stiffness_nm_per_rad",
    "person_damping_nms_per_rad",
    "person_load_nm",
    "person_contact",
    "current_noise_a",
    "stop",  # nonzero: a fall-safe stop is requested
    "remote_ground_rad",  # teleoperation: the remote ground's slope under the robot's foot
)
SIGNALS = (
    "reference_rad",
    "angle_rad",
    "measured_angle_rad",
    "speed_rad_s",
    "speed_estimate_rad_s",
    "pinion_angle_rad",
    "measured_pinion_angle_rad",
    "pinion_speed_rad_s",
    "current_a",
    "current_command_a",
    "measured_current_a",
    "voltage_v",
    "interaction_torque_nm",
    "voluntary_torque_nm",
    "estimated_torque_nm",
    "friction_torque_nm",
    "rendered_torque_nm",
    "passivity_energy_j",
    "person_torque_nm",
    "reflex_torque_nm",
    "guard_clamped",
    "remote_angle_rad",
    "remote_contact_nm",
    "channel_energy_j",
    "fault",
)
(
    REF,
    REF_SPEED,
    REF_ACCEL,
    FF_CURRENT,
    STIFFNESS,
    DAMPING,
    ENABLED,
    VOLUNTARY,
    P_STIFFNESS,
    P_DAMPING,
    P_LOAD,
    P_CONTACT,
    NOISE,
    STOP,
    GROUND,
) = range(len(INPUTS))
FALL_STOP = float(Fault.FALL_STOP)


class FeedforwardConstants(NamedTuple):
    """The inverse-dynamics feed-forward: on (1.0) or off, and the nominal load it adds to the
    observer's model: total inertia, and the seated user's ankle stiffness and damping."""

    on: float
    inertia: float
    stiffness: float
    damping: float


@njit(cache=True, fastmath=FAST, error_model="numpy")
def closed_loop(  # type: ignore[no-untyped-def]
    plant,
    law,
    x0,
    mode,
    ctrl,
    feedforward,
    obs,
    env,
    guard,
    person,
    remote,
    scheme,
    forward,
    backward,
    limits,
    inputs,
    fault_kind,
    fault_tick,
    fault_value,
    step,
    encoder_resolution,
):
    """Run ``len(inputs)`` ticks; returns an array ``(n, len(SIGNALS))``.

    ``inputs`` has one row per tick and the columns :data:`INPUTS`; ``feedforward``
    (:class:`FeedforwardConstants`) adds the inverse dynamics ``J a_ref + b_u w_ref + K_u
    theta_ref + F(w_ref)`` (the observer's model, the seated user's nominal foot and ankle) to
    the request, and in admittance rendering takes the estimated human torque off the loop.
    In teleoperation, ``forward[k]`` and ``backward[k]`` are the newest packets received at tick
    ``k`` by the remote robot and by the platform (-1: none yet; :func:`~anklelab.sim.capstan.
    remote.arrivals`), ``remote`` the robot and ``scheme`` :data:`SCHEMES`.
    """
    n = inputs.shape[0]
    dt = step.h * step.n_sub
    rc = plant.pulley_radius / plant.pinion_radius
    x = x0.copy()
    out = np.empty((n, len(SIGNALS)))
    first = encoder_angle(x[1], plant.gear_ratio, encoder_resolution)
    ctrl_state = new_control_state(first / rc)
    obs_state = new_observer_state()
    safety_state = new_safety_state()
    virtual = new_admittance_state()
    passivity = new_passivity_state()
    guard_state = new_guard_state(guard)
    person_state = new_person_state(x[3], person.delay_ticks)
    robot = new_remote_state()
    sent_forward = np.zeros((n, 3))  # per packet: wave (or angle), speed, energy sent so far
    sent_backward = np.zeros((n, 2))  # per packet: wave (or contact torque), energy so far
    used_forward = 0.0
    used_backward = 0.0
    contact = 0.0
    frozen = 0.0
    estimate = 0.0
    previous = 0.0
    for k in range(n):
        row_in = inputs[k]
        pinion = encoder_angle(x[1], plant.gear_ratio, encoder_resolution)
        angle = pinion / rc
        current = x[0] + row_in[NOISE]
        counter = float(k)
        if fault_kind > 0 and k >= fault_tick:
            if k == fault_tick:
                frozen = angle
            if fault_kind == 1:
                angle = np.nan
            elif fault_kind == 2:
                angle, counter = frozen, float(fault_tick)
            elif fault_kind == 3:
                angle += fault_value
            elif fault_kind == 4:
                angle = 2.0 * frozen - angle
            elif fault_kind == 5:
                current = np.nan
        ref, ref_speed, ref_accel = row_in[REF], row_in[REF_SPEED], row_in[REF_ACCEL]
        stiffness, damping = row_in[STIFFNESS], row_in[DAMPING]
        if mode == 1:
            offset, offset_speed, offset_accel = admittance_update(
                env, virtual, estimate, stiffness, damping, ref, dt
            )
            ref, ref_speed, ref_accel = (
                ref + offset,
                ref_speed + offset_speed,
                ref_accel + offset_accel,
            )
        elif mode == 2:
            ref, ref_speed, ref_accel = angle, 0.0, 0.0  # impedance: no position feedback
        request, speed = position_control_update(ctrl, ctrl_state, ref, ref_speed, angle)
        if feedforward.on != 0.0 and mode != 2:
            torque = friction_feedforward(obs, ref_speed)
            if mode == 1:  # the motor takes over the estimated human torque (disturbance obs.),
                # foot included: the platform alone is left to accelerate
                torque += obs.inertia * ref_accel
                torque -= estimate + env.lag1 * (estimate - previous) / dt
            else:
                torque += feedforward.inertia * ref_accel
                torque += feedforward.stiffness * ref + feedforward.damping * ref_speed
            request += torque / ctrl.torque_per_amp
        request += row_in[FF_CURRENT]
        rendered = 0.0
        if mode == 2:
            rendered = impedance_torque(stiffness, damping, angle, speed, row_in[REF])
            rendered, _ = passivity_update(
                passivity,
                rendered,
                angle - row_in[REF],
                dt,
                env.max_passivity_damping,
                env.passivity_control,
            )
            request += rendered / ctrl.torque_per_amp
        elif mode == 3:
            rendered, used_backward, used_forward, contact = _teleoperate(
                remote,
                scheme,
                robot,
                sent_forward,
                sent_backward,
                forward[k],
                backward[k],
                k,
                angle,
                speed,
                row_in[GROUND],
                used_forward,
                used_backward,
                dt,
            )
            request += rendered / ctrl.torque_per_amp
        enabled = row_in[ENABLED] != 0.0
        if not enabled:  # the drive's output stage is off: no current, no current noise
            request = 0.0
        request, clamped = guard_update(
            guard, guard_state, request, angle, speed, estimate, row_in[STOP]
        )
        applied = safety_update(limits, safety_state, angle, speed, counter, current, request)
        previous = estimate
        estimate = observer_update(obs, obs_state, angle, current)
        human, reflex = person_torque(
            person,
            person_state,
            row_in[P_STIFFNESS],
            row_in[P_DAMPING],
            row_in[P_LOAD],
            row_in[P_CONTACT],
            x[3],
            x[4],
        )
        interaction, friction, voltage = plant_advance(
            plant,
            law,
            step,
            x,
            applied,
            row_in[NOISE] if enabled else 0.0,
            row_in[VOLUNTARY] + human,
        )
        fault = safety_state[0]
        if fault == 0.0 and guard_state[0] != 0.0:
            fault = FALL_STOP
        row = out[k]
        row[0] = ref
        row[1] = x[3]
        row[2] = angle
        row[3] = x[4]
        row[4] = speed
        row[5] = x[1]
        row[6] = pinion
        row[7] = x[2]
        row[8] = x[0]
        row[9] = applied
        row[10] = current
        row[11] = voltage
        row[12] = interaction
        row[13] = row_in[VOLUNTARY]
        row[14] = estimate
        row[15] = friction
        row[16] = rendered
        row[17] = passivity[0]
        row[18] = human
        row[19] = reflex
        row[20] = clamped
        row[21] = robot[0]
        row[22] = contact
        row[23] = sent_forward[k, 2] + sent_backward[k, 1] - used_forward - used_backward
        row[24] = fault
    return out


@njit(cache=True, fastmath=FAST, error_model="numpy", inline="always")
def _teleoperate(  # type: ignore[no-untyped-def]
    remote,
    scheme,
    robot,
    sent_forward,
    sent_backward,
    newest_forward,
    newest_backward,
    k,
    angle,
    speed,
    ground,
    used_forward,
    used_backward,
    dt,
):
    """One tick of both ends of the channel: the torque for the platform to display, the
    energies let out so far by each receiver, and the ground's torque on the remote foot."""
    before = sent_forward[k - 1, 2] if k > 0 else 0.0
    before_back = sent_backward[k - 1, 1] if k > 0 else 0.0
    if scheme == 1:  # wave variables, each receiver bounded by the energy sent
        returned = 0.0
        if newest_backward >= 0:
            packet = sent_backward[newest_backward]
            returned = bounded_receive(packet[0], packet[1], used_backward, dt)
        used_backward += 0.5 * returned * returned * dt
        force, wave = wave_master(remote.wave_impedance, speed, returned)
        sent_forward[k, 0], sent_forward[k, 1] = wave, speed
        sent_forward[k, 2] = before + 0.5 * wave * wave * dt
        arrived = 0.0
        if newest_forward >= 0:
            packet = sent_forward[newest_forward]
            arrived = bounded_receive(packet[0], packet[2], used_forward, dt)
        used_forward += 0.5 * arrived * arrived * dt
        w_sd, _, back = wave_slave(remote, robot[0], robot[1], robot[2], arrived, dt)
        _, contact = remote_step(remote, robot, w_sd, ground, dt)
        sent_backward[k, 0] = back
        sent_backward[k, 1] = before_back + 0.5 * back * back * dt
        return -force, used_backward, used_forward, contact
    # direct: positions forward, the ground's torque back, no passivity
    sent_forward[k, 0], sent_forward[k, 1] = angle, speed
    target, target_speed = 0.0, 0.0
    if newest_forward >= 0:
        target, target_speed = sent_forward[newest_forward, 0], sent_forward[newest_forward, 1]
    robot[2] = target - dt * target_speed  # the joint's controller follows the sent angle
    _, contact = remote_step(remote, robot, target_speed, ground, dt)
    sent_backward[k, 0] = contact
    torque = sent_backward[newest_backward, 0] if newest_backward >= 0 else 0.0
    return torque, used_backward, used_forward, contact
