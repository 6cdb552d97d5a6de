"""End-to-end analyses: walking impedance (paper 000)."""

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
    "TimingPoint",
    "WalkingResults",
    "WalkingSettings",
    "analyze_walking",
    "fit_platform_filters",
    "load_walking_settings",
]
