"""No tracebacks from the CLI: every non-capstan command, driven with generated bad options and
bad files, ends in exit code 2 and exactly one ``error:`` line (issue 11).

Each example corrupts one *slot* of one command (an option value, an input file's content or
kind, an output path) and leaves the rest valid, so that the command would otherwise run. Bad
values: garbage bytes, empty files, wrong types, huge numbers, NaN and infinities, negative
counts, paths that are directories, missing, FIFOs or symbolic links, outputs that exist or lie
inside an input. Known failures that belong to other layers are listed at the end, marked
``xfail(strict=True)`` with the owner in the reason.

``ANKLELAB_FUZZ_EXAMPLES`` sets the number of examples (default 120); hypothesis's statistics
(``--hypothesis-show-statistics``) count the examples per slot and class.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from anklelab.platforms import platform_file
from anklelab.report.sections import FRICTION_FIGURES

EXAMPLES = int(os.environ.get("ANKLELAB_FUZZ_EXAMPLES", "120"))


# --- the valid world every example starts from ---------------------------------------------


@dataclass(frozen=True)
class World:
    session: Path  # a small twin session directory that every command accepts
    native: Path  # the same session as a native file
    ident: Path  # a capstan identification directory
    results: Path  # a results directory `report` accepts
    filters: dict = field(repr=False)  # a valid platform-filter document
    scratch: Path  # where each example makes its files

    def fresh(self) -> Path:
        return Path(tempfile.mkdtemp(dir=self.scratch))


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    from anklelab.data import save_session
    from anklelab.data.capstan_ident import write_ident_directory
    from anklelab.experiments import simulate_perturberator
    from anklelab.experiments.capstan_ident import simulate_ident
    from anklelab.pipelines.walking import WalkingSettings, fit_platform_filters

    root = tmp_path_factory.mktemp("fuzz")
    session = simulate_perturberator(
        trials_per_point=2, n_unperturbed=4, n_calibration=2, bench=False, seed=2
    )
    results = root / "results"
    results.mkdir()
    (results / "friction.json").write_text(
        json.dumps(
            {
                "inertia_kgm2": 7.5e-4,
                "viscous_nms_per_rad": {"cw": 6e-4, "ccw": 6e-4},
                "coulomb_nm": {"cw": 0.035, "ccw": 0.038},
                "stribeck_velocity_rad_s": 3.2,
                "static_friction_nm": 0.045,
            }
        )
    )
    filters = fit_platform_filters(session, WalkingSettings())[0].to_dict()
    (root / "scratch").mkdir()
    return World(
        save_session(session, root / "s", format="dir"),
        save_session(session, root / "s.h5"),
        write_ident_directory(simulate_ident(seed=1), root / "ident"),
        results,
        filters,
        root / "scratch",
    )


def invoke(args: list[str], monkeypatch, capsys) -> tuple[object, str]:
    from anklelab.cli import run

    monkeypatch.setattr(sys, "argv", ["anklelab", *map(str, args)])
    capsys.readouterr()
    try:
        run()
        code: object = 0
    except SystemExit as exit:
        code = exit.code
    return code, capsys.readouterr().err


# --- bad values -----------------------------------------------------------------------------

NOT_NUMBERS = st.sampled_from(["nan", "inf", "-inf", "1e400", "abc", "", "1,5", "0x1f"])
NOT_INTEGERS = NOT_NUMBERS | st.sampled_from(["1.5", "1e23", "2.5e3"])


def below(limit: float) -> st.SearchStrategy[str]:
    return st.floats(max_value=limit, exclude_max=True, allow_nan=False, allow_infinity=False).map(
        repr
    )


def above(limit: float) -> st.SearchStrategy[str]:
    return st.floats(min_value=limit, exclude_min=True, allow_nan=False, allow_infinity=False).map(
        repr
    )


def ints_below(limit: int) -> st.SearchStrategy[str]:
    return st.integers(max_value=limit - 1).map(str)


def not_one_of(*choices: str) -> st.SearchStrategy[str]:
    """Text that is none of ``choices`` (and no option name, such as ``--help``)."""
    return st.text(max_size=12).filter(lambda text: text not in choices and text[:1] != "-")


@dataclass(frozen=True)
class Bad:
    """A file or directory to make: ``kind`` and, for files, ``content``."""

    kind: str  # missing, directory, fifo, file, link-out (a symbolic link leaving the world)
    content: bytes = b""

    def make(self, folder: Path, name: str) -> Path:
        path = folder / name
        if self.kind == "directory":
            path.mkdir()
        elif self.kind == "fifo":
            os.mkfifo(path)
        elif self.kind == "file":
            path.write_bytes(self.content)
        elif self.kind == "link-out":
            path.symlink_to("/dev/zero")
        return path


def files(*contents: st.SearchStrategy[bytes]) -> st.SearchStrategy[Bad]:
    """Bad files: wrong kinds, garbage, and the given contents."""
    kinds = st.sampled_from([Bad("missing"), Bad("directory"), Bad("fifo"), Bad("link-out")])
    garbage = st.binary(max_size=300).map(lambda b: Bad("file", b"\xff\xfe" + b))
    return kinds | garbage | st.one_of(*contents).map(lambda b: Bad("file", b))


def deep(opening: str, closing: str, prefix: str = "") -> st.SearchStrategy[bytes]:
    return st.integers(2000, 6000).map(lambda n: (prefix + opening * n + closing * n).encode())


TOML_VALUES = st.sampled_from(['"text"', "nan", "-1", "-2.5", "{ a = 1 }", '[1, "a"]', "-inf"])


def toml_documents(keys: list[str]) -> st.SearchStrategy[bytes]:
    """TOML that parses but is wrong: a known key with a bad value, or an unknown key."""
    known = st.tuples(st.sampled_from(keys), TOML_VALUES).map(lambda kv: f"{kv[0]} = {kv[1]}\n")
    unknown = st.from_regex(r"[a-z_]{1,12}", fullmatch=True).filter(lambda k: k not in keys)
    return (known | unknown.map(lambda k: f"{k} = 1\n")).map(str.encode)


def corrupted_parameter_file(name: str) -> st.SearchStrategy[bytes]:
    """The shipped parameter file with one value replaced by a table, or one line dropped."""
    lines = platform_file(name).read_text().splitlines()
    values = [i for i, line in enumerate(lines) if line.split("=")[0].strip().isidentifier()]

    def corrupt(args: tuple[int, bool]) -> bytes:
        i, drop = args
        changed = list(lines)
        key = changed[i].split("=")[0].strip()
        changed[i] = "" if drop else f"{key} = {{ a = 1 }}"
        return "\n".join(changed).encode()

    return st.tuples(st.sampled_from(values), st.booleans()).map(corrupt)


JSON_VALUES = st.sampled_from(["text", [], {}, None, [[["x"]]], True, -1])
"""Values of the wrong type (``-1`` only where a key must be positive, see its use)."""
JSON_SHAPES = st.sampled_from([b"[1, 2]", b'"a string"', b"3", b"null", b"{}", b"{"])


def json_documents(valid: dict) -> st.SearchStrategy[bytes]:
    """JSON of the wrong shape: not an object, or one key of ``valid`` given a value of the
    wrong type."""
    wrong = JSON_VALUES.filter(lambda value: value != -1)
    broken = st.tuples(st.sampled_from(sorted(valid)), wrong).map(
        lambda kv: json.dumps({**valid, kv[0]: kv[1]}).encode()
    )
    return JSON_SHAPES | deep("[", "]") | broken


FILTER_KEYS = ["format", "inputs", "n_lags", "angle_lags", "method", "cutoff_hz", "filter_order",
               "derivative_window", "channels", "irf", "fs_hz", "order"]  # fmt: skip


def filter_file(w: World, value: object, folder: Path) -> Path:
    """A filter file: a wrong shape, or the valid one with one key given a bad value."""
    if isinstance(value, Bad):
        return value.make(folder, "f.json")
    key, bad = value
    (folder / "f.json").write_text(json.dumps({**w.filters, key: bad}))
    return folder / "f.json"


# --- slots: one corrupted part of one command -----------------------------------------------


@dataclass(frozen=True)
class Slot:
    name: str
    values: st.SearchStrategy
    args: Callable[[World, object, Path], list[str]]  # (world, bad value, fresh folder)


def option(command: list[str], flag: str, base: Callable[[World, Path], list[str]]):
    return lambda w, value, folder: [*command, *base(w, folder), flag, value]


def analyze_base(w: World, folder: Path) -> list[str]:
    return ["analyze", w.native, "--out", folder / "o", "--no-figures"]


def filters_base(w: World, folder: Path) -> list[str]:
    return ["identify", "platform-filters", w.session, "--out", folder / "f.json"]


def friction_base(w: World, folder: Path) -> list[str]:
    return ["identify", "friction", w.ident, "--out", folder / "o", "--no-figures"]


def simulate_base(w: World, folder: Path) -> list[str]:
    small = ["--trials-per-point", "1", "--unperturbed", "1", "--no-bench"]
    return ["simulate", "perturberator", "--out", folder / "x.h5", *small]


def file_slot(name, build):
    """A slot whose value is a :class:`Bad` file named ``name`` in the example's folder."""
    return lambda w, bad, folder: build(w, bad.make(folder, name), folder)


