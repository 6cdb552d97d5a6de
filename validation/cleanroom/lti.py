"""Exact discretisation of linear continuous-time systems and fast filtering across trials.

A continuous state-space model is discretised with a first-order hold (exact when the inputs
are piecewise linear between samples) and every input-to-output path becomes a cascade of
second-order sections, which :func:`scipy.signal.sosfilt` runs over all trials at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import signal

__all__ = ["DiscreteSystem", "second_order_lowpass"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class DiscreteSystem:
    """A continuous linear system discretised at ``fs`` Hz, ready to filter signals.

    Attributes
    ----------
    sos : dict of (str, str) to ndarray
        Second-order sections of each (input, output) path.
    inputs, outputs : tuple of str
        Names of the inputs and outputs, in the order of the continuous matrices.
    fs : float
        Sampling rate, Hz.
    """

    sos: dict[tuple[str, str], Array]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    fs: float

    @classmethod
    def from_continuous(
        cls,
        a: Array,
        b: Array,
        c: Array,
        d: Array,
        fs: float,
        inputs: tuple[str, ...],
        outputs: tuple[str, ...],
    ) -> DiscreteSystem:
        """Discretise ``x' = A x + B u, y = C x + D u`` with a first-order hold at ``fs`` Hz."""
        ad, bd, cd, dd, _ = signal.cont2discrete((a, b, c, d), 1 / fs, method="foh")
        sos = {}
        for i, name_in in enumerate(inputs):
            for j, name_out in enumerate(outputs):
                zeros, poles, gain = signal.ss2zpk(ad, bd, cd[j : j + 1], dd[j : j + 1], input=i)
                sos[name_in, name_out] = signal.zpk2sos(zeros, poles, gain)
        return cls(sos, tuple(inputs), tuple(outputs), fs)

    def response(self, inputs: dict[str, Array], outputs: tuple[str, ...]) -> dict[str, Array]:
        """Outputs for inputs sampled along the last axis, starting at rest.

        Parameters
        ----------
        inputs : dict of str to ndarray
            Input signals (any subset of :attr:`inputs`; missing ones are zero), equal shapes.
        outputs : tuple of str
            Names of the outputs wanted.

        Returns
        -------
        dict of str to ndarray
            Each output, shaped like the inputs.
        """
        result = {}
        for name_out in outputs:
            total = None
            for name_in, u in inputs.items():
                y = signal.sosfilt(self.sos[name_in, name_out], u, axis=-1)
                total = y if total is None else total + y
            result[name_out] = total
        return result

    def filter(self, u: Array) -> Array:
        """The single output for the single input ``u`` (sampled along the last axis)."""
        (name_in,), (name_out,) = self.inputs, self.outputs
        return signal.sosfilt(self.sos[name_in, name_out], u, axis=-1)


def second_order_lowpass(frequency_hz: float, damping_ratio: float, fs: float) -> DiscreteSystem:
    """A spring-damper mount ``(2ζω s + ω²) / (s² + 2ζω s + ω²)`` with unit static gain.

    This is the transmission from the force on a mass-spring-damper's mass to the force in its
    spring and damper: the plate on its piezo sensors.
    """
    omega = 2 * np.pi * frequency_hz
    a = np.array([[0.0, 1.0], [-(omega**2), -2 * damping_ratio * omega]])
    b = np.array([[0.0], [1.0]])
    c = np.array([[omega**2, 2 * damping_ratio * omega]])
    d = np.zeros((1, 1))
    return DiscreteSystem.from_continuous(a, b, c, d, fs, ("in",), ("out",))
