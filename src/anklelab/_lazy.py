"""Package names that import their module on first use (PEP 562).

A package lists its public names and the submodule defining each; importing the package then
costs nothing more, and ``package.name`` or ``from package import name`` imports only that
submodule. So a command loads only what it uses (reading a session never loads the twins'
compiled kernels, ``--help`` loads no SciPy). In a package's ``__init__.py``::

    _EXPORTS = {"FrictionIdentifier": "friction", "PlatformFilters": "irf"}
    __all__ = sorted(_EXPORTS)
    __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``, whose name ``n`` lives in the submodule
    ``exports[n]``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : mapping of str to str
        Public name to the submodule (relative to ``package``, or an absolute ``anklelab.``
        module name) that defines it.

    Returns
    -------
    (__getattr__, __dir__)
        Assign both at the package's top level. A name is looked up once, then cached in the
        package's namespace.
    """

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        path = module if module.startswith("anklelab.") else f"{package}.{module}"
        value = getattr(importlib.import_module(path), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
