"""The ``anklelab`` group imports a subcommand's module only when that subcommand is used."""

import pytest
import typer
from typer.testing import CliRunner

from anklelab.cli import COMMANDS, LazyCommand, LazyCommands, app
from tests.module_loading import loaded

runner = CliRunner()
RUN = "from anklelab.cli import run; run()"


def command_modules(code: str, *argv: str) -> set[str]:
    """The ``anklelab.commands`` modules loaded after running ``code`` with ``argv``."""
    return {m for m in loaded(code, *argv) if m.split(".")[:2] == ["anklelab", "commands"]}


def test_importing_the_cli_imports_no_command_module():
    assert command_modules("import anklelab.cli") == set()


def test_help_and_version_import_no_command_module():
    assert command_modules(RUN, "--help") == set()
    assert command_modules(RUN, "--version") == set()
    assert command_modules(RUN) == set()  # no arguments: the help


def test_a_command_imports_only_its_own_module():
    loaded = command_modules(RUN, "platform", "--help")
    assert "anklelab.commands.platform" in loaded
    assert not loaded & {"anklelab.commands.analyze", "anklelab.commands.capstan"}


def loaded_group():
    """The ``anklelab`` click group with every subcommand imported."""
    group = typer.main.get_command(app)
    return group, dict(group.commands.items())


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_short_help_is_the_commands_own(name):
    """The listed line equals the loaded command's at every width: they cannot drift apart."""
    _, commands = loaded_group()
    stand_in = typer.main.get_command(app).commands.listed(name)
    command = commands[name]
    assert command.name == name
    assert COMMANDS[name].short_help == command.get_short_help_str(10_000)
    for limit in range(1, 300):
        assert stand_in.get_short_help_str(limit) == command.get_short_help_str(limit), limit


@pytest.mark.parametrize("width", [40, 80, 200])
def test_help_lists_the_commands_as_typer_lists_the_loaded_ones(width):
    def help_page(group):
        context = group.make_context("anklelab", [], resilient_parsing=True, terminal_width=width)
        return group.get_help(context)

    lazy = typer.main.get_command(app)
    listing = help_page(lazy)
    assert lazy.commands._loaded == {}  # listing loaded nothing
    group, commands = loaded_group()
    assert list(commands) == list(COMMANDS)
    assert listing == help_page(group)  # now typer's own listing of the real commands
    result = runner.invoke(app, ["--help"], prog_name="anklelab", terminal_width=width)
    assert result.output == listing + "\n"


def test_a_mistyped_command_is_still_suggested():
    result = runner.invoke(app, ["analyse"])
    assert result.exit_code == 2
    assert "Did you mean 'analyze'?" in result.output


def test_lazy_commands_load_on_lookup_only():
    loads = []

    def load(name, entry):
        loads.append(name)
        return f"<{entry.target}>"

    commands = LazyCommands({"b": LazyCommand("m:b", "B."), "a": LazyCommand("m:a", "A.")}, load)
    commands["c"] = "<c>"
    assert list(commands) == ["b", "a", "c"] and len(commands) == 3
    assert "a" in commands and "z" not in commands and commands.get("z") is None
    assert commands.listed("a").get_short_help_str() == "A."
    assert loads == []
    assert commands["a"] == commands.get("a") == "<m:a>"
    assert loads == ["a"]
    del commands["b"]
    assert list(commands) == ["a", "c"] and loads == ["a"]
    with pytest.raises(KeyError):
        commands["b"]
