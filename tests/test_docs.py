"""The documentation stays true: generated pages match their sources, the worked example in the
user guide is a valid session whose commands and error messages are the real ones, and every
relative link points at a file that exists."""

from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from anklelab.cli import app
from anklelab.commands.platform import platform_markdown
from anklelab.platforms import PLATFORMS
from tests.cli_in_process import run_anklelab

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
OWN_DATA = DOCS / "guide" / "own-data.md"


@pytest.mark.parametrize("name", sorted(PLATFORMS))
def test_platform_pages_match_the_parameter_files(name):
    page = DOCS / "platforms" / f"{name}.md"
    expected = platform_markdown(name)
    assert page.read_text(encoding="utf-8") == expected, (
        f"{page.relative_to(ROOT)} is out of date with {name}.toml; regenerate it with "
        f"`anklelab platform show {name} --markdown > {page.relative_to(ROOT)}`"
    )


def test_platform_markdown_lists_every_value_with_its_source():
    text = platform_markdown("capstan")
    assert "| `friction.coulomb_ccw_nm` | 0.038 | paper 001, Table 2: T_cf (CCW) |" in text
    result = CliRunner().invoke(app, ["platform", "show", "capstan", "--markdown"])
    assert result.exit_code == 0 and result.output == text


def _links(path: Path) -> list[str]:
    return re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text(encoding="utf-8"))


@pytest.mark.parametrize(
    "page",
    [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))],
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_relative_links_resolve(page):
    broken = [
        link
        for link in _links(page)
        if not re.match(r"[a-z]+:", link) and not (page.parent / link).exists()
    ]
    assert broken == [], f"{page.relative_to(ROOT)}: broken links {broken}"


# --- the worked example of docs/guide/own-data.md ---------------------------------------------


def _blocks(text: str) -> list[tuple[str, str]]:
    """(info string, body) of every fenced code block."""
    return [(m[0].strip(), m[1]) for m in re.findall(r"```([^\n]*)\n(.*?)```", text, re.S)]


def _write_example_files(text: str, root: Path) -> list[str]:
    """Write every block whose info string names a ``file=...``; return their paths."""
    written = []
    for info, body in _blocks(text):
        match = re.search(r"file=(\S+)", info)
        if match:
            path = root / match[1]
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(body, encoding="utf-8")
            written.append(match[1])
    return written


def _anklelab(args: list[str], cwd: Path, monkeypatch, capsys) -> tuple[int, str, str]:
    """Run the ``anklelab`` entry point in-process in ``cwd``: (exit code, stdout, stderr)."""
    return run_anklelab(args, monkeypatch, capsys, cwd=cwd)


def test_worked_example_session_imports_and_its_commands_run(tmp_path, monkeypatch, capsys):
    text = OWN_DATA.read_text(encoding="utf-8")
    files = _write_example_files(text, tmp_path)
    assert {"my_session/session.toml", "my_session/walking/trials.csv"} <= set(files)
    commands = [
        shlex.split(line.removeprefix("$ "))[1:]
        for info, body in _blocks(text)
        if info.split()[:2] == ["console", "run"]
        for line in body.splitlines()
        if line.startswith("$ anklelab ")
    ]
    assert [c[:2] for c in commands] == [["session", "info"], ["import", "my_session"]]
    for args in commands:
        code, _, err = _anklelab(args, tmp_path, monkeypatch, capsys)
        assert code == 0, (args, err)
    assert (tmp_path / "my_session.h5").is_file()


def test_worked_example_errors_are_the_real_messages(tmp_path, monkeypatch, capsys):
    """Each ``console error`` block shows a broken copy of the example (made by the ``sed``
    line in it) and the exact message anklelab prints for it."""
    text = OWN_DATA.read_text(encoding="utf-8")
    errors = [body for info, body in _blocks(text) if info.split()[:2] == ["console", "error"]]
    assert len(errors) >= 3
    for number, body in enumerate(errors):
        case = tmp_path / str(number)
        _write_example_files(text, case)
        lines = body.splitlines()
        for edit in (line.removeprefix("$ ") for line in lines if line.startswith("$ sed ")):
            subprocess.run(shlex.split(edit), cwd=case, check=True)
        command = next(line for line in lines if line.startswith("$ anklelab "))
        shown = [line for line in lines if line.startswith("error: ")]
        code, _, err = _anklelab(shlex.split(command)[2:], case, monkeypatch, capsys)
        assert code == 2, (command, err)
        assert err.strip().splitlines()[-1:] == shown, command


