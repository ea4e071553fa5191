"""The identified values of any robot's fit written into a copy of its transmission spec.

:func:`~alpes_dyn.estimation.identification.identification.identify` fits a URDF + spec :class:`~alpes_dyn.Model` as
well as an Alpes model; its result goes into the robot's own spec file (``alpes-dyn identify --model PATH.urdf --spec
FILE.toml -o ident.toml``), which every command reads back (``--spec ident.toml``):

* a spring ``K_<joint>`` into ``[stiffness]``, a friction ``F_s_<joint>``, ``F_v_<joint>`` into ``[coulomb]``,
  ``[viscous]``; a motor's ``J_m_<motor>``, ``tendon_compliance_<motor>`` and ``capstan_<motor>`` into its ``[[motor]]`` entry;
* each with its standard error in the ``[identified]`` section (``source = "identified"``), with the fit's
  record (converged, trustworthy, the adequacy verdict, the residual: the fields of
  :data:`~alpes_dyn.model.params.IDENTIFICATION_FIELDS`);
* a mass ``m_<joint>`` has no place in a spec (the masses and inertias are the URDF's): :func:`identified_spec`
  refuses it (:func:`spec_misfits` names such parameters before a fit) unless ``masses="urdf"``, where it is left to
  :func:`identified_urdf`: the robot's URDF with that joint's child link's mass set to the fitted value and its
  inertia tensor scaled by the same ratio, its centre of mass kept (the fit's own parametrisation, the link's
  spatial inertia times m / m0, :class:`~alpes_dyn.symbolic.parametric.ParametricDynamics`), so that the pair
  ``--model ident.urdf --spec ident.toml`` is the identified robot; ``input_gain``, the encoder offsets and the tilt
  angles are of the recording and its sensors, not of the robot: they stay in the result.
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

__all__ = ["identified_spec", "identified_urdf", "write_identified_spec", "spec_misfits"]

_TABLE = {"K": "stiffness", "F_s": "coulomb", "F_v": "viscous"}
_MOTOR_FIELD = {"J_m": "rotor_inertia", "tendon_compliance": "tendon_compliance", "capstan": "capstan"}
_OF_THE_RECORDING = ("encoder_offset", "tilt", "input_gain")


def spec_misfits(model: Model, names: Sequence[str]) -> list[str]:
    """The parameters among ``names`` that a spec file cannot hold: the masses (the URDF's)."""
    cat = {p.name: p for p in parameter_catalogue(model)}
    return [n for n in names if n in cat and cat[n].kind == "m"]


def identified_spec(result: Any, base: TransmissionSpec, masses: str = "refuse") -> TransmissionSpec:
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
    if masses not in ("refuse", "urdf"):
        raise ModelError(f"masses: expected 'refuse' or 'urdf', got {masses!r}")
    misfits = spec_misfits(model, result.names)
    if misfits and masses == "refuse":
        raise ModelError(f"identified spec: {', '.join(misfits)}: a spec file holds no masses (they are the URDF's); "
                         "fit without them (e.g. --parameters K,friction) to write a spec")
    cat = {p.name: p for p in parameter_catalogue(model)}
    tables = {t: dict(getattr(base, t)) for t in _TABLE.values()}
    motors = {m.name: {"rotor_inertia": m.rotor_inertia, "tendon_compliance": m.tendon_compliance,
                       "capstan": m.capstan} for m in base.motors}
    std: dict[str, dict[str, float]] = {}
    for name, value, sd in zip(result.names, result.values, result.std):
        p = cat.get(name)
        if p is None or p.kind in _OF_THE_RECORDING or p.kind == "m":
            continue  # of the recording and its sensors (encoder zero, palm orientation, torque scale); a mass: URDF's
        sd = float(sd) if math.isfinite(sd) else math.inf
        if p.kind in _TABLE:
            tables[_TABLE[p.kind]][p.joint] = max(float(value), 0.0)
            std.setdefault(_TABLE[p.kind], {})[p.joint] = sd
        elif p.kind in _MOTOR_FIELD:
            value = max(float(value), 0.0) if p.kind in ("J_m", "capstan") else float(value)
            motors[p.motor][_MOTOR_FIELD[p.kind]] = value
            std.setdefault(_MOTOR_FIELD[p.kind], {})[p.motor] = sd
        else:
            raise ModelError(f"identified spec: {name!r} has no place in a spec file")
    new_motors = tuple(Motor(m.name, dict(m.joints), **motors[m.name], ratio_curve=m.ratio_curve) for m in base.motors)
    return dataclasses.replace(base, motors=new_motors, **tables, identified={"record": _record(result), **std})


def write_identified_spec(result: Any, base: TransmissionSpec, path: str | Path, masses: str = "refuse") -> Path:
    """Write :func:`identified_spec` to ``path`` (atomically), with a header naming the fit."""
    spec = identified_spec(result, base, masses)
    header = (f"# Identified by alpes_dyn from {_printable(result.recording_path) or 'a recording'} "
              f"(model {_printable(result.model.name)}, residual {result.residual_rms:.3g} counts RMS)\n")
    if not result.trustworthy:
        header += f"# NOT TRUSTWORTHY (written with --force): {_printable(result.status())}\n"
    return atomic_write(path, header + spec.to_toml())



def identified_urdf(result: Any, urdf: str) -> str:
    """``urdf`` (the text of the robot fitted, or of the whole robot a ``--chain`` sub-model was cut from: the links
    have the same names) with each fitted mass ``m_<joint>`` of ``result`` written on the joint's child link: mass
    m [kg], inertia tensor times m / m0, centre of mass kept (the module doc), and an XML comment with the values and
    their standard errors (and, for a fit not trustworthy, written with ``--force``, a second comment saying so with
    its status, as the spec's header does). :class:`~alpes_dyn.ModelError` if a fitted link is not in ``urdf`` or
    has no mass."""
    import xml.etree.ElementTree as ET

    from ...symbolic.parametric import _child_links

    links = _child_links(result.model)
    cat = {p.name: p for p in parameter_catalogue(result.model)}
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise ModelError(f"urdf: not XML ({exc})") from None
    by_name = {link.get("name"): link for link in root.iter("link")}
    notes = []
    for name, value, sd in zip(result.names, result.values, result.std):
        p = cat.get(name)
        if p is None or p.kind != "m":
            continue
        link = by_name.get(links[p.joint])
        mass = link.find("inertial/mass") if link is not None else None
        if mass is None or not float(mass.get("value")) > 0:
            raise ModelError(f"urdf: {name}: link {links[p.joint]!r} is not in the URDF with a mass")
        m0, m = float(mass.get("value")), float(value)
        if not (math.isfinite(m) and m > 0):
            raise ModelError(f"identified urdf: {name} = {m!r} kg is not a positive mass; not written")
        mass.set("value", repr(m))
        inertia = link.find("inertial/inertia")
        if inertia is not None:
            for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
                if inertia.get(key) is not None:
                    inertia.set(key, repr(float(inertia.get(key)) * m / m0))
        notes.append(f"{link.get('name')}: {m:.6g} kg (was {m0:.6g}, standard error {float(sd):.3g})")
    if not notes:
        raise ModelError("identified urdf: the fit has no mass (--parameters m or m_<joint>)")
    said = (f"identified by alpes_dyn from {_printable(result.recording_path) or 'a recording'} (model "
            f"{_printable(result.model.name)}): {'; '.join(notes)}")
    head = f"<!-- {said.replace('--', '- -')} -->\n"  # no "--" inside an XML comment
    if not result.trustworthy:  # as the spec's header says it (write_identified_spec)
        why = _printable(result.status()).replace("--", "- -")
        head += f"<!-- NOT TRUSTWORTHY (written with identify's force option): {why} -->\n"
    return '<?xml version="1.0"?>\n' + head + ET.tostring(root, encoding="unicode") + "\n"
