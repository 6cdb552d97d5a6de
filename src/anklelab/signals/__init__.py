"""Signal processing: zero-phase filters, derivatives, event detection, trials (epochs), VAF."""

from anklelab.metrics import vaf
from anklelab.signals.derivatives import derivative, kinematics
from anklelab.signals.epochs import Trials, bootstrap_weights, epoch, stack_recordings
from anklelab.signals.events import NOT_FOUND, Onsets, heel_contact, perturbation_onset
from anklelab.signals.filters import lowpass, lowpass_min_samples

__all__ = [
    "NOT_FOUND",
    "Onsets",
    "Trials",
    "bootstrap_weights",
    "derivative",
    "epoch",
    "heel_contact",
    "kinematics",
    "lowpass",
    "lowpass_min_samples",
    "perturbation_onset",
    "stack_recordings",
    "vaf",
]
