"""Every code block of the docs runs (issue 19).

Python blocks: the blocks of one page in order, in one namespace, in a temporary folder, as a reader would paste
them (a block that needs an optional package is skipped when it is missing: MuJoCo, python-control). Command
blocks (``.. code-block:: bash``): every ``alpes-dyn`` line of a page, in order, in one folder, must exit 0;
they fit and sweep for minutes, so they are marked ``commands``, left out of the default run and run by CI as a
step of its own (``python -m pytest -m commands``). Docstring examples (``>>>``, rendered on the API pages) run as
doctests; the gallery's scripts (``docs/examples/plot_*.py``, which sphinx-gallery runs to build its pages) run
as scripts, marked ``gallery`` (minutes: ``python -m pytest -m gallery``)."""

from __future__ import annotations

import doctest
import importlib
import re
import runpy
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
NEEDS = {"mujoco": "mujoco", "to_control": "control",
         "run_hand_control": "mujoco"}


def blocks(path: Path, language: str) -> list[tuple[int, list[str]]]:
    """(line, lines) of each ``.. code-block:: <language>`` of an rst page, the indentation cut."""
    lines = path.read_text(encoding="utf-8").split("\n")
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() == f".. code-block:: {language}":
            j = i + 1
            while j < len(lines) and (not lines[j].strip() or lines[j].startswith("   ")):
                j += 1
            out.append((i + 1, [ln[3:] for ln in lines[i + 1: j]]))
            i = j
        else:
            i += 1
    return out


def python_blocks(path: Path) -> list[tuple[int, str]]:
    """(line, code) of each ``.. code-block:: python`` of an rst page."""
    return [(line, "\n".join(body).strip("\n")) for line, body in blocks(path, "python")]


RUN_ELSEWHERE = {"user-guide/friction.rst": "tests/test_lugre_fit.py"}
"""Pages whose blocks a test module runs (:func:`run_page`) to assert on what they compute: run there once, not
again here (the friction guide's LuGre fit is test_lugre_fit's recording and fits)."""
PAGES = sorted(p for p in DOCS.rglob("*.rst") if python_blocks(p) and "_build" not in p.parts
               and str(p.relative_to(DOCS)) not in RUN_ELSEWHERE)


def test_the_docs_have_python_blocks():
    assert len(PAGES) >= 8  # the guides' examples: a runner that finds none would test nothing
    assert all(python_blocks(DOCS / page) for page in RUN_ELSEWHERE)


def run_page(page: Path, folder: Path) -> dict:
    """Run the python blocks of ``page`` in order, in one namespace, in ``folder`` (as a reader pastes them, the
    figures to a non-interactive backend); return the namespace. A block needing a missing optional package skips."""
    ns: dict = {"__name__": "__snippet__"}
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(folder)
        mp.setenv("MPLBACKEND", "Agg")
        for line, code in python_blocks(page):
            for word, module in NEEDS.items():
                if re.search(rf"\b{word}\b", code):
                    pytest.importorskip(module)
            try:
                exec(compile(code, f"{page.name}:{line}", "exec"), ns)
            except Exception as exc:  # the block's own line in the report
                raise AssertionError(f"{page.relative_to(DOCS)} line {line}: {type(exc).__name__}: {exc}") from exc
    return ns


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_page_snippets_run(page, tmp_path):
    run_page(page, tmp_path)


def command_blocks(path: Path) -> list[tuple[int, list[str]]]:
    """(line, commands) of each ``.. code-block:: bash`` of an rst page: the ``alpes-dyn`` lines, comments cut."""
    out = []
    for line, body in blocks(path, "bash"):
        cmds = [c for c in (ln.split(" #")[0].strip() for ln in body) if c.startswith("alpes-dyn ")]
        if cmds:
            out.append((line, cmds))
    return out


CMD_PAGES = sorted(p for p in DOCS.rglob("*.rst") if command_blocks(p) and "_build" not in p.parts)


@pytest.mark.commands
@pytest.mark.parametrize("page", CMD_PAGES, ids=[str(p.relative_to(DOCS)) for p in CMD_PAGES])
def test_page_commands_run(page, tmp_path):
    """The guides' ``alpes-dyn`` command lines, in order, in one folder: each exits 0."""
    import shlex
    import subprocess
    import sys

    for line, cmds in command_blocks(page):
        for cmd in cmds:
            argv = shlex.split(cmd)[1:]
            if "sweep" in argv:
                pytest.importorskip("distributed")
            r = subprocess.run([sys.executable, "-m", "alpes_dyn.cli", *argv], cwd=tmp_path, capture_output=True,
                               text=True, timeout=600)
            assert r.returncode == 0, f"{page.relative_to(DOCS)} line {line}: {cmd}: {r.stderr.strip()}"


