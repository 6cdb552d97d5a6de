"""What a closed-loop run of the capstan twin needs: the platform, the controller, the limits,
and the sensor faults one may inject.

:class:`CapstanSetup` gathers the platform, the user, the gains, the control rate, the
compensation options and the controller's friction model; :class:`FaultInjection` describes a
sensor fault to inject into a run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from anklelab.control.pid import PIDGains, design_critically_damped
from anklelab.control.safety import SafetyLimits
from anklelab.errors import ParameterError
from anklelab.experiments.capstan._loop import FAULTS
from anklelab.platforms import load_platform
from anklelab.platforms.capstan import CapstanParameters, FrictionParameters
from anklelab.sim.capstan import CapstanTwin

__all__ = ["CapstanSetup", "FaultInjection", "Mode"]

Mode = Literal["position", "admittance", "impedance", "open-loop"]


@dataclass(frozen=True)
class FaultInjection:
    """A sensor fault injected from ``time_s`` on.

    Attributes
    ----------
    kind : str
        ``encoder-nan``, ``encoder-stale`` (reading and sample counter freeze),
        ``encoder-jump`` (``value`` rad added), ``encoder-reversed`` (counts run backwards) or
        ``current-nan``.
    time_s : float
        Onset, s.
    value : float
        Size of an ``encoder-jump``, rad.
    """

    kind: str
    time_s: float
    value: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in FAULTS or self.kind == "none":
            raise ParameterError(
                f"fault kind must be one of {sorted(set(FAULTS) - {'none'})}; got {self.kind!r}"
            )


@dataclass(frozen=True)
class CapstanSetup:
    """Everything a closed-loop run of the capstan twin needs.

    Attributes
    ----------
    params : CapstanParameters
        The twin's (true) parameters.
    gains : PIDGains or None
        Controller gains; None designs critically damped ones from ``params``.
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
    """

    params: CapstanParameters = field(default_factory=lambda: load_platform("capstan"))
    gains: PIDGains | None = None
    fs: float = 1000.0
    with_user: bool = True
    gravity_compensation: bool = True
    friction_compensation: float = 0.0
    model_friction: FrictionParameters | None = None
    observer_cutoff_hz: float = 20.0
    coupled: bool = True
    safety: SafetyLimits | None = None
    max_step_s: float = 2e-4

    def resolved_gains(self) -> PIDGains:
        """The gains in use."""
        return self.gains if self.gains is not None else design_critically_damped(self.params)

    def twin(self) -> CapstanTwin:
        """The plant."""
        user = self.params.user if self.with_user else None
        return CapstanTwin(self.params, user, coupled=self.coupled, max_step_s=self.max_step_s)

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
