"""The estimation floor, in four sub-packages by concept, each pointing only at those before it:

* :mod:`alpes_dyn.estimation.experiments` -- what is done to the hand and the record it leaves (the recording's
  CSV, the experiment's design, simulation and adaptation, the seeded draws of a hand);
* :mod:`alpes_dyn.estimation.observers` -- the EKF and UKF, the estimation scenario, the observer on a recording;
* :mod:`alpes_dyn.estimation.identification` -- the fit of a finger's parameters, its adequacy verdict, the
  parameter file it writes;
* :mod:`alpes_dyn.estimation.cexport` -- the observer's step as standalone C.

The names a user needs most are here too, so that a script reads ``from alpes_dyn.estimation import identify``
(each imported on first use, like the sub-packages: importing this package costs nothing)::

    from alpes_dyn.estimation import adapted_experiment, ExperimentDesign, identify, estimate_recording

The module paths of before the split (``alpes_dyn.estimation.adapt``, ...: :data:`MOVED`) still import, the same
module, with a :class:`DeprecationWarning` naming the new path, and so do the names of the three modules that are
now rooms (``from alpes_dyn.estimation.identification import identify``); they go in the next release
(CHANGELOG.md).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

EXPORTS: dict[str, str] = {
    # experiments
    "Recording": "experiments.recording", "read_recording": "experiments.recording",
    "write_recording": "experiments.recording", "ExperimentDesign": "experiments.design",
    "experiment": "experiments.experiment", "model_experiment": "experiments.experiment",
    "adapted_experiment": "experiments.adapt", "hand_experiment": "experiments.hand_experiment",
    "perturbed_params": "experiments.draws",
    # observers
    "KalmanFilter": "observers.observers", "ExtendedKalmanFilter": "observers.observers",
    "UnscentedKalmanFilter": "observers.observers", "OnlineFilter": "observers.online_filter",
    "Estimate": "observers.observers", "make_observer": "observers.observers",
    "run_estimation": "observers.scenario", "estimate_recording": "observers.replay",
    # identification
    "identify": "identification.identification", "IdentificationResult": "identification.fit_result",
    "identified_params": "identification.fit_result", "fit_effects": "identification.effects",
    "write_identified_spec": "identification.identified_spec",
    # C export
    "write_c_observer": "cexport.cexport",
}
"""Public name -> the module (under ``alpes_dyn.estimation``) that defines it."""

SUBPACKAGES = ("experiments", "observers", "identification", "cexport")

MOVED: dict[str, str] = {
    **{m: f"experiments.{m}" for m in ("recording", "design", "draws", "excursion", "multisine", "trim",
                                        "experiment", "adapt", "hand_experiment")},
    **{m: f"observers.{m}" for m in ("covariance", "blocks", "scenario", "replay")},
    **{m: f"identification.{m}" for m in ("kkt", "shooting", "gauss_newton", "bounds", "fit_result",
                                           "identified_spec", "adequacy", "harmonics", "observer_check", "effects")},
    **{m: f"cexport.{m}" for m in ("cexport_ekf", "cexport_chains")},
}
"""The modules' paths before the split (issue 36) -> their sub-package's module, under ``alpes_dyn.estimation``.
``observers``, ``identification`` and ``cexport`` are now the sub-packages themselves (their module inside:
``observers.observers``, ...), so they are not here."""

__all__ = sorted(EXPORTS)


def __getattr__(name: str) -> object:
    if name in EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{EXPORTS[name]}"), name)
        globals()[name] = value
        return value
    if name in SUBPACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(EXPORTS) | set(SUBPACKAGES))


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports ``alpes_dyn.estimation.<old>`` (:data:`MOVED`) as the module at its new path, with a warning."""

    def find_spec(self, fullname, path=None, target=None):
        old = fullname.removeprefix(__name__ + ".")
        if old == fullname or old not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        new = f"{__name__}.{MOVED[spec.name.removeprefix(__name__ + '.')]}"
        warnings.warn(f"{spec.name} moved to {new}; the old path goes in the next release", DeprecationWarning,
                      stacklevel=2)
        module = importlib.import_module(new)
        spec.loader_state = module.__spec__  # the import system sets the old path's spec on it: kept to put back
        return module

    def exec_module(self, module):
        module.__spec__ = module.__spec__.loader_state  # the module at its new path, already run, with its own spec


if not any(isinstance(f, _MovedModules) for f in sys.meta_path):
    sys.meta_path.append(_MovedModules())
