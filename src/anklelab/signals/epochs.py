"""Trials as one array, MNE-Epochs style: data ``(n_trials, n_channels, n_times)``.

A :class:`Trials` object carries the data, the channel names, the sample rate, the time of the
first sample relative to the event each trial is aligned on, a per-trial metadata table (a
mapping of column name to array), and a drop log that says, for every trial it started with,
why it was rejected (an empty tuple if it was kept). Condition tags such as ``"dorsi/225"``
select trials the way MNE's event tags do: a trial matches when its ``condition`` holds every
tag of the key.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import SupportsIndex

import numpy as np
from numpy.typing import ArrayLike, NDArray

from anklelab.data.session import Recording
from anklelab.errors import ParameterError

__all__ = ["Trials", "advance", "bootstrap_weights", "epoch", "stack_recordings"]

Seed = int | np.random.Generator | None


class Trials:
    """A set of equally long trials aligned on an event.

    Parameters
    ----------
    data : array_like, shape (n_trials, n_channels, n_times)
        The trials.
    fs : float
        Sample rate, Hz.
    ch_names : sequence of str
        One name per channel.
    metadata : mapping of str to array_like, optional
        Per-trial columns, each of length ``n_trials``. A ``condition`` column of ``/``-separated
        tags (``"dorsi/225"``, ``"none"``) enables selection by tag.
    tmin : float
        Time of the first sample relative to the alignment event, s.
    drop_log : sequence of tuple of str, optional
        One entry per trial originally considered; defaults to every trial kept.
    selection : array_like of int, optional
        Positions in ``drop_log`` of the trials held (defaults to ``0 .. n_trials-1``).

    Examples
    --------
    >>> import numpy as np
    >>> t = Trials(np.arange(12.0).reshape(3, 2, 2), 1000.0, ["angle", "torque"],
    ...            {"condition": np.array(["dorsi/100", "plantar/100", "dorsi/225"])})
    >>> len(t["dorsi"]), len(t["100"]), t["dorsi/225"].selection.tolist()
    (2, 2, [2])
    >>> t.drop([True, False, False], "no heel contact").drop_log
    (('no heel contact',), (), ())
    """

    def __init__(
        self,
        data: ArrayLike,
        fs: float,
        ch_names: Sequence[str],
        metadata: Mapping[str, ArrayLike] | None = None,
        *,
        tmin: float = 0.0,
        drop_log: Sequence[tuple[str, ...]] | None = None,
        selection: ArrayLike | None = None,
    ) -> None:
        self.data = np.asarray(data, dtype=float)
        if self.data.ndim != 3:
            raise ParameterError(
                f"data: expected shape (n_trials, n_channels, n_times), got {self.data.shape}"
            )
        n_trials, n_channels, _ = self.data.shape
        self.ch_names = tuple(ch_names)
        if len(self.ch_names) != n_channels:
            raise ParameterError(f"ch_names: expected {n_channels} names, got {len(self.ch_names)}")
        if fs <= 0:
            raise ParameterError(f"fs: expected > 0 Hz, got {fs!r}")
        self.fs = float(fs)
        self.tmin = float(tmin)
        self.metadata = {key: np.asarray(value) for key, value in (metadata or {}).items()}
        for key, value in self.metadata.items():
            if len(value) != n_trials:
                raise ParameterError(
                    f"metadata[{key!r}]: expected {n_trials} values, got {len(value)}"
                )
        self.drop_log = tuple(tuple(r) for r in drop_log) if drop_log else ((),) * n_trials
        default = (
            np.arange(n_trials)
            if drop_log is None
            else np.flatnonzero([not r for r in self.drop_log])
        )
        self.selection = np.asarray(default if selection is None else selection, dtype=int)
        if self.selection.size != n_trials:
            raise ParameterError(
                f"selection: expected {n_trials} positions, got {self.selection.size}"
            )

    def __len__(self) -> int:
        return self.data.shape[0]

    def __repr__(self) -> str:
        n_dropped = sum(1 for r in self.drop_log if r)
        return (
            f"<Trials | {len(self)} trials, {len(self.ch_names)} channels, {self.n_times} "
            f"samples ({self.tmin:g} .. {self.times[-1]:g} s), {n_dropped} dropped>"
        )

    @property
    def n_times(self) -> int:
        """Samples per trial."""
        return self.data.shape[2]

    @property
    def times(self) -> NDArray[np.float64]:
        """Time of each sample relative to the alignment event, s."""
        return self.tmin + np.arange(self.n_times) / self.fs

    def _subset(self, index: NDArray[np.int64]) -> Trials:
        return Trials(
            self.data[index],
            self.fs,
            self.ch_names,
            {key: value[index] for key, value in self.metadata.items()},
            tmin=self.tmin,
            drop_log=self.drop_log,
            selection=self.selection[index],
        )

    def _match(self, key: str) -> NDArray[np.bool_]:
        if "condition" not in self.metadata:
            raise KeyError(f"{key!r}: these trials have no 'condition' metadata")
        tags = set(key.split("/"))
        names, inverse = np.unique(self.metadata["condition"].astype(str), return_inverse=True)
        return np.array([tags <= set(name.split("/")) for name in names], dtype=bool)[inverse]

    def __getitem__(
        self,
        key: str | SupportsIndex | slice | Sequence[int] | NDArray[np.integer | np.bool_],
    ) -> Trials:
        """Trials matching condition tags (``"dorsi/225"``), or by position/boolean mask."""
        if isinstance(key, str):
            return self._subset(np.flatnonzero(self._match(key)))
        return self._subset(np.arange(len(self))[key].reshape(-1))

    def conditions(self) -> list[str]:
        """Distinct conditions, in order of first appearance."""
        return list(dict.fromkeys(str(c) for c in self.metadata.get("condition", [])))

    def get_data(self, picks: str | Sequence[str] | None = None) -> NDArray[np.float64]:
        """The data, optionally only the named channels (a single name drops the channel axis)."""
        if picks is None:
            return self.data
        if isinstance(picks, str):
            return self.data[:, self._channel(picks)]
        return self.data[:, [self._channel(name) for name in picks]]

    def pick(self, names: Sequence[str]) -> Trials:
        """A copy holding only the channels ``names``, in that order (trials, metadata and drop
        log as they are)."""
        return Trials(
            self.get_data(list(names)),
            self.fs,
            names,
            self.metadata,
            tmin=self.tmin,
            drop_log=self.drop_log,
            selection=self.selection,
        )

    def _channel(self, name: str) -> int:
        try:
            return self.ch_names.index(name)
        except ValueError:
            raise KeyError(f"{name!r}: no such channel; have {', '.join(self.ch_names)}") from None

    def drop(self, mask: ArrayLike, reason: str | Sequence[str]) -> Trials:
        """A copy without the trials where ``mask`` is true, logging ``reason`` for each (one
        text for all, or one per dropped trial in order)."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (len(self),):
            raise ParameterError(f"mask: expected {len(self)} booleans, got shape {mask.shape}")
        positions = self.selection[mask]
        reasons = [reason] * len(positions) if isinstance(reason, str) else list(reason)
        if len(reasons) != len(positions):
            raise ParameterError(
                f"reason: expected one text or {len(positions)}, got {len(reasons)}"
            )
        log = list(self.drop_log)
        for position, text in zip(positions, reasons, strict=True):
            log[position] = (*log[position], text)
        kept = np.flatnonzero(~mask)
        out = self._subset(kept)
        out.drop_log = tuple(log)
        return out

    def average(self) -> NDArray[np.float64]:
        """Mean over trials, shape (n_channels, n_times)."""
        if len(self) == 0:
            raise ParameterError("average: no trials to average")
        return self.data.mean(axis=0)

    def bootstrap(
        self, n_reps: int = 100, fraction: float = 0.6, *, random_state: Seed = None
    ) -> Trials:
        """Averages of random subsets of the trials (paper 000: 100 x 60 %).

        Each repetition draws ``round(fraction * n_trials)`` (at least 1) distinct trials and
        averages them; all repetitions are one matrix product. The averages come back as
        trials (one per repetition, same channels and times, no metadata).

        Parameters
        ----------
        n_reps : int
            Number of repetitions.
        fraction : float
            Fraction of the trials in each subset (0 < fraction <= 1).
        random_state : int or numpy.random.Generator, optional
            Seed; the same seed gives the same subsets.

        Returns
        -------
        Trials
            ``n_reps`` averages, data shaped ``(n_reps, n_channels, n_times)``.
        """
        weights = bootstrap_weights(len(self), n_reps, fraction, random_state=random_state)
        return Trials(
            np.tensordot(weights, self.data, axes=1), self.fs, self.ch_names, tmin=self.tmin
        )


