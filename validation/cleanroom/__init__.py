"""A clean-room session generator for the Perturberator experiment (paper 000).

Written from the two papers and DESIGN.md alone, without reading anklelab's digital twin, so
that the walking analysis can be checked on data it was never developed against. See
``validation/cleanroom/README.md`` for the physics, every parameter and the ground truth.

>>> from validation.cleanroom import draw_config, generate
>>> session = generate(draw_config("human", 3, trials_per_point=2, n_calibration=1,
...                                calibration_duration_s=2.0), seed=3)
>>> sorted(session.truth["reference"])
['dorsi', 'plantar']
"""

from validation.cleanroom.config import (
    Config,
    DriveConfig,
    GaitConfig,
    HumanAnkle,
    NoiseConfig,
    PlateConfig,
    ProstheticFoot,
    ProtocolConfig,
)
from validation.cleanroom.draw import KINDS, draw_config
from validation.cleanroom.generate import generate
from validation.cleanroom.writer import write_session_dir

__all__ = [
    "KINDS",
    "Config",
    "DriveConfig",
    "GaitConfig",
    "HumanAnkle",
    "NoiseConfig",
    "PlateConfig",
    "ProstheticFoot",
    "ProtocolConfig",
    "draw_config",
    "generate",
    "write_session_dir",
]
