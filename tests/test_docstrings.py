"""Docstrings that define (issue 52): every public function and method of the public API documents every argument in
numpydoc's ``name : type`` form, as numpydoc's own parser reads it (after python-control's
``control/tests/docstrings_test.py``). The public API: the names in ``alpes_dyn.__all__`` and in each public
sub-package's ``__all__``; of a class, its constructor's arguments (in the class's docstring or ``__init__``'s) and
its public methods (defined on it or on a class of the library it inherits from, e.g. a mixin's)."""

from __future__ import annotations

import importlib
import inspect
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


def _public() -> Iterator[tuple[str, Any]]:
    """(qualified name, object) of every public function and class, each once (under its first package)."""
    seen: set[int] = set()
    for pkg in PACKAGES:
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


def _callables() -> Iterator[tuple[str, Callable, str]]:
    """(qualified name, callable, its docstring) of every public function, constructor and method."""
    for qual, obj in _public():
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
