"""The house: every floor's imports point down (no import up, no circle between modules); of the module paths
of version 0.1, the deprecated aliases are gone and the public one (``alpes_dyn.observability``) stays."""

from __future__ import annotations

import ast
import functools
import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import alpes_dyn
from alpes_dyn._moved import MOVED, REMOVED

PACKAGE = Path(alpes_dyn.__file__).parent

# Floors from the ground up; a module may import its own floor and the floors below it. The top floor is the
# package alpes_dyn.cli: its front door (main, exit codes), parser, common helpers and command-family modules.
FLOORS = ("base", "model", "symbolic", "simulation", "bench", "estimation", "analysis", "control", "studies", "cli")
BASE = {"errors", "checks", "limits", "fileio", "progress", "rebuild", "blas_threads", "_moved", "_version"}


def floor_of(dotted: str) -> str:
    """The floor of a module ``alpes_dyn.<dotted>`` (dotted relative to the package)."""
    head = dotted.split(".")[0]
    if head in BASE or head in ("", "__init__"):
        return "base"
    if head in FLOORS:
        return head
    raise AssertionError(f"module alpes_dyn.{dotted} belongs to no floor")


def module_imports(path: Path) -> set[str]:
    """The alpes_dyn modules (dotted, relative to the package) that ``path`` imports, top level or lazily (each
    module's text parsed once per session: the tests below walk the whole package several times)."""
    return set(_imports_of(path, path.read_text()))


@functools.lru_cache(maxsize=None)
def syntax_tree(text: str) -> ast.Module:
    """The module ``text`` parsed, once per session per text (the import and size rules read the same trees; none
    changes them)."""
    return ast.parse(text)


@functools.lru_cache(maxsize=None)
def _imports_of(path: Path, text: str) -> frozenset[str]:
    """:func:`module_imports` of the module ``path`` whose text is ``text``."""
    rel = path.relative_to(PACKAGE).with_suffix("")
    parts = list(rel.parts)
    pkg = parts[:-1] if parts[-1] != "__init__" else parts[:-1]
    found: set[str] = set()
    for node in ast.walk(syntax_tree(text)):
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
        elif isinstance(node, ast.ImportFrom) and node.module == "alpes_dyn":  # from alpes_dyn import x
            for a in node.names:
                sub = PACKAGE / a.name
                found.add(a.name if sub.is_dir() or sub.with_suffix(".py").exists() else "__init__")
        elif isinstance(node, ast.Import):  # import alpes_dyn, import alpes_dyn.model.robot
            found |= {"__init__" if a.name == "alpes_dyn" else a.name.removeprefix("alpes_dyn.")
                      for a in node.names if a.name == "alpes_dyn" or a.name.startswith("alpes_dyn.")}
    return frozenset(found)


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
            if target.split(".")[0] in MOVED or target.split(".")[0] in REMOVED:
                ups.append(f"{me} imports the old path {target}")
            elif FLOORS.index(floor_of(target)) > mine:
                ups.append(f"{me} ({FLOORS[mine]}) imports {target} ({floor_of(target)})")
    assert ups == []


FRONT_DOOR_PENDING: set[str] = set()
"""Modules below the command line that still import the package's front door: none (the last,
``control/cexport.py``'s ``from .. import __version__``, now imports :mod:`alpes_dyn._version`)."""


def test_only_the_command_line_imports_the_package_front_door():
    """``alpes_dyn/__init__`` imports the model, symbolic and analysis floors to re-export their names: a module of
    any floor below the command line that imports it (``from .. import __version__``, ``import alpes_dyn``) points
    up, whatever floor it is on. The version is :mod:`alpes_dyn._version`'s, on the base floor."""
    found = []
    for path in library_modules():
        me = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if me != "__init__" and floor_of(me) != "cli" and "__init__" in module_imports(path):
            found.append(me)
    assert sorted(found) == sorted(FRONT_DOOR_PENDING)


