"""Estimators: impulse-response filters, 2nd-order impedance, bench stiffness."""

from anklelab.ident.bench import BenchStiffness, bench_stiffness, interpolate_stiffness
from anklelab.ident.friction import FrictionIdentifier, SpindownFit, read_friction_json
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