def settings_keys() -> list[str]:
    from anklelab.pipelines import WalkingSettings

    return sorted(WalkingSettings.model_fields)


SETTINGS = files(toml_documents(settings_keys()), deep("[", "]", "x = "), deep("{a=", "}", "b = "))
PERTURBERATOR = files(corrupted_parameter_file("perturberator"), st.just(b""))
CAPSTAN = files(corrupted_parameter_file("capstan"), st.just(b""))


BAD_OUTS = st.sampled_from(["file", "directory", "inside", "parent-file", "link"])
BAD_OUTS_NO_INPUT = st.sampled_from(["file", "directory", "parent-file", "link"])


def bad_out(how: str, folder: Path, session: Path | None) -> Path:
    """An output path that must be refused: it exists (no --force), is a file under a file,
    lies inside the input ``session``, or is a symbolic link."""
    if how == "file":
        (folder / "o").write_text("precious")
    elif how == "directory":
        (folder / "o").mkdir()
        (folder / "o" / "notes.txt").write_text("mine")
    elif how == "inside":
        return session / "o"
    elif how == "parent-file":
        (folder / "f").write_text("x")
        return folder / "f" / "o"
    else:
        (folder / "o").symlink_to(folder / "elsewhere")
    return folder / "o"


def out_slot(name, build, reads=None):
    """A slot making ``--out`` bad; ``build(world, out)`` gives the command, ``reads(world)``
    its input (an output inside it is refused)."""

    def args(w, how, folder):
        return build(w, bad_out(how, folder, reads(w) if reads else None))

    return Slot(name, BAD_OUTS if reads else BAD_OUTS_NO_INPUT, args)


