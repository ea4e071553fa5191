"""The studies floor: many runs of the floors below, e.g. a robustness study over parameter draws
(:mod:`alpes_dyn.studies.sweep`), on Dask workers."""
