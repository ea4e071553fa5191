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
  angles are of the recording and its sensors, not of the robot: they stay in the result;
* a robot imported from an MJCF (``alpes-dyn import``) gets that MJCF back with the fitted values written in
  (:func:`identified_mjcf`, ``identify ... --mjcf ROBOT.xml -o ident.toml`` writes ``ident.xml``): the masses as
  :func:`identified_urdf` writes them, the springs, frictions and rotors where the import read them
  (:mod:`alpes_dyn.model.mjcf_update`), everything else as written; a tendon compliance (the encoder's reading of
  the cable's stretch, a sensor law MuJoCo's rigid tendon cannot hold) stays in the spec, said in the file.
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

__all__ = ["identified_spec", "identified_urdf", "identified_mjcf", "write_identified_spec", "spec_misfits"]

_TABLE = {"K": "stiffness", "F_s": "coulomb", "F_v": "viscous"}
_MOTOR_FIELD = {"J_m": "rotor_inertia", "tendon_compliance": "tendon_compliance", "capstan": "capstan"}
_OF_THE_RECORDING = ("encoder_offset", "tilt", "input_gain")


def spec_misfits(model: Model, names: Sequence[str]) -> list[str]:
    """The parameters among ``names`` that a spec file cannot hold: the masses (the URDF's).

    Parameters
    ----------
    model : Model
        The model the parameters are of.
    names : Sequence[str]
        Parameter names (:func:`~alpes_dyn.symbolic.parametric.parameter_catalogue`'s).

    Returns
    -------
    list[str]
        The masses among them, in their order.
    """
    cat = {p.name: p for p in parameter_catalogue(model)}
    return [n for n in names if n in cat and cat[n].kind == "m"]


def identified_spec(result: Any, base: TransmissionSpec, masses: str = "refuse") -> TransmissionSpec:
    """``base`` with the fitted values of ``result`` and the ``[identified]`` section: their standard errors and
    the fit's record (the module doc).

    Parameters
    ----------
    result : IdentificationResult
        An :class:`~alpes_dyn.estimation.identification.identification.IdentificationResult` of a model built on ``base``, or on
        its restriction to some branches (:meth:`~alpes_dyn.model.robot.Model.subtree`: the whole robot's spec with
        those values replaced).
    base : TransmissionSpec
        The spec the fitted model was built on.
    masses : str, optional
        ``"refuse"`` (default): a fitted mass is an error; ``"urdf"``: the masses are left out (to
        :func:`identified_urdf`).

    Returns
    -------
    TransmissionSpec
        The spec with the fitted values.

    Raises
    ------
    ModelError
        For a mass (``masses="refuse"``), a result whose joints or motors are not the spec's, or an unknown
        ``masses``.
    """
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
            # at the bound 0 where the fit crossed it (module bounds: a cable that shortens under tension has the
            # bound active); a negative tendon compliance made the file's own check refuse it after the whole fit
            value = max(float(value), 0.0) if p.kind in ("J_m", "capstan", "tendon_compliance") else float(value)
            motors[p.motor][_MOTOR_FIELD[p.kind]] = value
            std.setdefault(_MOTOR_FIELD[p.kind], {})[p.motor] = sd
        else:
            raise ModelError(f"identified spec: {name!r} has no place in a spec file")
    new_motors = tuple(Motor(m.name, dict(m.joints), **motors[m.name], ratio_curve=m.ratio_curve,
                             path=m.path) for m in base.motors)
    return dataclasses.replace(base, motors=new_motors, **tables, identified={"record": _record(result), **std})