FRICTION = {
    "inertia_kgm2": 1e-3,
    "viscous_nms_per_rad": {"cw": 1.0, "ccw": 1.0},
    "coulomb_nm": {"cw": 1.0, "ccw": 1.0},
    "stribeck_velocity_rad_s": 1.0,
    "static_friction_nm": 1.0,
}
WALKING = {"platform_filters": {}, "timing_points": []}
INTEGERS_ABOVE = st.integers(2, 10**30).map(str)


def session_of(w: World) -> Path:
    return w.session


SLOTS = [
    # session info / import: the session path's kind (its content is the data readers')
    Slot("session info SESSION", st.sampled_from([Bad("missing"), Bad("fifo"), Bad("link-out")]),
         file_slot("s", lambda w, p, f: ["session", "info", p])),
    Slot("import SOURCE", st.sampled_from([Bad("missing"), Bad("fifo")]),
         file_slot("s", lambda w, p, f: ["import", p, "--out", f / "o.h5"])),
    out_slot("import --out", lambda w, o: ["import", w.session, "--out", o], session_of),
    # analyze
    Slot("analyze --settings", SETTINGS,
         file_slot("st.toml", lambda w, p, f: [*analyze_base(w, f), "--settings", p])),
    Slot("analyze --filters",
         files(JSON_SHAPES, deep("[", "]")) | st.tuples(st.sampled_from(FILTER_KEYS), JSON_VALUES),
         lambda w, v, f: [*analyze_base(w, f), "--filters", filter_file(w, v, f)]),
    Slot("analyze --seed", ints_below(0) | NOT_INTEGERS, option([], "--seed", analyze_base)),
    out_slot("analyze --out", lambda w, o: ["analyze", w.session, "--out", o], session_of),
    # identify platform-filters
    Slot("platform-filters --settings", SETTINGS,
         file_slot("st.toml", lambda w, p, f: [*filters_base(w, f), "--settings", p])),
    Slot("platform-filters --inputs", not_one_of("angle", "velocity", "acceleration"),
         option([], "--inputs", filters_base)),
    Slot("platform-filters --fit-trial", ints_below(0) | NOT_INTEGERS | INTEGERS_ABOVE,
         option([], "--fit-trial", filters_base)),
    out_slot("platform-filters --out",
             lambda w, o: ["identify", "platform-filters", w.session, "--out", o], session_of),
    # identify friction
    Slot("friction DIR", st.sampled_from([Bad("missing"), Bad("fifo"), Bad("file", b"x")]),
         file_slot("ident", lambda w, p, f: ["identify", "friction", p, "--out", f / "o"])),
    Slot("friction --min-speed", below(0) | NOT_NUMBERS, option([], "--min-speed", friction_base)),
    Slot("friction --stribeck-exponent", below(0.1) | above(10) | NOT_NUMBERS,
         option([], "--stribeck-exponent", friction_base)),
    Slot("friction --zero-torque", below(0) | NOT_NUMBERS,
         option([], "--zero-torque", friction_base)),
    out_slot("friction --out", lambda w, o: ["identify", "friction", w.ident, "--out", o],
             lambda w: w.ident),
    # simulate perturberator / capstan-ident
    Slot("simulate --trials-per-point",
         ints_below(1) | st.integers(1001, 10**30).map(str) | NOT_INTEGERS,
         option([], "--trials-per-point", simulate_base)),
    Slot("simulate --unperturbed",
         ints_below(0) | st.integers(4001, 10**30).map(str) | NOT_INTEGERS,
         option([], "--unperturbed", simulate_base)),
    Slot("simulate --seed", ints_below(0) | NOT_INTEGERS, option([], "--seed", simulate_base)),
    Slot("simulate --foot", not_one_of("prosthetic", "human"), option([], "--foot", simulate_base)),
    Slot("simulate --format", not_one_of("h5", "dir"), option([], "--format", simulate_base)),
    Slot("simulate --params", PERTURBERATOR,
         file_slot("p.toml", lambda w, p, f: [*simulate_base(w, f), "--params", p])),
    out_slot("simulate --out", lambda w, o: ["simulate", "perturberator", "--out", o]),
    Slot("capstan-ident --sample-rate", below(1000) | above(10000) | NOT_NUMBERS,
         lambda w, v, f: ["simulate", "capstan-ident", "--out", f / "o", "--sample-rate", v]),
    Slot("capstan-ident --params", CAPSTAN,
         file_slot("p.toml",
                   lambda w, p, f: ["simulate", "capstan-ident", "--out", f / "o", "--params", p])),
    # report
    Slot("report DIR", st.sampled_from([Bad("missing"), Bad("fifo"), Bad("file", b"{}"),
                                        Bad("directory")]),
         file_slot("r", lambda w, p, f: ["report", p])),
    Slot("report friction.json", files(json_documents(FRICTION)),
         file_slot("friction.json", lambda w, p, f: ["report", f, "--out", f / "r.html"])),
    Slot("report results.json", files(json_documents(WALKING)),
         file_slot("results.json", lambda w, p, f: ["report", f, "--out", f / "r.html"])),
    Slot("report figure", st.sampled_from([Bad("fifo"), Bad("link-out"), Bad("directory")]),
         lambda w, bad, f: report_with_figure(w, bad, f)),
    Slot("report --out", BAD_OUTS, lambda w, how, f: report_out(w, how, f)),
    # platform show / check / bode
    Slot("platform show NAME", not_one_of("perturberator", "capstan"),
         lambda w, v, f: ["platform", "show", v]),
    Slot("platform show --params", CAPSTAN,
         file_slot("p.toml", lambda w, p, f: ["platform", "show", "capstan", "--params", p])),
    Slot("platform check FILE", PERTURBERATOR,
         file_slot("p.toml", lambda w, p, f: ["platform", "check", "perturberator", p])),
    Slot("platform bode --params", PERTURBERATOR,
         file_slot("p.toml", lambda w, p, f: ["platform", "bode", "--params", p])),
    Slot("platform bode --plot", st.sampled_from(["x.xyz", "x", "dir", "exists", "parent-file"]),
         lambda w, how, f: bode_plot(how, f)),
    # demo
    Slot("demo --seed", ints_below(0) | NOT_INTEGERS,
         lambda w, v, f: ["demo", "--quick", "--out", f / "d", "--seed", v]),
    out_slot("demo --out", lambda w, o: ["demo", "--quick", "--out", o]),
]  # fmt: skip


