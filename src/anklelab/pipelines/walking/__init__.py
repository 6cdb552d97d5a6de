"""Walking impedance: from a recorded session to ankle stiffness with uncertainty (paper 000).

The steps follow paper 000 (sections 2.2, 2.3, 2.4.2, 3) and DESIGN.md section 5:

1. **Platform filters** from the calibration trials (nobody on the plate): fitted on one trial,
   scored on the others (VAF per trial, pooled over channels, and per channel).
2. **Walking trials**: channels and motor angle zeroed over an unloaded baseline at the start of
   each file; heel contact detected from the vertical force; the platform's own force transients
   predicted from the motor angle and subtracted from the low-passed channels; GRF, COP and
   ankle torque computed with the COP and the ankle angle zeroed at heel contact; derivatives
   of the angle by a local quadratic fit; the true perturbation onset detected from the motor
   angle. Trials that fail a check are dropped with the reason logged.
3. **Responses** (:mod:`.responses`): for each timing point and direction, every perturbed
   trial is cut at its own detected onset and the unperturbed trials, cut at the same time after
   heel contact, are subtracted; angle and torque offsets (read before the low-pass has spread
   the perturbation backwards in time) are removed; each trial's own gait variation, predicted
   from its signals before the onset (:mod:`.adjustment`), is removed; trials far from their
   group's median (a glitch) are dropped with a reason.
4. **Model** (:mod:`.impedance`): ``T = I θ'' + b θ' + k(t) θ`` fitted to the all-trial average
   with a constant and a linearly changing stiffness, the model chosen per point
   (``stiffness_model = "auto"``), around one inertia fitted jointly over the session
   (``inertia_model = "session"``); 95 % intervals from resampling the trials, widened by what
   the data cannot pin down; paper 000's subset sd beside them; ``cop_m`` is the θ²-weighted
   nominal lever arm; plausibility checks (:mod:`.checks`).
5. **Bench**: stiffness per actuator distance and the walking-vs-bench error at ``cop_m``.

Everything is read from the session (sample rate, plate geometry and mounting, subject geometry,
trial manifest); no number of the digital twin is assumed.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "STANCE_CHANNELS": "stance",
    "STEPS": "analysis",
    "TimingPoint": "results",
    "WalkingResults": "results",
    "WalkingSettings": "settings",
    "analyze_walking": "analysis",
    "fit_platform_filters": "calibration",
    "load_walking_settings": "settings",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
