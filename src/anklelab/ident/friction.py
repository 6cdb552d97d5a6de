"""Friction and inertia of the capstan pinion shaft from spin-down and torque-chirp data.

Paper 001, section 3.3, in three stages (everything at the pinion, cw positive):

1. **Spin-down.** After the torque is cut, ``J w' + b w = -Tc sign(w)``, whose solution (the
   paper's eq. 13 is misprinted) is ``w(t) = (w0 + s c/a) exp(-a t) - s c/a`` with
   ``a = b/J``, ``c = Tc/J`` and ``s = sign(w)``. It is fitted, per direction, jointly to every
   coast above ``min_speed_rad_s`` (where the Stribeck term has died out): ``a`` and ``c`` shared,
   the start speed free per run. The integrated form ``w = w0 - a (theta - theta0) - s c t``,
   linear in the unknowns, gives the starting point; nonlinear least squares on the closed-form
   solution gives the estimate. Only the ratios follow.
2. **Chirp.** Over short windows in which the shaft turns one way without sticking, the
   integrated equation of motion ``J [dw + a int w + c int s] = int tau - int s (Ts - Tc) g(w)``
   (``g`` the Stribeck decay) is linear in ``J``: least squares fixes ``J``, hence ``b`` and ``Tc``.
3. **Low speed and breakaway.** With ``J``, ``b``, ``Tc`` fixed, the static friction ``Ts`` and
   the Stribeck velocity ``ws`` come from the slow parts of the spin-down runs: each coast's end
   (through the Stribeck region to the stop) and each start from rest (where the speed
   controller's torque breaks the shaft away). A least-squares fit to the friction map
   ``F = tau - J w'`` (``w``, ``w'`` from local quadratic fits to the encoder angle) starts
   them; output error refines them: the full model, sticking included, is simulated through
   every segment and its speed compared with the measured one (each coast end's start speed
   is free).

Stages 2 and 3 depend on each other through the Stribeck term and are iterated. Velocities are
integrated back to angle (exactly the encoder's, when the velocity column is its difference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numba import njit
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from anklelab._params import parameters_from_mapping, read_parameter_document
from anklelab.data.capstan_ident import IdentData, IdentRun
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.ident._base import Estimator, interval
from anklelab.metrics import vaf
from anklelab.platforms.capstan import FrictionParameters
from anklelab.signals import derivative
from anklelab.sim.capstan.friction_law import friction_array, friction_step, friction_torque

__all__ = ["FrictionIdentifier", "SpindownFit", "read_friction_json"]

DIRECTIONS = ("cw", "ccw")


@dataclass(frozen=True)
class SpindownFit:
    """One run's fitted coast, for plots and checks.

    Attributes
    ----------
    name : str
        Run file name.
    direction : {"cw", "ccw"}
        Turning direction.
    time_s, velocity_rad_s, fitted_rad_s : ndarray
        The fitted samples (time from the cut), measured and fitted speed.
    """

    name: str
    direction: str
    time_s: NDArray[np.float64]
    velocity_rad_s: NDArray[np.float64]
    fitted_rad_s: NDArray[np.float64]


@dataclass(frozen=True)
class _Coast:
    run: IdentRun
    sign: float
    cut: int  # first sample of the coast
    start: int  # first fitted sample
    stop: int  # one past the last fitted sample


def _coast(
    run: IdentRun, fs: float, min_speed: float, skip: int, zero_torque: float
) -> _Coast | None:
    """The run's coast above ``min_speed`` (None if it has fewer than 5 such samples)."""
    nonzero = np.flatnonzero(np.abs(run.torque_nm) > zero_torque)
    cut = int(nonzero[-1]) + 1 if nonzero.size else 0
    if cut >= run.time_s.size - 3:
        raise SessionFormatError(
            f"{run.name}: column 'torque_nm' is never cut to 0 (|torque| <= {zero_torque:g} N·m) "
            "before the end; expected a coast with zero torque after the speed-controlled phase"
        )
    start = cut + skip
    v = run.velocity_rad_s
    sign = float(np.sign(np.mean(v[cut : cut + max(skip, 3)])))
    slow = np.flatnonzero(sign * v[start:] < min_speed)
    stop = start + (int(slow[0]) if slow.size else v.size - start)
    if stop - start < 5 or sign == 0.0:
        return None
    return _Coast(run, sign, cut, start, stop)


