"""The house: every floor's imports point down (no import up, no circle between modules), and the
module paths of version 0.1 still import, as aliases of the new modules, with a DeprecationWarning."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import alpes_dyn
from alpes_dyn._moved import MOVED, PUBLIC

PACKAGE = Path(alpes_dyn.__file__).parent

# Floors from the ground up; a module may import its own floor and the floors below it. The top floor is the
# package alpes_dyn.cli: its front door (main, exit codes), parser, common helpers and command-family modules.
FLOORS = ("base", "model", "symbolic", "simulation", "estimation", "analysis", "control", "studies", "cli")
BASE = {"errors", "checks", "limits", "fileio", "progress", "rebuild", "_moved"}


def floor_of(dotted: str) -> str:
    """The floor of a module ``alpes_dyn.<dotted>`` (dotted relative to the package)."""
    head = dotted.split(".")[0]
    if head in BASE or head in ("", "__init__"):
        return "base"
    if head in FLOORS:
        return head
    raise AssertionError(f"module alpes_dyn.{dotted} belongs to no floor")


def module_imports(path: Path) -> set[str]:
    """The alpes_dyn modules (dotted, relative to the package) that ``path`` imports, top level or lazily."""
    rel = path.relative_to(PACKAGE).with_suffix("")
    parts = list(rel.parts)
    pkg = parts[:-1] if parts[-1] != "__init__" else parts[:-1]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = pkg[: len(pkg) - (node.level - 1)]
            target = ".".join(base + ([node.module] if node.module else []))
            if node.module is None:  # from . import x: a module, or a name of the package itself
                for a in node.names:
                    sub = PACKAGE.joinpath(*base, a.name)
                    is_module = sub.is_dir() or sub.with_suffix(".py").exists()
                    found.add(".".join(base + [a.name]) if is_module else ".".join(base) or "__init__")
            else:
                found.add(target)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("alpes_dyn."):
            found.add(node.module.removeprefix("alpes_dyn."))
    return found


def library_modules() -> list[Path]:
    old = {f"{name}.py" for name in MOVED}
    return [p for p in PACKAGE.rglob("*.py") if not (p.parent == PACKAGE and p.name in old)]


def test_every_import_points_down_or_sideways():
    ups = []
    for path in library_modules():
        me = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if me == "__init__":
            continue  # the package's front door re-exports from every floor
        mine = FLOORS.index(floor_of(me))
        for target in module_imports(path):
            if target.split(".")[0] in MOVED:
                ups.append(f"{me} imports the old path {target}")
            elif FLOORS.index(floor_of(target)) > mine:
                ups.append(f"{me} ({FLOORS[mine]}) imports {target} ({floor_of(target)})")
    assert ups == []


def test_no_import_circle_between_modules():
    graph: dict[str, set[str]] = {}
    for path in library_modules():
        me = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        # a package's __init__ stands for the package: an import of alpes_dyn.model is of model/__init__
        me = me.removesuffix(".__init__")
        graph[me] = {t for t in module_imports(path) if t != me}
    # top-level imports only are what can deadlock, but a lazy circle is still a tangle: count both
    seen: dict[str, int] = {}
    stack: list[str] = []
    circles: list[list[str]] = []

    def visit(node: str) -> None:
        seen[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in graph or nxt == "__init__" or "." not in nxt and nxt in FLOORS and node.startswith(nxt):
                continue  # a package's own __init__ re-exporting its module is not a circle
            if seen.get(nxt) == 1:
                circles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in seen:
                visit(nxt)
        stack.pop()
        seen[node] = 2

    for node in sorted(graph):
        if node not in seen and node != "__init__":
            visit(node)
    assert circles == []


def test_cli_is_a_package_on_the_top_floor():
    """The command line is the top floor, a package of modules; none of them but ``__main__`` imports its front
    door ``cli/__init__`` (which imports them all: the circle test lets a package's own ``__init__`` pass)."""
    assert FLOORS[-1] == "cli" and (PACKAGE / "cli" / "__init__.py").exists() and not (PACKAGE / "cli.py").exists()
    modules = sorted((PACKAGE / "cli").glob("*.py"))
    assert {floor_of(".".join(p.relative_to(PACKAGE).with_suffix("").parts)) for p in modules} == {"cli"}
    front = [p.name for p in modules if p.name not in ("__init__.py", "__main__.py") and "cli" in module_imports(p)]
    assert front == []
    below = [p for p in library_modules() if p.relative_to(PACKAGE).parts[0] != "cli"]
    assert [str(p) for p in below if any(floor_of(t) == "cli" for t in module_imports(p))] == []


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_module_path_is_an_alias_with_a_warning(old):
    code = (f"import warnings, importlib; warnings.simplefilter('always');\n"
            f"with warnings.catch_warnings(record=True) as w:\n"
            f"    m = importlib.import_module('alpes_dyn.{old}')\n"
            f"n = importlib.import_module('alpes_dyn.{MOVED[old]}')\n"
            f"print(m is n, sum(issubclass(x.category, DeprecationWarning) and 'alpes_dyn.{MOVED[old]}' in str(x.message)"
            f" for x in w))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out[0] == "True"
    assert int(out[1]) == (0 if old in PUBLIC else 1)


def test_old_names_of_renamed_packages_are_forwarded_with_a_warning():
    from alpes_dyn.simulation import codegen, integrate

    with pytest.warns(DeprecationWarning, match="alpes_dyn.simulation.codegen._CFLAGS"):
        from alpes_dyn.simulation import _CFLAGS
    assert _CFLAGS is codegen._CFLAGS
    with pytest.warns(DeprecationWarning, match="alpes_dyn.simulation.integrate._check_dt"):
        assert alpes_dyn.simulation._check_dt is integrate._check_dt
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from alpes_dyn.simulation import simulate  # public: no warning
        from alpes_dyn.model import Model
    assert simulate is integrate.simulate and Model is alpes_dyn.Model
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        importlib.import_module("alpes_dyn.control").nonexistent


def test_old_module_as_an_attribute_of_the_package():
    with pytest.warns(DeprecationWarning, match="alpes_dyn.model.params"):
        mod = alpes_dyn.params
    assert mod.default_params_path is importlib.import_module("alpes_dyn.model.params").default_params_path
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        alpes_dyn.nonexistent
