"""End-to-end analyses: walking impedance (paper 000); the demonstration on both twins."""

from anklelab.pipelines.demo import (
    CapstanDemo,
    DemoSettings,
    PerturberatorDemo,
    run_capstan,
    run_perturberator,
)
from anklelab.pipelines.walking import (
    STANCE_CHANNELS,
    STEPS,
    TimingPoint,
    WalkingResults,
    WalkingSettings,
    analyze_walking,
    fit_platform_filters,
    load_walking_settings,
)

__all__ = [
    "STANCE_CHANNELS",
    "STEPS",
    "CapstanDemo",
    "DemoSettings",
    "PerturberatorDemo",
    "TimingPoint",
    "WalkingResults",
    "WalkingSettings",
    "analyze_walking",
    "fit_platform_filters",
    "load_walking_settings",
    "run_capstan",
    "run_perturberator",
]