def test_the_front_door_rule_sees_every_spelling(monkeypatch):
    """The import counter on made-up text of a module: the relative, absolute and plain spellings of an import of
    the package's front door each count; a module of the package imported by name does not."""
    mod = PACKAGE / "estimation" / "cexport" / "cexport.py"
    for text, door in (("from ... import __version__", True), ("from alpes_dyn import __version__", True),
                       ("import alpes_dyn", True), ("from ... import errors", False),
                       ("from alpes_dyn import errors", False), ("from ..._version import __version__", False)):
        monkeypatch.setattr(Path, "read_text", lambda self, *a, _t=text, **k: _t)
        assert ("__init__" in module_imports(mod)) is door, text


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
def test_public_old_module_path_is_an_alias_without_a_warning(old):
    code = (f"import warnings, importlib; warnings.simplefilter('always');\n"
            f"with warnings.catch_warnings(record=True) as w:\n"
            f"    m = importlib.import_module('alpes_dyn.{old}')\n"
            f"n = importlib.import_module('alpes_dyn.{MOVED[old]}')\n"
            f"print(m is n, len(w))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "0"]


@pytest.mark.parametrize("old", sorted(REMOVED))
def test_removed_old_module_path_is_gone(old):
    """The deprecated aliases of version 0.1 are removed (CHANGELOG.md): no file at the package's root, no import,
    no attribute of the package; the module is at its new place."""
    assert not (PACKAGE / f"{old}.py").exists()
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(f"alpes_dyn.{old}")
    with pytest.raises(AttributeError, match=f"module 'alpes_dyn' has no attribute '{old}'"):
        getattr(alpes_dyn, old)
    assert importlib.import_module(f"alpes_dyn.{REMOVED[old]}").__name__ == f"alpes_dyn.{REMOVED[old]}"


def test_the_package_root_holds_only_the_base_floor_and_the_public_alias():
    """The root of the package: its front door, the base floor's modules and the public old path; every other
    module is in a floor's sub-package."""
    root = {p.stem for p in PACKAGE.glob("*.py")}
    assert root == BASE | {"__init__"} | set(MOVED)


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


def test_public_old_module_as_an_attribute_of_the_package():
    assert alpes_dyn.observability is importlib.import_module("alpes_dyn.analysis.observability")
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        alpes_dyn.nonexistent


# ----------------------------------------------------------------------------- the estimation floor's rooms
ESTIMATION_ROOMS = ("experiments", "observers", "identification", "cexport")
"""The estimation floor's sub-packages in order: each imports only those before it (issue 36), except that
``cexport`` (the observer as C) needs no fit: it may import experiments and observers, not identification."""


def test_estimation_sub_packages_point_only_at_those_before_them():
    est = PACKAGE / "estimation"
    assert {p.parent.name for p in est.glob("*/__init__.py")} == set(ESTIMATION_ROOMS)
    assert sorted(p.name for p in est.glob("*.py")) == ["__init__.py"]  # every module in a room
    wrong = []
    for room in ESTIMATION_ROOMS:
        allowed = set(ESTIMATION_ROOMS[: ESTIMATION_ROOMS.index(room) + 1]) - ({"identification"} if room == "cexport"
                                                                               else set())
        for path in (est / room).glob("*.py"):
            for target in module_imports(path):
                parts = target.split(".")
                if parts[0] == "estimation" and (len(parts) < 3 or parts[1] not in allowed):
                    wrong.append(f"{room}/{path.name} imports {target}")
        doc = ast.get_docstring(ast.parse((est / room / "__init__.py").read_text())) or ""
        assert len(doc.split()) > 40 and "eq" in doc, f"estimation/{room}/__init__.py: a paragraph naming the equations"
    assert wrong == []


def test_estimation_short_names_and_old_paths():
    """The common names at ``alpes_dyn.estimation`` are the defining module's objects; a module path of before the
    split imports the same module with one DeprecationWarning naming its new path (a fresh process)."""
    import alpes_dyn.estimation as est

    for name, module in est.EXPORTS.items():
        assert getattr(est, name) is getattr(importlib.import_module(f"alpes_dyn.estimation.{module}"), name), name
        assert getattr(est, name).__module__.startswith("alpes_dyn.estimation."), name
    assert set(est.__all__) == set(est.EXPORTS) and "identify" in dir(est)
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        est.nonexistent
    code = ("import warnings, importlib; warnings.simplefilter('always')\n"
            "with warnings.catch_warnings(record=True) as w:\n"
            "    old = importlib.import_module('alpes_dyn.estimation.adapt')\n"
            "new = importlib.import_module('alpes_dyn.estimation.experiments.adapt')\n"
            "print(old is new, new.__spec__.name, len(w), w[0].category.__name__, str(w[0].message).split()[3])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "alpes_dyn.estimation.experiments.adapt", "1", "DeprecationWarning",
                   "alpes_dyn.estimation.experiments.adapt;"]
    for room, name in (("identification", "identify"), ("observers", "make_observer"), ("cexport", "write_c_observer")):
        # a room that was a module: its module's names forwarded from the room, with a warning
        with pytest.warns(DeprecationWarning, match=f"alpes_dyn.estimation.{room}.{room}.{name}"):
            assert getattr(importlib.import_module(f"alpes_dyn.estimation.{room}"), name) is getattr(est, name)
    for old, new in est.MOVED.items():
        assert (PACKAGE / "estimation" / f"{new.replace('.', '/')}.py").is_file() and "." not in old
        assert not (PACKAGE / "estimation" / f"{old}.py").exists()


# ----------------------------------------------------------------------------- sizes a newcomer can read
MAX_FUNCTION_LINES = 80
"""Largest body of a function (its docstring excluded), lines, unless its docstring says why ("long because ...")."""
MAX_MODULE_LINES = 600
"""Largest module, lines, its docstrings excluded (as a function's body excludes its docstring): the numpydoc
entries that define each argument (issue 52) are not what makes a module long."""


def function_body_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function's body from its first statement after the docstring to its last line (a function that
    is only a docstring: 0)."""
    body = node.body
    if ast.get_docstring(node) is not None:
        body = body[1:]
    return node.end_lineno - body[0].lineno + 1 if body else 0


def long_functions(package: Path) -> list[str]:
    """``"module:line name (N lines)"`` for every function or method under ``package`` whose body is over
    :data:`MAX_FUNCTION_LINES` lines without "long because" (any case) in its docstring."""
    found = []
    for path in sorted(package.rglob("*.py")):
        for node in ast.walk(syntax_tree(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = function_body_lines(node)
                if lines > MAX_FUNCTION_LINES and "long because" not in (ast.get_docstring(node) or "").lower():
                    found.append(f"{path.relative_to(package)}:{node.lineno} {node.name} ({lines} lines)")
    return found


def module_lines(text: str) -> int:
    """Lines of a module's text less those of its docstrings (the module's, its classes' and its functions')."""
    doc = 0
    for node in ast.walk(syntax_tree(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                doc += first.end_lineno - first.lineno + 1
    return len(text.splitlines()) - doc


def long_modules(package: Path) -> list[str]:
    """``"module (N lines)"`` for every module under ``package`` over :data:`MAX_MODULE_LINES` lines, its
    docstrings excluded (:func:`module_lines`)."""
    sizes = {p: module_lines(p.read_text(encoding="utf-8")) for p in sorted(package.rglob("*.py"))}
    return [f"{p.relative_to(package)} ({n} lines)" for p, n in sizes.items() if n > MAX_MODULE_LINES]


def test_size_rules_count_what_they_say(tmp_path):
    """The counters on a made-up package: a docstring is not body; 81 lines of body fail, 80 pass, and so does
    81 with a reason; a module of 601 lines fails, 600 passes, and so does one of 600 lines and a docstring."""
    def fn(name: str, body: int, doc: str = "A function.") -> str:
        return f'def {name}():\n    """{doc}\n\n    more doc\n    """\n' + "    x = 1\n" * (body - 1) + "    return x\n"

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "a.py").write_text(fn("fine", 80) + "\n\n" + fn("too_long", 81) + "\n\n"
                              + fn("argued", 81, "Long because one formula of the report.") + "\n\n"
                              + "class C:\n" + "\n".join("    " + line for line in fn("method", 82).splitlines()) + "\n")
    (pkg / "b.py").write_text("x = 1\n" * 600)
    (pkg / "c.py").write_text("x = 1\n" * 601)
    (pkg / "d.py").write_text('"""A module.\n\nMore doc.\n"""\n' + "x = 1\n" * 600)
    assert sorted(f.split(" ", 1)[1] for f in long_functions(pkg)) == ["method (82 lines)", "too_long (81 lines)"]
    assert long_modules(pkg) == ["c.py (601 lines)"]


def test_functions_and_modules_a_newcomer_can_read():
    """No function body over 80 lines (docstring excluded) unless its docstring says "long because" and why; no
    module over 600 lines, its docstrings excluded (issue 18)."""
    assert long_functions(PACKAGE) == []
    assert long_modules(PACKAGE) == []
