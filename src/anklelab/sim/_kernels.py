"""Compiled time-stepping kernel of the Perturberator twin (one batch of trials per call).

Everything that must run at the drive's rates lives here, in one numba module (numba's cache
does not track changes across modules): the drive firmware's cascade arithmetic (position loop
at the position-loop rate, velocity PI at the velocity-loop rate, one-sample computation delay),
the plant (current loop as a first-order torque lag, motor and gearhead inertia, compliant
coupler, hinge with the force plate, Coulomb/viscous losses, torque limit), the foot coupled to
the hinge, and the force plate's signal chain (top-plate inertial and gravity-tilt loads,
structural modes and the anti-alias filter, run at the position-loop rate).

Speed: inside the time-stepping loop the state, the platform constants and the foot's scalars
are tuples (values in registers), and no helper that branches takes an array: numba counts the
references of arrays passed to inlined helpers atomically, which cost a quarter of the time.

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
FL_FOOT, FL_PLATE, FL_INERTIA, FL_LOOP, FL_NSUB, FL_RESUME = range(6)
N_FL = 6
# snapshot of a trial's state at the start of a step: plant, then controller
S_INTEG, S_TH0, S_FLAT, S_VCMD, S_TAU, S_ENC = range(7, 13)
N_SNAP = 13
# outputs
O_THM, O_THH, O_PHI, O_TA, O_TAU = range(5)
N_MECH = 5
N_WRENCH = 6  # Fx, Fy, Fz, Mx, My, Mz
L_ENC, L_CTRL, L_CMD = range(3)


@njit(cache=True, inline="always")
def _gait_index(t, fs, n_samples):
    """Where the gait samples (rate ``fs``) are interpolated at time ``t``: ``(i, f, inside)``,
    the sample before ``t``, the fraction of the interval, and whether ``t`` lies within the
    record (outside it the channels read zero)."""
    x = t * fs
    i = math.floor(x)
    return i, x - i, 0 <= i < n_samples - 1


@njit(cache=True, inline="always")
def _row8(a):
    """The eight gait channels ``a`` as a tuple."""
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7])


@njit(cache=True, inline="always")
def _axpy(s, a, d):
    """``s + a d`` for 7-tuples."""
    return (
        s[0] + a * d[0], s[1] + a * d[1], s[2] + a * d[2], s[3] + a * d[3], s[4] + a * d[4],
        s[5] + a * d[5], s[6] + a * d[6],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _rk4_update(s, a, k1, k2, k3, k4):
    """``s + a (k1 + 2 k2 + 2 k3 + k4)`` for 7-tuples."""
    return (
        s[0] + a * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        s[1] + a * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
        s[2] + a * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
        s[3] + a * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]),
        s[4] + a * (k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4]),
        s[5] + a * (k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5]),
        s[6] + a * (k1[6] + 2.0 * k2[6] + 2.0 * k3[6] + k4[6]),
    )


_COS_SERIES = tuple((-1) ** k / math.factorial(2 * k) for k in range(6, -1, -1))
_SIN_SERIES = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(5, -1, -1))


@njit(cache=True, inline="always")
def _cos_sin(x):
    """``(cos x, sin x)``: by their Taylor series up to ``x¹²`` and ``x¹¹`` where ``|x| <= 0.25``
    rad (within one unit in the last place of ``math.cos`` and ``math.sin``), by ``math`` beyond.

    With the reciprocals of :func:`run_batch`, this takes a tenth off the kernel's time.
    """
    if abs(x) > 0.25:
        return math.cos(x), math.sin(x)
    x2 = x * x
    c = sn = 0.0
    for a in _COS_SERIES:  # Horner's scheme in x²
        c = c * x2 + a
    for a in _SIN_SERIES:
        sn = sn * x2 + a
    return c, x * sn


@njit(cache=True, inline="always")
def _rhs(s, tau_cmd, gv, pc, fp, shell, per_step):
    """Derivative of the state ``s = (tau, thm, wm, thh, wh, thf, wf)``.

    Returns ``(d, T_A, Lx, Lz)``: the derivative (a 7-tuple), the external dorsiflexing moment
    on the foot about the ankle, and the foot's load on the plate in the sagittal plate frame.
    ``gv`` holds the gait channels, ``pc`` the platform constants and ``fp`` the trial's foot
    scalars (tuples). ``per_step`` holds ``(th0, fric, c, sn, inv_jm)``: while the foot is flat
    on the plate (``G_CONTACT``) its angles count from ``th0``, the hinge angle at foot flat; the
    Coulomb friction ``fric`` and the hinge tilt's ``c = cos(thh)``, ``sn = sin(thh)`` are
    evaluated once per integration step (they change little within one); ``inv_jm = 1 / J_M``.
    """
    tau, thm, wm, thh, wh, thf, wf = s
    th0, fric, c, sn, inv_jm = per_step
    d0 = (tau_cmd - tau) * pc[INV_TC]
    ts = pc[K_S] * (thm - thh) + pc[C_S] * (wm - wh)
    d2 = (tau - ts - pc[B_M] * wm - fric) * inv_jm
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
        d5 = wf
        d6 = (tsh - k * phi - b * dphi) / fp[F_IF]
        d4 = (hinge - ta - ex * lz - ez * lx) / pc[J_H]
    else:
        inertia = contact * fp[F_IF]
        rest = gv[G_TNOM] + (1.0 + m) * (k * (thh - th0) + b * wh)
        d4 = (hinge - rest - ex * lz - ez * lx) / (pc[J_H] + inertia)
        ta = rest + inertia * d4
        d5 = wh
        d6 = d4
    return (d0, wm, d2, wh, d4, d5, d6), ta, lx, lz


@njit(cache=True, inline="always")
def _plate_wrench(wh, ah, ta, lx, lz, gv, pc, fp, inertia, c, sn):
    """Load on the sensors (sagittal plate frame, about the sensor-plane centre), a 6-tuple;
    ``wh``, ``ah`` are the hinge's speed and acceleration."""
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
    return fx, ly, fz, cy * lz - az0 * ly, my, cx * ly - cy * lx


