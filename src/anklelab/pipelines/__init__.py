"""End-to-end analyses: walking impedance (paper 000).

Analysing recorded data never imports the digital twins and their compiled kernels; the
demonstration on both twins is an application of its own, :mod:`anklelab.demo`.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    name: "walking"
    for name in (
        "STANCE_CHANNELS",
        "STEPS",
        "TimingPoint",
        "WalkingResults",
        "WalkingSettings",
        "analyze_walking",
        "fit_platform_filters",
        "load_walking_settings",
    )
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
