"""Figures rendered in worker processes are the figures drawn in the calling process."""

import atexit
import hashlib
import multiprocessing
import os

import pytest
from matplotlib.figure import Figure

from anklelab.report.render import FigureRenderer


def draw(size: float, name: str) -> Figure:
    """A small figure titled ``name`` (module level: the workers import it from here)."""
    if name == "broken":
        raise ValueError("no such figure: broken")
    fig = Figure(figsize=(size, size), layout="constrained")
    ax = fig.subplots()
    ax.plot([0, 1, 2], [0, len(name), 1])
    ax.set_title(name)
    return fig


def dies_in_workers(data: tuple[float, int], name: str) -> Figure:
    """:func:`draw`, except in any process but ``data[1]``, which it kills."""
    size, parent = data
    if os.getpid() != parent:
        os._exit(3)
    return draw(size, name)


def marks_its_exit(data: tuple[float, str], name: str) -> Figure:
    """:func:`draw`, after registering an exit handler that appends to the file ``data[1]``."""
    size, mark = data
    atexit.register(lambda: open(mark, "a").write(f"{os.getpid()}\n"))
    return draw(size, name)


NAMES = ["one", "two", "three"]


def test_workers_render_the_same_pngs_as_the_calling_process():
    serial = FigureRenderer(processes=1)
    assert serial.processes == 1 and serial._pool is None  # nothing is started
    expected = serial.render(draw, 2.0, NAMES)
    with FigureRenderer([__name__], processes=2) as renderer:
        rendered = renderer.render(draw, 2.0, NAMES)
    assert list(rendered) == NAMES
    assert rendered == expected
    assert all(png.startswith(b"\x89PNG") for png in rendered.values())
    assert len({hashlib.sha256(png).digest() for png in rendered.values()}) == len(NAMES)


@pytest.mark.parametrize("method", ["forkserver", "spawn"])
def test_the_workers_end_without_tearing_their_interpreter_down(tmp_path, monkeypatch, method):
    """A worker's exit handlers (here one each registers while drawing) never run: the
    interpreter's teardown with matplotlib loaded took 0.3 s that the command waited for."""
    import anklelab.report.render as render

    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method} here")
    monkeypatch.setattr(render, "_start_method", lambda: method)
    mark = tmp_path / "teardown"
    with FigureRenderer([__name__], processes=2) as renderer:
        assert list(renderer.render(marks_its_exit, (2.0, str(mark)), NAMES)) == NAMES
        workers = list(renderer._pool._processes.values())
    assert [worker.exitcode for worker in workers] == [0, 0]
    assert not mark.exists(), mark.read_text()


def test_a_figure_that_fails_to_draw_raises_in_the_caller_and_the_workers_stop():
    renderer = FigureRenderer([__name__], processes=2)
    with renderer, pytest.raises(ValueError, match="no such figure: broken"):
        renderer.render(draw, 2.0, ["one", "broken"])
    assert renderer._pool is None
    renderer.close()  # idempotent


def test_the_walking_figures_saved_by_workers_match_those_drawn_here(tmp_path):
    from anklelab.experiments import simulate_perturberator
    from anklelab.pipelines import WalkingSettings, analyze_walking
    from anklelab.report.figures_walking import (
        WALKING_FIGURES,
        save_walking_figures,
        submit_filters_figure,
    )

    session = simulate_perturberator(trials_per_point=4, n_unperturbed=8, n_calibration=2, seed=3)
    results = analyze_walking(session, WalkingSettings(bootstrap_reps=5))
    here = save_walking_figures(results, tmp_path / "here")
    with FigureRenderer(["anklelab.report.figures_walking"], processes=2) as renderer:
        there = save_walking_figures(results, tmp_path / "workers", renderer)
        # the filters' figure started early (as `anklelab analyze` does) is not drawn again
        early = submit_filters_figure(results.filters, renderer)
        assert early.names == ("filters",)
        ahead = save_walking_figures(results, tmp_path / "early", renderer, submitted=early)
    assert [p.stem for p in there] == [p.stem for p in ahead] == list(WALKING_FIGURES)
    assert [p.read_bytes() for p in there] == [p.read_bytes() for p in here]
    assert [p.read_bytes() for p in ahead] == [p.read_bytes() for p in here]


def test_without_worker_processes_the_figures_are_drawn_here(monkeypatch):
    import anklelab.report.render as render

    def no_semaphores(method):
        raise OSError("[Errno 38] Function not implemented")

    monkeypatch.setattr(render, "get_context", no_semaphores)
    with FigureRenderer([__name__], processes=2) as renderer:
        assert renderer._pool is None
        rendered = renderer.render(draw, 2.0, NAMES)
    assert rendered == FigureRenderer(processes=1).render(draw, 2.0, NAMES)


def test_a_worker_that_dies_leaves_the_figures_to_the_calling_process():
    expected = FigureRenderer(processes=1).render(draw, 2.0, NAMES)
    with FigureRenderer([__name__], processes=2) as renderer:
        rendered = renderer.render(dies_in_workers, (2.0, os.getpid()), NAMES)
        assert renderer._pool is None  # the broken pool is shut down
    assert rendered == expected


