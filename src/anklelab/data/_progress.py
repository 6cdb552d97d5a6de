"""Progress reporting for readers and writers: ``progress(done, total)`` after each recording."""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["Progress", "ticker"]

Progress = Callable[[int, int], None]
"""Called as ``progress(done, total)`` after each recording is read or written."""


def ticker(progress: Progress | None, total: int) -> Callable[[], None]:
    """A no-argument callable that reports one more recording done out of ``total``.

    Examples
    --------
    >>> tick = ticker(lambda done, total: print(f"{done}/{total}"), 2)
    >>> tick(); tick()
    1/2
    2/2
    """
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total)

    return tick
