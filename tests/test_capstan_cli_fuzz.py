"""Property-based: every `capstan` subcommand, `simulate capstan-ident` and `identify friction`,
given generated bad options or files, ends in exit code 2 with exactly one `error:` line and no
traceback.

The `capstan` group turns its usage errors (a value that is not a number, an unknown option or
choice) into one `error:` line itself. `simulate` and `identify` are other groups: for them the
generated values are well-formed numbers and files that the capstan implementation must refuse
(their usage errors are the command line's own business).
"""

from __future__ import annotations

import contextlib
import io
import sys
from functools import cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from anklelab.cli import run

BAD_NUMBERS = ["nan", "inf", "-inf", "-1", "-1e300", "1e300", "abc", "", "0x1p3", "--"]
COMMON = {  # shared options of the simulating capstan commands
    "--sample-rate": ["nan", "inf", "0", "-1000", "50", "1e9", "fast"],
    "--friction-comp": ["nan", "-0.5", "1.5", "inf"],
    "--settling-time": ["nan", "0", "-1", "1e9"],
    "--person": ["sitting", "", "NONE", "robot"],
    "--seed": ["1.5", "x", "nan"],
}
OWN = {
    "tune": {"--integral-fraction": ["-5", "nan", "inf", "1e9"], "--settling-time": ["0", "nan"]},
    "step": {"--hold": ["-1", "0", "nan", "inf", "1e6"], "--degrees": ["abc", "5,,10", "1e9"]},
    "chirp": {
        "--amplitude": ["0", "-5", "nan", "90"],
        "--f0": ["0", "nan", "-1"],
        "--f1": ["nan", "0", "1e6"],
        "--duration": ["0", "-3", "nan", "1e9"],
        "--tracking": ["ilc", "PID", ""],
    },
    "envelope": {
        "--low": ["0", "nan", "-1"],
        "--high": ["nan", "1e9"],
        "--points": ["1", "-3", "x"],
    },
    "observe": {
        "--task": ["juggle", ""],
        "--cutoff": ["0", "nan", "-20", "1e9"],
        "--torque-rms": ["-1", "nan", "0"],
        "--band": ["0", "nan", "1e9"],
        "--duration": ["0", "1", "nan"],
    },
    "render": {
        "--stiffness": ["-500", "nan", "-inf"],
        "--damping": ["-1", "nan", "inf"],
        "--inertia": ["0", "-0.2", "nan"],
        "--mode": ["teleport", ""],
        "--duration": ["0", "2", "nan"],
        "--speed": ["0", "-1", "nan"],
        "--terrain": ["nofile.csv", "/"],
    },
    "zwidth": {"--damping": ["abc", "-1", "nan", "1e9"], "--iterations": ["0", "-1", "100"]},
    "teleop": {
        "--delays": ["abc", "-50", "nan", "1e9"],
        "--jitter": ["-1", "nan", "inf"],
        "--scheme": ["tcp", ""],
        "--duration": ["0", "nan", "1"],
    },
}
BAD_FILES = {
    "missing": None,
    "directory": "dir",
    "empty": b"",
    "garbage": b"\x00\xff\xfe binary \x9c",
    "not toml": b"this is = = not toml [",
    "wrong types": b'[motor]\nresistance_ohm = "high"\n',
    "nested deep": b"a = " + b"[" * 5000 + b"]" * 5000 + b"\n",
    "json array": b"[1, 2, 3]\n",
}


def anklelab(*args: str) -> tuple[int, str]:
    """Run the entry point in-process; (exit code, stderr)."""
    err, out = io.StringIO(), io.StringIO()
    argv = sys.argv
    sys.argv = ["anklelab", *args]
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            run()
        code = 0
    except SystemExit as exit:
        code = exit.code if isinstance(exit.code, int) else 1
    finally:
        sys.argv = argv
    return code, err.getvalue()


def assert_one_error_line(code: int, err: str, args: tuple[str, ...]) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, (args, code, err)
    assert "Traceback" not in err, (args, err)
    assert sum(line.startswith("error:") for line in lines) == 1, (args, err)
    assert lines[0].startswith("error:"), (args, err)


def bad_file(tmp: Path, kind: str) -> str:
    path = tmp / f"bad_{kind.replace(' ', '_')}"
    content = BAD_FILES[kind]
    if content is None:
        return str(path)
    if content == "dir":
        path.mkdir(exist_ok=True)
        return str(path)
    path.write_bytes(content)  # type: ignore[arg-type]
    return str(path)


@cache
def ident_directory(root: str) -> Path:
    """A real identification directory (made once), for the options of `identify friction`."""
    out = Path(root) / "ident"
    code, err = anklelab("simulate", "capstan-ident", "--out", str(out))
    assert code == 0, err
    return out


FAST = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
OPTION_CASES = [
    (command, option, value)
    for command, own in OWN.items()
    for option, values in {**(COMMON if command != "tune" else {}), **own}.items()
    for value in values
    if not (command == "tune" and option in COMMON)
]