def test_submitted_figures_are_drawn_while_the_caller_goes_on_even_if_a_worker_dies():
    expected = FigureRenderer(processes=1).render(draw, 2.0, NAMES)
    with FigureRenderer([__name__], processes=2) as renderer:
        pending = renderer.submit(draw, 2.0, NAMES)
        dying = renderer.submit(dies_in_workers, (2.0, os.getpid()), NAMES)
        assert pending.names == dying.names == tuple(NAMES)
        assert dying.result() == expected  # drawn here once the pool broke
        assert pending.result() == expected  # whether or not it was drawn before the break


def test_data_that_cannot_be_sent_to_the_workers_is_drawn_here():
    expected = FigureRenderer(processes=1).render(draw, 2.0, NAMES)
    with FigureRenderer([__name__], processes=2) as renderer:
        rendered = renderer.render(lambda size, name: draw(size, name), 2.0, NAMES)
        assert renderer._pool is None
    assert rendered == expected


def test_the_workers_exit_when_the_process_that_started_them_is_killed(tmp_path):
    """However the command dies (SIGKILL here), its workers do not wait for tasks forever."""
    import signal
    import subprocess
    import sys
    import time

    script = tmp_path / "start.py"
    script.write_text(
        "import os, signal, time\n"
        "from anklelab.report.render import FigureRenderer\n"
        "if __name__ == '__main__':\n"
        "    renderer = FigureRenderer(processes=2)\n"
        "    while len(renderer._pool._processes) < 2:  # started by a thread\n"
        "        time.sleep(0.01)\n"
        "    print(' '.join(str(p) for p in renderer._pool._processes), flush=True)\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    # files, not pipes: the workers inherit them, and a pipe would stay open while they live
    out, err = tmp_path / "out", tmp_path / "err"
    with out.open("w") as stdout, err.open("w") as stderr:
        code = subprocess.run([sys.executable, str(script)], stdout=stdout, stderr=stderr)
    assert code.returncode == -signal.SIGKILL, err.read_text()
    workers = [int(pid) for pid in out.read_text().split()]
    assert len(workers) == 2

    def alive(pid: int) -> bool:
        try:
            with open(f"/proc/{pid}/stat") as stat:
                return stat.read().split(")")[-1].split()[0] != "Z"
        except FileNotFoundError:
            return False

    deadline = time.monotonic() + 30.0
    while any(map(alive, workers)) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [pid for pid in workers if alive(pid)]
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left


def test_a_ctrl_c_while_workers_start_reaches_the_command_once_they_have():
    """The workers must not inherit Ctrl-C, but one pressed while they start is the user's: it
    is held back, then delivered (it was ignored, and the command ran to its end)."""
    import signal

    from anklelab.report.render import _ctrl_c_held

    received = []
    previous = signal.signal(signal.SIGINT, lambda number, frame: received.append(number))
    try:
        with _ctrl_c_held():
            os.kill(os.getpid(), signal.SIGINT)
            assert received == []
        assert received == [signal.SIGINT]
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_taken_by_another_thread_is_held_back_too():
    """A signal sent to the process may be taken by any thread that does not block it (a
    thread pool's); its handler then runs in the main thread at once, block or no block."""
    import signal
    import threading
    import time

    from anklelab.report.render import _ctrl_c_held

    received = []
    previous = signal.signal(signal.SIGINT, lambda number, frame: received.append(number))
    done = threading.Event()
    other = threading.Thread(target=done.wait)  # started before the block: SIGINT unblocked
    other.start()
    try:
        with _ctrl_c_held():
            for _ in range(20):  # the kernel picks a thread that does not block it
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.005)
            assert received == []
        assert received == [signal.SIGINT]  # one Ctrl-C held is one delivered
    finally:
        done.set()
        other.join()
        signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("moment", ["before", "after"])
def test_an_interruption_while_the_workers_start_ends_them_without_a_traceback(tmp_path, moment):
    """SIGTERM (here a KeyboardInterrupt raised just before or after the thread that starts the
    workers starts) inside the constructor: the workers are ended before the command ends. Left
    starting, one found its semaphores gone once the command had ended and printed a
    ``FileNotFoundError`` traceback after the command's last line; and ending them must not
    join a thread that never started."""
    import subprocess
    import sys
    import time

    script = tmp_path / "start.py"
    script.write_text(
        "import threading\n"
        "from anklelab.report.render import FigureRenderer\n"
        "if __name__ == '__main__':\n"
        "    original = threading.Thread.start\n"
        "    def start(self):\n"
        "        starter = getattr(getattr(self, '_target', None), '__name__', '') == '_start'\n"
        f"        if starter and {moment == 'before'}:\n"
        "            raise KeyboardInterrupt\n"
        "        original(self)\n"
        "        if starter:\n"
        "            raise KeyboardInterrupt\n"
        "    threading.Thread.start = start\n"
        "    try:\n"
        "        FigureRenderer(processes=2)\n"
        "    except KeyboardInterrupt:\n"
        "        print('interrupted', flush=True)\n"
    )
    out, err = tmp_path / "out", tmp_path / "err"  # files: the workers inherit them
    with out.open("w") as stdout, err.open("w") as stderr:
        subprocess.run([sys.executable, str(script)], stdout=stdout, stderr=stderr, check=True)
    time.sleep(2.0)  # a worker left starting prints its traceback within a second
    assert out.read_text() == "interrupted\n"
    assert "Traceback" not in err.read_text(), err.read_text()
