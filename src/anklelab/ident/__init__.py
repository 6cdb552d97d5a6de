"""Estimators: impulse-response filters, 2nd-order impedance, bench stiffness.

The capstan friction estimator's names load on first use: it builds on the capstan twin's
compiled friction model, and analysing walking data must not import numba.
"""

from typing import Any

from anklelab.ident.bench import BenchStiffness, bench_stiffness, interpolate_stiffness
from anklelab.ident.impedance import (
    ImpedanceFit,
    ImpedanceModel,
    StiffnessModel,
    fit_impedance,
    impedance_torque,
)
from anklelab.ident.irf import FILTERS_FORMAT, INPUTS, ImpulseResponse, PlatformFilters

__all__ = [
    "FILTERS_FORMAT",
    "INPUTS",
    "BenchStiffness",
    "FrictionIdentifier",
    "ImpedanceFit",
    "ImpedanceModel",
    "ImpulseResponse",
    "PlatformFilters",
    "SpindownFit",
    "StiffnessModel",
    "bench_stiffness",
    "fit_impedance",
    "impedance_torque",
    "interpolate_stiffness",
    "read_friction_json",
]

_FRICTION_NAMES = ("FrictionIdentifier", "SpindownFit", "read_friction_json")


def __getattr__(name: str) -> Any:
    if name in _FRICTION_NAMES:
        from anklelab.ident import friction

        return getattr(friction, name)
    raise AttributeError(f"module 'anklelab.ident' has no attribute {name!r}")