def report_with_figure(w: World, bad: Bad, folder: Path) -> list[str]:
    """A figure that is not a regular file inside DIR: never embedded (a warning), and the
    report is written; so this slot expects exit 0. Handled in the test."""
    (folder / "friction.json").write_text(json.dumps(FRICTION))
    bad.make(folder, f"{FRICTION_FIGURES[0][0]}.png")
    return ["report", folder, "--out", folder / "r.html"]


def report_out(w: World, how: str, folder: Path) -> list[str]:
    results = folder / "r"
    results.mkdir()
    (results / "friction.json").write_text(json.dumps(FRICTION))
    if how == "inside":  # replacing a file the report reads
        return ["report", results, "--out", results / "friction.json", "--force"]
    return ["report", results, "--out", bad_out(how, folder, None)]


def bode_plot(how: str, folder: Path) -> list[str]:
    if how in ("x.xyz", "x"):
        return ["platform", "bode", "--plot", folder / how]
    if how == "dir":
        (folder / "d.png").mkdir()
        return ["platform", "bode", "--plot", folder / "d.png"]
    if how == "exists":
        (folder / "b.png").write_text("mine")
        return ["platform", "bode", "--plot", folder / "b.png"]
    (folder / "f").write_text("x")
    return ["platform", "bode", "--plot", folder / "f" / "b.png"]


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_bad_input_ends_in_one_error_line(world, data, monkeypatch, capsys):
    slot = data.draw(st.sampled_from(SLOTS), label="slot")
    value = data.draw(slot.values, label="value")
    event(slot.name)
    event(f"class: {value.kind if isinstance(value, Bad) else 'option value'}")
    args = slot.args(world, value, world.fresh())
    code, err = invoke(args, monkeypatch, capsys)
    assert "Traceback" not in err, (args, err)
    if slot.name == "report figure":  # refused with a warning; the rest of the report is fine
        assert code == 0 and "not embedded" in err, (args, err)
        return
    errors = [line for line in err.splitlines() if line.startswith("error: ")]
    assert code == 2 and len(errors) == 1, (args, code, err)
    event(f"ends: {errors[0].split(':')[-1].strip()[:40]}")


