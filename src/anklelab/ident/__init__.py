"""Estimators: impulse-response filters, 2nd-order impedance, bench stiffness, friction.

Every name loads its module on first use: the capstan friction estimator builds on the capstan
twin's compiled friction model, and analysing walking data must not import numba.
"""

from anklelab._lazy import lazy_exports

_EXPORTS = {
    "BenchStiffness": "bench",
    "bench_stiffness": "bench",
    "interpolate_stiffness": "bench",
    "FrictionIdentifier": "friction",
    "SpindownFit": "friction",
    "read_friction_json": "friction",
    "ImpedanceFit": "impedance",
    "ImpedanceModel": "impedance",
    "InertiaTerms": "impedance",
    "StiffnessModel": "impedance",
    "fit_impedance": "impedance",
    "impedance_torque": "impedance",
    "inertia_terms": "impedance",
    "FILTERS_FORMAT": "irf",
    "INPUTS": "irf",
    "ImpulseResponse": "irf",
    "PlatformFilters": "irf",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
