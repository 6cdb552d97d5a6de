"""anklelab: digital twins, controllers and identification for ankle actuation platforms.

Importing anklelab reads no files and imports nothing heavy (no NumPy, SciPy, matplotlib or
numba): every public name loads its module on first use. Subpackages hold the layers of
DESIGN.md section 2 (``platforms``, ``sim``, ``control``, ``data``, ``signals``, ``ident``,
``pipelines``, ``report``).

>>> import anklelab
>>> anklelab.load_platform("capstan").capstan.ratio
20.0
"""

from anklelab._lazy import lazy_exports
from anklelab.errors import (
    AnklelabError,
    AnklelabWarning,
    EventNotFoundError,
    NotFittedError,
    OutputError,
    ParameterError,
    ResultsFormatError,
    SafetyLimitError,
    SessionFormatError,
)

_EXPORTS = {
    "__version__": "_version",
    "CHANNELS": "forceplate",
    "GrfCopPlate": "forceplate",
    "PlateGeometry": "forceplate",
    "SixAxisPlate": "forceplate",
    "ankle_torque": "forceplate",
    "channels_from_load": "forceplate",
    "resultants": "forceplate",
    "sagittal_load": "forceplate",
    "load_platform": "platforms",
}
__all__ = [
    "AnklelabError",
    "AnklelabWarning",
    "EventNotFoundError",
    "NotFittedError",
    "OutputError",
    "ParameterError",
    "ResultsFormatError",
    "SafetyLimitError",
    "SessionFormatError",
    *sorted(_EXPORTS),
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
