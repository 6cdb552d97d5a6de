"""The compiled closed loop of the capstan twin: sensors, faults, controller, safety, observer,
virtual environment and plant, one control tick at a time.

Every tick: the motor encoder is read (quantised to whole counts) and the current sensor (with
its noise); an injected fault may corrupt them; the controller computes a current request; the
safety monitor passes, clamps or (latched fault) zeroes it; the disturbance observer updates its
estimate of the human torque from the same two readings; in admittance rendering that estimate
drives the virtual dynamics whose state is the next reference; finally the plant advances one
period.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from anklelab.control.haptics import admittance_update, impedance_torque
from anklelab.control.observer import new_observer_state, observer_update
from anklelab.control.pid import new_control_state, position_control_update
from anklelab.control.safety import new_safety_state, safety_update
from anklelab.sim.capstan._jit import FAST
from anklelab.sim.capstan.plant import encoder_angle, plant_advance

MODES = {"position": 0, "admittance": 1, "impedance": 2, "open-loop": 3}
FAULTS = {
    "none": 0,
    "encoder-nan": 1,
    "encoder-stale": 2,
    "encoder-jump": 3,
    "encoder-reversed": 4,
    "current-nan": 5,
}
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
    "fault",
)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def closed_loop(  # type: ignore[no-untyped-def]
    plant,
    law,
    x0,
    mode,
    ctrl,
    obs,
    env,
    limits,
    reference,
    reference_speed,
    command,
    voluntary,
    current_noise,
    fault_kind,
    fault_tick,
    fault_value,
    step,
    encoder_resolution,
):
    """Run ``len(reference)`` ticks; returns an array ``(n, len(SIGNALS))``.

    ``reference`` is the angle reference (mode ``position``; NaN disables the drive for that
    tick), or the environment's equilibrium angle (``admittance``, ``impedance``); ``command`` is
    the current (mode ``open-loop``).
    """
    n = len(reference)
    dt = step.h * step.n_sub
    rc = plant.pulley_radius / plant.pinion_radius
    x = x0.copy()
    out = np.empty((n, len(SIGNALS)))
    first = encoder_angle(x[1], plant.gear_ratio, encoder_resolution)
    ctrl_state = new_control_state(first / rc)
    obs_state = new_observer_state()
    safety_state = new_safety_state()
    virtual = np.array([first / rc, 0.0])
    frozen = 0.0
    for k in range(n):
        pinion = encoder_angle(x[1], plant.gear_ratio, encoder_resolution)
        angle = pinion / rc
        current = x[0] + current_noise[k]
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
        if mode == 1:
            ref, ref_speed = virtual[0], virtual[1]
        elif mode == 0:
            ref, ref_speed = reference[k], reference_speed[k]
        else:
            ref, ref_speed = angle, 0.0  # impedance and open loop: no position feedback
        request, speed = position_control_update(
            ctrl, ctrl_state, ref if np.isfinite(ref) else angle, ref_speed, angle
        )
        disabled = mode == 0 and not np.isfinite(reference[k])
        if disabled:  # the drive's output stage is off: no current, no current noise
            request = 0.0
        elif mode == 2:
            request += impedance_torque(env, angle, speed, reference[k]) / ctrl.torque_per_amp
        elif mode == 3:
            request = command[k]
        applied = safety_update(limits, safety_state, angle, speed, counter, current, request)
        estimate = observer_update(obs, obs_state, angle, current)
        if mode == 1:
            admittance_update(env, virtual, estimate, reference[k], dt)
        interaction, friction, voltage = plant_advance(
            plant, law, step, x, applied, 0.0 if disabled else current_noise[k], voluntary[k]
        )
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
        row[13] = voluntary[k]
        row[14] = estimate
        row[15] = friction
        row[16] = safety_state[0]
    return out