def test_every_slot_corrupts_a_command_that_otherwise_runs(world, monkeypatch, capsys):
    """The valid base of the cheap commands runs (exit 0): a slot's error is its own."""
    folder = world.fresh()
    for args in (
        [*filters_base(world, folder)],
        ["report", world.results, "--out", folder / "r.html"],
        ["platform", "check", "perturberator", platform_file("perturberator")],
        ["session", "info", world.session],
    ):
        code, err = invoke(args, monkeypatch, capsys)
        assert code == 0, (args, err)


# --- damaged session directories: one clear error, no output --------------------------------


def corrupted_session(world: World, folder: Path, change: str) -> Path:
    import shutil

    session = Path(shutil.copytree(world.session, folder / "s"))
    if change == "toml nested 5000 deep":
        with (session / "session.toml").open("a") as f:
            f.write("x = " + "[" * 5000 + "]" * 5000 + "\n")
    else:  # a 200 KB text cell in a recording
        recording = sorted((session / "walking").glob("*.csv"))[-1]
        lines = recording.read_text().splitlines()
        lines[3] = "x" * 200_000 + lines[3]
        recording.write_text("\n".join(lines) + "\n")
    return session


@pytest.mark.parametrize("change", ["toml nested 5000 deep", "200 KB text cell"])
def test_data_reader_cases(world, monkeypatch, capsys, change):
    folder = world.fresh()
    session = corrupted_session(world, folder, change)
    code, err = invoke(["import", session, "--out", folder / "o.h5"], monkeypatch, capsys)
    assert code == 2 and "Traceback" not in err, err
    assert not (folder / "o.h5").exists()


# --- known failures in other layers (the owner removes the mark with the fix) ---------------


@pytest.mark.xfail(strict=True, reason="settings model (pipelines): lead; infinities accepted")
@pytest.mark.parametrize("line", ["window_ms = inf", "heel_contact_hold_ms = inf"])
def test_infinite_settings(world, monkeypatch, capsys, line):
    folder = world.fresh()
    (folder / "st.toml").write_text(line + "\n")
    args = [*analyze_base(world, folder), "--settings", folder / "st.toml"]
    code, err = invoke(args, monkeypatch, capsys)
    assert code == 2 and "Traceback" not in err, err
