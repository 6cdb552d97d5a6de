"""Platform parameter sets: TOML files loaded into typed, validated, frozen objects.

Importing this package costs nothing: every name but :data:`PLATFORM_NAMES` loads its module
(pydantic, the parameter models) on first use, so ``anklelab --help`` stays fast.

>>> from anklelab.platforms import load_platform
>>> load_platform("perturberator").transmission.ratio
70.0
"""

from anklelab._lazy import lazy_exports

PLATFORM_NAMES = ("perturberator", "capstan")
"""The platforms that have a shipped parameter file, as the CLI offers them."""

_EXPORTS = {
    "PLATFORMS": "registry",
    "load_platform": "registry",
    "platform_file": "registry",
    "SOURCE_KINDS": "anklelab._params",
    "Parameters": "anklelab._params",
    "load_parameters": "anklelab._params",
    "CapstanParameters": "capstan",
    "PerturberatorParameters": "perturberator",
}
__all__ = ["PLATFORM_NAMES", *sorted(_EXPORTS)]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