README = Path(__file__).resolve().parents[1] / "README.md"


def readme_python() -> str:
    """The README's ```python block (its ten-line example)."""
    text = README.read_text(encoding="utf-8")
    start = text.index("```python\n") + len("```python\n")
    return text[start: text.index("```", start)]


@pytest.mark.commands
def test_the_readme_example_runs_and_observes_the_joints(tmp_path, monkeypatch):
    """The README's ten lines, as a reader pastes them: the finger observable (rank 6), the fit of a finger drawn
    20 % off converged and adequate, its file written, and the EKF on that file within 0.5 degree of the true
    joints on every joint (a fit's minutes: with the guides' commands)."""
    import numpy as np

    monkeypatch.chdir(tmp_path)
    ns: dict = {"__name__": "__readme__"}
    exec(compile(readme_python(), "README.md", "exec"), ns)
    assert ns["obs"].rank == 6 and ns["obs"].observable
    assert ns["fit"].trustworthy and (tmp_path / "ident.toml").exists()
    assert np.all(np.degrees(ns["ekf"].rmse) < 0.5)


SRC = Path(__file__).resolve().parents[1] / "src" / "alpes_dyn"
DOCTEST_MODULES = sorted("alpes_dyn." + ".".join(p.relative_to(SRC).with_suffix("").parts)
                         for p in SRC.rglob("*.py") if ">>> " in p.read_text(encoding="utf-8"))


def test_the_docstrings_have_examples():
    assert DOCTEST_MODULES  # a runner that finds none would test nothing


@pytest.mark.parametrize("module", DOCTEST_MODULES)
def test_docstring_examples_run(module):
    """The ``>>>`` examples of the docstrings (the API pages show them): each runs, its output as printed."""
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0, result


GALLERY = sorted((DOCS / "examples").glob("plot_*.py"))


@pytest.mark.gallery
@pytest.mark.parametrize("script", GALLERY, ids=[p.name for p in GALLERY])
def test_gallery_script_runs(script, tmp_path, monkeypatch):
    """A gallery script as sphinx-gallery runs it to build its page (the figures to a non-interactive backend)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    runpy.run_path(str(script), run_name="__main__")


def _extras_in_getting_started() -> dict[str, set[str]]:
    """Each ``pip install ".[extra]"`` line of getting-started with the packages its comment lists (continuation
    lines included; descriptions after a colon or in parentheses cut)."""
    out: dict[str, set[str]] = {}
    current = None
    for line in (DOCS / "getting-started.rst").read_text(encoding="utf-8").splitlines():
        m = re.match(r'\s*\$ pip install "\.\[(\w+)\]"\s*#\s*\+\s*(.*)', line)
        cont = re.match(r"\s*#\s{3}(.*)", line)
        if m:
            current, text = m.group(1), m.group(2)
        elif cont and current:
            text = cont.group(1)
        else:
            current = None
            continue
        text = re.sub(r"\([^)]*\)", "", text.split(":")[0])
        out.setdefault(current, set()).update(w.strip() for w in text.split(",") if w.strip())
    return out


def test_getting_started_lists_every_extras_package():
    """The install lines of getting-started name exactly the packages of pyproject.toml's extras (issue 19: the
    lists were incomplete), python-control written for its distribution name ``control``."""
    import tomllib
    project = tomllib.loads((DOCS.parent / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    documented = _extras_in_getting_started()
    for extra, requirements in project["optional-dependencies"].items():
        names = {re.split(r"[<>=!~ ;]", r, maxsplit=1)[0] for r in requirements}
        names = {"python-control" if n == "control" else n for n in names}
        assert documented.get(extra) == names, (extra, documented.get(extra), names)


def test_the_real_time_snippet_names_where_each_of_its_names_comes_from():
    """The observers guide's real-time block (issue 52: it used ``ekf``, ``z0``, ``P0``, ``W``, ``Y`` unexplained):
    every name it reads and does not assign is a builtin or named in its first line, a comment saying where it is
    built (the page's first example, which test_page_snippets_run runs before it)."""
    import ast
    import builtins

    page = DOCS / "user-guide" / "observers.rst"
    code = next(c for _, c in python_blocks(page) if ".online(" in c)
    tree = ast.parse(code)
    names = [n for n in ast.walk(tree) if isinstance(n, ast.Name)]
    assigned = {n.id for n in names if isinstance(n.ctx, ast.Store)}
    free = {n.id for n in names if isinstance(n.ctx, ast.Load)} - assigned - set(dir(builtins))
    first = code.splitlines()[0]
    assert free == {"ekf", "z0", "P0", "W", "Y"} and first.startswith("#")
    assert all(re.search(rf"\b{name}\b", first) for name in free), first
