"""The zero-phase low-pass: ``anklelab.iir`` against ``scipy.signal.sosfiltfilt``.

Two rows, because the trade is between them. Filtering alone, in a warm process, SciPy's C
loop is faster than our block matrix products (about 1.8x). But a command that filters must
first import ``scipy.signal``, which costs more than the filtering of a whole paper-size
session. The second row times that: a fresh interpreter that imports what it needs and filters
once. The data are 800 trials x 8 channels x 1400 samples at 1 kHz (paper 000's walking
session), filtered at 20 Hz, order 4.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from scipy import signal

from anklelab.signals import lowpass
from benchmarks._harness import Result, compare

SHAPE = (800, 8, 1400)
_DATA = f"import numpy as np; x = np.random.default_rng(0).standard_normal({SHAPE})\n"
OURS = _DATA + "from anklelab.signals import lowpass; lowpass(x, 1000.0, 20.0)\n"
SCIPY = (
    _DATA + "from scipy import signal\n"
    "signal.sosfiltfilt(signal.butter(4, 20.0, fs=1000.0, output='sos'), x)\n"
)


def _process(code: str) -> None:
    subprocess.run([sys.executable, "-c", code], check=True)


def run() -> list[Result]:
    x = np.random.default_rng(0).standard_normal(SHAPE)
    sos = signal.butter(4, 20.0, fs=1000.0, output="sos")
    return [
        compare(
            "zero-phase low-pass, 800x8x1400 samples, warm",
            lambda: lowpass(x, 1000.0, 20.0),
            lambda: signal.sosfiltfilt(sos, x),
            "scipy.signal.sosfiltfilt (C loop)",
        ),
        compare(
            "the same as a whole process (imports included)",
            lambda: _process(OURS),
            lambda: _process(SCIPY),
            "importing scipy.signal to call it",
        ),
    ]
