"""Force-plate resultants for a full walking session vs a per-sample Python loop."""

from __future__ import annotations

import numpy as np

from anklelab.forceplate import PlateGeometry, resultants
from benchmarks._harness import Result, compare


def _per_sample(channels: np.ndarray, g: PlateGeometry) -> np.ndarray:
    """Baseline: the Kistler formulas evaluated sample by sample."""
    out = np.empty((channels.shape[0], 2, channels.shape[2]))
    a, b, az0 = g.a_m, g.b_m, g.az0_m
    for trial in range(channels.shape[0]):
        for k in range(channels.shape[2]):
            fx12, fx34, fy14, fy23, fz1, fz2, fz3, fz4 = channels[trial, :, k]
            fx, fy, fz = fx12 + fx34, fy14 + fy23, fz1 + fz2 + fz3 + fz4
            mx = b * (fz1 + fz2 - fz3 - fz4)
            my = a * (-fz1 + fz2 + fz3 - fz4)
            out[trial, 0, k] = (fx * az0 - my) / fz
            out[trial, 1, k] = (fy * az0 + mx) / fz
    return out


def run() -> list[Result]:
    rng = np.random.default_rng(0)
    g = PlateGeometry(a_m=0.12, b_m=0.2, az0_m=-0.045)
    channels = rng.normal(100.0, 10.0, (100, 8, 800))  # 100 trials x 0.8 s at 1 kHz
    ours = compare(
        "force plate: COP of 100 trials x 800 samples",
        lambda: resultants(channels, g),
        lambda: _per_sample(channels, g),
        "per-sample Python loop",
    )
    np.testing.assert_allclose(_per_sample(channels[:2], g)[:, 0], resultants(channels[:2], g).ax)
    return [ours]
