"""Every module imports only from its own layer or the layers above it (DESIGN.md section 2).

Imports are read from the source with ``ast``, including imports inside functions and
``TYPE_CHECKING`` blocks: a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import anklelab

PACKAGE = Path(anklelab.__file__).parent

# top (imported by everything) to bottom, by the first name below ``anklelab``
RANK = {
    "_lazy": 0,
    "_params": 0,
    "_atomic": 0,
    "_lock": 0,
    "_runs": 0,
    "_version": 0,
    "errors": 0,
    "forceplate": 0,
    "metrics": 0,
    "_student_t": 0,  # Student's t without SciPy: the analysis's intervals
    "_session_limits": 0,  # the largest twin session simulated on request
    "_json": 0,  # results as JSON (no NaN): the analysis and the studies write it
    "iir": 0,  # filter designs and the zero-phase filter: the twin and the analysis share them
    "platforms": 1,
    "sim": 2,
    "control": 3,
    "data": 4,
    "experiments": 4,  # protocol runners on the twin: may import data
    "signals": 5,
    "ident": 6,
    "pipelines": 7,
    "studies": 7.5,  # many sessions through the twin and the pipelines, on Dask; above report
    "report": 8,
    "demo": 9,  # an application of every layer above (the twins, analyses, report rendering)
    "commands": 10,
    "cli": 11,
}
# the twin produces sessions; the session layer and the analysis layers only read them
FORBIDDEN = {("data", "experiments"), ("signals", "experiments"), ("ident", "experiments")}


def layer(parts: tuple[str, ...]) -> str:
    assert parts and parts[0] in RANK, f"anklelab.{'.'.join(parts)} belongs to no layer"
    return parts[0]


def imports(source: str, parts: tuple[str, ...], is_package: bool = False):
    """(line, name below ``anklelab``) of every anklelab import in ``source``.

    ``parts`` is the importing module's name below ``anklelab``, used for relative imports.
    A name imported from ``anklelab`` itself is either a module (``from anklelab import sim``)
    or a re-export, which is attributed to the module it comes from.
    """
    package = parts if is_package else parts[:-1]
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [alias.name.split(".") for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            module = node.module.split(".") if node.module else []
            if node.level:
                module = ["anklelab", *package[: len(package) - node.level + 1], *module]
            if module == ["anklelab"]:
                names = [["anklelab", *REEXPORTS.get(a.name, (a.name,))] for a in node.names]
            else:
                names = [module]
        else:
            continue
        found += [(node.lineno, tuple(n[1:])) for n in names if n[0] == "anklelab" and n[1:]]
    return found


def _reexports() -> dict[str, tuple[str, ...]]:
    """Names that anklelab/__init__.py re-exports -> the module they come from: imported ones,
    and those it loads on first use (its ``_EXPORTS`` table: name -> submodule)."""
    found = {}
    for node in ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("anklelab."):
            module = next(name for _, name in imports(f"from {node.module} import x\n", ()))
            found |= {alias.name: module for alias in node.names}
        elif isinstance(node, ast.Assign) and ast.unparse(node.targets[0]) == "_EXPORTS":
            pairs = zip(node.value.keys, node.value.values, strict=True)
            found |= {k.value: (v.value,) for k, v in pairs}
    return found


REEXPORTS = _reexports()


def modules() -> list[Path]:
    # anklelab/__init__.py re-exports the public API; checked on its own below
    return sorted(p for p in PACKAGE.rglob("*.py") if p != PACKAGE / "__init__.py")


def violations(path: Path, package: Path = PACKAGE) -> list[str]:
    parts = path.relative_to(package).with_suffix("").parts
    parts = parts[:-1] if parts[-1] == "__init__" else parts
    source = layer(parts)
    found = imports(path.read_text(encoding="utf-8"), parts, path.name == "__init__.py")
    return [
        f"{path.relative_to(package.parent)}:{line}: {source} imports anklelab.{'.'.join(name)}"
        for line, name in found
        if RANK[layer(name)] > RANK[source] or (source, layer(name)) in FORBIDDEN
    ]


def test_no_module_imports_a_lower_layer():
    problems = [problem for path in modules() for problem in violations(path)]
    assert not problems, "layering violations (DESIGN.md section 2):\n" + "\n".join(problems)


def test_top_level_package_imports_only_core_and_platforms():
    found = imports((PACKAGE / "__init__.py").read_text(encoding="utf-8"), (), is_package=True)
    assert found
    assert max(RANK[layer(name)] for _, name in found) <= RANK["platforms"]


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("import anklelab.ident.irf as irf\n", [(1, ("ident", "irf"))]),
        ("def f():\n    from anklelab.report import html\n", [(2, ("report",))]),
        ("from anklelab import experiments, errors\n", [(1, ("experiments",)), (1, ("errors",))]),
        ("from ..experiments import capstan\n", [(1, ("experiments",))]),
        ("from . import store\nfrom .hdf5 import x\n", [(1, ("data",)), (2, ("data", "hdf5"))]),
        ("import numpy\nfrom scipy import signal\n", []),
    ],
)
def test_import_reader(source, expected):
    assert imports(source, ("data", "directory")) == expected


def test_reader_flags_a_lower_layer(tmp_path):
    probe = tmp_path / "anklelab" / "data" / "probe.py"
    probe.parent.mkdir(parents=True)
    probe.write_text("def f():\n    from anklelab.experiments import capstan\n")
    found = violations(probe, package=tmp_path / "anklelab")
    assert found == ["anklelab/data/probe.py:2: data imports anklelab.experiments"]


def test_reexports_are_attributed_to_their_module():
    assert imports("from anklelab import load_platform\n", ("sim", "x")) == [(1, ("platforms",))]
    assert imports("from anklelab import ParameterError\n", ("sim", "x")) == [(1, ("errors",))]
    assert imports("from anklelab import __version__\n", ("sim", "x")) == [(1, ("_version",))]
