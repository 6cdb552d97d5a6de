"""Units of measurement that lab files and mappings name, by quantity, with their SI factors.

A mapping spells a unit as :data:`UNITS` does (``"deg"``, ``"N*mm"``); a lab file may spell it
otherwise (a C3D file's ``ANALOG:UNITS`` ``"Nmm"``, ``"degrees"``): :func:`read_unit` reads both.
"""

from __future__ import annotations

import math

__all__ = ["UNITS", "read_unit", "si_unit"]

UNITS: dict[str, dict[str, float]] = {
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "force": {"N": 1.0, "kN": 1e3},
    "moment": {"N*m": 1.0, "N*mm": 1e-3},
    "time": {"s": 1.0, "ms": 1e-3},
}
"""Units a mapping may give, by quantity, with their factor to the SI unit."""

_SPELLINGS = {
    "deg": ("degree", "degrees", "°"),
    "rad": ("radian", "radians"),
    "N*m": ("Nm", "N.m", "N·m"),
    "N*mm": ("Nmm", "N.mm", "N·mm"),
    "s": ("sec",),
}
_READ = {
    spelling.casefold(): (quantity, unit)
    for quantity, units in UNITS.items()
    for unit in units
    for spelling in (unit, *_SPELLINGS.get(unit, ()))
}


def read_unit(text: str) -> tuple[str, str] | None:
    """The quantity and the unit (spelt as in :data:`UNITS`) that ``text`` names.

    Case and spaces are ignored; ``None`` for an empty text or a unit of none of these
    quantities (``"V"``, ``"counts"``).

    >>> read_unit("N mm"), read_unit("Degrees"), read_unit("V")
    (('moment', 'N*mm'), ('angle', 'deg'), None)
    """
    return _READ.get(text.replace(" ", "").casefold())


def si_unit(quantity: str) -> str:
    """The SI unit of ``quantity`` (its factor is 1).

    >>> si_unit("angle")
    'rad'
    """
    return next(unit for unit, factor in UNITS[quantity].items() if factor == 1.0)
