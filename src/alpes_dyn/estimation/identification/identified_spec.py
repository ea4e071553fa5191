"""The identified values of any robot's fit written into a copy of its transmission spec.

:func:`~alpes_dyn.estimation.identification.identification.identify` fits a URDF + spec :class:`~alpes_dyn.Model` as
well as an Alpes model; its result goes into the robot's own spec file (``alpes-dyn identify --model PATH.urdf --spec
FILE.toml -o ident.toml``), which every command reads back (``--spec ident.toml``):

* a spring ``K_<joint>`` into ``[stiffness]``, a friction ``F_s_<joint>``, ``F_v_<joint>`` into ``[coulomb]``,
  ``[viscous]``; a motor's ``J_m_<motor>`` and ``tendon_compliance_<motor>`` into its ``[[motor]]`` entry;
* each with its standard error in the ``[identified]`` section (``source = "identified"``), with the fit's
  record (converged, trustworthy, the adequacy verdict, the residual: the fields of
  :data:`~alpes_dyn.model.params.IDENTIFICATION_FIELDS`);
* a mass ``m_<joint>`` has no place in a spec (the masses and inertias are the URDF's): :func:`identified_spec`
  refuses it (:func:`spec_misfits` names such parameters before a fit); so are ``input_gain``, the encoder
  offsets and the tilt angles, of the recording and its sensors, not of the robot: they stay in the result.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Sequence

from ...errors import ModelError
from ...fileio import atomic_write
from ...model.robot import Model
from ...model.spec import Motor, TransmissionSpec
from ...symbolic.parametric import parameter_catalogue
from .fit_result import _printable, _record  # the same record as a parameter file's [identification.<chain>]

__all__ = ["identified_spec", "write_identified_spec", "spec_misfits"]

_TABLE = {"K": "stiffness", "F_s": "coulomb", "F_v": "viscous"}
_MOTOR_FIELD = {"J_m": "rotor_inertia", "tendon_compliance": "tendon_compliance"}
_OF_THE_RECORDING = ("encoder_offset", "tilt", "input_gain")


def spec_misfits(model: Model, names: Sequence[str]) -> list[str]:
    """The parameters among ``names`` that a spec file cannot hold: the masses (the URDF's)."""
    cat = {p.name: p for p in parameter_catalogue(model)}
    return [n for n in names if n in cat and cat[n].kind == "m"]


def identified_spec(result: Any, base: TransmissionSpec) -> TransmissionSpec:
    """``base`` with the fitted values of ``result`` (an
    :class:`~alpes_dyn.estimation.identification.identification.IdentificationResult` of a model built on ``base``, or
    on its restriction to some branches, :meth:`~alpes_dyn.model.robot.Model.subtree`: the whole robot's spec with
    those values replaced) and the ``[identified]`` section: their standard errors and the fit's record (the
    module doc).
    :class:`~alpes_dyn.ModelError` for a mass, or a result whose joints or motors are not the spec's."""
    if not isinstance(base, TransmissionSpec):
        raise ModelError(f"base: expected a TransmissionSpec, got {type(base).__name__}")
    model = result.model
    fitted = {m.name: dict(m.joints) for m in model.spec.motors} if model.spec is not None else {}
    ours = {m.name: dict(m.joints) for m in base.motors}
    if set(fitted) != set(model.motor_names) or any(ours.get(n) != j for n, j in fitted.items()):
        raise ModelError(f"base: the spec's motors {', '.join(m.name for m in base.motors)} do not hold the fitted "
                         f"model's {', '.join(model.motor_names)} (with their joints)")
    masses = spec_misfits(model, result.names)
    if masses:
        raise ModelError(f"identified spec: {', '.join(masses)}: a spec file holds no masses (they are the URDF's); "
                         "fit without them (e.g. --parameters K,friction) to write a spec")
    cat = {p.name: p for p in parameter_catalogue(model)}
    tables = {t: dict(getattr(base, t)) for t in _TABLE.values()}
    motors = {m.name: {"rotor_inertia": m.rotor_inertia, "tendon_compliance": m.tendon_compliance}
              for m in base.motors}
    std: dict[str, dict[str, float]] = {}
    for name, value, sd in zip(result.names, result.values, result.std):
        p = cat.get(name)
        if p is None or p.kind in _OF_THE_RECORDING:
            continue  # of the recording and its sensors (encoder zero, palm orientation, torque scale)
        sd = float(sd) if math.isfinite(sd) else math.inf
        if p.kind in _TABLE:
            tables[_TABLE[p.kind]][p.joint] = max(float(value), 0.0)
            std.setdefault(_TABLE[p.kind], {})[p.joint] = sd
        elif p.kind in _MOTOR_FIELD:
            value = max(float(value), 0.0) if p.kind == "J_m" else float(value)
            motors[p.motor][_MOTOR_FIELD[p.kind]] = value
            std.setdefault(_MOTOR_FIELD[p.kind], {})[p.motor] = sd
        else:
            raise ModelError(f"identified spec: {name!r} has no place in a spec file")
    new_motors = tuple(Motor(m.name, dict(m.joints), **motors[m.name]) for m in base.motors)
    return dataclasses.replace(base, motors=new_motors, **tables, identified={"record": _record(result), **std})


def write_identified_spec(result: Any, base: TransmissionSpec, path: str | Path) -> Path:
    """Write :func:`identified_spec` to ``path`` (atomically), with a header naming the fit."""
    spec = identified_spec(result, base)
    header = (f"# Identified by alpes_dyn from {_printable(result.recording_path) or 'a recording'} "
              f"(model {_printable(result.model.name)}, residual {result.residual_rms:.3g} counts RMS)\n")
    if not result.trustworthy:
        header += f"# NOT TRUSTWORTHY (written with --force): {_printable(result.status())}\n"
    return atomic_write(path, header + spec.to_toml())

