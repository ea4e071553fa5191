"""Typed errors of alpes_dyn. Every message is one line that names the faulty field or input."""

from __future__ import annotations


class AlpesDynError(Exception):
    """Base class of every error raised on purpose by alpes_dyn."""


class ModelError(AlpesDynError, ValueError):
    """A parameter file, URDF, model name, tip/frame name or model option is invalid."""


class InputError(AlpesDynError, ValueError):
    """A numeric input (vector, matrix, time step...) has the wrong shape or is not finite."""


class RecordingError(InputError):
    """A recording (CSV of an experiment) is missing a column, has wrong units, is too short or unexcited."""
