"""A rich progress bar for commands that read or write many recordings."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

__all__ = ["recording_progress"]


@contextmanager
def recording_progress(
    *, transient: bool = True
) -> Iterator[Callable[[str], Callable[[int, int], None]]]:
    """Yield ``task(description)``, which adds a bar and returns its ``progress(done, total)``.

    Bars go to stderr, so stdout carries only the command's output; they disappear when done
    unless ``transient`` is false. Each shows the time elapsed and an estimate of the time left
    (a long study's first question).
    """
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=Console(stderr=True), transient=transient) as bar:

        def task(description: str) -> Callable[[int, int], None]:
            task_id = bar.add_task(description, total=None)
            return lambda done, total: bar.update(task_id, completed=done, total=total)

        yield task
