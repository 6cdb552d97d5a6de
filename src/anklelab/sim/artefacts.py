"""Switches for the measurement artefacts of the Perturberator twin."""

from __future__ import annotations

from dataclasses import dataclass, fields

__all__ = ["Artefacts"]


@dataclass(frozen=True)
class Artefacts:
    """Which non-ideal effects the twin adds on top of the ideal physics.

    With everything off, the recorded plate signals are the foot's load sampled exactly, the
    motor angle and goniometer read the true angles, onsets follow heel contact by exactly the
    delay (to the motion plan's 0.4 ms update) and every trial has the nominal gait.

    Attributes
    ----------
    plate_inertia : bool
        The top plate's inertial and gravity-tilt loads on the sensors while the hinge moves.
    resonance : bool
        The plate's structural modes (~300 Hz vertical, ~500 Hz horizontal).
    anti_alias : bool
        The amplifier's low-pass in front of the DAQ (its phase lag).
    noise : bool
        Force-channel, goniometer and load-cell noise.
    drift : bool
        Charge-amplifier drift of each force channel.
    quantisation : bool
        16-bit DAQ, the servo analog output's resolution and the encoder's.
    onset_jitter : bool
        Trial-to-trial trigger offset and delay-counter error of the microcontroller.
    gait_variability : bool
        Trial-to-trial variability of stance time, loading, GRF, COP and foot placement.

    Examples
    --------
    >>> Artefacts.none().noise, Artefacts().noise
    (False, True)
    """

    plate_inertia: bool = True
    resonance: bool = True
    anti_alias: bool = True
    noise: bool = True
    drift: bool = True
    quantisation: bool = True
    onset_jitter: bool = True
    gait_variability: bool = True

    @classmethod
    def none(cls) -> Artefacts:
        """Every artefact off: ideal sensors on ideal physics."""
        return cls(**{f.name: False for f in fields(cls)})

    @classmethod
    def coerce(cls, value: bool | Artefacts) -> Artefacts:
        """``True`` -> all on, ``False`` -> all off, an :class:`Artefacts` unchanged."""
        if isinstance(value, Artefacts):
            return value
        return cls() if value else cls.none()