def write_identified_spec(result: Any, base: TransmissionSpec, path: str | Path, masses: str = "refuse") -> Path:
    """Write :func:`identified_spec` to ``path`` (atomically), with a header naming the fit.

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit of a URDF robot.
    base : TransmissionSpec
        The spec fitted from, whose values the fit's replace.
    path : str or Path
        The TOML file.
    masses : {"refuse", "urdf"}, optional
        Fitted masses refused (a spec holds none), or left to the URDF written beside
        (:func:`identified_urdf`).

    Returns
    -------
    Path
        The file written.
    """
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
    its status, as the spec's header does).

    Parameters
    ----------
    result : IdentificationResult
        An :class:`~alpes_dyn.estimation.identification.identification.IdentificationResult` with fitted masses ``m_<joint>``.
    urdf : str
        The URDF's text (of the robot fitted, or of the whole robot a ``--chain`` sub-model was cut from).

    Returns
    -------
    str
        The URDF's text with the fitted masses.

    Raises
    ------
    ModelError
        If a fitted link is not in ``urdf`` or has no mass.
    """
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


_MJCF_JOINT = {"K": "stiffness", "F_s": "frictionloss", "F_v": "damping"}


def identified_mjcf(result: Any, base: TransmissionSpec, mjcf: str | Path, out: str | Path) -> tuple[str, list[str]]:
    """The text of the MJCF file ``mjcf`` that the fitted robot was imported from (``alpes-dyn import``;
    :mod:`alpes_dyn.model.mjcf_import`), with the values of ``result`` (a fit on the imported URDF + ``base``, or on
    a sub-model of it) written in for the file to be saved at ``out``
    (:func:`~alpes_dyn.model.mjcf_update.updated_mjcf`): ``m_<joint>`` as the joint's child body's mass (its
    inertia times m / m0, as :func:`identified_urdf`), ``K_<joint>`` as the joint's ``stiffness`` (and its
    ``springref``, where MuJoCo's differs, set to the spec's rest angle), ``F_s_<joint>`` as ``frictionloss``,
    ``F_v_<joint>`` as ``damping``, ``J_m_<motor>`` as the rotor of the motor's actuator; an XML comment before
    ``<mujoco>`` with the values and standard errors (and, for a fit not trustworthy, written with ``--force``,
    a second one saying so).

    Parameters
    ----------
    result : IdentificationResult
        An :class:`~alpes_dyn.estimation.identification.identification.IdentificationResult`: a fit on the imported URDF + ``base``,
        or on a sub-model of it.
    base : TransmissionSpec
        The spec the fitted model was built on.
    mjcf : str or pathlib.Path
        The MJCF file the robot was imported from.
    out : str or pathlib.Path
        Where the text is to be saved (its relative paths are written for that place).

    Returns
    -------
    tuple[str, list[str]]
        The text, and the fitted parameters the MJCF cannot hold (``tendon_compliance_<motor>``, named in the
        comment).

    Raises
    ------
    ModelError
        If a fitted mass's body has not the URDF's mass in the MJCF (not the file the robot was imported from) or
        for what ``updated_mjcf`` refuses.
    """
    from ...model.mjcf_equality import own_joint_values
    from ...model.mjcf_import import _compile, _mj, _name
    from ...model.mjcf_update import updated_mjcf
    from ...symbolic.parametric import _child_links

    if not isinstance(base, TransmissionSpec):
        raise ModelError(f"base: expected a TransmissionSpec, got {type(base).__name__}")
    mujoco = _mj()
    m = _compile(mjcf)
    O = mujoco.mjtObj
    bodies = {_name(mujoco, m, O.mjOBJ_BODY, b, "body"): b for b in range(1, m.nbody)}  # the import's names
    hinges = {_name(mujoco, m, O.mjOBJ_JOINT, j, "joint"): j for j in range(m.njnt)}
    cat = {p.name: p for p in parameter_catalogue(result.model)}
    links = _child_links(result.model)
    masses: dict[str, float] = {}
    joints: dict[str, dict[str, float]] = {}
    rotors: dict[str, float] = {}
    notes, omitted = [], []
    for name, value, sd in zip(result.names, result.values, result.std):
        p = cat.get(name)
        if p is None or p.kind in _OF_THE_RECORDING:
            continue
        v = float(value)
        if p.kind == "tendon_compliance":
            omitted.append(name)
            notes.append(f"{name} {v:.6g} {p.unit} NOT in this file (a sensor law MuJoCo's rigid tendon cannot hold; "
                         "in the spec)")
            continue
        if p.kind == "m":
            body = links[p.joint]
            b = bodies.get(body, -1)
            if b < 0 or not math.isclose(float(m.body_mass[b]), p.nominal, rel_tol=1e-9):
                was = "none" if b < 0 else f"{float(m.body_mass[b]):.6g} kg"
                raise ModelError(f"mjcf: body {body!r} (of {name}): {was} in the MJCF, {p.nominal:.6g} kg in the "
                                 "model's URDF; not the MJCF the model was imported from")
            if not (math.isfinite(v) and v > 0):
                raise ModelError(f"identified mjcf: {name} = {v!r} kg is not a positive mass; not written")
            masses[body] = v
        elif p.kind in _MJCF_JOINT:
            v = max(v, 0.0)
            joints.setdefault(p.joint, {})[_MJCF_JOINT[p.kind]] = v
            j = hinges.get(p.joint, -1)
            rest = float(base.rest_angle.get(p.joint, 0.0))
            if p.kind == "K" and j >= 0 and float(m.qpos_spring[m.jnt_qposadr[j]]) != rest:
                joints[p.joint]["springref"] = rest
        elif p.kind == "J_m":
            v = rotors[p.motor] = max(v, 0.0)
        else:
            raise ModelError(f"identified mjcf: {name!r} has no place in an MJCF file")
        notes.append(f"{name} {v:.6g} {p.unit} (was {p.nominal:.6g}, standard error {float(sd):.3g})")
    said = (f"identified by alpes_dyn from {_printable(result.recording_path) or 'a recording'} (model "
            f"{_printable(result.model.name)}): {'; '.join(notes)}")
    lines = [said] + ([] if result.trustworthy else [
        f"NOT TRUSTWORTHY (written with identify's force option): {_printable(result.status())}"])
    joints = own_joint_values(mujoco, m, joints, base.rest_angle)  # a joint others are tied to: its own values
    return updated_mjcf(mjcf, out, masses=masses, joints=joints, rotors=rotors, note=lines), omitted
