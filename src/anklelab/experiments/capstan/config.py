"""What a closed-loop run of the capstan twin needs: the platform, the controller, the limits,
and the sensor faults one may inject.

:class:`CapstanSetup` gathers the platform, the user, the gains, the control rate, the
compensation options and the controller's friction model; :class:`FaultInjection` describes a
sensor fault to inject into a run.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Literal

from anklelab.control.pid import PIDGains, design_critically_damped
from anklelab.control.safety import SafetyLimits
from anklelab.control.tracking import ClosedLoopModel, closed_loop_model
from anklelab.errors import ParameterError
from anklelab.experiments.capstan._loop import FAULTS
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters, UserParameters
from anklelab.platforms.perturberator import PerturberatorParameters
from anklelab.sim.capstan import CapstanTwin
from anklelab.sim.capstan.person import ACTIVITIES, Activity, person_foot

__all__ = ["CapstanSetup", "Channel", "FaultInjection", "Mode"]

PERSON_FALLS = "person-falls"


@functools.cache
def _shipped_human() -> PerturberatorParameters:
    """The shipped Perturberator set (frozen, so read once)."""
    return load_platform("perturberator")  # type: ignore[no-any-return]


Mode = Literal["position", "admittance", "impedance", "teleoperation", "open-loop"]


@dataclass(frozen=True)
class Channel:
    """The network between the platform and the remote robot in teleoperation.

    Attributes
    ----------
    scheme : {"wave", "direct"}
        ``wave``: wave variables with energy-bounded receivers (passive for any delay);
        ``direct``: the platform's angle forward, the remote ground's torque back (not passive).
    delay_s : float
        One-way delay, s.
    jitter_s : float
        Each packet is further delayed by a uniform random time in ``[0, jitter_s]``.
    """

    scheme: Literal["wave", "direct"] = "wave"
    delay_s: float = 0.0
    jitter_s: float = 0.0

    def __post_init__(self) -> None:
        if self.scheme not in ("wave", "direct"):
            raise ParameterError(f"scheme must be 'wave' or 'direct'; got {self.scheme!r}")
        if not (0 <= self.delay_s <= 2.0 and 0 <= self.jitter_s <= 2.0):
            raise ParameterError(
                f"delay and jitter must lie in [0, 2] s; got {self.delay_s}, {self.jitter_s}"
            )


@dataclass(frozen=True)
class FaultInjection:
    """A sensor fault injected from ``time_s`` on.

    Attributes
    ----------
    kind : str
        ``encoder-nan``, ``encoder-stale`` (reading and sample counter freeze),
        ``encoder-jump`` (``value`` rad added), ``encoder-reversed`` (counts run backwards),
        ``current-nan``, or ``person-falls`` (the standing or stepping person's load, impedance
        and reflex vanish: they fall off the platform).
    time_s : float
        Onset, s.
    value : float
        Size of an ``encoder-jump``, rad.
    """

    kind: str
    time_s: float
    value: float = 0.0

    def __post_init__(self) -> None:
        kinds = sorted([*set(FAULTS) - {"none"}, PERSON_FALLS])
        if self.kind not in kinds:
            raise ParameterError(f"fault kind must be one of {kinds}; got {self.kind!r}")
        if not (math.isfinite(self.time_s) and self.time_s >= 0 and math.isfinite(self.value)):
            raise ParameterError(
                f"fault time must be finite and >= 0 s and its value finite; got "
                f"{self.time_s}, {self.value}"
            )


@dataclass(frozen=True)
class CapstanSetup:
    """Everything a closed-loop run of the capstan twin needs.

    Attributes
    ----------
    params : CapstanParameters
        The twin's (true) parameters.
    gains : PIDGains or None
        Controller gains; None designs critically damped ones from ``params`` for
        ``settling_time_s``.
    settling_time_s : float
        Design settling time of the PD loop when ``gains`` is None, s.
    fs : float
        Control rate, Hz.
    with_user : bool
        Put the user's foot (``params.user``) on the platform.
    gravity_compensation : bool
        Feed-forward gravity (paper 001, eqs. 3-4).
    friction_compensation : float
        Fraction of the model friction compensated (0: off).
    model_friction : FrictionParameters or None
        The controller's and observer's friction/inertia model (e.g. identified); None: truth.
    observer_cutoff_hz : float
        Disturbance-observer Q-filter cut-off, Hz.
    coupled : bool
        False disconnects the cable: the motor, gearhead and pinion turn alone (the
        identification rig); angles are then the pinion's divided by the capstan ratio.
    safety : SafetyLimits or None
        Safety limits (angle, speed, current); None takes them from ``params.safety``.
    max_step_s : float
        Longest physics sub-step, s.
    feedforward : bool
        Add the inverse dynamics of the controller's model, ``J a_ref + F(w_ref)`` (inertia and
        friction of ``model_friction``), to the PID while tracking or rendering admittance.
    lag_compensation : bool
        Admittance rendering: compensate the observer's Q-filter lag
        (:mod:`anklelab.control.haptics`).
    passivity_control : bool
        Impedance rendering: the passivity controller dissipates the energy the rendering
        produces (:mod:`anklelab.control.passivity`).
    person : {"standing", "walking"} or None
        A person on the platform instead of the seated user (``with_user`` is then ignored):
        the twin's human ankle (``human``), body weight, sway, reflex
        (:mod:`anklelab.sim.capstan.person`).
    human : PerturberatorParameters or None
        Where the person's ankle, mass and gait come from; None: the shipped Perturberator set.
    guard : bool
        Run the person guard (torque and jerk limits, fall-safe stop) whenever someone is on
        the platform.
    fall_detection : bool
        With a standing or stepping person, the guard also detects a fall from the observer's
        torque estimate (the load vanishing). A rendered terrain changes the ankle's torque as
        fast as a fall does; scenes rely on the stop request (a fall detector of the VR system
        or harness) instead.
    """

    params: CapstanParameters = field(default_factory=lambda: load_platform("capstan"))
    gains: PIDGains | None = None
    settling_time_s: float = 0.2
    fs: float = 1000.0
    with_user: bool = True
    gravity_compensation: bool = True
    friction_compensation: float = 0.0
    model_friction: FrictionParameters | None = None
    observer_cutoff_hz: float = 20.0
    coupled: bool = True
    safety: SafetyLimits | None = None
    max_step_s: float = 2e-4
    feedforward: bool = False
    lag_compensation: bool = False
    passivity_control: bool = False
    person: Activity | None = None
    human: PerturberatorParameters | None = None
    guard: bool = True
    fall_detection: bool = True

    def __post_init__(self) -> None:
        if self.person is not None and self.person not in ACTIVITIES:
            raise ParameterError(f"person must be one of {list(ACTIVITIES)}; got {self.person!r}")
        if not self.fs > 0:
            raise ParameterError(f"fs must be > 0 Hz; got {self.fs}")

    @classmethod
    def for_rendering(cls, **changes: object) -> CapstanSetup:
        """The setup faithful admittance rendering needs: the position loop follows the virtual
        motion with the inverse-dynamics feed-forward, the estimated human torque taken off the
        loop, and the observer's lag compensated. ``changes`` override any field.
        """
        fields = {"feedforward": True, "lag_compensation": True}
        return cls(**(fields | changes))  # type: ignore[arg-type]

    def resolved_gains(self) -> PIDGains:
        """The gains in use."""
        if self.gains is not None:
            return self.gains
        return design_critically_damped(self.params, settling_time_s=self.settling_time_s)

    def resolved_human(self) -> PerturberatorParameters:
        """Where the person's ankle, mass and gait come from."""
        return _shipped_human() if self.human is None else self.human

    def loop_model(self) -> ClosedLoopModel:
        """The sampled closed loop's model, reference to angle (for the ZPETC)."""
        return closed_loop_model(
            self.params,
            self.resolved_gains(),
            self.fs,
            feedforward=self.feedforward,
            user=self.foot(),
            model_friction=self.model_friction,
        )

    def foot(self) -> UserParameters | None:
        """What rests on the platform: the person's foot, the seated user, or nothing."""
        if self.person is not None:
            return person_foot(self.resolved_human())
        return self.params.user if self.with_user else None

    def twin(self) -> CapstanTwin:
        """The plant."""
        return CapstanTwin(
            self.params, self.foot(), coupled=self.coupled, max_step_s=self.max_step_s
        )

    def safety_limits(self) -> SafetyLimits:
        """The safety limits in force: ``safety``, or those of ``params.safety``."""
        if self.safety is not None:
            return self.safety
        s = self.params.safety
        return SafetyLimits(
            position_min=-s.angle_limit_rad,
            position_max=s.angle_limit_rad,
            velocity_max=s.velocity_limit_rad_s,
            output_max=self.params.drive.current_limit_a,
            output_trip=s.current_trip_a,
            sensor_min=-s.sensor_range_rad,
            sensor_max=s.sensor_range_rad,
            max_stale_ticks=s.max_stale_ticks,
        )
