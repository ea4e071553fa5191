"""The observer's step exported as standalone C, no Python (``alpes-dyn codegen``): the export and its test program
(:mod:`.cexport`), the EKF's step with its covariance arithmetic written out as loops over the nonzeros in the
order of :mod:`alpes_dyn.estimation.observers.covariance` (:mod:`.cexport_ekf`), and the model's code per chain,
the chains of one structure side by side in vector lanes (:mod:`.cexport_chains`). The filter is the one of
:mod:`alpes_dyn.estimation.observers` (report eqs. 3.1, 3.3, 3.13, 3.16), its estimates equal bit for bit.

Before the split this path was the module now at ``alpes_dyn.estimation.cexport.cexport``: a name of that module taken
from here still works, with a DeprecationWarning naming its new path, for one release (import it from the module,
or from :mod:`alpes_dyn.estimation` where it is listed there)."""

from ..._moved import package_getattr

__getattr__ = package_getattr("estimation.cexport", ("cexport",))
