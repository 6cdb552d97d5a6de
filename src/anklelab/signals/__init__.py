"""Signal processing: zero-phase filters, derivatives, event detection, trials (epochs), VAF."""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "derivative": "derivatives",
    "kinematics": "derivatives",
    "Trials": "epochs",
    "advance": "epochs",
    "bootstrap_weights": "epochs",
    "epoch": "epochs",
    "stack_recordings": "epochs",
    "NOT_FOUND": "events",
    "Onsets": "events",
    "heel_contact": "events",
    "perturbation_onset": "events",
    "lowpass": "filters",
    "lowpass_min_samples": "filters",
    "vaf": "anklelab.metrics",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
