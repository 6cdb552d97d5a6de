"""A rich progress bar for commands that read or write many recordings."""

from __future__ import annotations

import datetime
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    Task,
    TextColumn,
    TimeElapsedColumn,
)
from rich.text import Text

__all__ = ["recording_progress"]

_SPEED_WINDOW_S = 600.0
"""The time left is estimated from the progress of the last ten minutes (rich's 30 s saw no
progress at all between a slow study's sessions)."""


class _TimeLeft(ProgressColumn):
    """``0:08:12 left`` once the time left can be estimated; nothing before or when done."""

    def render(self, task: Task) -> Text:
        left = task.time_remaining
        if left is None or task.finished:
            return Text("")
        return Text(f"{datetime.timedelta(seconds=round(left))} left", style="progress.remaining")


@contextmanager
def recording_progress(
    *, transient: bool = True
) -> Iterator[Callable[[str], Callable[[int, int], None]]]:
    """Yield ``task(description)``, which adds a bar and returns its ``progress(done, total)``.

    Bars go to stderr, so stdout carries only the command's output; they disappear when done
    unless ``transient`` is false. Each shows the time elapsed and, once it can be estimated,
    the time left (a long study's first question).
    """
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        _TimeLeft(),
    )
    console = Console(stderr=True)
    with Progress(
        *columns, console=console, transient=transient, speed_estimate_period=_SPEED_WINDOW_S
    ) as bar:

        def task(description: str) -> Callable[[int, int], None]:
            task_id = bar.add_task(description, total=None)
            return lambda done, total: bar.update(task_id, completed=done, total=total)

        yield task
