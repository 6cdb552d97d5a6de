"""Platform parameter sets: TOML files loaded into typed, validated, frozen objects.

>>> from anklelab.platforms import load_platform
>>> load_platform("perturberator").transmission.ratio
70.0
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from anklelab._params import SOURCE_KINDS, Parameters, load_parameters
from anklelab.errors import ParameterError
from anklelab.platforms.capstan import CapstanParameters
from anklelab.platforms.perturberator import PerturberatorParameters

__all__ = [
    "PLATFORMS",
    "SOURCE_KINDS",
    "CapstanParameters",
    "Parameters",
    "PerturberatorParameters",
    "load_parameters",
    "load_platform",
    "platform_file",
]

PLATFORMS: dict[str, type[Parameters]] = {
    "perturberator": PerturberatorParameters,
    "capstan": CapstanParameters,
}


def platform_file(name: str) -> Path:
    """Path of the parameter file shipped for platform ``name``."""
    if name not in PLATFORMS:
        raise ParameterError(
            f"platform: unknown platform {name!r}; expected one of {sorted(PLATFORMS)}"
        )
    return Path(str(resources.files("anklelab.platforms") / f"{name}.toml"))


def load_platform(name: str, path: str | Path | None = None) -> Any:
    """Load a platform's parameters: the shipped set, or a user's TOML file for that platform.

    Parameters
    ----------
    name : {"perturberator", "capstan"}
        Which platform (selects the parameter model).
    path : str or Path, optional
        A user's parameter file; defaults to the one shipped with anklelab.

    Returns
    -------
    PerturberatorParameters or CapstanParameters
    """
    file = platform_file(name) if path is None else Path(path)
    return load_parameters(PLATFORMS[name], file)