def bootstrap_weights(
    n_trials: int, n_reps: int = 100, fraction: float = 0.6, *, random_state: Seed = None
) -> NDArray[np.float64]:
    """Averaging weights of random subsets drawn without replacement.

    Parameters
    ----------
    n_trials : int
        Number of trials to draw from.
    n_reps : int
        Number of subsets.
    fraction : float
        Fraction of the trials in each subset (0 < fraction <= 1); each subset holds
        ``max(1, round(fraction * n_trials))`` distinct trials.
    random_state : int or numpy.random.Generator, optional
        Seed.

    Returns
    -------
    ndarray, shape (n_reps, n_trials)
        Row ``r`` is ``1/m`` on the trials of subset ``r`` and 0 elsewhere, so
        ``weights @ x`` averages each subset of ``x`` (trials first).

    Examples
    --------
    >>> w = bootstrap_weights(5, 3, 0.6, random_state=0)
    >>> w.shape, (w > 0).sum(axis=1).tolist(), w.sum(axis=1).round(12).tolist()
    ((3, 5), [3, 3, 3], [1.0, 1.0, 1.0])
    """
    if n_trials < 1:
        raise ParameterError(f"n_trials: expected at least 1 trial, got {n_trials!r}")
    if int(n_reps) != n_reps or n_reps < 1:
        raise ParameterError(f"n_reps: expected a positive integer, got {n_reps!r}")
    if not 0 < fraction <= 1:
        raise ParameterError(f"fraction: expected 0 < fraction <= 1, got {fraction!r}")
    rng = np.random.default_rng(random_state)
    size = max(1, round(fraction * n_trials))
    chosen = np.argsort(rng.random((int(n_reps), n_trials)), axis=1)[:, :size]
    weights = np.zeros((int(n_reps), n_trials))
    np.put_along_axis(weights, chosen, 1.0 / size, axis=1)
    return weights


