"""IIR filters as second-order sections, designed in closed form and run with NumPy alone.

Paper 000 filters with a bidirectional Butterworth low-pass, and the twin runs its plate
resonances and amplifier anti-alias filter as second-order sections. Both designs are a few lines
of the bilinear transform (pre-warped), and the zero-phase filter is a few matrix products per
pass (below), so neither needs ``scipy.signal``: importing it costs every command 1-1.7 s of
start-up (SciPy 1.17 parses the docstring of each of its functions on import), more than the
whole analysis of a session's filtering.

A pass runs the cascade as one state-space system over blocks of samples (:data:`_SPAN` or
more, by the signal's length). Within a block, the outputs are the block's inputs times a
lower-triangular Toeplitz matrix of the impulse response, plus the block's initial state times
the observability matrix; the state at the block's end is the initial state times ``A^span``
plus the inputs times the reachability matrix. Every block of every signal thus goes through
three matrix products at once, and only the state, a few numbers per signal, steps from block
to block. On 5 334 signals of 1 100 samples (a paper-size session's stance) this takes 0.27 s
where a LAPACK triangular band solve per section took 0.53 s.

The results equal SciPy's ``butter(..., output="sos")`` and ``sosfiltfilt`` (odd extension,
steady-state initial conditions, the default pad length) to rounding (tests compare them).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.errors import ParameterError

__all__ = ["butterworth_sos", "edge_padding", "resonance_sos", "sosfiltfilt"]

_SPAN = 16
"""Samples per block of a pass, at least: fewer make more steps from block to block, more make
the block's Toeplitz product do more work for the same outputs (16 is the fastest for stance
signals)."""
_STEPS = 128
"""Steps from block to block in a pass, at most: a long signal takes longer blocks (a step costs
the same for one signal as for hundreds). The blocks depend on the signal's length alone, so
that a signal is filtered alike whatever it is filtered with."""
_ROWS = 512
"""Signals filtered together: their temporaries stay within a core's cache."""


