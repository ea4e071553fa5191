"""The identification: a finger's physical parameters (springs K_i, masses m_i, friction, and the effects of a real
hand) fitted to a recording by output error with multiple shooting, the model's encoder reading q_m = S q (report
eq. 3.13) against the recorded one. The fit (:mod:`.identification`, ``alpes-dyn identify``), its shooting problem
(:mod:`.shooting`), its sparse linear algebra (:mod:`.kkt`) and constrained Gauss-Newton solver
(:mod:`.gauss_newton`), the parameters' physical bounds (:mod:`.bounds`), the result and the parameter file it
makes (:mod:`.fit_result`, :mod:`.identified_spec` for any robot's spec), the adequacy verdict -- does the model
explain the record or only fit it (:mod:`.adequacy`, :mod:`.harmonics`), judged again by the observer the file feeds
(:mod:`.observer_check`) -- and the fit extended with the real hand's effects (:mod:`.effects`, rotor inertia J_m
of eq. 2.8, stick-slip, the tendon's compliance, the tilt; ``--effects auto``'s rounds a table, :mod:`.rounds`).
Uses the experiments' recordings and the observers.

Before the split this path was the module now at ``alpes_dyn.estimation.identification.identification``: a name of that
module taken from here still works, with a DeprecationWarning naming its new path, for one release (import it from the
module, or from :mod:`alpes_dyn.estimation` where it is listed there)."""

from ..._moved import package_getattr

__getattr__ = package_getattr("estimation.identification", ("identification",))
