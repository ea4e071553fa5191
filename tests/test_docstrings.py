"""Docstrings that define (issue 52): every public function and method of the public API documents every argument in
numpydoc's ``name : type`` form, as numpydoc's own parser reads it (after python-control's
``control/tests/docstrings_test.py``). The public API: the names in ``alpes_dyn.__all__`` and in each public
sub-package's ``__all__``; of a class, its constructor's arguments (in the class's docstring or ``__init__``'s) and
its public methods (defined on it or on a class of the library it inherits from, e.g. a mixin's)."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import warnings
from typing import Any, Callable, Iterator

import pytest

docscrape = pytest.importorskip("numpydoc.docscrape")  # the test extra (pyproject's [test]) installs it

PACKAGES = ("alpes_dyn", "alpes_dyn.model", "alpes_dyn.simulation", "alpes_dyn.symbolic", "alpes_dyn.bench",
            "alpes_dyn.estimation", "alpes_dyn.analysis", "alpes_dyn.control", "alpes_dyn.studies")

# The callables whose docstrings are not yet in numpydoc's form (``name: prose`` entries, or arguments not
# documented): 44 at issue 52, when the front door (alpes_dyn.__all__'s functions, identify, fit_effects) was made
# clean; none since (every public callable documents every argument). The list only shrinks: a callable fixed must
# leave it (test_the_allow_list_only_shrinks), none may join.
NOT_YET: frozenset[str] = frozenset()


def _public(packages: tuple[str, ...] = PACKAGES) -> Iterator[tuple[str, Any]]:
    """(qualified name, object) of every public function and class of ``packages``' ``__all__``, each once (under
    its first package)."""
    seen: set[int] = set()
    for pkg in packages:
        module = importlib.import_module(pkg)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and id(obj) not in seen:
                seen.add(id(obj))
                yield f"{pkg}.{name}", obj


def _documented(doc: str) -> dict[str, str]:
    """name -> type of the ``Parameters`` and ``Other Parameters`` entries numpydoc's parser reads in ``doc``
    (``a, b : float`` gives both; ``*args`` and ``**kwargs`` their bare names, numpydoc's form for them having
    no type)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpydoc warns of sections it does not know (ours: none)
        parsed = docscrape.NumpyDocString(doc or "")
    out = {}
    for section in ("Parameters", "Other Parameters"):
        for entry in parsed[section]:
            for name in entry.name.split(","):
                name = name.strip()
                out[name.lstrip("*")] = entry.type or ("(starred)" if name.startswith("*") else "")
    return out


def _undocumented(fn: Callable, doc: str) -> list[str]:
    """The arguments of ``fn`` that ``doc`` does not document as ``name : type``."""
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):  # a builtin's
        return []
    have = _documented(doc)
    return [a for a in sig.parameters if a not in ("self", "cls") and not a.startswith("_") and not have.get(a)]


def _callables(packages: tuple[str, ...] = PACKAGES) -> Iterator[tuple[str, Callable, str]]:
    """(qualified name, callable, its docstring) of every public function, constructor and method of
    ``packages``."""
    for qual, obj in _public(packages):
        if inspect.isfunction(obj):
            yield qual, obj, inspect.getdoc(obj) or ""
            continue
        if issubclass(obj, BaseException) or getattr(obj, "_is_protocol", False):  # BaseException's or a
            continue  # Protocol's constructor (its message; none)
        init = obj.__dict__.get("__init__")
        if init is not None and not hasattr(obj, "__dataclass_fields__"):  # a dataclass's fields: its Attributes
            yield qual, init, (inspect.getdoc(obj) or "") + "\n\n" + (inspect.getdoc(init) or "")
        seen: set[str] = set()
        for cls in obj.__mro__:  # its own methods and those of the library's classes it inherits (a mixin's)
            if not cls.__module__.startswith("alpes_dyn"):
                continue
            for name, member in cls.__dict__.items():
                fn = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                if name not in seen and not name.startswith("_") and inspect.isfunction(fn):
                    yield f"{qual}.{name}", fn, inspect.getdoc(fn) or ""
                seen.add(name)


@pytest.fixture(scope="module")
def failing() -> dict[str, list[str]]:
    return {qual: bad for qual, fn, doc in _callables() if (bad := _undocumented(fn, doc))}


def test_every_public_argument_is_documented_as_name_colon_type(failing):
    """Every public callable outside NOT_YET documents each argument as ``name : type``."""
    new = {q: b for q, b in failing.items() if q not in NOT_YET}
    assert not new, "arguments not documented as `name : type`: " + "; ".join(f"{q} {b}" for q, b in new.items())


def test_the_allow_list_only_shrinks(failing):
    """Each callable of NOT_YET still fails (fixed ones leave the list) and still exists."""
    names = {q for q, _, _ in _callables()}
    assert NOT_YET <= names, f"gone from the API: {sorted(NOT_YET - names)}"
    fixed = NOT_YET - set(failing)
    assert not fixed, f"fixed: remove from NOT_YET: {sorted(fixed)}"


def test_the_parser_reads_what_the_rule_asks():
    """The check itself: ``name : type`` is read, ``name: prose`` (identify's former form) is not, a missing
    argument is named, and ``a, b : float`` documents both."""
    def good(x, y=1):
        """Do.

        Parameters
        ----------
        x, y : float
            Numbers.
        """

    def prose(x, threads=None):
        """Do.

        Parameters
        ----------
        x: the number.
        """

    assert _undocumented(good, inspect.getdoc(good)) == []
    assert _undocumented(prose, inspect.getdoc(prose)) == ["x", "threads"]


def test_the_front_door_is_clean(failing):
    """alpes_dyn.__all__'s functions and the commands' fit (identify, fit_effects) are not on the allow-list."""
    import alpes_dyn as ad

    front = [f"alpes_dyn.{n}" for n in ad.__all__ if inspect.isfunction(getattr(ad, n))]
    front += ["alpes_dyn.estimation.identify", "alpes_dyn.estimation.fit_effects"]
    assert not [q for q in front if q in failing or q in NOT_YET]


# ----------------------------------------------------------------------------- the modules' own APIs
def _modules() -> list[str]:
    """Every public module of the library (not a package's ``__init__``, not ``cli``, no ``_private`` part)."""
    import alpes_dyn

    return sorted(m.name for m in pkgutil.walk_packages(alpes_dyn.__path__, "alpes_dyn.")
                  if not m.ispkg and not m.name.startswith("alpes_dyn.cli")
                  and not any(p.startswith("_") for p in m.name.split(".")))


def module_failures() -> dict[str, int]:
    """Module (without ``alpes_dyn.``) -> how many of its own public callables (:func:`_callables` of the names
    of its ``__all__`` defined in it) leave an argument undocumented; modules with none left out."""
    out: dict[str, int] = {}
    for name in _modules():
        module = importlib.import_module(name)
        own = {n for n in getattr(module, "__all__", ())
               if getattr(getattr(module, n, None), "__module__", None) == name}
        bad = sum(1 for qual, fn, doc in _callables((name,)) if qual[len(name) + 1:].split(".")[0] in own
                  and _undocumented(fn, doc))
        if bad:
            out[name[len("alpes_dyn."):]] = bad
    return out


def test_module_apis_documented():
    """Every module's own public callables (:func:`module_failures`) document each argument as ``name : type``:
    none is left undocumented (issue 52's audit found 516 of 859 in 114 modules; all were documented since, and a
    new public function documents its arguments in numpydoc's form)."""
    found = module_failures()
    assert not found, f"undocumented arguments (name : type), callables per module: {found}"
