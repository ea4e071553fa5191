"""Moved to :mod:`alpes_dyn.analysis.observability` (this path is an alias of it)."""

from ._moved import alias

alias(__name__.rpartition(".")[2])