def advance(x: ArrayLike, lead: float) -> NDArray[np.float64]:
    """``x`` moved ``lead`` samples earlier along its last axis: a signal recorded ``lead``
    samples late, realigned (a fraction of a sample by linear interpolation, accurate for
    signals well below the sample rate; the last value is held at the end). A negative
    ``lead`` delays ``x``, holding its first value at the start.

    Examples
    --------
    >>> advance([0.0, 1.0, 2.0, 3.0], 1.5).tolist()
    [1.5, 2.5, 3.0, 3.0]
    >>> advance([0.0, 1.0, 2.0, 3.0], -0.5).tolist()
    [0.0, 0.5, 1.5, 2.5]
    """
    x = np.asarray(x, dtype=float)
    if lead == 0:
        return x
    whole = int(np.floor(lead))
    last = x.shape[-1] - 1
    index = np.arange(x.shape[-1]) + whole
    fraction = lead - whole
    before, after = np.clip(index, 0, last), np.clip(index + 1, 0, last)
    return (1.0 - fraction) * x[..., before] + fraction * x[..., after]


def stack_recordings(
    recordings: Sequence[Recording], columns: Sequence[str], width: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Stack the named columns of many recordings into one padded array.

    Parameters
    ----------
    recordings : sequence of Recording
        Trials of possibly different lengths.
    columns : sequence of str
        Column names to stack, in order.
    width : int, optional
        Samples per row, at least the longest recording's (default: the longest's), so that
        the stacks of several groups of recordings line up.

    Returns
    -------
    data : ndarray, shape (n_recordings, n_columns, width)
        Each recording padded at its end with its last value.
    lengths : ndarray of int
        Samples in each recording.
    """
    lengths = np.array([rec.n_samples for rec in recordings], dtype=np.int64)
    longest = int(lengths.max(initial=0))
    if width is not None and width < longest:
        raise ValueError(f"width: expected at least the longest recording's {longest}, got {width}")
    data = np.empty((len(recordings), len(columns), longest if width is None else width))
    for row, rec in zip(data, recordings, strict=True):
        row[:, : rec.n_samples] = rec.stack(tuple(columns))
        row[:, rec.n_samples :] = row[:, rec.n_samples - 1 : rec.n_samples]
    return data, lengths


def epoch(
    data: ArrayLike,
    fs: float,
    events: ArrayLike,
    tmin: float,
    tmax: float,
    *,
    ch_names: Sequence[str],
    metadata: Mapping[str, ArrayLike] | None = None,
    lengths: ArrayLike | None = None,
    drop_log: Sequence[Sequence[str]] | None = None,
) -> Trials:
    """Cut equally long windows around one event per trial (one fancy-indexing operation).

    Parameters
    ----------
    data : array_like, shape (n_trials, n_channels, n_samples)
        Continuous trials (e.g. from :func:`stack_recordings`).
    fs : float
        Sample rate, Hz.
    events : array_like of int, shape (n_trials,)
        Sample index of the alignment event in each trial.
    tmin, tmax : float
        Window around the event, s (both ends included).
    ch_names : sequence of str
        Channel names.
    metadata : mapping, optional
        Per-trial columns passed to :class:`Trials`.
    lengths : array_like of int, optional
        Valid samples in each trial (default: all).
    drop_log : sequence of sequence of str, optional
        Reasons already known for rejecting trials (one entry per trial, empty to keep); those
        trials are not cut and keep their reasons.

    Returns
    -------
    Trials
        Trials whose window leaves their recording are dropped too (and logged).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.arange(20.0).reshape(2, 1, 10)
    >>> t = epoch(x, 1000.0, [2, 8], -0.001, 0.002, ch_names=["a"])
    >>> t.get_data("a").tolist(), t.drop_log[1]
    ([[1.0, 2.0, 3.0, 4.0]], ('window -0.001 .. 0.002 s leaves the recording',))
    """
    data = np.asarray(data, dtype=float)
    events = np.asarray(events, dtype=np.int64)
    n_trials, _, n_samples = data.shape
    log = [tuple(r) for r in drop_log] if drop_log is not None else [()] * n_trials
    if len(events) != n_trials or len(log) != n_trials:
        raise ParameterError(
            f"events, drop_log: expected one entry per trial ({n_trials}), "
            f"got {len(events)} and {len(log)}"
        )
    lengths = np.full(n_trials, n_samples) if lengths is None else np.asarray(lengths)
    offsets = np.arange(round(tmin * fs), round(tmax * fs) + 1)
    outside = (events + offsets[0] < 0) | (events + offsets[-1] >= lengths)
    reason = f"window {tmin:g} .. {tmax:g} s leaves the recording"
    log = [r or ((reason,) if out else ()) for r, out in zip(log, outside, strict=True)]
    kept = np.flatnonzero([not r for r in log])
    if kept.size and np.all(events[kept] == events[kept[0]]):  # one window for all: a slice
        start = events[kept[0]] + offsets[0]
        cut = data[kept, :, start : start + offsets.size]
    else:
        index = events[kept, None] + offsets
        cut = data[kept[:, None, None], np.arange(data.shape[1])[:, None], index[:, None, :]]
    meta = {key: np.asarray(value)[kept] for key, value in (metadata or {}).items()}
    return Trials(cut, fs, ch_names, meta, tmin=offsets[0] / fs, drop_log=log, selection=kept)