@njit(cache=True, nogil=True)
def run_batch(
    pc, fp, g, gait_fs, ref, inj, flags, plate_sos, plate_sections, plate_every, rec_every,
    span, resume, fork, enc_fault, enc_jump, mech, wrench, loop, snap, fault,
):  # fmt: skip
    """Simulate each trial of a batch; fills ``mech``, ``wrench`` and ``loop`` in place.

    Parameters
    ----------
    pc : (N_PC,) tuple of the platform constants.
    fp : (n_trials, N_FP) foot scalars.
    g : (n_trials, n_gait, N_G) gait channels sampled at ``gait_fs``.
    ref : (n_trials, n_ticks) position reference at the position-loop ticks, rad.
    inj : (n_trials, n_ticks) or (n_trials, 0) velocity command added at the position-loop
        output (loop measurements), rad/s.
    flags : (N_FL,) int switches; ``flags[FL_NSUB]`` physics sub-steps per velocity step.
    plate_sos : (N_WRENCH, n_sections, 6) second-order sections at the plate rate that filter
        each wrench component in turn (structural mode, then anti-alias); only the first
        ``plate_sections[c]`` of component ``c`` are used.
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
    n_gait = g.shape[1]
    n_sub = flags[FL_NSUB]
    dt = pc[DT]
    h = dt / n_sub
    hh = 0.5 * h
    h6 = h / 6.0
    inv_jm = 1.0 / pc[J_M]  # multiplications, not divisions, in the loop
    inv_weps = 1.0 / pc[W_EPS]
    foot = flags[FL_FOOT] == 1
    gv = np.zeros(N_G)
    gv1 = np.zeros(N_G)
    gvm = np.zeros(N_G)
    w = np.zeros(N_WRENCH)
    z = np.zeros((N_WRENCH, 2 * plate_sos.shape[1]))  # the filters' states (direct form II T)
    has_inj = inj.shape[1] > 0
    for n in range(n_trials):
        z[:, :] = 0.0
        fpn = (fp[n, 0], fp[n, 1], fp[n, 2], fp[n, 3], fp[n, 4], fp[n, 5], fp[n, 6])
        shell = foot and fpn[F_KSH] > 0.0
        if flags[FL_RESUME] == 1:
            s = (
                resume[n, 0], resume[n, 1], resume[n, 2], resume[n, 3], resume[n, 4],
                resume[n, 5], resume[n, 6],
            )  # fmt: skip
            integ, th0, flat = resume[n, S_INTEG], resume[n, S_TH0], resume[n, S_FLAT] > 0.0
            vcmd, tau_next, enc_prev = resume[n, S_VCMD], resume[n, S_TAU], resume[n, S_ENC]
        else:
            s = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            integ, th0, flat, vcmd, tau_next, enc_prev = 0.0, 0.0, False, 0.0, 0.0, 0.0
        code = 0
        locked = False
        lock_angle = held = 0.0
        j0 = span[n, 0]
        last_frame = j0 - 1
        if foot:  # the gait at the first step
            i, f, inside = _gait_index(j0 * dt, gait_fs, n_gait)
            for c in range(N_G):
                gv1[c] = g[n, i, c] + f * (g[n, i + 1, c] - g[n, i, c]) if inside else 0.0
        plate_phase = j0 % plate_every  # j % plate_every, without a division per step
        rec_phase = j0 % rec_every
        for j in range(j0, min(span[n, 1], n_steps)):
            t = j * dt
            if j == fork[n]:
                for c in range(7):
                    snap[n, c] = s[c]
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
                if foot:  # the gait at the sub-step's start (the previous end) and end
                    i, f, inside = _gait_index(t + q * h + h, gait_fs, n_gait)
                    for c in range(N_G):
                        gv[c] = gv1[c]
                        gv1[c] = g[n, i, c] + f * (g[n, i + 1, c] - g[n, i, c]) if inside else 0.0
                        gvm[c] = 0.5 * (gv[c] + gv1[c])
                    if gv[G_CONTACT] == 0.0:  # the foot moves with the plate
                        s = (s[0], s[1], s[2], s[3], s[4], s[3], s[4])
                    elif not flat:
                        th0 = s[3]
                    flat = gv[G_CONTACT] > 0.0
                g0, gm, g1 = _row8(gv), _row8(gvm), _row8(gv1)
                fric = pc[T_COUL] * math.tanh(s[2] * inv_weps)
                cth, sth = _cos_sin(s[3])
                per_step = (th0, fric, cth, sth, inv_jm)
                k1, ta, lx, lz = _rhs(s, tau_cmd, g0, pc, fpn, shell, per_step)
                if q == 0 and plate_phase == 0:
                    if flags[FL_PLATE] == 1:
                        load = _plate_wrench(
                            s[4], k1[4], ta, lx, lz, g0, pc, fpn, flags[FL_INERTIA], cth, sth
                        )
                        for c in range(N_WRENCH):
                            y = load[c]
                            for k in range(plate_sections[c]):
                                out = plate_sos[c, k, 0] * y + z[c, 2 * k]
                                z[c, 2 * k] = (
                                    plate_sos[c, k, 1] * y - plate_sos[c, k, 4] * out
                                    + z[c, 2 * k + 1]
                                )  # fmt: skip
                                z[c, 2 * k + 1] = plate_sos[c, k, 2] * y - plate_sos[c, k, 5] * out
                                y = out
                            w[c] = y
                    if rec_phase == 0:
                        r = j // rec_every
                        mech[n, O_THM, r] = s[1]
                        mech[n, O_THH, r] = s[3]
                        if flat:
                            mech[n, O_PHI, r] = s[5] - th0 + fpn[F_MIS] * (s[3] - th0)
                        else:
                            mech[n, O_PHI, r] = 0.0
                        mech[n, O_TA, r] = ta
                        mech[n, O_TAU, r] = s[0]
                        if flags[FL_PLATE] == 1:
                            for c in range(N_WRENCH):
                                wrench[n, c, r] = w[c]
                k2 = _rhs(_axpy(s, hh, k1), tau_cmd, gm, pc, fpn, shell, per_step)[0]
                k3 = _rhs(_axpy(s, hh, k2), tau_cmd, gm, pc, fpn, shell, per_step)[0]
                k4 = _rhs(_axpy(s, h, k3), tau_cmd, g1, pc, fpn, shell, per_step)[0]
                s = _rk4_update(s, h6, k1, k2, k3, k4)
                if locked:  # the holding brake holds the motor shaft
                    s = (s[0], lock_angle, 0.0, s[3], s[4], s[5], s[6])
            plate_phase = 0 if plate_phase == plate_every - 1 else plate_phase + 1
            rec_phase = 0 if rec_phase == rec_every - 1 else rec_phase + 1
