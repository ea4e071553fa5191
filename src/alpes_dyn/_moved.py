"""Old import paths of version 0.1 that still hold: ``alpes_dyn.observability``, documented public API, an alias of
its module :mod:`alpes_dyn.analysis.observability` (no warning); and the names the old modules ``model``,
``symbolic``, ``simulation`` and ``control`` held that their packages do not re-export, forwarded with a
:class:`DeprecationWarning` (:func:`package_getattr`). The other old module paths (``alpes_dyn.params``,
``alpes_dyn.observers``, ...: :data:`REMOVED`) were deprecated aliases for one release and are gone."""

from __future__ import annotations

import importlib
import sys
import warnings
from types import ModuleType

__all__: list[str] = []

MOVED: dict[str, str] = {"observability": "analysis.observability"}
"""Old module (under ``alpes_dyn``) -> its new place (under ``alpes_dyn``), for the old paths that stay public."""

REMOVED: dict[str, str] = {
    "params": "model.params", "spec": "model.spec", "transmission": "model.transmission",
    "description": "model.description", "inertial": "model.inertial", "extras": "model.extras",
    "stops": "model.stops", "mjcf": "model.mjcf", "reference": "model.reference",
    "parametric": "symbolic.parametric", "statespace": "symbolic.statespace",
    "identifiability": "analysis.identifiability",
    "sensitivity": "simulation.sensitivity", "buildcache": "simulation.buildcache",
    "observers": "estimation.observers.observers", "recording": "estimation.experiments.recording",
    "experiment": "estimation.experiments.experiment", "identification": "estimation.identification.identification",
    "scenario": "estimation.observers.scenario",
}
"""The old module paths of version 0.1 that were deprecated aliases and are removed -> where the module is."""


def alias(old: str) -> ModuleType:
    """Make ``alpes_dyn.<old>`` the module ``alpes_dyn.<MOVED[old]>`` (a public old path: no warning)."""
    new = MOVED[old]
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
