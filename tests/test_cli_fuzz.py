"""No tracebacks from the CLI: every command, driven with generated bad options and bad files,
ends in exit code 2 and exactly one ``error:`` line (issue 11).

Each example corrupts one *slot* of one command (an option value, an input file's content or
kind, an output path) and leaves the rest valid, so that the command would otherwise run. Bad
values: garbage bytes, empty files, wrong types, huge numbers, NaN and infinities, negative
counts, paths that are directories, missing, FIFOs or symbolic links, outputs that exist or lie
inside an input. The reader and settings cases that once failed are kept at the end as
regression tests.

``ANKLELAB_FUZZ_EXAMPLES`` sets the number of examples (default 300); hypothesis's statistics
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

EXAMPLES = int(os.environ.get("ANKLELAB_FUZZ_EXAMPLES", "300"))
SCENE = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "hill_walk.toml"


# --- the valid world every example starts from ---------------------------------------------


@dataclass(frozen=True)
class World:
    session: Path  # a small twin session directory that every command accepts
    native: Path  # the same session as a native file
    ident: Path  # a capstan identification directory
    results: Path  # a results directory `report` accepts
    study: Path  # a tiny study file (`study` would run it)
    filters: dict = field(repr=False)  # a valid platform-filter document
    scratch: Path  # where each example makes its files
    scene: Path  # a capstan scene file

    def fresh(self) -> Path:
        return Path(tempfile.mkdtemp(dir=self.scratch))


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    from anklelab.data import save_session
    from anklelab.data.capstan_ident import write_ident_directory
    from anklelab.experiments import simulate_perturberator
    from anklelab.experiments.capstan import simulate_ident
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
    (root / "study.toml").write_text(STUDY)
    scene = root / "scene.toml"
    scene.write_bytes(SCENE.read_bytes())
    return World(
        save_session(session, root / "s", format="dir"),
        save_session(session, root / "s.h5"),
        write_ident_directory(simulate_ident(seed=1), root / "ident"),
        results,
        root / "study.toml",
        filters,
        root / "scratch",
        scene,
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


def corrupted_toml(path: Path, *, drop: bool = True) -> st.SearchStrategy[bytes]:
    """A valid TOML file with one value replaced by a table, or (``drop``) one line dropped."""
    lines = path.read_text().splitlines()
    values = [i for i, line in enumerate(lines) if line.split("=")[0].strip().isidentifier()]

    def corrupt(args: tuple[int, bool]) -> bytes:
        i, dropped = args
        changed = list(lines)
        key = changed[i].split("=")[0].strip()
        changed[i] = "" if dropped else f"{key} = {{ a = 1 }}"
        return "\n".join(changed).encode()

    return st.tuples(st.sampled_from(values), st.booleans() if drop else st.just(False)).map(
        corrupt
    )


def corrupted_parameter_file(name: str) -> st.SearchStrategy[bytes]:
    """The shipped parameter file with one value replaced by a table, or one line dropped."""
    return corrupted_toml(platform_file(name))


JSON_VALUES = st.sampled_from(["text", [], {}, None, [[["x"]]], True, -1])
"""Values of the wrong type (``-1`` only where a key must be positive, see its use)."""
JSON_SHAPES = st.sampled_from([b"[1, 2]", b'"a string"', b"3", b"null", b"{}", b"{"])


def json_documents(valid: dict) -> st.SearchStrategy[bytes]:
    """JSON of the wrong shape: not an object, or one key of ``valid`` given a value of the
    wrong type."""
    wrong = JSON_VALUES.filter(lambda value: value != -1)
    broken = (
        st.tuples(st.sampled_from(sorted(valid)), wrong)
        .filter(lambda kv: kv[1] != valid[kv[0]])  # `[]` is a valid list of timing points
        .map(lambda kv: json.dumps({**valid, kv[0]: kv[1]}).encode())
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


STUDY = """name = "tiny"
seeds = [0, 1]
[twin]
trials_per_point = 3
foot = "prosthetic"
[analysis]
bootstrap_reps = 10
[grid]
"analysis.window_ms" = [75.0, 100.0]
"""
STUDY_TOP = ["seeds", "format", "params_file", "twin", "analysis", "grid", "sample", "params"]
STUDY_INNER = ["twin.trials_per_point", "twin.foot", "twin.noise_scale", "twin.randomised",
               "analysis.bootstrap_reps", "analysis.window_ms"]  # fmt: skip


def study_document(args: tuple[str, str]) -> bytes:
    """The tiny study with one key (top level, in a table, or a grid value) given a bad value,
    or an unknown key added."""
    key, value = args
    if "." in key:
        table, name = key.split(".")
        lines = [line for line in STUDY.splitlines() if not line.startswith(f"{name} =")]
        at = lines.index(f"[{table}]") + 1
        return "\n".join([*lines[:at], f"{name} = {value}", *lines[at:]]).encode()
    if key == "grid-value":
        return STUDY.replace("[75.0, 100.0]", f"[75.0, {value}]").encode()
    kept, skip = [], False
    for line in STUDY.splitlines():  # drop the key's line or table
        if line.startswith("["):
            skip = line == f"[{key}]"
        if not skip and not line.startswith(f"{key} ="):
            kept.append(line)
    return f"{key} = {value}\n{chr(10).join(kept)}".encode()


STUDY_FILES = files(
    st.tuples(st.sampled_from([*STUDY_TOP, *STUDY_INNER, "grid-value"]), TOML_VALUES).map(
        study_document
    ),
    st.from_regex(r"[a-z_]{1,12}", fullmatch=True)
    .filter(lambda k: k not in (*STUDY_TOP, "name"))
    .map(lambda k: f"{k} = 1\n{STUDY}".encode()),
)


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


def study_base(w: World, folder: Path) -> list[str]:
    return ["study", w.study, "--out", folder / "o", "--no-figures"]


def design_base(w: World, folder: Path) -> list[str]:
    return ["design", "--out", folder / "o", "--pilot", "2,3", "--seeds", "1"]


def batch_base(w: World, folder: Path) -> list[str]:
    return ["batch", w.native, "--out", folder / "o", "--no-figures"]


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
_ESTIMATE = {"mean": 1200.0, "sd": 10.0, "ci95": [1180.0, 1230.0], "poorly_determined": False}
TIMING_POINT = {
    "delay_ms": 100.0,
    "direction": "dorsi",
    "n_perturbed": 2,
    "n_unperturbed": 4,
    "cop_m": 0.06,
    "stiffness_nm_per_rad": _ESTIMATE,
    "damping_nms_per_rad": _ESTIMATE,
    "inertia_kgm2": _ESTIMATE,
    "vaf_percent": _ESTIMATE,
    "stiffness_change_fraction": _ESTIMATE,
    "stiffness_model": "constant",
    "stiffness_changes": False,
    "window_sensitivity": {"75": {"stiffness_nm_per_rad": 1190.0}},
    "warnings": ["dorsi/100: a doubt"],
}
"""A valid ``results.json`` timing point as the report reads it (intervals, flags, warnings)."""
TIMING_POINT_PATHS = [(key,) for key in TIMING_POINT] + [
    ("stiffness_nm_per_rad", key) for key in _ESTIMATE
]


def walking_document(change: tuple[tuple[str, ...], object]) -> bytes:
    """A walking ``results.json`` with one timing point, one of its values (or one of its
    stiffness estimate's) replaced."""
    path, value = change
    point = {**TIMING_POINT, "stiffness_nm_per_rad": dict(_ESTIMATE)}
    node = point
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return json.dumps({**WALKING, "timing_points": [point], "warnings": ["a doubt"]}).encode()


def valid_walking(folder: Path) -> Path:
    """A results directory holding :data:`TIMING_POINT` in a walking ``results.json``."""
    (folder / "w").mkdir()
    document = {**WALKING, "timing_points": [TIMING_POINT]}
    (folder / "w" / "results.json").write_text(json.dumps(document))
    return folder / "w"


TIMING_POINT_VALUES = st.tuples(
    st.sampled_from(TIMING_POINT_PATHS),
    JSON_VALUES | st.sampled_from([[1.0], [1.0, "x"], [1.0, 2.0, 3.0], "plantar", 1e308]),
).map(walking_document)
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
    Slot("report timing point", TIMING_POINT_VALUES.map(lambda b: Bad("file", b)),
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
    # study / design / batch (they run on Dask: every slot must fail before a worker starts)
    Slot("study STUDY", STUDY_FILES,
         file_slot("st.toml", lambda w, p, f: ["study", p, "--out", f / "o"])),
    Slot("study --workers", ints_below(1) | NOT_INTEGERS, option([], "--workers", study_base)),
    Slot("study --retries", ints_below(0) | NOT_INTEGERS, option([], "--retries", study_base)),
    out_slot("study --out", lambda w, o: ["study", w.study, "--out", o], lambda w: w.study),
    Slot("design --interval", below(0) | NOT_NUMBERS | st.just("0"),
         option([], "--interval", design_base)),
    Slot("design --change", below(0) | NOT_NUMBERS | st.just("0"),
         option([], "--change", design_base)),
    Slot("design --power", below(0) | above(1) | NOT_NUMBERS | st.sampled_from(["0", "1"]),
         option([], "--power", design_base)),
    Slot("design --pilot", st.sampled_from(["", "a", "5", "1,2", "10,10", "-3,4", "2;3", "2,,3"]),
         option([], "--pilot", design_base)),
    Slot("design --seeds", ints_below(1) | NOT_INTEGERS, option([], "--seeds", design_base)),
    Slot("design --foot", not_one_of("prosthetic", "human"), option([], "--foot", design_base)),
    Slot("design --params", PERTURBERATOR,
         file_slot("p.toml", lambda w, p, f: [*design_base(w, f), "--params", p])),
    Slot("design --settings", SETTINGS,
         file_slot("st.toml", lambda w, p, f: [*design_base(w, f), "--settings", p])),
    out_slot("design --out", lambda w, o: ["design", "--out", o, "--pilot", "2,3"]),
    Slot("batch SESSIONS", st.sampled_from([Bad("missing"), Bad("fifo"), Bad("link-out")]),
         file_slot("s", lambda w, p, f: ["batch", w.native, p, "--out", f / "o"])),
    Slot("batch --settings", SETTINGS,
         file_slot("st.toml", lambda w, p, f: [*batch_base(w, f), "--settings", p])),
    Slot("batch --workers", ints_below(1) | NOT_INTEGERS, option([], "--workers", batch_base)),
    out_slot("batch --out", lambda w, o: ["batch", w.session, "--out", o], session_of),
    # demo
    Slot("demo --seed", ints_below(0) | NOT_INTEGERS,
         lambda w, v, f: ["demo", "--quick", "--out", f / "d", "--seed", v]),
    out_slot("demo --out", lambda w, o: ["demo", "--quick", "--out", o]),
]  # fmt: skip


# --- the capstan commands -------------------------------------------------------------------

CAPSTAN_BASES = {  # a short valid run of each command; a slot's value comes last and wins
    "tune": [],
    "step": ["--degrees", "5", "--hold", "0.3"],
    "chirp": ["--duration", "1", "--f1", "2"],
    "envelope": ["--no-check", "--points", "3"],
    "observe": ["--duration", "2"],
    "render": ["--duration", "6"],
    "scene": [SCENE],
    "zwidth": ["--damping", "0", "--iterations", "1"],
    "teleop": ["--delays", "0", "--duration", "4"],
}
SIMULATING = [name for name in CAPSTAN_BASES if name != "tune"]


def from_zero(limit: float) -> st.SearchStrategy[str]:
    """Not above ``limit``: a strict lower bound, 0 included."""
    return below(limit) | st.just(str(limit))


def ranged(low: st.SearchStrategy[str], high: float) -> st.SearchStrategy[str]:
    return low | above(high) | NOT_NUMBERS


def capstan_args(command: str, *more: object) -> list[object]:
    return ["capstan", command, *CAPSTAN_BASES[command], *more]


def capstan_option(command: str, flag: str, values: st.SearchStrategy) -> Slot:
    return Slot(f"capstan {command} {flag}", values,
                lambda w, v, f: capstan_args(command, flag, v))  # fmt: skip


def shared_option(flag: str, values: st.SearchStrategy) -> Slot:
    """An option every simulating capstan command shares, on one of them."""
    return Slot(f"capstan * {flag}", st.tuples(st.sampled_from(SIMULATING), values),
                lambda w, v, f: capstan_args(v[0], flag, v[1]))  # fmt: skip


def shared_file(flag: str, name: str, bad: st.SearchStrategy[Bad]) -> Slot:
    return Slot(f"capstan * {flag}", st.tuples(st.sampled_from(SIMULATING), bad),
                lambda w, v, f: capstan_args(v[0], flag, v[1].make(f, name)))  # fmt: skip


TERRAINS = files(st.sampled_from([
    b"distance_m,height_m\n0,0\n",
    b"a,b\n1,2\n3,4\n",
    b"distance_m,height_m\n0,nan\n1,2\n",
    b"distance_m,height_m\n0,0\n1\n",
    b"distance_m,height_m\n0,0\n1,x\n",
]))  # fmt: skip
SCENE_KEYS = ["name", "walking_speed_m_s", "foot_length_m", "person", "voluntary_torque_rms_nm",
              "terrain", "compliant"]  # fmt: skip
INVALID_SCENES = st.sampled_from([
    b'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slope"\nlength_m = 2\n',
    b'name = "x"\nwalking_speed_m_s = -1.0\n[[terrain]]\nkind = "flat"\nlength_m = 2\n',
    b'name = "x"\nwalking_speed_m_s = 1.0\nterrain = []\n',
    b'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "flat"\nlength_m = 2\n'
    b"[[compliant]]\nstart_m = 1.0\nlength_m = 5.0\nstiffness_nm_per_rad = 50\n"
    b"damping_nms_per_rad = 1\n",
    b'name = "wall"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slope"\nlength_m = 3\n'
    b"grade_deg = 39\n",
])  # fmt: skip
NUMBER_LISTS = st.sampled_from(["abc", "5,,10", "", "5;10", "1,x"])
SETTLING = ranged(from_zero(0), 10)

CAPSTAN_SLOTS = [
    shared_option("--sample-rate", ranged(below(1000), 10000)),
    shared_option("--friction-comp", ranged(below(0), 1)),
    shared_option("--settling-time", SETTLING),
    shared_option("--person", not_one_of("none", "seated", "standing", "walking")),
    shared_option("--seed", ints_below(0) | NOT_INTEGERS),
    shared_file("--params", "p.toml", CAPSTAN),
    shared_file("--friction-model", "friction.json", files(json_documents(FRICTION))),
    out_slot("capstan --out", lambda w, o: ["capstan", "tune", "--out", o]),
    out_slot("capstan scene --out", lambda w, o: ["capstan", "scene", w.scene, "--out", o],
             lambda w: w.scene),
    capstan_option("tune", "--integral-fraction", ranged(below(0), 10)),
    capstan_option("tune", "--settling-time", SETTLING),
    capstan_option("step", "--hold", ranged(from_zero(0), 60)),
    capstan_option("step", "--degrees", NUMBER_LISTS | below(-90) | above(90)),
    capstan_option("chirp", "--amplitude", ranged(from_zero(0), 40)),
    capstan_option("chirp", "--f0", ranged(from_zero(0), 100)),
    capstan_option("chirp", "--f1", ranged(from_zero(0), 100)),
    capstan_option("chirp", "--duration", ranged(below(0.5), 600)),
    capstan_option("chirp", "--tracking", not_one_of("pid", "feedforward", "zpetc")),
    capstan_option("envelope", "--low", ranged(below(0.01), 100)),
    capstan_option("envelope", "--high", ranged(below(0.01), 100)),
    capstan_option("envelope", "--points", ints_below(2) | INTEGERS_ABOVE.filter(
        lambda n: int(n) > 60) | NOT_INTEGERS),
    capstan_option("observe", "--task", not_one_of("hold", "track")),
    capstan_option("observe", "--cutoff", ranged(from_zero(0), 5000)),
    capstan_option("observe", "--torque-rms", ranged(from_zero(0), 20)),
    capstan_option("observe", "--band", ranged(below(0.2), 50)),
    capstan_option("observe", "--duration", ranged(below(2), 600)),
    capstan_option("render", "--stiffness",
                   below(0) | st.sampled_from(["nan", "-inf", "abc", "", "1,5"])),
    capstan_option("render", "--damping", ranged(below(0), 1000)),
    capstan_option("render", "--inertia", ranged(from_zero(0), 10)),
    capstan_option("render", "--mode", not_one_of("admittance", "impedance")),
    capstan_option("render", "--speed", ranged(from_zero(0), 3)),
    capstan_option("render", "--torque-rms", ranged(from_zero(0), 20)),
    capstan_option("render", "--duration", ranged(below(6), 600)),
    Slot("capstan render --terrain", TERRAINS,
         file_slot("t.csv", lambda w, p, f: capstan_args("render", "--terrain", p))),
    Slot("capstan scene SCENE",
         files(INVALID_SCENES, toml_documents(SCENE_KEYS), corrupted_toml(SCENE, drop=False)),
         file_slot("s.toml", lambda w, p, f: ["capstan", "scene", p])),
    capstan_option("zwidth", "--damping", NUMBER_LISTS | below(0) | above(100)),
    capstan_option("zwidth", "--iterations", ints_below(1) | INTEGERS_ABOVE.filter(
        lambda n: int(n) > 20) | NOT_INTEGERS),
    capstan_option("teleop", "--delays", NUMBER_LISTS | below(0) | above(2000)),
    capstan_option("teleop", "--jitter", ranged(below(0), 1000)),
    capstan_option("teleop", "--scheme", not_one_of("wave", "direct")),
    capstan_option("teleop", "--duration", ranged(below(4), 600)),
]  # fmt: skip
SLOTS += CAPSTAN_SLOTS


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
    if slot.name == "report timing point" and code == 0:  # a value the schema allows
        assert (args[-1]).is_file(), (args, err)
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
        ["report", valid_walking(folder), "--out", folder / "w.html"],
        ["platform", "check", "perturberator", platform_file("perturberator")],
        ["session", "info", world.session],
        capstan_args("tune"),
        capstan_args("envelope"),
        capstan_args("step"),
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


# --- cases that once failed in the data readers and the settings model ----------------------


@pytest.mark.parametrize(
    "line", ["window_ms = inf", "heel_contact_hold_ms = inf", "cutoff_hz = nan"]
)
def test_infinite_settings(world, monkeypatch, capsys, line):
    folder = world.fresh()
    (folder / "st.toml").write_text(line + "\n")
    args = [*analyze_base(world, folder), "--settings", folder / "st.toml"]
    code, err = invoke(args, monkeypatch, capsys)
    assert code == 2 and "Traceback" not in err, err
