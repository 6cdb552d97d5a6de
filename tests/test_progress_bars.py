"""The progress bars' estimate of the time left."""

from __future__ import annotations

import rich.progress

from anklelab.commands import _progress_bars


def test_the_time_left_counts_only_progress_made_in_this_run(monkeypatch):
    """A resumed study reports the sessions done before at once; counted as progress, they would
    make the time left read near zero for the estimate's whole ten-minute window (rich leaves
    the first report out of its speed)."""
    clock = [0.0]
    bars: list[rich.progress.Progress] = []

    class Clocked(rich.progress.Progress):
        def __init__(self, *columns, **options):
            super().__init__(*columns, **options | {"get_time": lambda: clock[0], "disable": True})
            bars.append(self)

    monkeypatch.setattr(_progress_bars, "Progress", Clocked)
    with _progress_bars.recording_progress() as task:
        progress = task("sessions")
        progress(500, 1000)  # done by an earlier run
        for second in range(1, 31):  # then 10 sessions a second
            clock[0] = float(second)
            progress(500 + 10 * second, 1000)
        (state,) = bars[0].tasks
        assert state.time_remaining == 20  # 200 sessions left at 10 a second
        left = _progress_bars._TimeLeft().render(state).plain
    assert left == "0:00:20 left"
