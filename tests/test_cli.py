"""The anklelab command: version, help, parameter inspection, error exit codes."""

import os
import subprocess
import sys

from typer.testing import CliRunner

from anklelab import __version__
from anklelab.cli import app

runner = CliRunner()


def test_version():
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and __version__ in result.output


def test_help_lists_command_groups():
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "platform" in result.output and "demo" in result.output


def test_platform_show_lists_sources():
    result = runner.invoke(app, ["platform", "show", "perturberator"])
    assert result.exit_code == 0
    assert "transmission.ratio" in result.output and "paper 000" in result.output


def test_bad_parameter_file_exits_2_with_message(tmp_path):
    bad = tmp_path / "capstan.toml"
    bad.write_text("[motor]\nresistance_ohm = -1\n")
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            "from anklelab.cli import run; run()",
            "platform",
            "check",
            "capstan",
            str(bad),
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert str(bad) in proc.stderr and "motor.resistance_ohm" in proc.stderr


def test_import_does_not_load_matplotlib():
    code = "import sys, anklelab, anklelab.cli; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_report_exports_every_figure_function_without_importing_matplotlib():
    import anklelab.report
    from anklelab.report import figures_capstan, figures_walking

    for module in (figures_walking, figures_capstan):
        for name in module.__all__:
            assert name in anklelab.report.__all__
            assert getattr(anklelab.report, name) is getattr(module, name)
    code = "import sys, anklelab.report; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_cli_startup_loads_no_implementation():
    # commands import their implementation inside the command function, so that `--help` and
    # every command's start do not pay for numba, scipy, h5py or the twins
    heavy = ["numba", "scipy", "h5py", "matplotlib", "anklelab.sim", "anklelab.control"]
    heavy += ["anklelab.data", "anklelab.experiments", "anklelab.ident", "anklelab.pipelines"]
    code = f"import sys, anklelab.cli; print([m for m in {heavy!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_usage_error_exits_2_without_traceback():
    proc = subprocess.run(
        [sys.executable, "-c", "from anklelab.cli import run; run()", "import", "somewhere"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "Missing option" in proc.stderr and "Traceback" not in proc.stderr


def test_invalid_argument_value_exits_2_with_message():
    # a value the library rejects (ParameterError) is a clean error, not a traceback
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            "from anklelab.cli import run; run()",
            "capstan",
            "observe",
            "--task",
            "juggle",
            "--duration",
            "1",
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "--task" in proc.stderr and "'juggle'" in proc.stderr and "Traceback" not in proc.stderr


def test_analysis_pipeline_does_not_load_the_twins():
    code = (
        "import sys, anklelab.pipelines, anklelab.report;"
        "print('anklelab.experiments' in sys.modules);"
        "import anklelab.demo; print('anklelab.experiments' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


def _command_paths(command, path=()):
    """Every command and group below ``command``, as the words that name it."""
    yield path
    for name, sub in getattr(command, "commands", {}).items():
        yield from _command_paths(sub, (*path, name))


def test_every_help_page_speaks_to_users():
    """No command's --help sends users to the design document or shows type placeholders
    (``<str>``, ``<bool>``, ``TEXT``-style names of Python types) instead of what to give."""
    import typer

    paths = list(_command_paths(typer.main.get_command(app)))
    assert len(paths) > 30  # every command and group, capstan's included
    for path in paths:
        result = runner.invoke(app, [*path, "--help"], terminal_width=200)
        assert result.exit_code == 0, (path, result.output)
        for bad in ("DESIGN.md", "<str>", "<bool>", "<int>", "<float>"):
            assert bad not in result.output, (path, bad)


ENTRIES = ("run", "program")


def test_the_program_ends_at_once_with_its_code_its_output_and_its_exit_handlers(tmp_path):
    # the console script's program() skips the interpreter's teardown; what it must still do:
    # the exit code, every line printed (stdout block-buffered into a pipe), the exit handlers
    marker = tmp_path / "exit-handler-ran"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}

    def anklelab(entry, *argv):
        code = (
            f"import atexit, pathlib; atexit.register(pathlib.Path({str(marker)!r}).touch)\n"
            f"from anklelab.cli import {entry}; {entry}()"
        )
        proc = subprocess.run(
            [sys.executable, "-c", code, *argv], capture_output=True, text=True, env=env
        )
        assert marker.exists()
        marker.unlink()
        return proc

    shown = {entry: anklelab(entry, "platform", "show", "perturberator") for entry in ENTRIES}
    assert shown["program"].returncode == 0 and shown["program"].stdout == shown["run"].stdout
    assert "transmission.ratio" in shown["program"].stdout
    failed = anklelab("program", "import", "somewhere")
    assert failed.returncode == 2 and "Missing option" in failed.stderr
