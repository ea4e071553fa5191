"""Transmission spec: what a URDF cannot hold about a tendon-driven robot, for any URDF.

A :class:`TransmissionSpec` names the motors, the joints each drives with their ratios and the rotor
inertia of each, the encoder resolution, and per-joint springs, friction and joint-side inertia. With a URDF it makes a
:class:`~alpes_dyn.Model` (``Model(urdf, spec)``, ``Model.from_urdf_file(path, spec)``) that has
everything an Alpes model has: motor input, encoder outputs, springs, friction, rotor inertia. The
Alpes models themselves are built the same way, from the spec :func:`alpes_spec` makes out of the
parameter file.

Conventions (report Section 3, eq. 3.13): motor k reads q_m,k = sum_i ratio_ki q_i over the joints it
drives, i.e. q_m = S q with S (m, n); by power balance the motor torques act on the joints as
Gamma = S^T tau_m. Joint i carries a spring torque k_i (q_i - q_rest,i) (k in N m/rad; zero at the rest angle
q_rest,i, rad, the ``[rest_angle]`` table, default 0), friction
F_s,i sign(qd_i) + F_v,i qd_i (N m, N m s/rad; eq. 2.6-2.7) and a joint-side inertia I_a,i (kg m^2,
the ``[armature]`` table: added to A's diagonal, Pinocchio's ``armature``; e.g. a motor or a gearbox
that drives that joint alone). Joints a table does not list get zero.

Rotor inertia on the tendon (eq. 2.8's I_a, the motor's side): motor k's ``rotor_inertia`` J_m,k
(kg m^2 about the motor shaft) turns with qd_m,k = S_k qd, so its kinetic energy 1/2 J_m,k (S_k qd)^2
adds S^T diag(J_m) S to the mass matrix: J_m,k ratio_ki ratio_kj on *every* entry (i, j) of the joints the
motor drives, not only on the diagonal. A motor that drives one joint with ratio N adds N^2 J_m to
that joint's diagonal: the same as an ``[armature]`` entry N^2 J_m.

Tendon compliance (a series-elastic tendon in its quasi-static limit): motor k's ``tendon_compliance`` C_k
(rad of motor shaft per N m of motor torque) is the cable's stretch the encoder sees, y_k = S_k q + C_k
tau_m,k, with tau_m,k the torque held over the period before the reading (in a sampled record the tension at
t_j has seen the torque of [t_j-1, t_j): :func:`~alpes_dyn.model.transmission.torque_before`). A cable of stiffness k_t (N/m) on a motor pulley of radius r_m has C = 1 / (k_t r_m^2). This holds
while the rotor on the cable (J_m on k_t r_m^2) resonates well above the motion's band and the cable stays
taut; the joints' dynamics are the rigid tendon's (with the rotor's J_m S^T S). 0 (default): a rigid tendon.

Tendon-sheath friction (capstan): motor k's ``capstan`` mu theta (dimensionless, >= 0: the friction coefficient of
its cable on the sheaths and pulleys it slides over times their total wrap angle, rad) makes the tendon lose a
fraction of its tension that grows with the tension, 1 - exp(-mu theta) where the motor pulls the cable (the capstan
equation T_out = T_in exp(-mu theta)): the joints get S^T (tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c)), a
friction on the motor side proportional to the tension and opposing the tendon's velocity v_m = S qd
(:func:`~alpes_dyn.model.transmission.capstan_torque`, the smooth sign's scale v_c = v_s max_i |ratio_i|). 0
(default): no sheath friction. A Bowden sheath bent through 90 degrees with mu = 0.2 is mu theta = 0.31.

Configuration-dependent ratios (a tendon over sites and wrapping geometry, a measured moment-arm curve): a motor's
``ratio_curve`` {joint: [c_1, ..., c_P]} makes that joint's ratio rho_i(q_i) = ratio_i + c_1 q_i + ... + c_P q_i^P
(P <= 16; ``joints`` gives the ratio at q = 0). The motor angle is then the tendon's length over the pulley radius,
s(q) = sum_i int_0^q_i rho_i, its Jacobian rho(q) maps the motor torques onto the joints (rho(q)^T tau_m) and the
rotor adds rho(q)^T J_m rho(q) and its velocity product (:mod:`alpes_dyn.model.ratio_curve`;
:func:`~alpes_dyn.model.ratio_curve.fit_ratio_curve` turns a measured curve into these coefficients). Without it
the ratios are constant and everything is as above.

The TOML file (every key optional except ``[[motor]]`` entries' ``name`` and ``joints``)::

    name = "allegro_tendon"        # model label (default: the URDF's robot name)
    encoder_counts = 4096          # encoder counts per motor revolution (quantisation)
    smooth_velocity = 0.01         # rad/s, tanh(v / v_s) replaces sign(v) where smoothness is needed
    gravity = [0.0, 0.0, -9.81]    # m/s^2 in the base frame (default: this one)
    tips = ["link_3.0_tip"]        # tip frames, the first is the default tip (default: the URDF's leaves,
                                   # and no default tip where there are several: Model.default_tip)

    [[motor]]                      # one table per motor, in motor order
    name = "index"
    joints = { "joint_1.0" = 2.0, "joint_2.0" = 1.6, "joint_3.0" = 1.2 }   # joint -> ratio
    rotor_inertia = 1.0e-7         # kg m^2 on the motor shaft (optional, default 0)
    tendon_compliance = 0.1        # rad/(N m): the tendon's stretch seen by the encoder (optional, default 0)
    capstan = 0.3                  # mu theta: the tendon-sheath friction (optional, default 0; see below)
    ratio_curve = { "joint_1.0" = [-0.5, 0.1] }   # optional: the ratio changes with the joint (below)

    [stiffness]                    # N m/rad
    "joint_1.0" = 0.2
    [rest_angle]                   # rad, where the joint's spring exerts no torque (default 0; any sign)
    "joint_1.0" = 0.1              # (only on a joint of [stiffness]: a rest angle belongs to a spring)
    [coulomb]                      # N m
    [viscous]                      # N m s/rad
    [armature]                     # kg m^2, joint-side (diagonal) inertia

    [stops]                        # joint stops (optional; default: sized to the robot, alpes_dyn.model.stops)
    stiffness = 40.0               # N m/rad (> 0), every joint with a finite limit
    damping = 0.05                 # N m s/rad (>= 0)
    [stops.joints]                 # per joint, over the robot-wide values (either key may be left out)
    "joint_1.0" = { stiffness = 80.0, damping = 0.1 }

    [identified]                   # optional, written by `alpes-dyn identify -o`: the values it fitted
    source = "identified"          # (source = "identified"), the fit's record (IDENTIFICATION_FIELDS) ...
    recording = "rec.csv"
    converged = true
    trustworthy = true
    residual_rms = 0.58            # counts RMS
    [identified.stiffness]         # ... and the standard error of each value it wrote, in the value's unit
    "joint_1.0" = 4.0e-5           # (inf: a value the recording does not see; the start kept)
    [identified.tendon_compliance] # per motor: rotor_inertia, tendon_compliance, capstan
    index = 1.0e-3

The ``[stops]`` table gives the unilateral spring-damper end stops of :class:`~alpes_dyn.model.stops.JointStops`
(``JointStops.of(model)``, ``simulate(..., stops=)``), the MJCF export (each such joint's ``solreflimit`` and
``solimplimit``, :mod:`alpes_dyn.model.mjcf_export`) and ``alpes-dyn dynamics``' stop table (source ``spec``): a joint
the table leaves without a value gets the sized one (:func:`~alpes_dyn.model.stops.sized_stops`; a damping left out
is sized to the stiffness given). A value on a joint without a finite limit is refused where stops are built.

Every table of ``[identified]`` names values the spec holds (a joint of its ``[stiffness]``, ``[coulomb]``,
``[viscous]`` table, a motor of its ``[[motor]]`` entries); the record is informative, the values are used as
they are (:data:`IDENTIFIED_TABLES`).

The shipped example for the Allegro hand of example-robot-data is ``example_spec_path("allegro_hand")``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np

from .description import Layout
from ..errors import ModelError
from ..fileio import load_toml, read_text
from .extras import JointExtras, spring_stiffness
from .params import IDENTIFICATION_FIELDS, HandParams
from .spec_values import STOP_KEYS, STOPS_TABLE, _name, _number, _ratio_curve, parse_stops, stop_values, stops_toml
from .spatial_path import spatial_path
from .transmission import Transmission

__all__ = ["Motor", "TransmissionSpec", "load_spec", "alpes_spec", "alpes_motors", "alpes_transmission", "example_spec_path", "JOINT_TABLES",
           "IDENTIFIED_TABLES", "REST_TABLE", "STOPS_TABLE", "STOP_KEYS"]

JOINT_TABLES: tuple[str, ...] = ("stiffness", "coulomb", "viscous", "armature")
"""Per-joint tables of a spec: spring k (N m/rad), Coulomb F_s (N m), viscous F_v (N m s/rad), joint-side
inertia (kg m^2, the diagonal; a motor's rotor on its tendon is the motor's ``rotor_inertia``)."""
REST_TABLE = "rest_angle"
"""The per-joint table of the springs' rest angles q_rest (rad, either sign; default 0): the spring torque is
k (q - q_rest) (:func:`~alpes_dyn.model.extras.spring_law`). Only on a joint the ``[stiffness]`` table lists."""
_TOP_KEYS = ("name", "encoder_counts", "smooth_velocity", "gravity", "tips", "spring", "motor") + JOINT_TABLES + (
    REST_TABLE, STOPS_TABLE, "identified")
IDENTIFIED_TABLES: tuple[str, ...] = ("stiffness", "coulomb", "viscous", "rotor_inertia", "tendon_compliance",
                                      "capstan")
"""The tables of a spec's ``[identified]`` section: the standard error of each identified value, by joint (the
per-joint tables) or by motor (``rotor_inertia``, ``tendon_compliance``, ``capstan``)."""
_MOTOR_KEYS = ("name", "joints", "rotor_inertia", "tendon_compliance", "ratio_curve", "capstan", "path")
_MOTOR_REQUIRED = ("name", "joints")


@dataclass(frozen=True)
class Motor:
    """One motor and its tendon: q_m = sum_i ratio_i q_i over ``joints`` {joint name: ratio}.

    ``ratio`` is rad of motor shaft per rad of joint (r_i / r_m for a pulley of radius r_i on the
    joint and r_m on the motor); non-zero and finite. ``rotor_inertia``: J_m (kg m^2, >= 0) of the
    rotor (and gearbox) about the motor shaft, which adds J_m ratio_i ratio_j to the mass matrix's
    entry (i, j) (eq. 2.8's I_a on the tendon coordinate; see the module doc). ``tendon_compliance``: C
    (rad/(N m), finite) of the tendon: the encoder reads S q + C tau_m, tau_m held before the reading (the module doc; 0 is rigid).
    ``ratio_curve``: {joint name: (c_1, ..., c_P)} the coefficients of q^1 .. q^P of that joint's ratio
    (rad/rad^(p+1); P <= :data:`~alpes_dyn.model.ratio_curve.MAX_CURVE_DEGREE`), each joint one of ``joints``; empty
    (default): constant ratios. ``capstan``: mu theta (dimensionless, finite, >= 0) of the tendon's sheath friction
    (the module doc; 0: none). ``path``: the tendon's geometry, its ratios from its length (``joints`` those at q = 0;
    :func:`~alpes_dyn.model.spatial_path.spatial_path`); None (default): none.
    """

    name: str
    joints: Mapping[str, float]
    rotor_inertia: float = 0.0
    tendon_compliance: float = 0.0
    ratio_curve: Mapping[str, Sequence[float]] = field(default_factory=dict)
    capstan: float = 0.0
    path: Any = None

    def __post_init__(self) -> None:
        _name(self.name, "motor.name")
        where = f"motor {self.name!r}"
        if not isinstance(self.joints, Mapping) or not self.joints:
            raise ModelError(f"{where}.joints: expected a non-empty table joint name -> ratio, got {self.joints!r}")
        clean: dict[str, float] = {}
        for j, r in self.joints.items():
            _name(j, f"{where}.joints")
            x = _number(r, f"{where}.joints.{j}", unit="-")
            if x == 0.0:
                raise ModelError(f"{where}.joints.{j}: a ratio must be non-zero (leave the joint out instead)")
            clean[j] = x
        object.__setattr__(self, "joints", MappingProxyType(clean))
        object.__setattr__(self, "rotor_inertia", _number(self.rotor_inertia, f"{where}.rotor_inertia", 0.0,
                                                                   unit="kg m^2"))
        object.__setattr__(self, "tendon_compliance", _number(self.tendon_compliance, f"{where}.tendon_compliance",
                                                                       0.0, unit="rad/(N m)"))
        object.__setattr__(self, "ratio_curve", _ratio_curve(self.ratio_curve, clean, where))
        object.__setattr__(self, "capstan", _number(self.capstan, f"{where}.capstan", 0.0, unit="-"))
        if self.path is not None:
            object.__setattr__(self, "path", spatial_path(self.path, bool(self.ratio_curve), where))


_TABLE_UNITS = {"stiffness": "N m/rad", "coulomb": "N m", "viscous": "N m s/rad", "armature": "kg m^2", "rest_angle": "rad"}


def _table(value: Any, name: str, low: float | None) -> Mapping[str, float]:
    if value is None:
        return MappingProxyType({})
    if not isinstance(value, Mapping):
        raise ModelError(f"{name}: expected a table joint name -> number, got {value!r}")
    return MappingProxyType({_name(j, name): _number(x, f"{name}.{j}", low, unit=_TABLE_UNITS.get(name, ""))
                             for j, x in value.items()})


@dataclass(frozen=True)
class TransmissionSpec:
    """Motors, encoder and per-joint extras of a robot, by joint name (see the module doc).

    Parameters
    ----------
    motors: the motors in order (their order is the order of tau_m and of the encoder vector).
    stiffness, coulomb, viscous, armature: {joint name: value} (N m/rad, N m, N m s/rad, kg m^2),
        all >= 0; joints not listed get 0.
    rest_angle: {joint name: q_rest} (rad, finite, either sign) where each spring exerts no torque; only joints
        of ``stiffness``; joints not listed rest at 0.
    encoder_counts: encoder counts per motor revolution (> 0).
    smooth_velocity: v_s (rad/s, > 0) of the smooth sign tanh(v / v_s).
    gravity: (3,) m/s^2 in the base frame, or None (the model's default).
    tips: tip frame names, or None (the URDF's leaf frames; a default tip only where there is one leaf).
    name: model label, or None (the URDF's robot name).
    spring: a label of the spring law shown in reports (default ``"torsional"`` if any stiffness
        is non-zero, else ``"none"``); the torque is always k (q - q_rest).
    identified: the ``[identified]`` section (module doc), or None: {"record": {field: value}, table: {joint or
        motor: standard error}} for the tables of :data:`IDENTIFIED_TABLES`.
    stops: the ``[stops]`` table (module doc), or None (stops sized to the robot): {"stiffness": N m/rad,
        "damping": N m s/rad, "joints": {joint: {"stiffness": ..., "damping": ...}}}, every key optional.
    """

    motors: tuple[Motor, ...] = ()
    stiffness: Mapping[str, float] = field(default_factory=dict)
    coulomb: Mapping[str, float] = field(default_factory=dict)
    viscous: Mapping[str, float] = field(default_factory=dict)
    armature: Mapping[str, float] = field(default_factory=dict)
    encoder_counts: float = 4096.0
    smooth_velocity: float = 0.01
    gravity: tuple[float, float, float] | None = None
    tips: tuple[str, ...] | None = None
    name: str | None = None
    spring: str | None = None
    identified: Mapping[str, Any] | None = None
    rest_angle: Mapping[str, float] = field(default_factory=dict)
    stops: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        motors = tuple(self.motors) if isinstance(self.motors, (list, tuple)) else None
        if motors is None or not all(isinstance(m, Motor) for m in motors):
            raise ModelError(f"motors: expected a sequence of Motor, got {self.motors!r}")
        names = [m.name for m in motors]
        dup = next((n for n in names if names.count(n) > 1), None)
        if dup is not None:
            raise ModelError(f"motors: motor name {dup!r} appears twice")
        object.__setattr__(self, "motors", motors)
        for t in JOINT_TABLES:
            object.__setattr__(self, t, _table(getattr(self, t), t, 0.0))
        object.__setattr__(self, REST_TABLE, _table(self.rest_angle, REST_TABLE, None))
        object.__setattr__(self, STOPS_TABLE, parse_stops(self.stops))
        for j in self.rest_angle:
            if j not in self.stiffness:
                raise ModelError(f"{REST_TABLE}.{j}: joint {j!r} has no spring (no [stiffness] value); a rest angle "
                                 "is where a spring exerts no torque")
        counts = _number(self.encoder_counts, "encoder_counts", 0.0, strict=True, unit="counts/rev")
        if not counts.is_integer():
            raise ModelError(f"encoder_counts: expected a whole number of counts per revolution, got {counts:g}")
        object.__setattr__(self, "encoder_counts", counts)
        object.__setattr__(self, "smooth_velocity", _number(self.smooth_velocity, "smooth_velocity", 0.0, strict=True,
                                                            unit="rad/s"))
        if self.gravity is not None:
            g = self.gravity
            if not isinstance(g, (list, tuple, np.ndarray)) or len(g) != 3:
                raise ModelError(f"gravity: expected 3 numbers, got {g!r}")
            object.__setattr__(self, "gravity", tuple(_number(x, "gravity", unit="m/s^2") for x in g))
        if self.tips is not None:
            if isinstance(self.tips, str) or not isinstance(self.tips, (list, tuple)) or not self.tips:
                raise ModelError(f"tips: expected a non-empty list of frame names, got {self.tips!r}")
            object.__setattr__(self, "tips", tuple(_name(t, "tips") for t in self.tips))
        if self.name is not None:
            _name(self.name, "name")
        if self.spring is None:
            object.__setattr__(self, "spring", "torsional" if any(self.stiffness.values()) else "none")
        _name(self.spring, "spring")
        if self.identified is not None:
            object.__setattr__(self, "identified", _identified(self.identified, self))

    # ------------------------------------------------------------------ file form
    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "TransmissionSpec":
        """A spec from the parsed TOML (see the module doc); unknown keys are refused.

        Parameters
        ----------
        data : mapping
            The parsed TOML (its top keys, ``motor`` an array of tables).

        Returns
        -------
        TransmissionSpec
            The spec.

        Raises
        ------
        ModelError
            An unknown or missing key, or a value not of its form, named.
        """
        if not isinstance(data, Mapping):
            raise ModelError(f"spec: expected a table, got {type(data).__name__}")
        for k in data:
            if k not in _TOP_KEYS:
                raise ModelError(f"{k}: unknown key (expected one of {', '.join(_TOP_KEYS)})")
        raw_motors = data.get("motor", [])
        if not isinstance(raw_motors, list):
            raise ModelError("motor: expected an array of tables ([[motor]] entries)")
        motors = []
        for i, m in enumerate(raw_motors):
            if not isinstance(m, Mapping):
                raise ModelError(f"motor[{i}]: expected a table with name and joints")
            for k in m:
                if k not in _MOTOR_KEYS:
                    raise ModelError(f"motor[{i}].{k}: unknown key (expected one of {', '.join(_MOTOR_KEYS)})")
            for k in _MOTOR_REQUIRED:
                if k not in m:
                    raise ModelError(f"motor[{i}].{k}: missing field")
            motors.append(Motor(m["name"], m["joints"], m.get("rotor_inertia", 0.0), m.get("tendon_compliance", 0.0),
                                m.get("ratio_curve", {}), m.get("capstan", 0.0), m.get("path")))
        kw = {k: data[k] for k in _TOP_KEYS if k in data and k != "motor"}
        if "tips" in kw and isinstance(kw["tips"], list):
            kw["tips"] = tuple(kw["tips"])
        if "gravity" in kw and isinstance(kw["gravity"], list):
            kw["gravity"] = tuple(kw["gravity"])
        return cls(motors=tuple(motors), **kw)

    @classmethod
    def from_toml(cls, text: str, source: str = "spec") -> "TransmissionSpec":
        """Parse the TOML text of a spec; errors name ``source`` and the field. A file with nothing in it (empty, or
        only comments: a truncated or wrong file) is refused; a spec of no motors says so with its other keys.

        Parameters
        ----------
        text : str
            The TOML text.
        source : str, optional
            The file's name, as errors name it (default ``"spec"``).

        Returns
        -------
        TransmissionSpec
            The spec.

        Raises
        ------
        ModelError
            Text that is not TOML, holds nothing, or a field not of its form, naming ``source`` and the field.
        """
        data = load_toml(text, f"spec file {source!r}", ModelError)
        if not data:
            raise ModelError(f"spec file {source!r}: holds nothing (no [[motor]], no table, no key); a spec names at "
                             "least the robot's motors")
        try:
            return cls.from_dict(data)
        except ModelError as exc:
            raise ModelError(f"spec file {source!r}: {exc}") from None

    def to_toml(self) -> str:
        """The TOML text of this spec (``TransmissionSpec.from_toml(spec.to_toml()) == spec``)."""
        q = _toml_key
        out = []
        if self.name is not None:
            out.append(f"name = {_toml_str(self.name)}")
        out.append(f"spring = {_toml_str(self.spring or 'none')}")
        out.append(f"encoder_counts = {self.encoder_counts!r}")
        out.append(f"smooth_velocity = {self.smooth_velocity!r}")
        if self.gravity is not None:
            out.append(f"gravity = [{', '.join(repr(float(x)) for x in self.gravity)}]")
        if self.tips is not None:
            out.append(f"tips = [{', '.join(_toml_str(t) for t in self.tips)}]")
        for m in self.motors:
            out += ["", "[[motor]]", f"name = {_toml_str(m.name)}",
                    "joints = { " + ", ".join(f"{q(j)} = {r!r}" for j, r in m.joints.items()) + " }"]
            if m.rotor_inertia:
                out.append(f"rotor_inertia = {m.rotor_inertia!r}")
            if m.tendon_compliance:
                out.append(f"tendon_compliance = {m.tendon_compliance!r}")
            if m.capstan:
                out.append(f"capstan = {m.capstan!r}")
            if m.ratio_curve:
                out.append("ratio_curve = { " + ", ".join(f"{q(j)} = [{', '.join(repr(x) for x in c)}]"
                                                          for j, c in m.ratio_curve.items()) + " }")
            if m.path is not None:
                out.append(f"path = {m.path.to_toml()}")
        for t in JOINT_TABLES + (REST_TABLE,):
            table = getattr(self, t)
            if table:
                out += ["", f"[{t}]"] + [f"{q(j)} = {x!r}" for j, x in table.items()]
        out += stops_toml(self.stops, q)
        if self.identified is not None:
            out += ["", "[identified]", 'source = "identified"']
            for key, value in self.identified["record"].items():
                out.append(f"{key} = {_toml_value(value)}")
            for t in IDENTIFIED_TABLES:
                if self.identified.get(t):
                    out += ["", f"[identified.{t}]"] + [f"{q(j)} = {_toml_value(x)}"
                                                         for j, x in self.identified[t].items()]
        return "\n".join(out) + "\n"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TransmissionSpec):
            return NotImplemented
        return (self.motors == other.motors and all(dict(getattr(self, t)) == dict(getattr(other, t))
                                                    for t in JOINT_TABLES + (REST_TABLE,))
                and (self.encoder_counts, self.smooth_velocity, self.gravity, self.tips, self.name, self.spring)
                == (other.encoder_counts, other.smooth_velocity, other.gravity, other.tips, other.name, other.spring)
                and _plain(self.identified) == _plain(other.identified) and _plain(self.stops) == _plain(other.stops))

    __hash__ = None  # type: ignore[assignment]

    # ------------------------------------------------------------------ applied to a URDF's joints
    def check(self, joint_names: Sequence[str], frame_names: Sequence[str] = ()) -> None:
        """Every joint and tip the spec names exists.

        Parameters
        ----------
        joint_names : sequence of str
            The model's joints, in its order.
        frame_names : sequence of str, optional
            The URDF's frames (default none: the tips are not checked).

        Raises
        ------
        ModelError
            A joint or tip that does not exist, named.
        """
        known = set(joint_names)
        listing = ", ".join(joint_names)
        for m in self.motors:
            for j in m.joints:
                if j not in known:
                    raise ModelError(f"motor {m.name!r}.joints: unknown joint {j!r} (URDF joints: {listing})")
        for t in JOINT_TABLES + (REST_TABLE,):
            for j in getattr(self, t):
                if j not in known:
                    raise ModelError(f"{t}.{j}: unknown joint {j!r} (URDF joints: {listing})")
        for j in (self.stops or {}).get("joints", {}):
            if j not in known:
                raise ModelError(f"{STOPS_TABLE}.joints.{j}: unknown joint {j!r} (URDF joints: {listing})")
        if self.tips is not None and frame_names:
            frames = set(frame_names)
            for tip in self.tips:
                if tip not in frames:
                    raise ModelError(f"tips: unknown frame {tip!r} in the URDF")

    def extras(self, joint_names: Sequence[str]) -> JointExtras:
        """The per-joint tables as :class:`~alpes_dyn.JointExtras` in ``joint_names`` order (0 where a table names
        no value).

        Parameters
        ----------
        joint_names : sequence of str
            The model's joints, in its order.
        """
        self.check(joint_names)
        idx = {j: i for i, j in enumerate(joint_names)}
        arrays = {}
        for t in JOINT_TABLES + (REST_TABLE,):
            a = np.zeros(len(joint_names))
            for j, x in getattr(self, t).items():
                a[idx[j]] = x
            arrays[t] = a
        return JointExtras(stiffness=arrays["stiffness"], armature=arrays["armature"], coulomb=arrays["coulomb"],
                           viscous=arrays["viscous"], smooth_velocity=self.smooth_velocity, rest=arrays[REST_TABLE])

    def stop_values(self, joint_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """The ``[stops]`` table in ``joint_names`` order (:func:`~alpes_dyn.model.spec_values.stop_values`):
        stiffness (n,) N m/rad and damping (n,) N m s/rad, NaN where it gives none.

        Parameters
        ----------
        joint_names : sequence of str
            The model's joints, in its order.
        """
        self.check(joint_names)
        return stop_values(self.stops, joint_names)

    def transmission(self, joint_names: Sequence[str]) -> Transmission | None:
        """The :class:`~alpes_dyn.Transmission` (S, its sum pattern, encoder) in ``joint_names`` order,
        None without motors.

        Parameters
        ----------
        joint_names : sequence of str
            The model's joints, in its order.
        """
        if not self.motors:
            return None
        self.check(joint_names)
        idx = {j: i for i, j in enumerate(joint_names)}
        S = np.zeros((len(self.motors), len(joint_names)))
        for k, m in enumerate(self.motors):
            for j, r in m.joints.items():
                S[k, idx[j]] = r
        P = max((len(c) for m in self.motors for c in m.ratio_curve.values()), default=0)
        C = np.zeros((P, len(self.motors), len(joint_names))) if P else None
        for k, m in enumerate(self.motors):
            for j, c in m.ratio_curve.items():
                C[:len(c), k, idx[j]] = c
        return Transmission(tuple(m.name for m in self.motors), S, (S != 0).astype(float), self.encoder_counts,
                            np.array([m.rotor_inertia for m in self.motors]),
                            np.array([m.tendon_compliance for m in self.motors]), C,
                            np.array([m.capstan for m in self.motors]), tuple(m.path for m in self.motors),
                            tuple(joint_names))


def _identified(data: Any, spec: "TransmissionSpec") -> Mapping[str, Any]:
    """The ``[identified]`` section validated against ``spec`` (module doc): {"record": {...}, table: {...}}."""
    if not isinstance(data, Mapping):
        raise ModelError(f"identified: expected a table, got {data!r}")
    record: dict[str, Any] = {}
    out: dict[str, Any] = {"record": record}
    motors = {m.name: m for m in spec.motors}
    for key, value in data.items():
        if key == "record":  # the Python form (TransmissionSpec(identified=...)): the record as one table
            if not isinstance(value, Mapping):
                raise ModelError(f"identified.record: expected a table, got {value!r}")
            for k, v in value.items():
                record[k] = _record_field(k, v)
        elif key == "source":
            if value != "identified":
                raise ModelError(f"identified.source: expected \"identified\", got {value!r}")
        elif key in IDENTIFIED_TABLES:
            if not isinstance(value, Mapping):
                raise ModelError(f"identified.{key}: expected a table {'joint' if key in JOINT_TABLES else 'motor'} "
                                 f"name -> standard error, got {value!r}")
            table = {}
            for j, sd in value.items():
                if key in JOINT_TABLES and j not in getattr(spec, key):
                    raise ModelError(f"identified.{key}.{j}: the spec has no {key} value for joint {j!r}")
                if key not in JOINT_TABLES and j not in motors:
                    raise ModelError(f"identified.{key}.{j}: unknown motor {j!r} (motors: {', '.join(motors)})")
                if isinstance(sd, bool) or not isinstance(sd, (int, float)) or math.isnan(sd) or sd < 0:
                    raise ModelError(f"identified.{key}.{j}: expected a standard error >= 0 (inf: not seen), "
                                     f"got {sd!r}")
                table[j] = float(sd)
            out[key] = MappingProxyType(table)
        else:
            record[key] = _record_field(key, value)
    out["record"] = MappingProxyType(record)
    return MappingProxyType(out)


def _record_field(key: str, value: Any) -> Any:
    """One field of the fit's record (:data:`~alpes_dyn.model.params.IDENTIFICATION_FIELDS`), validated."""
    kind = IDENTIFICATION_FIELDS.get(key)
    if kind is None:
        raise ModelError(f"identified.{key}: unknown key (expected source, one of {', '.join(IDENTIFICATION_FIELDS)}"
                         f", or a table {', '.join(IDENTIFIED_TABLES)})")
    ok = (isinstance(value, bool) if kind is bool else
          (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0)
          if kind is float else (isinstance(value, list) and all(isinstance(v, str) for v in value))
          if kind is list else isinstance(value, str))
    if not ok:
        want = {bool: "true or false", float: "a non-negative number", list: "a list of strings", str: "a string"}
        raise ModelError(f"identified.{key}: expected {want[kind]}, got {value!r}")
    return float(value) if kind is float else (list(value) if kind is list else value)


def _plain(x: Any) -> Any:
    """Mappings as dicts (the comparison of two ``identified`` sections)."""
    return {k: _plain(v) for k, v in x.items()} if isinstance(x, Mapping) else x


def _toml_value(x: Any) -> str:
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):  # JSON's escapes are TOML's (a control character as \\uXXXX)
        return json.dumps(x, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(x, list):
        return "[" + ", ".join(_toml_value(v) for v in x) + "]"
    x = float(x)
    return "inf" if x == math.inf else repr(x)


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _toml_key(s: str) -> str:
    return s if s.replace("_", "").replace("-", "").isalnum() and s.isascii() else _toml_str(s)


def load_spec(path: str | Path) -> TransmissionSpec:
    """Read a spec file (TOML, see the module doc).

    Parameters
    ----------
    path : str or Path
        The spec file.

    Returns
    -------
    TransmissionSpec
        The spec.

    Raises
    ------
    ModelError
        A file that cannot be read or a field not of its form, naming the file and the field.
    """
    text = read_text(path, "spec file", ModelError)
    return TransmissionSpec.from_toml(text, os.fspath(path))


def example_spec_path(name: str = "allegro_hand") -> Path:
    """Path of a spec file shipped with the package (``"allegro_hand"``: the Allegro hand's tendon spec;
    ``"finger_edu"``: the TriFinger finger_edu as a one-tendon finger, the force control's example).

    Parameters
    ----------
    name : str, optional
        The spec's name (default ``"allegro_hand"``).

    Returns
    -------
    pathlib.Path
        The file's path.

    Raises
    ------
    ModelError
        An unknown name (the shipped ones listed).
    """
    data = Path(str(resources.files("alpes_dyn") / "data"))
    p = data / f"{name}_spec.toml"
    if not isinstance(name, str) or "/" in name or not p.is_file():
        shipped = sorted(f.name.removesuffix("_spec.toml") for f in data.glob("*_spec.toml"))
        raise ModelError(f"unknown example spec {name!r} (shipped: {', '.join(shipped)})")
    return p


def alpes_motors(lay: Layout, ratio: float, abduction_ratio: float, rotor_inertia: float = 0.0,
                 tendon_compliance: float = 0.0, capstan: float = 0.0) -> tuple[Motor, ...]:
    """The Alpes motors: one per chain (``ratio`` on each of its joints, chain order), then one per
    ab/adduction joint (``abduction_ratio``), named ``<chain>_abduction``; each with ``rotor_inertia``
    J_m (kg m^2 on the motor shaft); the chains' tendons with ``tendon_compliance`` (rad/(N m)) and the sheath
    friction ``capstan`` (mu theta; the ab/adduction is a gear, rigid, without sheath).

    Parameters
    ----------
    lay : Layout
        The model's layout (:func:`~alpes_dyn.model.description.layout`): its chains.
    ratio : float
        The chains' ratio r/r_m on each joint, rad of motor per rad of joint.
    abduction_ratio : float
        The ab/adduction motors' ratio.
    rotor_inertia : float, optional
        J_m, kg m^2 on the motor shaft (default 0).
    tendon_compliance : float, optional
        The chains' tendon compliance, rad/(N m) (default 0).
    capstan : float, optional
        The chains' sheath friction mu theta (default 0).

    Returns
    -------
    tuple of Motor
        The motors, chains first.
    """
    motors = [Motor(ch.name, {j: ratio for j in ch.joints}, rotor_inertia, tendon_compliance, capstan=capstan)
              for ch in lay.chains]
    motors += [Motor(f"{ch.name}_abduction", {ch.abduction: abduction_ratio}, rotor_inertia)
               for ch in lay.chains if ch.abduction]
    return tuple(motors)


def alpes_transmission(lay: Layout, joint_names: tuple[str, ...], ratio: float, abduction_ratio: float = 1.0,
                       counts_per_rev: float = 4096.0) -> Transmission:
    """The transmission of an Alpes layout: one motor per chain (``ratio`` on each of its joints), one per
    ab/adduction joint (``abduction_ratio``); the same motors as :func:`alpes_spec` (Sec. 3, eq. 3.13).

    Parameters
    ----------
    lay : Layout
        The model's layout (:func:`~alpes_dyn.model.description.layout`): its chains.
    joint_names : tuple of str
        The model's joints, in its order.
    ratio : float
        The chains' ratio r/r_m on each joint, rad/rad.
    abduction_ratio : float, optional
        The ab/adduction motors' ratio (default 1).
    counts_per_rev : float, optional
        The encoders' counts per motor revolution (default 4096).

    Returns
    -------
    Transmission
        The transmission.
    """
    tr = TransmissionSpec(motors=alpes_motors(lay, ratio, abduction_ratio),
                          encoder_counts=counts_per_rev).transmission(joint_names)
    assert tr is not None
    return tr


def alpes_spec(lay: Layout, params: HandParams, spring: str = "torsional", friction: bool = False,
               rotor_inertia: bool = False) -> TransmissionSpec:
    """The spec of an Alpes model from its layout and the parameter file (what :meth:`Model.alpes` uses).

    One motor per chain (ratio r/r_m on each of its flexion joints), one for the thumb's
    ab/adduction (``transmission.abduction_ratio``); springs K_i under the ``spring`` law (eq. 2.14);
    with ``friction`` F_s and F_v on every joint (eq. 2.6-2.7; a chain's per-joint ``F_s``/``F_v`` -- a
    finger's own first -- and the thumb's ``abduction_F_s``/``abduction_F_v`` where the file gives them); with
    ``rotor_inertia`` the file's ``transmission.J_m`` on every motor, acting on its tendon (eq. 2.8): a
    chain's motor adds (r/r_m)^2 J_m to every entry of its chain's block of the mass matrix, the
    ab/adduction motor abduction_ratio^2 J_m on its joint. (``transmission.N`` is not used: the
    tendon's ratio is r/r_m, which the file's N equals.) The file's ``transmission.tendon_compliance``
    (default 0) goes on every chain's motor: it changes the encoder reading only; so does its
    ``transmission.capstan`` (mu theta, default 0: the tendons' sheath friction).

    Parameters
    ----------
    lay : Layout
        The model's layout (:func:`~alpes_dyn.model.description.layout`): its chains.
    params : HandParams
        The parameter file's values.
    spring : str, optional
        The spring law, one of :data:`~alpes_dyn.model.extras.SPRING_MODELS` (default ``"torsional"``).
    friction : bool, optional
        F_s and F_v on every joint (default False: none).
    rotor_inertia : bool, optional
        The file's J_m on every motor (default False: none).

    Returns
    -------
    TransmissionSpec
        The spec.
    """
    ratio, abd = params.transmission_ratio, params.abduction_ratio
    motors = alpes_motors(lay, ratio, abd, params.J_m if rotor_inertia else 0.0, params.tendon_compliance,
                          params.capstan)
    K: dict[str, float] = {}
    Fs: dict[str, float] = {}
    Fv: dict[str, float] = {}
    for ch in lay.chains:
        chain = params.chain(ch.name)  # per-joint chain friction where the file gives it (a finger's own first)
        for i, (j, k) in enumerate(zip(ch.joints, ch.stiffness)):
            K[j] = k
            Fs[j] = float(chain.F_s[i]) if getattr(chain, "F_s", None) is not None else params.F_s
            Fv[j] = float(chain.F_v[i]) if getattr(chain, "F_v", None) is not None else params.F_v
        if ch.abduction:
            K[ch.abduction] = lay.abduction_stiffness
            Fs[ch.abduction] = params.F_s if params.abduction_F_s is None else params.abduction_F_s
            Fv[ch.abduction] = params.F_v if params.abduction_F_v is None else params.abduction_F_v
    joints = list(K)
    k = spring_stiffness(np.array([K[j] for j in joints]), spring, params.b, params.r)
    zeros: dict[str, float] = {}
    return TransmissionSpec(
        motors=tuple(motors),
        stiffness={j: float(x) for j, x in zip(joints, k)},
        coulomb=Fs if friction else zeros,
        viscous=Fv if friction else zeros,
        encoder_counts=params.encoder_counts, smooth_velocity=params.smooth_velocity,
        gravity=tuple(float(x) for x in params.gravity), tips=lay.tips, name=lay.model, spring=spring,
    )