def _check_signs(data: IdentData) -> None:
    """While the torque drives a spin-down run, the shaft must turn the way it pushes."""
    for run in data.spindown:
        driven = (np.abs(run.torque_nm) > 0) & (np.abs(run.velocity_rad_s) > 0)
        if driven.sum() < 10:
            continue
        agree = np.mean(np.sign(run.torque_nm[driven]) == np.sign(run.velocity_rad_s[driven]))
        if agree < 0.5:
            raise SessionFormatError(
                f"spindown/{run.name}: the velocity runs against the driving torque in "
                f"{100 * (1 - agree):.0f} % of the driven samples; expected positive torque to "
                "turn the shaft clockwise (positive velocity): is a sign flipped?"
            )


def _coast_model(
    t: NDArray[np.float64], w0: NDArray[np.float64] | float, a: float, c: float, sign: float
) -> NDArray[np.float64]:
    """Exact coast ``w(t)`` of ``w' = -a w - sign c`` from ``w0`` at ``t = 0``."""
    return (w0 + sign * c / a) * np.exp(-a * t) - sign * c / a


@njit(cache=True)
def _simulate_angle(torque, fs, law, inertia, w0, n_sub):  # type: ignore[no-untyped-def]
    """Angle (rad, from 0) at each sample of the shaft driven by ``torque`` (zero-order hold)."""
    n = len(torque)
    h = 1.0 / (fs * n_sub)
    angle = np.empty(n)
    w, q = w0, 0.0
    angle[0] = 0.0
    for k in range(n - 1):
        for _ in range(n_sub):
            w, _f = friction_step(w, torque[k], inertia, h, law)
            q += h * w
        angle[k + 1] = q
    return angle


