"""Moved to :mod:`alpes_dyn.simulation.buildcache` (this path is an alias of it, with a DeprecationWarning, for one release)."""

from ._moved import alias

alias(__name__.rpartition(".")[2])
