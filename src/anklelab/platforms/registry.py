"""The platforms' parameter models and their shipped files (see :mod:`anklelab.platforms`)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from anklelab._params import Parameters, load_parameters
from anklelab.errors import ParameterError
from anklelab.platforms import PLATFORM_NAMES
from anklelab.platforms.capstan import CapstanParameters
from anklelab.platforms.perturberator import PerturberatorParameters

__all__ = ["PLATFORMS", "load_platform", "platform_file"]

PLATFORMS: dict[str, type[Parameters]] = {
    "perturberator": PerturberatorParameters,
    "capstan": CapstanParameters,
}
assert tuple(PLATFORMS) == PLATFORM_NAMES, "anklelab.platforms.PLATFORM_NAMES is out of date"


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
