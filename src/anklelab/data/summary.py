"""A short, JSON-ready description of a session: what it holds and how much of it."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from anklelab.data._checks import info_to_mapping
from anklelab.data.session import Recording, Session

__all__ = ["summarize"]


def _durations(recordings: list[Recording], fs: float) -> dict[str, float] | None:
    if not recordings:
        return None
    seconds = np.array([r.n_samples / fs for r in recordings])
    return {
        "min": float(seconds.min()),
        "median": float(np.median(seconds)),
        "max": float(seconds.max()),
        "total": float(seconds.sum()),
    }


def summarize(session: Session) -> dict[str, Any]:
    """Counts, durations and metadata of ``session`` as plain JSON-ready values.

    Returns
    -------
    dict
        ``info`` (the session.toml document), ``calibration`` / ``walking`` / ``bench``
        counts and durations (s; a recording of n samples lasts n / fs), walking counts per
        timing point (``direction``, ``delay_ms``, ``n``), bench distances (m), whether a
        ``truth`` tree is present and its top-level keys, and the provenance.

    Examples
    --------
    >>> from anklelab.data._synthetic import random_session
    >>> s = summarize(random_session(n_walking=6, n_samples=100))
    >>> [(p["direction"], p["delay_ms"], p["n"]) for p in s["walking"]["timing_points"]]
    [('dorsi', 100.0, 2), ('plantar', 225.0, 2)]
    >>> s["walking"]["n_unperturbed"], s["walking"]["duration_s"]["median"]
    (2, 0.1)
    """
    fs = session.info.sample_rate_hz
    walking = list(session.walking)
    points = Counter((t.direction, float(t.delay_ms)) for t in walking if t.perturbed)
    info = info_to_mapping(session.info)
    return {
        "info": {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in info.items()},
        "calibration": {
            "n": len(session.calibration),
            "duration_s": _durations(list(session.calibration), fs),
        },
        "walking": {
            "n": len(walking),
            "n_perturbed": sum(t.perturbed for t in walking),
            "n_unperturbed": sum(not t.perturbed for t in walking),
            "timing_points": [
                {"direction": d, "delay_ms": delay, "n": n}
                for (d, delay), n in sorted(
                    points.items(), key=lambda item: (item[0][1], item[0][0])
                )
            ],
            "duration_s": _durations([t.recording for t in walking], fs),
        },
        "bench": {
            "n": len(session.bench),
            "distances_m": sorted({float(b.distance_m) for b in session.bench}),
        },
        "truth": session.truth is not None,
        "truth_keys": sorted(session.truth) if session.truth is not None else [],
        "provenance": {
            k: v for k, v in session.provenance.items() if isinstance(v, str | int | float)
        },
    }