@FAST
@given(case=st.sampled_from(OPTION_CASES), extra=st.booleans())
def test_bad_options_of_every_capstan_command_end_in_one_error_line(tmp_path, case, extra):
    command, option, value = case
    args = ["capstan", command]
    if command == "scene":
        args.append("examples/scenes/hill_walk.toml")
    args += [option, value]
    if extra:  # an unknown option as well: still one error line
        args += ["--no-such-option"]
    assert_one_error_line(*anklelab(*args), tuple(args))


@FAST
@given(
    command=st.sampled_from(
        ["tune", "step", "chirp", "envelope", "observe", "render", "zwidth", "teleop"]
    ),
    kind=st.sampled_from(sorted(BAD_FILES)),
    option=st.sampled_from(["--params", "--friction-model"]),
)
def test_bad_parameter_and_model_files_end_in_one_error_line(tmp_path, command, kind, option):
    if command == "tune" and option == "--friction-model":
        option = "--params"
    args = ("capstan", command, option, bad_file(tmp_path, kind))
    assert_one_error_line(*anklelab(*args), args)


@FAST
@given(kind=st.sampled_from(sorted(BAD_FILES)))
def test_bad_scene_files_end_in_one_error_line(tmp_path, kind):
    args = ("capstan", "scene", bad_file(tmp_path, kind))
    assert_one_error_line(*anklelab(*args), args)


@pytest.mark.parametrize(
    "scene",
    [
        'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slope"\nlength_m = 2\n',
        'name = "x"\nwalking_speed_m_s = -1.0\n[[terrain]]\nkind = "flat"\nlength_m = 2\n',
        'name = "x"\nwalking_speed_m_s = 1.0\nterrain = []\n',
        'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "flat"\nlength_m = 2\n'
        "[[compliant]]\nstart_m = 1.0\nlength_m = 5.0\nstiffness_nm_per_rad = 50\n"
        "damping_nms_per_rad = 1\n",
        'name = "wall"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slope"\nlength_m = 3\n'
        "grade_deg = 39\n",
    ],
)
def test_invalid_scenes_end_in_one_error_line(tmp_path, scene):
    path = tmp_path / "scene.toml"
    path.write_text(scene)
    args = ("capstan", "scene", str(path))
    assert_one_error_line(*anklelab(*args), args)


@FAST
@given(
    value=st.sampled_from(["nan", "inf", "-inf", "0", "-5", "1e300", "50", "99.9", "1e6"]),
)
def test_simulate_capstan_ident_bad_sample_rates(tmp_path, value):
    args = ("simulate", "capstan-ident", "--out", str(tmp_path / "o"), "--sample-rate", value)
    assert_one_error_line(*anklelab(*args), args)


@FAST
@given(kind=st.sampled_from(sorted(BAD_FILES)))
def test_simulate_capstan_ident_bad_parameter_file(tmp_path, kind):
    args = (
        "simulate",
        "capstan-ident",
        "--out",
        str(tmp_path / "o"),
        "--params",
        bad_file(tmp_path, kind),
    )
    assert_one_error_line(*anklelab(*args), args)


@FAST
@given(
    option=st.sampled_from(["--min-speed", "--stribeck-exponent", "--zero-torque"]),
    value=st.sampled_from(["nan", "-1", "0", "-inf", "-1e300"]),
)
def test_identify_friction_bad_options(tmp_path_factory, option, value):
    if option == "--zero-torque" and value == "0":
        value = "-0.5"  # 0 is valid there
    directory = ident_directory(str(tmp_path_factory.getbasetemp()))
    out = tmp_path_factory.mktemp("fit")
    args = ("identify", "friction", str(directory), "--out", str(out), option, value)
    assert_one_error_line(*anklelab(*args), args)


@FAST
@given(kind=st.sampled_from(sorted(BAD_FILES)))
def test_identify_friction_bad_directories(tmp_path, kind):
    args = ("identify", "friction", bad_file(tmp_path, kind), "--out", str(tmp_path / "fit"))
    assert_one_error_line(*anklelab(*args), args)


def test_identify_friction_on_a_flipped_velocity_sign(tmp_path_factory):
    import shutil

    source = ident_directory(str(tmp_path_factory.getbasetemp()))
    flipped = tmp_path_factory.mktemp("flipped") / "ident"
    shutil.copytree(source, flipped)
    for path in [*flipped.glob("spindown/*_*.csv"), *flipped.glob("chirp/*.csv")]:
        lines = path.read_text().splitlines()
        header = lines[0].split(",")
        k = header.index("velocity_rad_s")
        rows = [line.split(",") for line in lines[1:]]
        for row in rows:
            row[k] = repr(-float(row[k]))
        path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    args = ("identify", "friction", str(flipped), "--out", str(tmp_path_factory.mktemp("fit")))
    code, err = anklelab(*args)
    assert_one_error_line(code, err, args)
    assert "sign flipped" in err