class FrictionIdentifier(Estimator):
    """Identify ``J``, ``b`` and ``Tc`` (per direction), ``ws`` and ``Ts`` (scikit-learn style).

    Parameters
    ----------
    min_speed_rad_s : float
        Spin-downs are fitted with the closed-form solution only above this speed (the Stribeck
        term must be negligible there); raised to ``3.5 ws`` if the fitted ``ws`` asks for it.
    skip_s : float
        Samples right after the torque cut left out (the current decays), s.
    window_s : float
        Window of the chirp regression for ``J``, s.
    chirp_min_speed_rad_s : float
        Chirp windows must stay above this speed (no sticking), rad/s.
    derivative_window_s : float
        Local quadratic (Savitzky-Golay) window for speed and acceleration at low speed, s.
    low_speed_floor_rad_s : float
        Friction-map samples need the speed above this throughout their window (no stop).
    tail_s : float
        Longest stretch of each coast's end (below ``min_speed_rad_s``) used at low speed, s.
    zero_torque_nm : float
        A spin-down's coast is its final stretch with ``|torque| <=`` this (0: exact zeros, as
        DESIGN.md section 6 prescribes; raise it for measured, noisy torques).
    stribeck_exponent : float
        Exponent ``sigma`` of the Stribeck decay ``exp(-(|w|/ws)^sigma)`` (assumed, not fitted).
    substeps : int
        Integration sub-steps per sample in the output-error simulation.
    iterations : int
        Rounds of the chirp (``J``) and low-speed (``Ts``, ``ws``) stages.

    Attributes
    ----------
    inertia_kgm2_ : float
        Pinion-shaft inertia ``J``.
    viscous_nms_per_rad_, coulomb_nm_ : dict
        ``{"cw": ..., "ccw": ...}``.
    stribeck_velocity_rad_s_, static_friction_nm_ : float
        Stribeck velocity and static (breakaway) friction.
    decay_per_s_, coulomb_over_inertia_ : dict
        The spin-down ratios ``b/J`` and ``Tc/J`` per direction.
    spindown_vaf_percent_, chirp_vaf_percent_ : float
        VAF of the closed-form spin-down fit and of the full model simulated through the chirps
        (each pooled over its runs).
    spindown_fits_ : list of SpindownFit
        Per-run fitted coasts.
    chirp_prediction_ : ndarray
        The model's velocity through the first chirp, rad/s.
    fs_ : float
        The identification data's sample rate, Hz (:meth:`predict` and :meth:`score` take
        torques at this rate).

    Examples
    --------
    >>> from anklelab.experiments.capstan import simulate_ident
    >>> model = FrictionIdentifier().fit(simulate_ident(seed=1))
    >>> round(model.inertia_kgm2_ / 7.54e-4, 2), round(model.coulomb_nm_["ccw"] / 0.038, 2)
    (1.0, 1.0)
    """

    _parameter_constraints: ClassVar = {
        **{
            name: [interval(0, closed="neither")]
            for name in (
                "min_speed_rad_s",
                "window_s",
                "chirp_min_speed_rad_s",
                "derivative_window_s",
                "low_speed_floor_rad_s",
                "tail_s",
                "stribeck_exponent",
            )
        },
        "skip_s": [interval(0)],
        "zero_torque_nm": [interval(0)],
        "substeps": [interval(1, integer=True)],
        "iterations": [interval(1, integer=True)],
    }
    _fitted_attribute: ClassVar = "stribeck_velocity_rad_s_"

    def __init__(
        self,
        *,
        min_speed_rad_s: float = 10.0,
        skip_s: float = 0.01,
        window_s: float = 0.02,
        chirp_min_speed_rad_s: float = 1.0,
        derivative_window_s: float = 0.02,
        low_speed_floor_rad_s: float = 0.5,
        zero_torque_nm: float = 0.0,
        tail_s: float = 1.0,
        stribeck_exponent: float = 2.0,
        substeps: int = 4,
        iterations: int = 3,
    ) -> None:
        self.min_speed_rad_s = min_speed_rad_s
        self.skip_s = skip_s
        self.window_s = window_s
        self.chirp_min_speed_rad_s = chirp_min_speed_rad_s
        self.derivative_window_s = derivative_window_s
        self.low_speed_floor_rad_s = low_speed_floor_rad_s
        self.zero_torque_nm = zero_torque_nm
        self.tail_s = tail_s
        self.stribeck_exponent = stribeck_exponent
        self.substeps = substeps
        self.iterations = iterations

    # ------------------------------------------------------------------------- fitting
    def fit(self, data: IdentData) -> FrictionIdentifier:
        """Fit every parameter from an identification session (see the module docstring).

        Raises
        ------
        SessionFormatError
            The data cannot be a spin-down and chirp of one shaft: the velocity runs against
            the torque that drives it (a flipped sign), or the fit finds no positive inertia.
        """
        self._validate_params()
        _check_signs(data)
        fs = self.fs_ = data.sample_rate_hz
        min_speed = self.min_speed_rad_s
        for _ in range(2):  # once more if the Stribeck velocity reaches into the fitted coasts
            skip = round(self.skip_s * fs)
            found = [_coast(r, fs, min_speed, skip, self.zero_torque_nm) for r in data.spindown]
            coasts = [c for c in found if c is not None]
            self._fit_spindown(coasts, fs)
            ts = ws = None
            for _ in range(self.iterations):
                self._fit_inertia(data.chirp, fs, ts, ws)
                ts, ws = self._fit_low_speed(coasts, data.spindown, fs)
            assert ws is not None  # iterations >= 1 (validated above)
            if min_speed >= 3.5 * ws:
                break
            min_speed = 3.5 * ws
        predictions = [self.predict(run.torque_nm) for run in data.chirp]
        self.chirp_prediction_ = predictions[0]
        self.chirp_vaf_percent_ = float(  # pooled over every chirp
            vaf(np.concatenate([r.velocity_rad_s for r in data.chirp]), np.concatenate(predictions))
        )
        return self

    def _fit_spindown(self, coasts: list[_Coast], fs: float) -> None:
        self.decay_per_s_: dict[str, float] = {}
        self.coulomb_over_inertia_: dict[str, float] = {}
        self.spindown_fits_: list[SpindownFit] = []
        residuals, measured = [], []
        for direction, sign in (("cw", 1.0), ("ccw", -1.0)):
            mine = [c for c in coasts if c.sign == sign]
            if not mine:
                raise SessionFormatError(
                    f"spindown: no {direction} run coasts for 5 samples above the fitted speed "
                    "range; expected spin-downs from well above the Stribeck region in both "
                    "directions (or a lower min_speed_rad_s, --min-speed)"
                )
            pieces = []
            for coast in mine:
                v = coast.run.velocity_rad_s[coast.start : coast.stop]
                angle = np.cumsum(v) / fs
                pieces.append((coast, v, np.arange(v.size) / fs, angle - angle[0]))
            # linear start: w = w0_r - a (theta - theta0) - sign c t
            rows = sum(p[1].size for p in pieces)
            design = np.zeros((rows, 2 + len(pieces)))
            target = np.concatenate([p[1] for p in pieces])
            row = 0
            for r, (_, v, t, angle) in enumerate(pieces):
                design[row : row + v.size, 0] = -angle
                design[row : row + v.size, 1] = -sign * t
                design[row : row + v.size, 2 + r] = 1.0
                row += v.size
            start = np.linalg.lstsq(design, target, rcond=None)[0]

            def residual(x: NDArray[np.float64], pieces: list[Any] = pieces, sign: float = sign):
                a, c = x[0], x[1]
                return np.concatenate(
                    [
                        _coast_model(t, x[2 + r], a, c, sign) - v
                        for r, (_, v, t, _a) in enumerate(pieces)
                    ]
                )

            start[:2] = np.maximum(start[:2], 1e-6)
            sol = least_squares(
                residual, start, bounds=(np.r_[0.0, 0.0, [-np.inf] * len(pieces)], np.inf)
            )
            a, c = float(sol.x[0]), float(sol.x[1])
            self.decay_per_s_[direction] = a
            self.coulomb_over_inertia_[direction] = c
            for r, (coast, v, t, _) in enumerate(pieces):
                fitted = _coast_model(t, sol.x[2 + r], a, c, sign)
                self.spindown_fits_.append(SpindownFit(coast.run.name, direction, t, v, fitted))
                residuals.append(v - fitted)
                measured.append(v)
        self.spindown_vaf_percent_ = float(
            vaf(np.concatenate(measured), np.concatenate(measured) - np.concatenate(residuals))
        )

    def _stribeck_gain(self, w: NDArray[np.float64], ws: float | None) -> NDArray[np.float64]:
        if ws is None:
            return np.zeros_like(w)
        return np.exp(-((np.abs(w) / ws) ** self.stribeck_exponent))

    def _fit_inertia(
        self, chirps: tuple[IdentRun, ...], fs: float, ts: float | None, ws: float | None
    ) -> None:
        width = max(2, round(self.window_s * fs))
        lhs, rhs = [], []
        for run in chirps:
            v, tau = run.velocity_rad_s, run.torque_nm
            # windows [i0, i0 + width] starting at sample 1 (sample i0 - 1 must exist)
            first = np.arange(1, v.size - width, width)
            idx = first[:, None] + np.arange(width + 1)
            s = np.sign(v)
            valid = (np.abs(v[idx]) > self.chirp_min_speed_rad_s).all(1) & (
                s[idx] == s[idx[:, :1]]
            ).all(1)
            idx = idx[valid]
            if idx.size == 0:
                continue
            sw = s[idx[:, 0]]
            a = np.where(sw > 0, self.decay_per_s_["cw"], self.decay_per_s_["ccw"])
            c = np.where(
                sw > 0, self.coulomb_over_inertia_["cw"], self.coulomb_over_inertia_["ccw"]
            )
            g = self._stribeck_gain(v[idx[:, 1:]], ws)
            # velocity sample k is the mean over (t_k-1, t_k]: dv spans the window shifted back
            # by half a sample, and so does the integral of the zero-order-held torque
            dv = v[idx[:, -1]] - v[idx[:, 0]]
            moved = v[idx[:, 1:]].sum(1) / fs
            stick_free = (1.0 - g).sum(1) / fs
            lhs.append(dv + a * moved + sw * c * stick_free)
            torque = (
                tau[idx[:, :-1]].sum(1) + 0.5 * (tau[idx[:, 0] - 1] - tau[idx[:, -1] - 1])
            ) / fs
            rhs.append(torque - sw * (ts or 0.0) * g.sum(1) / fs)
        x = np.concatenate(lhs) if lhs else np.zeros(0)
        y = np.concatenate(rhs) if rhs else np.zeros(0)
        if x.size < 10:
            raise SessionFormatError(
                f"chirp: only {x.size} windows where the shaft turns one way above "
                f"{self.chirp_min_speed_rad_s:g} rad/s; expected a chirp that keeps it moving"
            )
        inertia = float(np.dot(y, x) / np.dot(x, x))
        if not (math.isfinite(inertia) and inertia > 0):
            raise SessionFormatError(
                f"chirp: the torque and the speed change disagree (fitted inertia {inertia:.3g} "
                "kg·m²); expected positive torque to speed the shaft up clockwise (positive "
                "velocity): is one sign flipped?"
            )
        self.inertia_kgm2_ = inertia
        self.viscous_nms_per_rad_ = {d: self.decay_per_s_[d] * inertia for d in DIRECTIONS}
        self.coulomb_nm_ = {d: self.coulomb_over_inertia_[d] * inertia for d in DIRECTIONS}

    def _fit_low_speed(
        self, coasts: list[_Coast], runs: tuple[IdentRun, ...], fs: float
    ) -> tuple[float, float]:
        """Fit ``Ts`` and ``ws``: a start from the friction map, then output error on speed."""
        ts, ws = self._fit_friction_map(runs, fs)
        segments = self._low_speed_segments(coasts, fs)
        free = [k for k, (_, _, w0) in enumerate(segments) if w0 is not None]

        def simulate(x: NDArray[np.float64]) -> NDArray[np.float64]:
            law = self._law(x[0], x[1])
            out = []
            for k, (tau, v, w0) in enumerate(segments):
                start = x[2 + free.index(k)] if w0 is not None else 0.0
                angle = _simulate_angle(tau, fs, law, self.inertia_kgm2_, start, self.substeps)
                out.append(np.diff(angle) * fs - v[1:])
            return np.concatenate(out)

        top = max(self.coulomb_nm_.values())
        x0 = np.r_[ts, ws, [segments[k][2] for k in free]]
        lower = np.r_[0.0, 1e-3, [-np.inf] * len(free)]
        upper = np.r_[10.0 * top + 1.0, 10.0 * self.min_speed_rad_s, [np.inf] * len(free)]
        sol = least_squares(
            simulate,
            np.clip(x0, lower + 1e-9, upper - 1e-9),
            bounds=(lower, upper),
            x_scale=np.r_[top, 1.0, [1.0] * len(free)],
            diff_step=1e-4,
        )
        self.static_friction_nm_ = float(sol.x[0])
        self.stribeck_velocity_rad_s_ = float(sol.x[1])
        return self.static_friction_nm_, self.stribeck_velocity_rad_s_

    def _low_speed_segments(
        self, coasts: list[_Coast], fs: float
    ) -> list[tuple[NDArray[np.float64], NDArray[np.float64], float | None]]:
        """(torque, speed, start speed or None from rest) of each coast's end and each start
        from rest, up to ``min_speed_rad_s``."""
        segments: list[tuple[NDArray[np.float64], NDArray[np.float64], float | None]] = []
        limit = round(self.tail_s * fs)
        for c in coasts:
            v, tau = c.run.velocity_rad_s, c.run.torque_nm
            fit = next(f for f in self.spindown_fits_ if f.name == c.run.name).fitted_rad_s
            begin = c.stop - 1
            tail_tau = np.where(np.arange(begin, v.size) < c.cut, tau[begin:], 0.0)[:limit]
            segments.append(
                (tail_tau, v[begin : begin + limit], float(1.5 * fit[-1] - 0.5 * fit[-2]))
            )
            rest = np.flatnonzero(np.abs(v[: c.cut]) > 0.0)
            fast = np.flatnonzero(np.abs(v[: c.cut]) > self.min_speed_rad_s)
            if rest.size and fast.size and rest[0] > 0 and np.all(v[: rest[0]] == 0.0):
                begin = max(0, int(rest[0]) - round(0.1 * fs))
                segments.append((tau[begin : fast[0]], v[begin : fast[0]], None))
        return segments

    def _parameters(self, ts: float, ws: float) -> FrictionParameters:
        """The model with the fitted ``J``, ``b``, ``Tc`` and these ``Ts``, ``ws``."""
        return FrictionParameters(
            inertia_kgm2=self.inertia_kgm2_,
            viscous_cw_nms_per_rad=self.viscous_nms_per_rad_["cw"],
            viscous_ccw_nms_per_rad=self.viscous_nms_per_rad_["ccw"],
            coulomb_cw_nm=self.coulomb_nm_["cw"],
            coulomb_ccw_nm=self.coulomb_nm_["ccw"],
            stribeck_velocity_rad_s=ws,
            static_friction_nm=ts,
            stribeck_exponent=self.stribeck_exponent,
        )

    def _law(self, ts: float, ws: float) -> NDArray[np.float64]:
        return friction_array(self._parameters(ts, ws))

    def _fit_friction_map(self, runs: tuple[IdentRun, ...], fs: float) -> tuple[float, float]:
        """Starting ``Ts``, ``ws``: least squares on the friction map ``F = tau - J w'``."""
        speeds, frictions = [], []
        width = 2 * round(self.derivative_window_s * fs / 2) + 1
        for run in runs:
            angle = np.cumsum(run.velocity_rad_s) / fs
            if angle.size < 2 * width:
                continue
            w = derivative(angle, fs, width, deriv=1)
            accel = derivative(angle, fs, width, deriv=2)
            # torque k acts over [t_k, t_k+1) while angle k is at t_k: average it the same way
            torque = derivative(
                np.r_[run.torque_nm[0], run.torque_nm[:-1]], fs, width, deriv=0, polyorder=0
            )
            half = width // 2
            slowest = sliding_window_view(np.abs(w), width).min(1)
            same = sliding_window_view(np.sign(w), width)
            keep = np.zeros(w.size, dtype=bool)
            keep[half:-half] = (slowest > self.low_speed_floor_rad_s) & (same == same[:, :1]).all(1)
            keep &= np.abs(w) < self.min_speed_rad_s
            speeds.append(w[keep])
            frictions.append(torque[keep] - self.inertia_kgm2_ * accel[keep])
        w, f = np.concatenate(speeds), np.concatenate(frictions)
        if w.size < 20:
            raise SessionFormatError(
                f"spindown: only {w.size} samples between {self.low_speed_floor_rad_s:g} and "
                f"{self.min_speed_rad_s:g} rad/s; expected coasts that run down to a stop"
            )
        s = np.sign(w)
        tc = np.where(s > 0, self.coulomb_nm_["cw"], self.coulomb_nm_["ccw"])
        b = np.where(s > 0, self.viscous_nms_per_rad_["cw"], self.viscous_nms_per_rad_["ccw"])
        excess = s * (f - b * w) - tc  # the Stribeck part, (Ts - Tc) g(w)

        def residual(x: NDArray[np.float64]) -> NDArray[np.float64]:
            return (x[0] - tc) * self._stribeck_gain(w, x[1]) - excess

        top = max(self.coulomb_nm_.values())
        sol = least_squares(
            residual,
            np.array([1.2 * top, self.min_speed_rad_s / 4.0]),
            bounds=([0.0, 1e-3], [10.0 * top + 1.0, 10.0 * self.min_speed_rad_s]),
            x_scale=np.array([top, 1.0]),
        )
        self.friction_map_ = (w, f)
        return float(sol.x[0]), float(sol.x[1])

    # ---------------------------------------------------------------------- using the model
    def predict(self, torque_nm: ArrayLike, *, velocity0: float = 0.0) -> NDArray[np.float64]:
        """Velocity (rad/s) of the identified shaft under a torque record sampled at ``fs_``,
        as an encoder would report it (mean over each sample interval), from ``velocity0``."""
        self._check_fitted()
        torque = np.ascontiguousarray(torque_nm, dtype=float)
        law = friction_array(self.to_parameters())
        angle = _simulate_angle(torque, self.fs_, law, self.inertia_kgm2_, velocity0, self.substeps)
        return np.r_[velocity0, np.diff(angle) * self.fs_]

    def friction_torque(self, speed_rad_s: ArrayLike) -> NDArray[np.float64]:
        """The identified kinetic friction (N·m) at the given pinion speeds."""
        self._check_fitted()
        return friction_torque(speed_rad_s, self.to_parameters())

    def score(self, torque_nm: ArrayLike, velocity_rad_s: ArrayLike) -> float:
        """VAF (%) of :meth:`predict` against a measured velocity (both at ``fs_``)."""
        return float(vaf(velocity_rad_s, self.predict(torque_nm)))

    def to_dict(self) -> dict[str, Any]:
        """The ``friction.json`` content (DESIGN.md section 6 keys plus the fit VAFs)."""
        self._check_fitted()
        return {
            "inertia_kgm2": self.inertia_kgm2_,
            "viscous_nms_per_rad": dict(self.viscous_nms_per_rad_),
            "coulomb_nm": dict(self.coulomb_nm_),
            "stribeck_velocity_rad_s": self.stribeck_velocity_rad_s_,
            "static_friction_nm": self.static_friction_nm_,
            "fit": {
                "spindown_vaf_percent": self.spindown_vaf_percent_,
                "chirp_vaf_percent": self.chirp_vaf_percent_,
            },
        }

    def to_parameters(self) -> FrictionParameters:
        """The identified model as parameters the controller and observer accept."""
        self._check_fitted()
        return self._parameters(self.static_friction_nm_, self.stribeck_velocity_rad_s_)


