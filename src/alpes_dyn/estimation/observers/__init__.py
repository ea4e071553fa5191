"""The observers: a finger's passive joints q_1..q_n estimated from its motor encoder. The EKF and UKF on the
report's state space (eqs. 3.1, 3.3, 3.16) discretised by one RK4 step per sample (:mod:`.observers`; the discrete
model, or the stick-slip law's steps, :mod:`.discrete`), their
covariance arithmetic in one fixed order of operations (:mod:`.covariance`), the observer as a block of the
simulation loop (:mod:`.blocks`), the estimation scenario -- a finger moved by its motor from the equilibrium of eq.
2.11, its encoder (eq. 3.13) and torque sensor simulated (:mod:`.scenario`, ``alpes-dyn estimate``) -- and the
observer run on a recording (:mod:`.replay`, ``alpes-dyn estimate --data``). Reads the recordings of
:mod:`alpes_dyn.estimation.experiments`; knows nothing of the fit.

Before the split this path was the module now at ``alpes_dyn.estimation.observers.observers``: a name of that module
taken from here still works, with a DeprecationWarning naming its new path, for one release (import it from the module,
or from :mod:`alpes_dyn.estimation` where it is listed there)."""

from ..._moved import package_getattr

__getattr__ = package_getattr("estimation.observers", ("observers",))
