"""Old import paths of the modules moved into sub-packages (version 0.2): each old module name is an
alias of its new module, importable for one release with a :class:`DeprecationWarning`."""

from __future__ import annotations

import importlib
import sys
import warnings
from types import ModuleType

__all__: list[str] = []

MOVED: dict[str, str] = {
    "params": "model.params", "spec": "model.spec", "transmission": "model.transmission",
    "description": "model.description", "inertial": "model.inertial", "extras": "model.extras",
    "stops": "model.stops", "mjcf": "model.mjcf", "reference": "model.reference",
    "parametric": "symbolic.parametric", "statespace": "symbolic.statespace",
    "identifiability": "analysis.identifiability", "observability": "analysis.observability",
    "sensitivity": "simulation.sensitivity", "buildcache": "simulation.buildcache",
    "observers": "estimation.observers", "recording": "estimation.recording", "experiment": "estimation.experiment",
    "identification": "estimation.identification", "scenario": "estimation.scenario",
}
"""Old module (under ``alpes_dyn``) -> its new place (under ``alpes_dyn``)."""

PUBLIC: frozenset[str] = frozenset({"observability"})
"""Old paths that stay documented public API (no warning): ``alpes_dyn.observability``."""


def alias(old: str) -> ModuleType:
    """Make ``alpes_dyn.<old>`` the module ``alpes_dyn.<MOVED[old]>`` (warning unless public)."""
    new = MOVED[old]
    if old not in PUBLIC:
        warnings.warn(f"alpes_dyn.{old} moved to alpes_dyn.{new}; the old path goes in the next release",
                      DeprecationWarning, stacklevel=3)
    module = importlib.import_module(f"alpes_dyn.{new}")
    sys.modules[f"alpes_dyn.{old}"] = module
    return module


def forward(package: str, module: str, name: str) -> object:
    """A name the package's old module held that its ``__init__`` does not re-export: taken from
    ``alpes_dyn.<package>.<module>`` with a :class:`DeprecationWarning` (module ``__getattr__``)."""
    mod = importlib.import_module(f"alpes_dyn.{package}.{module}")
    try:
        value = getattr(mod, name)
    except AttributeError:
        raise AttributeError(f"module 'alpes_dyn.{package}' has no attribute {name!r}") from None
    warnings.warn(f"alpes_dyn.{package}.{name} moved to alpes_dyn.{package}.{module}.{name}; the old path goes in "
                  "the next release", DeprecationWarning, stacklevel=3)
    return value


def package_getattr(package: str, modules: tuple[str, ...]):
    """The module ``__getattr__`` of a package that was a module (``alpes_dyn.model``, ...): a name of the old
    module that the package does not re-export is taken from the first of ``modules`` that has it, with a
    DeprecationWarning (:func:`forward`)."""
    def __getattr__(name: str) -> object:
        if name.startswith("__"):
            raise AttributeError(name)
        for module in modules:
            try:
                return forward(package, module, name)
            except AttributeError:
                continue
        raise AttributeError(f"module 'alpes_dyn.{package}' has no attribute {name!r}")
    return __getattr__
