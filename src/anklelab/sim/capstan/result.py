"""Simulation result: labelled, equally sampled signals with units, a table export and a plot."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from anklelab.errors import ParameterError

__all__ = ["SimulationResult"]


@dataclass(frozen=True)
class SimulationResult:
    """Signals sampled at ``fs`` Hz, one array each, starting at ``t = 0``.

    Attributes
    ----------
    fs : float
        Sample rate, Hz.
    signals : mapping of str to ndarray
        Each signal, shape ``(n_samples,)``; names carry units (``angle_rad``).
    meta : mapping
        What produced the run (protocol, settings, fault, ...).

    Examples
    --------
    >>> r = SimulationResult(1000.0, {"angle_rad": np.zeros(3)})
    >>> r.time_s
    array([0.   , 0.001, 0.002])
    """

    fs: float
    signals: Mapping[str, NDArray[np.float64]]
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        lengths = {len(v) for v in self.signals.values()}
        if len(lengths) > 1:
            raise ParameterError(f"signals must have equal lengths; got {sorted(lengths)}")

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; available: {', '.join(self.signals)}") from None

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(next(iter(self.signals.values()))) if self.signals else 0

    @property
    def time_s(self) -> NDArray[np.float64]:
        """Sample times, s."""
        return np.arange(self.n_samples) / self.fs

    def to_csv(self, path: str | Path, names: Iterable[str] | None = None) -> Path:
        """Write ``time_s`` and the chosen signals (default: all) as CSV, atomically."""
        names = list(self.signals if names is None else names)
        table = np.column_stack([self.time_s, *(self[n] for n in names)])
        path = Path(path)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w") as handle:
                np.savetxt(
                    handle,
                    table,
                    delimiter=",",
                    header=",".join(["time_s", *names]),
                    comments="",
                    fmt="%.9g",
                )
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return path

    def plot(self, names: Iterable[str], ax: Any = None) -> Any:
        """Plot signals against time on one matplotlib axis (created if not given)."""
        if ax is None:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            ax = plt.subplots(figsize=(8, 3))[1]
        for name in names:
            ax.plot(self.time_s, self[name], label=name)
        ax.set_xlabel("time (s)")
        ax.legend(loc="best", fontsize="small")
        return ax
