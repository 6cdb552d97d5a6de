"""End-to-end analyses: walking impedance (paper 000); the demonstration on both twins.

The demonstration's names load on first use, so analysing recorded data never imports the
digital twins and their compiled kernels.
"""

from typing import Any

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

_DEMO_NAMES = (
    "CapstanDemo",
    "DemoSettings",
    "PerturberatorDemo",
    "run_capstan",
    "run_perturberator",
)


def __getattr__(name: str) -> Any:
    if name in _DEMO_NAMES:
        from anklelab.pipelines import demo

        return getattr(demo, name)
    raise AttributeError(f"module 'anklelab.pipelines' has no attribute {name!r}")
