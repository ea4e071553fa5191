"""The parameter file's schema: its sections and fields with their lengths, constraints and units, the optional
fields, the per-finger overrides, the sources and the fields of an identification record.

Read by :mod:`alpes_dyn.model.params` (validation on load, the writer's order); one concept: what a parameter file
may hold.
"""

from __future__ import annotations

__all__ = ["SOURCES", "OVERRIDE_FIELDS", "IDENTIFICATION_FIELDS"]

# field name -> (length or None for a scalar, constraint) ; constraint in {"pos", "nonneg", "any", "str", "unit"}
_SCHEMA: dict[str, dict[str, tuple[int | None, str]]] = {
    "finger": {
        "L": (3, "pos"), "s": (3, "pos"), "m": (3, "pos"), "I": (3, "pos"), "r": (None, "pos"),
        "K": (3, "nonneg"), "b": (None, "nonneg"), "radius": (None, "pos"),
        "lower": (None, "any"), "upper": (None, "any"), "F_s": (3, "nonneg"), "F_v": (3, "nonneg"),
        "encoder_offset": (None, "any")},
    "thumb": {
        "L": (2, "pos"), "s": (2, "pos"), "m": (2, "pos"), "I": (2, "pos"), "K": (2, "nonneg"),
        "radius": (None, "pos"), "base_mass": (None, "pos"), "abduction_K": (None, "nonneg"), "abduction_axis": (3, "unit"),
        "abduction_lower": (None, "any"), "abduction_upper": (None, "any"), "F_s": (2, "nonneg"), "F_v": (2, "nonneg"),
        "abduction_F_s": (None, "nonneg"), "abduction_F_v": (None, "nonneg"),
        "encoder_offset": (None, "any"), "abduction_encoder_offset": (None, "any")},
    "palm": {"finger_names": (4, "str"), "finger_x": (4, "any"), "finger_y": (4, "any"), "thumb_xyz": (3, "any"),
             "thumb_yaw": (None, "any")},
    "transmission": {
        "r_m": (None, "pos"), "abduction_ratio": (None, "pos"), "J_m": (None, "nonneg"),
        "N": (None, "pos"), "encoder_counts": (None, "pos"), "tau_max": (None, "pos"),
        "tendon_compliance": (None, "nonneg"), "capstan": (None, "nonneg"), "torque_delay": (None, "nonneg"),
    },
    "friction": {"F_s": (None, "nonneg"), "F_v": (None, "nonneg"), "smooth_velocity": (None, "pos"),
                 "law": (None, "law"), "sigma0": (None, "pos"), "sigma1": (None, "pos"),
                 "creep_kappa": (None, "pos"), "creep_rate": (None, "pos"), "model_error": (None, "nonneg"),
                 "observer_law": (None, "observer_law")},
    "environment": {"gravity": (3, "any")},
}
# per-joint friction of a chain: optional, overrides friction.F_s / friction.F_v on that chain's joints
_OPTIONAL = {"finger.F_s", "finger.F_v", "thumb.F_s", "thumb.F_v", "thumb.abduction_F_s", "thumb.abduction_F_v",
             "transmission.tendon_compliance", "transmission.capstan", "transmission.torque_delay",
             "finger.encoder_offset", "thumb.encoder_offset", "thumb.abduction_encoder_offset",
             "friction.law", "friction.sigma0", "friction.sigma1", "friction.creep_kappa",
             "friction.creep_rate", "friction.model_error",
             "friction.observer_law"}  # the law with a state: model.friction
# the unit each field's value is read in: a file giving another one is refused (no conversion is made)
_UNITS: dict[str, str] = {
    **{f"finger.{k}": "m" for k in ("L", "s", "r", "b", "radius")}, "finger.m": "kg", "finger.I": "kg m^2",
    "finger.K": "N m/rad", "finger.lower": "rad", "finger.upper": "rad", "finger.F_s": "N m",
    "finger.F_v": "N m s/rad", "finger.encoder_offset": "rad",
    **{f"thumb.{k}": "m" for k in ("L", "s", "radius")}, "thumb.m": "kg", "thumb.I": "kg m^2", "thumb.K": "N m/rad",
    "thumb.base_mass": "kg", "thumb.abduction_K": "N m/rad", "thumb.abduction_axis": "-", "thumb.abduction_lower": "rad",
    "thumb.abduction_upper": "rad", "thumb.F_s": "N m", "thumb.F_v": "N m s/rad", "thumb.abduction_F_s": "N m",
    "thumb.abduction_F_v": "N m s/rad", "thumb.encoder_offset": "rad", "thumb.abduction_encoder_offset": "rad",
    "palm.finger_names": "-", "palm.finger_x": "m", "palm.finger_y": "m", "palm.thumb_xyz": "m", "palm.thumb_yaw": "rad",
    "transmission.r_m": "m", "transmission.abduction_ratio": "-", "transmission.J_m": "kg m^2", "transmission.N": "-",
    "transmission.encoder_counts": "counts/rev", "transmission.tau_max": "N m",
    "transmission.tendon_compliance": "rad/(N m)", "transmission.capstan": "-", "transmission.torque_delay": "samples",
    "friction.F_s": "N m", "friction.F_v": "N m s/rad", "friction.smooth_velocity": "rad/s",
    "friction.law": "-", "friction.sigma0": "N m/rad", "friction.sigma1": "N m s/rad",
    "friction.creep_kappa": "-", "friction.creep_rate": "1/s", "friction.model_error": "F_s",
    "friction.observer_law": "-",
    "environment.gravity": "m/s^2",
}
_INTEGER = {"transmission.encoder_counts", "transmission.torque_delay"}  # fields whose value must be a whole number
_ENTRY_KEYS = {"value", "unit", "source", "reason", "description", "std"}
# per-finger overrides: a table [finger.<name>] (name from palm.finger_names) with any of these fields, which
# replace the shared [finger] values on that finger only (a real hand's fingers differ link by link)
OVERRIDE_FIELDS: dict[str, tuple[int, str]] = {
    "K": (3, "nonneg"), "m": (3, "pos"), "I": (3, "pos"), "F_s": (3, "nonneg"), "F_v": (3, "nonneg"),
    "encoder_offset": (None, "any"),
}
"""Fields a per-finger section ``[finger.<name>]`` may hold: 3-arrays, one entry per phalanx, and that finger's
encoder zero ``encoder_offset`` (rad of its motor)."""
SOURCES: tuple[str, ...] = ("report", "assumed", "identified")
IDENTIFICATION_FIELDS: dict[str, type] = {
    "model": str, "recording": str, "converged": bool, "stop": str, "adequate": bool, "trustworthy": bool,
    "verdict": str, "likely_missing": list, "residual_rms": float, "sensor_floor": float, "not_identified": list,
    "standard_errors": str, "friction": bool,
}
"""Fields of a table ``[identification.<chain>]`` (each optional): the model fitted, the recording, whether
the fit converged and why it stopped, the adequacy verdict (``adequate``, its one-line ``verdict``, the
``likely_missing`` effects), ``trustworthy`` (converged and adequate: false only in a file written with
``alpes-dyn identify --force``), the residual and the sensor floor (counts RMS), and ``not_identified``: each
parameter the fit did not identify, with why and the effect the data do not support (its value never written:
:mod:`~alpes_dyn.estimation.identification.bounds`), and ``standard_errors``: how the ``std`` written were made
(the larger of the classical and the robust HAC sandwich's, which parameters the robust one:
:mod:`~alpes_dyn.estimation.identification.robust_covariance`); ``friction``: the model fitted had friction
(:func:`~alpes_dyn.model.trust.fitted_friction`)."""