def butterworth_sos(order: int, cutoff_hz: float, fs: float) -> NDArray[np.float64]:
    """Butterworth low-pass as second-order sections ``[b0, b1, b2, 1, a1, a2]`` at rate ``fs``.

    The analog Butterworth poles ``wa exp(i pi (2k + 1 + n) / 2n)`` (``wa`` the pre-warped
    cut-off) in conjugate pairs, each pair (and, for an odd order, the real pole) one section
    of unit DC gain, the section nearest the unit circle last (as ``scipy.signal.butter``).

    Parameters
    ----------
    order : int
        Filter order (number of poles), at least 1.
    cutoff_hz : float
        -3 dB frequency, Hz (0 < cutoff < fs/2).
    fs : float
        Sample rate, Hz.

    Returns
    -------
    ndarray, shape (ceil(order / 2), 6)

    Examples
    --------
    >>> sos = butterworth_sos(4, 400.0, 8000.0)
    >>> z = np.exp(2j * np.pi * 400.0 / 8000.0)
    >>> h = np.prod([np.polyval(s[:3], z) / np.polyval(s[3:], z) for s in sos])
    >>> sos.shape, round(float(abs(h)) ** 2, 6)   # half power at the cut-off
    ((2, 6), 0.5)
    """
    wa = _prewarp(cutoff_hz, fs)
    angles = np.pi * (2 * np.arange(order // 2) + 1 + order) / (2 * order)
    # pairs s² - 2 Re(p) s + |p|², the least damped (nearest the unit circle) last
    sections = [_bilinear_section(wa * wa, -2 * wa * np.cos(a), fs) for a in angles[::-1]]
    if order % 2:
        k = wa / (2 * fs + wa)
        sections.insert(0, np.array([k, k, 0.0, 1.0, (wa - 2 * fs) / (2 * fs + wa), 0.0]))
    return np.array(sections)


def resonance_sos(
    natural_frequency_hz: float, damping_ratio: float, fs: float
) -> NDArray[np.float64]:
    """One second-order section of ``w²/(s² + 2 zeta w s + w²)`` (unit DC gain) at rate ``fs``.

    Bilinear transform pre-warped at the natural frequency, so the discrete resonance sits
    exactly at ``natural_frequency_hz``.

    Examples
    --------
    >>> sos = resonance_sos(300.0, 0.05, 8000.0)
    >>> z = np.exp(2j * np.pi * np.array([0.0, 300.0]) / 8000.0)
    >>> h = np.polyval(sos[0, :3], z) / np.polyval(sos[0, 3:], z)
    >>> round(float(abs(h[0])), 9), round(float(abs(h[1])), 3)   # DC gain 1, peak 1/(2 zeta)
    (1.0, 10.0)
    """
    wa = _prewarp(natural_frequency_hz, fs)
    return _bilinear_section(wa * wa, 2 * damping_ratio * wa, fs)[None, :]


def group_delay_at_dc(sos: NDArray[np.float64]) -> float:
    """Delay of the second-order sections ``sos`` for slow signals, samples (their group delay
    at zero frequency: for each section ``Σ k b_k / Σ b_k - Σ k a_k / Σ a_k``).

    Examples
    --------
    >>> round(group_delay_at_dc(butterworth_sos(4, 400.0, 8000.0)) / 8.0, 3)  # ms at 8 kHz
    1.031
    """
    k = np.arange(3)
    b, a = np.asarray(sos, dtype=float)[:, :3], np.asarray(sos, dtype=float)[:, 3:]
    return float(np.sum((b @ k) / b.sum(axis=1) - (a @ k) / a.sum(axis=1)))


def edge_padding(sos: NDArray[np.float64]) -> int:
    """Samples :func:`sosfiltfilt` extends each end by: ``3 (2 n_sections + 1 - first_order)``.

    ``first_order`` counts the sections that are first-order (a zero ``b2`` and ``a2``), as
    ``scipy.signal.sosfiltfilt``'s default ``padlen``.

    Examples
    --------
    >>> [edge_padding(butterworth_sos(order, 20.0, 1000.0)) for order in (3, 4)]
    [12, 15]
    """
    first_order = min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    return 3 * (2 * len(sos) + 1 - first_order)


def sosfiltfilt(sos: NDArray[np.float64], x: ArrayLike, axis: int = -1) -> NDArray[np.float64]:
    """Zero-phase filtering: the sections run forwards, then backwards, over ``x``.

    As ``scipy.signal.sosfiltfilt`` with its defaults: each end is extended by an odd reflection
    of :func:`edge_padding` samples, and each pass starts in the steady state of its first
    sample, so a constant passes unchanged. Each pass runs every signal at once, in blocks of
    samples (module docstring).

    Parameters
    ----------
    sos : ndarray, shape (n_sections, 6)
        Sections ``[b0, b1, b2, 1, a1, a2]`` (``a0`` normalised to 1).
    x : array_like
        Signals, any shape, longer than the padding along ``axis``.
    axis : int
        Time axis.

    Returns
    -------
    ndarray
        Filtered signals, same shape as ``x``.

    Raises
    ------
    ParameterError
        If ``x`` has no more samples along ``axis`` than the padding.

    Examples
    --------
    >>> t = np.arange(2000) / 1000.0
    >>> y = sosfiltfilt(butterworth_sos(4, 20.0, 1000.0), 2.0 + np.sin(2 * np.pi * 150 * t))
    >>> bool(np.allclose(y[200:-200], 2.0, atol=1e-4))
    True
    """
    x = np.asarray(x, dtype=float)
    n, pad = (x.shape[axis] if x.ndim else 1), edge_padding(sos)
    if n <= pad:
        raise ParameterError(
            f"x: {n} samples along axis {axis}; the zero-phase filter ({len(sos)} second-order "
            f"sections) needs at least {pad + 1}: it extends each end by {pad} samples"
        )
    x = np.moveaxis(x, axis, -1)
    rows = x.reshape(-1, x.shape[-1])
    out = np.empty_like(rows)
    for start in range(0, len(rows), _ROWS):
        block = rows[start : start + _ROWS]
        first, last = block[:, :1], block[:, -1:]
        extended = np.concatenate(
            [2 * first - block[:, pad:0:-1], block, 2 * last - block[:, -2 : -pad - 2 : -1]],
            axis=1,
        )
        backward = _causal(sos, _causal(sos, extended)[:, ::-1])[:, ::-1]
        out[start : start + _ROWS] = backward[:, pad : pad + n]
    return np.moveaxis(out.reshape(x.shape), -1, axis)


def _state_space(
    sos: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
    """``(A, B, C, D)`` of the cascade: each section in controllable canonical form, fed by
    the output of the sections before it."""
    a, b, c, d = np.zeros((0, 0)), np.zeros(0), np.zeros(0), 1.0
    for b0, b1, b2, _, a1, a2 in sos:
        m = len(b)
        grown = np.zeros((m + 2, m + 2))
        grown[:m, :m] = a
        grown[m, :m] = c  # the section's input: the output of the sections before it
        grown[m:, m:] = [[-a1, -a2], [1.0, 0.0]]
        b = np.concatenate([b, [d, 0.0]])
        c = np.concatenate([b0 * c, [b1 - b0 * a1, b2 - b0 * a2]])
        a, d = grown, b0 * d
    return a, b, c, d


def _causal(sos: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cascade over each row of ``u`` (time along axis 1), from the steady state of the
    row's first sample: before it, the input stood at that value forever (module docstring)."""
    rows, m = u.shape
    span = max(_SPAN, -(-m // _STEPS))
    toeplitz, observe, reach, step, steady = _block_matrices(sos.tobytes(), len(sos), span)
    blocks = -(-m // span)
    padded = np.empty((rows, blocks * span))  # the tail past the end only feeds discarded outputs
    padded[:, :m], padded[:, m:] = u, u[:, -1:]
    flat = padded.reshape(-1, span)
    y = (flat @ toeplitz.T).reshape(rows, blocks, span)
    gained = (flat @ reach).reshape(rows, blocks, -1)
    initial = np.empty_like(gained)
    state = u[:, :1] * steady
    for k in range(blocks):  # a few numbers per signal, from block to block
        initial[:, k] = state
        state = state @ step + gained[:, k]
    y += (initial.reshape(blocks * rows, -1) @ observe.T).reshape(rows, blocks, span)
    return y.reshape(rows, -1)[:, :m]


@functools.lru_cache(maxsize=32)
def _block_matrices(sos_bytes: bytes, n_sections: int, span: int) -> tuple[NDArray[Any], ...]:
    """For blocks of ``span`` samples: the Toeplitz matrix of the impulse response ``[out,
    in]``, the observability matrix ``(span, n)`` (initial state to outputs), the reachability
    matrix ``(span, n)`` (each input to the final state), ``A^span`` transposed, and the steady
    state per unit input."""
    a, b, c, d = _state_space(np.frombuffer(sos_bytes).reshape(n_sections, 6))
    observe, reach = [c], [b]  # c A^j, A^j b
    for _ in range(span - 1):
        observe.append(observe[-1] @ a)
        reach.append(a @ reach[-1])
    impulse = np.array([d, *(row @ b for row in observe[:-1])])
    lag = np.arange(span)
    toeplitz = np.where(lag[:, None] >= lag, impulse[lag[:, None] - lag], 0.0)
    step = np.linalg.matrix_power(a, span).T
    steady = np.linalg.solve(np.eye(len(b)) - a, b)
    return toeplitz, np.array(observe), np.array(reach[::-1]), step, steady


def _prewarp(frequency_hz: float, fs: float) -> float:
    """Analog frequency that the bilinear transform at ``fs`` maps onto ``frequency_hz``, rad/s."""
    return float(2 * fs * np.tan(np.pi * frequency_hz / fs))


def _bilinear_section(w2: float, c1: float, fs: float) -> NDArray[np.float64]:
    """``[b0, b1, b2, 1, a1, a2]`` of ``w2 / (s² + c1 s + w2)`` by ``s = 2 fs (z - 1)/(z + 1)``."""
    f2 = (2 * fs) ** 2
    a0 = f2 + 2 * fs * c1 + w2
    b = w2 / a0
    return np.array([b, 2 * b, b, 1.0, 2 * (w2 - f2) / a0, (f2 - 2 * fs * c1 + w2) / a0])