@pytest.mark.parametrize("page", sorted((DOCS / "guide").glob("*.md")), ids=lambda p: p.name)
def test_python_snippets_run(page, tmp_path, monkeypatch):
    """Every ``python`` block of a guide page runs, in a directory holding the worked example
    session of own-data.md."""
    _write_example_files(OWN_DATA.read_text(encoding="utf-8"), tmp_path)
    monkeypatch.chdir(tmp_path)
    for info, body in _blocks(page.read_text(encoding="utf-8")):
        if info == "python":
            exec(compile(body, f"{page.name} snippet", "exec"), {"__name__": "__docs__"})


# --- README and the settings table --------------------------------------------------------------


def _same_within(shown: str, printed: str, rel: float) -> bool:
    """Lines match word by word; numbers may differ by ``rel`` (relative) or 0.15 (absolute)."""
    shown_lines, printed_lines = shown.strip().splitlines(), printed.strip().splitlines()
    if len(shown_lines) != len(printed_lines):
        return False
    for a_line, b_line in zip(shown_lines, printed_lines, strict=True):
        a_words, b_words = a_line.split(), b_line.split()
        if len(a_words) != len(b_words):
            return False
        for a, b in zip(a_words, b_words, strict=True):
            try:
                x, y = float(a.strip("()")), float(b.strip("()"))
            except ValueError:
                if a != b:
                    return False
                continue
            if abs(x - y) > max(rel * abs(y), 0.15):
                return False
    return True


def test_readme_example_runs_and_prints_what_the_readme_shows(capsys):
    blocks = _blocks((ROOT / "README.md").read_text(encoding="utf-8"))
    infos = [info for info, _ in blocks]
    code = blocks[infos.index("python")][1]
    shown = blocks[infos.index("python") + 1]
    assert shown[0] == "text", "the README's python block must be followed by its output"
    assert len(code.strip().splitlines()) <= 15
    exec(compile(code, "README.md", "exec"), {"__name__": "__readme__"})
    printed = capsys.readouterr().out
    # same seed, same numbers; the tolerance only absorbs floating-point differences between
    # machines (a change of method shows up as a larger difference)
    assert _same_within(shown[1], printed, rel=0.01), printed


def test_settings_table_lists_every_setting_with_its_default():
    from anklelab.pipelines import WalkingSettings

    text = (DOCS / "guide" / "walking-analysis.md").read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+) \|", text, re.M))
    defaults = WalkingSettings().model_dump(mode="json")
    assert set(rows) == set(defaults)
    for key, value in defaults.items():
        assert json.loads(rows[key].strip()) == value, key


def test_real_sized_session_commands_print_what_the_guide_shows(tmp_path, monkeypatch, capsys):
    """own-data.md: example 02's directory, then `anklelab import` and `anklelab analyze`."""
    text = OWN_DATA.read_text(encoding="utf-8")
    block = next(body for info, body in _blocks(text) if "$ python examples/02_" in body)
    lines = block.splitlines()
    script = ROOT / lines[0].split()[2]
    subprocess.run(
        [sys.executable, str(script), "lab"], cwd=tmp_path, check=True, capture_output=True
    )
    shown_rows = [line for line in lines if re.match(r"\s+(dorsi|plantar)/\d+ ", line)]
    commands = [shlex.split(line)[2:] for line in lines if line.startswith("$ anklelab ")]
    assert [c[0] for c in commands] == ["import", "analyze"]
    printed = ""
    for args in commands:
        code, out, err = _anklelab(args, tmp_path / "lab", monkeypatch, capsys)
        assert code == 0, (args, err)
        printed += out
    rows = [line for line in printed.splitlines() if re.match(r"\s+(dorsi|plantar)/\d+ ", line)]
    assert len(shown_rows) == 8
    assert _same_within("\n".join(shown_rows), "\n".join(rows), rel=0.01), printed
