"""Compiled time-stepping kernel of the Perturberator twin (one batch of trials per call).

Everything that must run at the drive's rates lives here, in one numba module (numba's cache
does not track changes across modules): the drive firmware's cascade arithmetic (position loop
at the position-loop rate, velocity PI at the velocity-loop rate, one-sample computation delay),
the plant (current loop as a first-order torque lag, motor and gearhead inertia, compliant
coupler, hinge with the force plate, Coulomb/viscous losses, torque limit), the foot coupled to
the hinge, and the force plate's signal chain (top-plate inertial and gravity-tilt loads,
structural modes and the anti-alias filter, run at the position-loop rate).

Conventions: angles and torques referred to the platform output, dorsiflexion positive. Plate
vectors are in the *sagittal plate frame*: Kistler axes (x anterior, y right, z down) of the
tilted plate, origin at the centre of the sensor plane; a dorsiflexion is a positive rotation
about +y. The lab ground reaction force (plate on foot) enters as ``gx`` (anterior), ``gy``
(right) and ``gz`` (up). The meaning of every index below is documented where the arrays are
built (:mod:`anklelab.sim.drivetrain`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# platform constants (pc)
J_M, K_S, C_S, B_M, T_COUL, W_EPS, J_H, B_H, K_G, TAU_MAX, INV_TC = range(11)
KPP, KVP, WI, ENC_Q, AZ0, X_H, H_H, M_T, I_T, X_T, Z_T, GRAV, DT = range(11, 24)
POS_MAX, VEL_MAX, FOLLOW_MAX, ENC_TIMEOUT, B_DB, BRAKE_STEPS = range(24, 30)
N_PC = 30
# drive faults (anklelab.sim.drivetrain.DriveFault)
D_ENCODER, D_POSITION, D_VELOCITY, D_FOLLOWING, D_STALE = 1, 2, 3, 4, 5
# injected encoder faults (anklelab.sim.drivetrain.EncoderFault)
E_NAN, E_STALE, E_JUMP = 1, 2, 3
# per-trial foot scalars (fp)
F_IF, F_XA, F_DZ, F_MIS, F_KLEG, F_KSH, F_BSH = range(7)
N_FP = 7
# gait channels (g), sampled at GAIT_FS
G_X, G_Y, G_Z, G_TNOM, G_CY, G_K, G_B, G_CONTACT = range(8)
N_G = 8
# flags
FL_FOOT, FL_PLATE, FL_INERTIA, FL_RESON, FL_AA, FL_LOOP, FL_NSUB, FL_RESUME = range(8)
N_FL = 8
# snapshot of a trial's state at the start of a step: plant, then controller
S_INTEG, S_TH0, S_FLAT, S_VCMD, S_TAU, S_ENC = range(7, 13)
N_SNAP = 13
# outputs
O_THM, O_THH, O_PHI, O_TA, O_TAU = range(5)
N_MECH = 5
N_WRENCH = 6  # Fx, Fy, Fz, Mx, My, Mz
L_ENC, L_CTRL, L_CMD = range(3)


@njit(cache=True, inline="always")
def _gait_at(g, t, fs, out):
    """Linear interpolation of the gait samples ``g`` (n_samples, N_G) at time ``t`` (zero
    outside the record)."""
    x = t * fs
    i = math.floor(x)
    n = g.shape[0]
    if i < 0 or i >= n - 1:
        for c in range(N_G):
            out[c] = 0.0
        return
    f = x - i
    for c in range(N_G):
        out[c] = g[i, c] + f * (g[i + 1, c] - g[i, c])


@njit(cache=True, inline="always")
def _rhs(s, tau_cmd, gv, pc, fp, shell, th0, fric, c, sn, d):
    """Derivative ``d`` of the state ``s = (tau, thm, wm, thh, wh, thf, wf)``.

    Returns ``(T_A, Lx, Lz)``.

    ``T_A`` is the external dorsiflexing moment on the foot about the ankle, ``(Lx, Lz)`` the
    foot's load on the plate in the sagittal plate frame. While the foot is flat on the plate
    (``G_CONTACT``) its angles count from ``th0``, the hinge angle at foot flat. The Coulomb
    friction ``fric`` and the hinge tilt's ``c = cos(thh)``, ``sn = sin(thh)`` are evaluated
    once per integration step (they change little within one).
    """
    tau, thm, wm, thh, wh, thf, wf = s[0], s[1], s[2], s[3], s[4], s[5], s[6]
    d[0] = (tau_cmd - tau) * pc[INV_TC]
    ts = pc[K_S] * (thm - thh) + pc[C_S] * (wm - wh)
    d[1] = wm
    d[2] = (tau - ts - pc[B_M] * wm - fric) / pc[J_M]
    d[3] = wh
    hinge = ts - pc[B_H] * wh - pc[K_G] * sn
    contact = gv[G_CONTACT]
    ex = fp[F_XA] - pc[X_H]
    ez = fp[F_DZ] - pc[H_H]
    gz = gv[G_Z] + contact * fp[F_KLEG] * ex * thh
    lx = -c * gv[G_X] - sn * gz
    lz = -sn * gv[G_X] + c * gz
    k = gv[G_K]
    b = gv[G_B]
    m = fp[F_MIS]
    if shell and contact > 0.0:
        phi = thf - th0 + m * (thh - th0)
        dphi = wf + m * wh
        tsh = fp[F_KSH] * (thh - thf) + fp[F_BSH] * (wh - wf)
        ta = gv[G_TNOM] + tsh
        d[5] = wf
        d[6] = (tsh - k * phi - b * dphi) / fp[F_IF]
        d[4] = (hinge - ta - ex * lz - ez * lx) / pc[J_H]
    else:
        inertia = contact * fp[F_IF]
        rest = gv[G_TNOM] + (1.0 + m) * (k * (thh - th0) + b * wh)
        d[4] = (hinge - rest - ex * lz - ez * lx) / (pc[J_H] + inertia)
        ta = rest + inertia * d[4]
        d[5] = wh
        d[6] = d[4]
    return ta, lx, lz


@njit(cache=True, inline="always")
def _biquad(x, sos, z, row):
    """Filter one sample through the cascade ``sos`` with state ``z[row]`` (direct form II T)."""
    y = x
    for k in range(sos.shape[0]):
        b0, b1, b2, a1, a2 = sos[k, 0], sos[k, 1], sos[k, 2], sos[k, 4], sos[k, 5]
        out = b0 * y + z[row, 2 * k]
        z[row, 2 * k] = b1 * y - a1 * out + z[row, 2 * k + 1]
        z[row, 2 * k + 1] = b2 * y - a2 * out
        y = out
    return y


@njit(cache=True, inline="always")
def _plate_wrench(s, d, ta, lx, lz, gv, pc, fp, inertia, c, sn, w):
    """Load on the sensors (sagittal plate frame, about the sensor-plane centre) into ``w``."""
    az0 = pc[AZ0]
    ly = -gv[G_Y]
    cy = gv[G_CY]
    dz = fp[F_DZ]
    xa = fp[F_XA]
    cx = xa + (ta + lx * dz) / lz if lz > 1e-9 else xa
    fx = lx
    fz = lz
    my = az0 * lx - xa * lz - ta - lx * dz
    if inertia:
        wh, ah = s[4], d[4]
        rx = pc[X_T] - pc[X_H]
        rz = pc[Z_T] - (az0 - pc[H_H])
        ax = ah * rz - wh * wh * rx
        az = -ah * rx - wh * wh * rz
        mt = pc[M_T]
        gr = pc[GRAV]
        fxa = mt * (-gr * sn - ax)
        fza = mt * (gr * (c - 1.0) - az)
        fx += fxa
        fz += fza
        my += pc[Z_T] * fxa - pc[X_T] * fza - pc[I_T] * ah
    w[0] = fx
    w[1] = ly
    w[2] = fz
    w[3] = cy * lz - az0 * ly
    w[4] = my
    w[5] = cx * ly - cy * lx


@njit(cache=True, nogil=True)
def run_batch(
    pc, fp, g, gait_fs, ref, inj, flags, sos_v, sos_h, sos_aa, plate_every, rec_every,
    span, resume, fork, enc_fault, enc_jump, mech, wrench, loop, snap, fault,
):  # fmt: skip
    """Simulate each trial of a batch; fills ``mech``, ``wrench`` and ``loop`` in place.

    Parameters
    ----------
    pc : (N_PC,) platform constants.
    fp : (n_trials, N_FP) foot scalars.
    g : (n_trials, n_gait, N_G) gait channels sampled at ``gait_fs``.
    ref : (n_trials, n_ticks) position reference at the position-loop ticks, rad.
    inj : (n_trials, n_ticks) or (n_trials, 0) velocity command added at the position-loop
        output (loop measurements), rad/s.
    flags : (N_FL,) int switches; ``flags[FL_NSUB]`` physics sub-steps per velocity step.
    sos_v, sos_h, sos_aa : second-order sections at the plate rate (vertical mode, horizontal
        mode, anti-alias).
    plate_every, rec_every : velocity steps per plate tick / per recorded sample.
    span : (n_trials, 2) first and end velocity step simulated.
    resume : (n_trials, N_SNAP) state at the first step (used with ``flags[FL_RESUME]``).
    fork : (n_trials,) step at whose start the state is copied into ``snap`` (-1: never).
    enc_fault : (n_trials, 2) fault injection: the step from which the encoder fails (-1: never)
        and how (``E_NAN`` reads NaN, ``E_STALE`` sends no new frame, ``E_JUMP`` reads
        ``enc_jump`` rad off).
    enc_jump : (n_trials,) offset of an ``E_JUMP`` fault, rad.
    mech, wrench : (n_trials, N_MECH | 6, n_rec) outputs; loop : (n_trials, 3, n_ticks) or empty.
    fault : (n_trials, 2) output: the drive's latched fault code (``D_*``, 0 none) and step.

    Fault reaction (see :mod:`anklelab.sim.drivetrain`): after a position or following-error
    fault the velocity loop is commanded to zero speed (controlled stop, then hold); after a
    lost or stale encoder or overspeed the windings are shorted (dynamic brake, torque
    ``-B_DB w_m`` within the torque limit) and the holding brake locks the motor shaft
    ``BRAKE_STEPS`` steps later. A resumed trial starts healthy.
    """
    n_trials, n_ticks = ref.shape
    n_steps = 2 * n_ticks
    n_sub = flags[FL_NSUB]
    dt = pc[DT]
    h = dt / n_sub
    shell_any = flags[FL_FOOT] == 1
    s = np.zeros(7)
    k1 = np.zeros(7)
    k2 = np.zeros(7)
    k3 = np.zeros(7)
    k4 = np.zeros(7)
    tmp = np.zeros(7)
    gv = np.zeros(N_G)
    gv1 = np.zeros(N_G)
    gvm = np.zeros(N_G)
    w = np.zeros(N_WRENCH)
    zr = np.zeros((N_WRENCH, 2 * max(sos_v.shape[0], sos_h.shape[0])))
    za = np.zeros((N_WRENCH, 2 * sos_aa.shape[0]))
    has_inj = inj.shape[1] > 0
    foot = flags[FL_FOOT] == 1
    for n in range(n_trials):
        zr[:, :] = 0.0
        za[:, :] = 0.0
        shell = shell_any and fp[n, F_KSH] > 0.0
        if flags[FL_RESUME] == 1:
            s[:] = resume[n, :7]
            integ, th0, flat = resume[n, S_INTEG], resume[n, S_TH0], resume[n, S_FLAT] > 0.0
            vcmd, tau_next, enc_prev = resume[n, S_VCMD], resume[n, S_TAU], resume[n, S_ENC]
        else:
            s[:] = 0.0
            integ, th0, flat, vcmd, tau_next, enc_prev = 0.0, 0.0, False, 0.0, 0.0, 0.0
        code = 0
        locked = False
        lock_angle = held = 0.0
        j0 = span[n, 0]
        last_frame = j0 - 1
        for j in range(j0, min(span[n, 1], n_steps)):
            t = j * dt
            if j == fork[n]:
                snap[n, :7] = s
                snap[n, S_INTEG], snap[n, S_TH0], snap[n, S_FLAT] = integ, th0, 1.0 if flat else 0.0
                snap[n, S_VCMD], snap[n, S_TAU], snap[n, S_ENC] = vcmd, tau_next, enc_prev
            # drive: encoder, position loop (every second velocity step), velocity PI
            enc = s[1]
            if pc[ENC_Q] > 0.0:
                enc = math.floor(s[1] / pc[ENC_Q] + 0.5) * pc[ENC_Q]
            frame = j  # the encoder's frame counter
            if 0 <= enc_fault[n, 0] <= j:
                kind = enc_fault[n, 1]
                if kind == E_NAN:
                    enc = math.nan
                elif kind == E_STALE:
                    if j == enc_fault[n, 0]:
                        held = enc_prev
                    enc = held
                    frame = enc_fault[n, 0] - 1
                else:
                    enc += enc_jump[n]
            last_frame = max(last_frame, frame)
            vel = (enc - enc_prev) / dt if j > j0 else 0.0
            if code == 0:
                if not math.isfinite(enc):
                    code = D_ENCODER
                elif j - last_frame > pc[ENC_TIMEOUT]:
                    code = D_STALE
                elif abs(vel) > pc[VEL_MAX]:
                    code = D_VELOCITY
                elif abs(enc) > pc[POS_MAX]:
                    code = D_POSITION
                elif j % 2 == 0 and abs(ref[n, j // 2] - enc) > pc[FOLLOW_MAX]:
                    code = D_FOLLOWING
                if code != 0:
                    fault[n, 0] = code
                    fault[n, 1] = j
            if code == 0 or code == D_POSITION or code == D_FOLLOWING:
                if code != 0:  # controlled stop: zero speed, then hold
                    vcmd = 0.0
                elif j % 2 == 0:
                    i = j // 2
                    ctrl = pc[KPP] * (ref[n, i] - enc)
                    vcmd = ctrl + (inj[n, i] if has_inj else 0.0)
                    if flags[FL_LOOP] == 1:
                        loop[n, L_ENC, i] = enc
                        loop[n, L_CTRL, i] = ctrl
                        loop[n, L_CMD, i] = vcmd
                err = vcmd - vel
                raw = pc[KVP] * (err + integ)
                if abs(raw) < pc[TAU_MAX] or raw * err < 0.0:
                    integ += pc[WI] * err * dt
                tau_cmd = tau_next  # one velocity-loop sample of computation delay
                tau_next = min(max(raw, -pc[TAU_MAX]), pc[TAU_MAX])
            else:  # dynamic brake (no feedback), then the holding brake
                tau_cmd = min(max(-pc[B_DB] * s[2], -pc[TAU_MAX]), pc[TAU_MAX])
                if not locked and j - fault[n, 1] >= pc[BRAKE_STEPS]:
                    locked = True
                    lock_angle = s[1]
            enc_prev = enc
            # plant: RK4 sub-steps with the torque command held
            for q in range(n_sub):
                tq = t + q * h
                if foot:
                    if j == j0 and q == 0:
                        _gait_at(g[n], tq, gait_fs, gv)
                    else:  # the previous step's end
                        for c in range(N_G):
                            gv[c] = gv1[c]
                    _gait_at(g[n], tq + h, gait_fs, gv1)
                    for c in range(N_G):
                        gvm[c] = 0.5 * (gv[c] + gv1[c])
                    if gv[G_CONTACT] == 0.0:
                        s[5] = s[3]
                        s[6] = s[4]
                    elif not flat:
                        th0 = s[3]
                    flat = gv[G_CONTACT] > 0.0
                fric = pc[T_COUL] * math.tanh(s[2] / pc[W_EPS])
                cth = math.cos(s[3])
                sth = math.sin(s[3])
                ta, lx, lz = _rhs(s, tau_cmd, gv, pc, fp[n], shell, th0, fric, cth, sth, k1)
                if q == 0 and j % plate_every == 0:
                    if flags[FL_PLATE] == 1:
                        _plate_wrench(
                            s, k1, ta, lx, lz, gv, pc, fp[n], flags[FL_INERTIA], cth, sth, w
                        )
                        for c in range(N_WRENCH):
                            x = w[c]
                            if flags[FL_RESON] == 1:
                                x = _biquad(x, sos_v if c >= 2 and c <= 4 else sos_h, zr, c)
                            if flags[FL_AA] == 1:
                                x = _biquad(x, sos_aa, za, c)
                            w[c] = x
                    if j % rec_every == 0:
                        r = j // rec_every
                        mech[n, O_THM, r] = s[1]
                        mech[n, O_THH, r] = s[3]
                        if flat:
                            mech[n, O_PHI, r] = s[5] - th0 + fp[n, F_MIS] * (s[3] - th0)
                        else:
                            mech[n, O_PHI, r] = 0.0
                        mech[n, O_TA, r] = ta
                        mech[n, O_TAU, r] = s[0]
                        if flags[FL_PLATE] == 1:
                            for c in range(N_WRENCH):
                                wrench[n, c, r] = w[c]
                for c in range(7):
                    tmp[c] = s[c] + 0.5 * h * k1[c]
                _rhs(tmp, tau_cmd, gvm, pc, fp[n], shell, th0, fric, cth, sth, k2)
                for c in range(7):
                    tmp[c] = s[c] + 0.5 * h * k2[c]
                _rhs(tmp, tau_cmd, gvm, pc, fp[n], shell, th0, fric, cth, sth, k3)
                for c in range(7):
                    tmp[c] = s[c] + h * k3[c]
                _rhs(tmp, tau_cmd, gv1, pc, fp[n], shell, th0, fric, cth, sth, k4)
                for c in range(7):
                    s[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c])
                if locked:  # the holding brake holds the motor shaft
                    s[1] = lock_angle
                    s[2] = 0.0
