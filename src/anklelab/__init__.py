"""anklelab: digital twins, controllers and identification for ankle actuation platforms.

Importing anklelab reads no files and does not import matplotlib; subpackages hold the layers of
DESIGN.md section 2 (``platforms``, ``sim``, ``control``, ``data``, ``signals``, ``ident``,
``pipelines``, ``report``).

>>> import anklelab
>>> anklelab.load_platform("capstan").capstan.ratio
20.0
"""

from anklelab._version import __version__
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
from anklelab.forceplate import (
    CHANNELS,
    GrfCopPlate,
    PlateGeometry,
    SixAxisPlate,
    ankle_torque,
    channels_from_load,
    resultants,
    sagittal_load,
)
from anklelab.platforms import load_platform

__all__ = [
    "CHANNELS",
    "AnklelabError",
    "AnklelabWarning",
    "EventNotFoundError",
    "GrfCopPlate",
    "NotFittedError",
    "OutputError",
    "ParameterError",
    "PlateGeometry",
    "ResultsFormatError",
    "SafetyLimitError",
    "SessionFormatError",
    "SixAxisPlate",
    "__version__",
    "ankle_torque",
    "channels_from_load",
    "load_platform",
    "resultants",
    "sagittal_load",
]