def read_friction_json(path: str | Path, *, stribeck_exponent: float = 2.0) -> FrictionParameters:
    """Load ``friction.json`` (DESIGN.md section 6) as validated friction parameters.

    Raises
    ------
    ParameterError
        Naming the file and the missing or invalid key.
    """
    data = read_parameter_document(path, "json", what="friction model (friction.json)")

    def get(*keys: str) -> Any:
        node = data
        for key in keys:
            if not isinstance(node, dict) or key not in node:
                raise ParameterError(f"{path}: {'.'.join(keys)}: required key is missing")
            node = node[key]
        return float(node) if isinstance(node, int) and not isinstance(node, bool) else node

    mapping = {
        "inertia_kgm2": get("inertia_kgm2"),
        "viscous_cw_nms_per_rad": get("viscous_nms_per_rad", "cw"),
        "viscous_ccw_nms_per_rad": get("viscous_nms_per_rad", "ccw"),
        "coulomb_cw_nm": get("coulomb_nm", "cw"),
        "coulomb_ccw_nm": get("coulomb_nm", "ccw"),
        "stribeck_velocity_rad_s": get("stribeck_velocity_rad_s"),
        "static_friction_nm": get("static_friction_nm"),
        "stribeck_exponent": float(stribeck_exponent),
    }
    return parameters_from_mapping(FrictionParameters, mapping, origin=str(path))
