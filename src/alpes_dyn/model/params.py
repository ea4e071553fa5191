"""Physical parameters of the Alpes hand: loading and validation of the TOML parameter file.

The shipped file ``alpes_dyn/data/alpes_hand.toml`` holds the report's Table 1.2 (``source =
"report"``) and, marked ``source = "assumed"`` with a one-line reason each, every value the report
does not give. :func:`load_params` validates it; any defect is a :class:`~alpes_dyn.ModelError`
that names the field, e.g. ``finger.m: value must be > 0 (got -0.03 at index 0)``; every number must lie within
the accepted range of its unit (:data:`alpes_dyn.limits.PHYSICAL_RANGES`: a length of 1e300 m, a ratio of 1e300,
a subnormal 1e-320 are refused with the field's name and the range).

The four fingers share ``[finger]``; a finger may have values of its own in a table ``[finger.<name>]``
(``<name>`` from ``palm.finger_names``) holding any of :data:`OVERRIDE_FIELDS` (``K``, ``m``, ``I``,
``F_s``, ``F_v``, ``encoder_offset``), which replace the shared ones on that finger only (:meth:`HandParams.chain`,
:func:`chain_params`): an identified hand differs link by link.

What ``identify`` finds of the rig is in the file too (optional): a chain's encoder zero ``encoder_offset`` (rad,
:meth:`HandParams.encoder_offset_of`), the torque's lag ``transmission.torque_delay`` (samples), the palm's tilt as
the ``environment.gravity`` it turns. An identified file records per chain how far the fit is to be trusted:
``[identification.<chain>]`` (``finger``, a finger's name, ``thumb``) with :data:`IDENTIFICATION_FIELDS`
(:attr:`HandParams.identification`); a chain marked ``trustworthy = false`` (``identify --force``) is refused by
the commands and loaders that use its values unless forced (:func:`~alpes_dyn.model.trust.check_trusted`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError
from ..fileio import atomic_write, load_toml, read_text
from ..limits import check_physical
from .friction import CREEP_KAPPA, CREEP_RATE, SIGMA0, SIGMA1
from .param_values import check_value
from .params_schema import (_ENTRY_KEYS, _INTEGER, _OPTIONAL, _SCHEMA, _UNITS, IDENTIFICATION_FIELDS,  # noqa: F401
                            OVERRIDE_FIELDS, SOURCES)  # (SOURCES, the *_FIELDS: importable from here, as before)

__all__ = ["Param", "ChainParams", "HandParams", "SOURCES", "OVERRIDE_FIELDS", "load_params", "default_params_path",
           "params_toml", "with_values", "write_params", "chain_params", "IDENTIFICATION_FIELDS"]


@dataclass(frozen=True)
class Param:
    """One parameter: its value, unit, provenance (``report``, ``assumed`` or ``identified``), why if
    assumed (or how if identified), and for an identified value its standard error ``std`` (same shape)."""

    value: Any
    unit: str
    source: str
    reason: str = ""
    description: str = ""
    std: Any = None


@dataclass(frozen=True)
class ChainParams:
    """A serial planar chain of phalanges (a finger or the thumb's flexion chain).

    Arrays have one entry per phalanx, proximal first. Units: m, kg, kg m^2, N m/rad.
    ``I`` is the inertia about the phalanx's own (proximal) joint axis, as in the report's table;
    ``I_com = I - m d^2`` with ``d = L - s`` the COM distance to that joint. ``F_s``, ``F_v``: per-joint
    friction (N m, N m s/rad) when the file gives it per phalanx, else None (``friction.F_s``/``F_v`` apply).
    """

    L: np.ndarray
    s: np.ndarray
    m: np.ndarray
    I: np.ndarray
    K: np.ndarray
    radius: float
    F_s: np.ndarray | None = None
    F_v: np.ndarray | None = None
    encoder_offset: float = 0.0
    """rad of the chain's (flexion) motor: its encoder's zero as identified, y = S q + offset (optional
    ``encoder_offset``; 0, the default: the encoder reads 0 at q = 0)."""

    @property
    def n(self) -> int:
        """Number of phalanges."""
        return int(self.L.shape[0])

    @property
    def com_from_joint(self) -> np.ndarray:
        """Distance d_i = L_i - s_i from joint i to the COM of phalanx i (m)."""
        return self.L - self.s

    @property
    def I_com(self) -> np.ndarray:
        """Inertia about the COM, perpendicular to the phalanx: I_i - m_i d_i^2 (kg m^2)."""
        return self.I - self.m * self.com_from_joint**2


@dataclass(frozen=True)
class HandParams:
    """All parameters of the hand, as loaded from a parameter file.

    ``raw`` keeps every :class:`Param` (with its unit, source and reason) by ``"section.field"``.
    """

    finger: ChainParams
    thumb: ChainParams
    r: float
    b: float
    r_m: float
    J_m: float
    N: float
    abduction_ratio: float
    encoder_counts: float
    tau_max: float
    F_s: float
    F_v: float
    smooth_velocity: float
    gravity: np.ndarray
    finger_lower: float
    finger_upper: float
    abduction_K: float
    thumb_base_mass: float
    abduction_axis: np.ndarray
    abduction_lower: float
    abduction_upper: float
    finger_names: tuple[str, ...]
    finger_xy: np.ndarray  # (4, 2)
    thumb_xyz: np.ndarray
    thumb_yaw: float
    path: str = ""
    raw: dict[str, Param] = field(default_factory=dict, repr=False)
    fingers: dict[str, ChainParams] = field(default_factory=dict, repr=False)
    abduction_F_s: float | None = None  # the ab/adduction joint's own friction (N m, N m s/rad), else friction.F_s/F_v
    abduction_F_v: float | None = None
    tendon_compliance: float = 0.0
    """C_t, rad/(N m): the flexion tendons' stretch seen by the encoder per N m of recorded motor torque,
    y_k = S q_k + C_t tau_m,k-1, the torque held before the reading (optional ``transmission.tendon_compliance``; 0, the default, is a rigid tendon)."""
    torque_delay: int = 0
    """Whole samples by which the recorded motor torque lags the motor's (the current's filter and the bus), as
    identified (optional ``transmission.torque_delay``; 0, the default: none)."""
    abduction_encoder_offset: float = 0.0
    """rad of the thumb's ab/adduction motor: its encoder's zero (optional ``thumb.abduction_encoder_offset``)."""
    capstan: float = 0.0
    """mu theta (dimensionless): the flexion tendons' sheath friction, the joints getting
    tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c) (optional ``transmission.capstan``; 0, the default: none;
    :func:`~alpes_dyn.model.transmission.capstan_torque`)."""
    friction_law: str = "tanh"
    """The joints' friction law (optional ``friction.law``, :data:`~alpes_dyn.model.friction.FRICTION_MODELS`):
    ``tanh`` (default) or ``lugre`` with ``sigma0`` (N m/rad) and ``sigma1`` (N m s/rad) (:mod:`~alpes_dyn.model.friction`)."""
    sigma0: float = SIGMA0
    sigma1: float = SIGMA1
    creep_kappa: float = CREEP_KAPPA
    """The ``creep`` law's band inertia (optional ``friction.creep_kappa``, :class:`~alpes_dyn.model.friction.Creep`)."""
    creep_rate: float = CREEP_RATE
    """The ``creep`` law's band rate, 1/s (optional ``friction.creep_rate``)."""
    model_error: float | None = None
    """The observer's model error, in units of each joint's F_s (optional ``friction.model_error``, >= 0, unit
    ``F_s``): a white torque per sample of standard deviation ``model_error`` F_s,i on each joint i, calibrated on
    the identification record by ``identify``
    (:func:`~alpes_dyn.estimation.observers.noise_calibration.calibrate_model_error`); every observer built from
    the file carries it (:func:`~alpes_dyn.estimation.observers.friction_noise.with_friction_noise`). None: the
    library's default."""
    observer_law: str | None = None
    """The observers' dry-friction law on this file (optional ``friction.observer_law``,
    :data:`~alpes_dyn.model.friction.OBSERVER_LAWS`): written by ``identify``, the law its observer check chose by
    measurement (:mod:`~alpes_dyn.estimation.identification.law_choice`); read by every observer built from the
    file (:func:`~alpes_dyn.simulation.stick.observer_friction_law`). None: the default for ``friction.law``."""
    identification: dict[str, dict[str, Any]] = field(default_factory=dict, repr=False)
    """Per chain fitted (``finger``, a finger's name, ``thumb``): the record of ``[identification.<chain>]``."""

    @property
    def untrusted(self) -> list[str]:
        """The chains whose identified values are marked not trustworthy (written with ``--force``)."""
        return [c for c, rec in self.identification.items() if rec.get("trustworthy") is False]

    def encoder_offset_of(self, motor: str, chain: str | None = None) -> float:
        """The encoder zero the file holds for a motor.

        Parameters
        ----------
        motor : str
            ``"finger"`` (a finger model's motor), a finger's name (``palm.finger_names``), ``"thumb"`` or
            ``"thumb_abduction"``; another name (no such motor in the file) has 0.
        chain : str, optional
            For ``motor="finger"``: the finger whose zero it is (default the shared ``[finger]``).

        Returns
        -------
        float
            The offset, rad of the motor.

        Raises
        ------
        ModelError
            An unknown ``chain`` (:meth:`chain`).
        """
        if motor == "thumb_abduction":
            return float(self.abduction_encoder_offset)
        if motor == "finger":
            return float(self.chain(chain or "finger").encoder_offset)
        if motor == "thumb" or motor in self.finger_names:
            return float(self.chain(motor).encoder_offset)
        return 0.0

    def chain(self, name: str) -> ChainParams:
        """The parameters of one chain.

        Parameters
        ----------
        name : str
            A finger by its name (``palm.finger_names``: the shared ``[finger]`` values with that finger's
            ``[finger.<name>]`` overrides), ``"thumb"``, or ``"finger"`` (the shared values).

        Returns
        -------
        ChainParams

        Raises
        ------
        ModelError
            Another name (the message lists the chains).
        """
        if name == "thumb":
            return self.thumb
        if name == "finger":
            return self.finger
        if isinstance(name, str) and name in self.finger_names:
            return self.fingers.get(name, self.finger)
        raise ModelError(f"chain: unknown chain {name!r} (expected one of {', '.join(self.chain_names)})")

    @property
    def chain_names(self) -> tuple[str, ...]:
        """The hand's chains, one per motor's tendon: the fingers (``palm.finger_names``), then ``thumb``."""
        return tuple(self.finger_names) + ("thumb",)

    def overrides(self, finger: str) -> dict[str, Param]:
        """The per-finger entries ``[finger.<finger>]`` of the file.

        Parameters
        ----------
        finger : str
            A finger's name (``palm.finger_names``).

        Returns
        -------
        dict of str to Param
            By field (of :data:`~alpes_dyn.model.params_schema.OVERRIDE_FIELDS`); empty if the finger has none (or
            no finger has that name).
        """
        pre = f"finger.{finger}."
        return {k[len(pre):]: prm for k, prm in self.raw.items() if k.startswith(pre)}

    @property
    def transmission_ratio(self) -> float:
        """Pulley to motor-shaft ratio r / r_m of the tendon transmission (Section 3)."""
        return self.r / self.r_m

    def assumptions(self) -> list[tuple[str, Param]]:
        """The parameters the report does not give, with their reasons, in file order."""
        return [(k, p) for k, p in self.raw.items() if p.source == "assumed"]


def default_params_path() -> Path:
    """Path of the parameter file shipped with the package."""
    return Path(str(resources.files("alpes_dyn") / "data" / "alpes_hand.toml"))


def _header_line(text: str) -> str:
    """One comment line of a file header: control characters written as escapes (TOML refuses them raw)."""
    return "".join(c if c.isprintable() else f"\\x{ord(c):02x}" if ord(c) < 256 else f"\\u{ord(c):04x}"
                   for c in text)


def _identification(data: Any, names: tuple[str, ...]) -> dict[str, dict[str, Any]]:
    """The optional ``[identification.<chain>]`` tables, validated."""
    if not isinstance(data, dict):
        raise ModelError("identification: must be a table of [identification.<chain>] tables")
    out: dict[str, dict[str, Any]] = {}
    chains = ("finger", "thumb") + tuple(names)
    for chain, rec in data.items():
        if chain not in chains:
            raise ModelError(f"identification.{chain}: unknown chain (expected one of {', '.join(chains)})")
        if not isinstance(rec, dict):
            raise ModelError(f"identification.{chain}: must be a table")
        for key, value in rec.items():
            kind = IDENTIFICATION_FIELDS.get(key)
            if kind is None:
                raise ModelError(f"identification.{chain}.{key}: unknown key (expected one of "
                                 f"{', '.join(IDENTIFICATION_FIELDS)})")
            ok = (isinstance(value, bool) if kind is bool else
                  (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                   and value >= 0) if kind is float else
                  (isinstance(value, list) and all(isinstance(v, str) for v in value)) if kind is list else
                  isinstance(value, str))
            if not ok:
                want = {bool: "true or false", float: "a non-negative number", list: "a list of strings",
                        str: "a string"}[kind]
                raise ModelError(f"identification.{chain}.{key}: expected {want}, got {value!r}")
        out[chain] = {k: (float(v) if IDENTIFICATION_FIELDS[k] is float else v) for k, v in rec.items()}
    return out


def _parse(data: dict[str, Any]) -> dict[str, Param]:
    out: dict[str, Param] = {}
    for section in data:
        if section == "identification":
            continue  # the fit's record, read by _identification
        if section not in _SCHEMA:
            raise ModelError(f"{section}: unknown section (expected one of {', '.join(_SCHEMA)})")
    for section, fields in _SCHEMA.items():
        if section not in data:
            raise ModelError(f"{section}: missing section")
        table = data[section]
        if not isinstance(table, dict):
            raise ModelError(f"{section}: must be a table")
        for key in table:
            sub = table[key]
            if key in fields or (section == "finger" and isinstance(sub, dict) and "value" not in sub):
                continue  # a field, or a per-finger table [finger.<name>], checked once the names are known
            raise ModelError(f"{section}.{key}: unknown key (expected one of {', '.join(fields)})")
        for key, (length, kind) in fields.items():
            name = f"{section}.{key}"
            if key not in table:
                if name in _OPTIONAL:
                    continue
                raise ModelError(f"{name}: missing field")
            out[name] = _entry(name, table[key], length, kind)
    names = out["palm.finger_names"].value
    for nm in names:
        if nm in _SCHEMA["finger"] or nm in _SCHEMA or nm == "thumb":
            raise ModelError(f"palm.finger_names: {nm!r} is a field or section name; a finger needs another name")
    for key, sub in data["finger"].items():
        if key in _SCHEMA["finger"]:
            continue
        if key not in names:  # not a field of [finger] nor a finger: the unknown-key error of the section
            raise ModelError(f"finger.{key}: unknown key (expected one of {', '.join(_SCHEMA['finger'])}, "
                             f"or a finger name for its own values: {', '.join(names)})")
        for k, entry in sub.items():
            if k not in OVERRIDE_FIELDS:
                raise ModelError(f"finger.{key}.{k}: unknown key (a finger's own values are "
                                 f"{', '.join(OVERRIDE_FIELDS)})")
            out[f"finger.{key}.{k}"] = _entry(f"finger.{key}.{k}", entry, *OVERRIDE_FIELDS[k])
    return out


def _entry(name: str, entry: Any, length: int | None, kind: str) -> Param:
    """One ``{ value, unit, source, ... }`` entry, validated."""
    if not isinstance(entry, dict):
        raise ModelError(f"{name}: must be a table with value, unit, source")
    for k in entry:
        if k not in _ENTRY_KEYS:
            raise ModelError(f"{name}.{k}: unknown key (expected one of {', '.join(sorted(_ENTRY_KEYS))})")
    for k in ("value", "unit", "source"):
        if k not in entry:
            raise ModelError(f"{name}.{k}: missing field")
    source = entry["source"]
    if source not in SOURCES:
        raise ModelError(f"{name}.source: must be one of {', '.join(repr(x) for x in SOURCES)} (got {source!r})")
    reason = entry.get("reason", "")
    if source in ("assumed", "identified") and not (isinstance(reason, str) and reason.strip()):
        raise ModelError(f"{name}.reason: an {source} value needs a one-line reason")
    value = check_value(name, entry["value"], length, kind)
    field_name = ".".join(name.split(".")[::2]) if name.count(".") == 2 else name  # finger.<nm>.K -> finger.K
    unit, expected = entry["unit"], _UNITS.get(field_name)
    if expected is not None and (not isinstance(unit, str) or " ".join(unit.split()) not in
                                 ((expected, "", "1") if expected == "-" else (expected,))):
        raise ModelError(f"{name}.unit: the value is read in {expected!r}, got {unit!r} (convert it; no other unit "
                         "is accepted)")
    if expected is not None and kind in ("pos", "nonneg", "any"):  # an angle of 1e300 rad, a ratio of 1e300: refused
        check_physical(value, name, expected, kind, ModelError)
    if field_name in _INTEGER and not float(value).is_integer():
        raise ModelError(f"{name}: value must be a whole number, got {value:g}")
    std = None
    if "std" in entry:
        if source != "identified":
            raise ModelError(f"{name}.std: only an identified value has a standard error")
        std = check_value(f"{name}.std", entry["std"], length, "nonneg" if kind != "str" else kind)
    return Param(value, str(entry["unit"]), source, str(reason), str(entry.get("description", "")), std)


def _chain(raw: dict[str, Param], sec: str, K: np.ndarray, over: str = "") -> ChainParams:
    """The chain of section ``sec``; with ``over`` (``finger.<name>``) that finger's own values replace them."""
    def get(k: str) -> Any:
        for name in ((f"{over}.{k}",) if over else ()) + (f"{sec}.{k}",):
            if name in raw:
                return raw[name].value
        return None

    L, s, m, I = (get(k) for k in ("L", "s", "m", "I"))
    K = get("K") if over else K
    Fs, Fv, radius, offset = get("F_s"), get("F_v"), get("radius"), get("encoder_offset")
    sec = over or sec
    if np.any(s > L):
        i = int(np.argmax(s > L))
        raise ModelError(f"{sec}.s: COM distance s must not exceed L (s={s[i]:g} > L={L[i]:g} at index {i})")
    d = L - s
    I_com = I - m * d**2
    if np.any(I_com <= 0):
        i = int(np.argmax(I_com <= 0))
        raise ModelError(
            f"{sec}.I: not physically consistent: I about the joint must exceed m d^2 = {m[i] * d[i] ** 2:.4g} "
            f"(parallel-axis theorem, d = L - s) but is {I[i]:.4g} at index {i}"
        )
    return ChainParams(L=L, s=s, m=m, I=I, K=K, radius=radius, F_s=Fs, F_v=Fv,
                       encoder_offset=0.0 if offset is None else float(offset))


def load_params(path: str | Path | None = None) -> HandParams:
    """Load and validate a parameter file.

    Parameters
    ----------
    path : str or Path or None, optional
        The TOML file; ``None`` loads the shipped ``alpes_hand.toml``.

    Returns
    -------
    HandParams
        The parameters, each with its unit, source and reason.

    Raises
    ------
    ModelError
        Empty file name, unreadable or non-UTF-8 file, TOML syntax error, missing or unknown section/field, wrong length, a
        non-positive length or mass, or an inertia that violates the parallel-axis theorem.
    """
    src = path if path is not None else default_params_path()
    text = read_text(src, "parameter file", ModelError)
    return _from_text(text, str(src))


def _from_text(text: str, path: str) -> HandParams:
    data = load_toml(text, f"parameter file {path!r}", ModelError)
    raw = _parse(data)
    v = {k: prm.value for k, prm in raw.items()}
    ident = _identification(data.get("identification", {}), tuple(v["palm.finger_names"]))
    if v["finger.lower"] >= v["finger.upper"]:
        raise ModelError("finger.lower: must be below finger.upper")
    if v["thumb.abduction_lower"] >= v["thumb.abduction_upper"]:
        raise ModelError("thumb.abduction_lower: must be below thumb.abduction_upper")
    finger = _chain(raw, "finger", v["finger.K"])
    fingers = {nm: (_chain(raw, "finger", v["finger.K"], f"finger.{nm}")
                    if any(k.startswith(f"finger.{nm}.") for k in raw) else finger) for nm in v["palm.finger_names"]}
    return HandParams(
        finger=finger,
        thumb=_chain(raw, "thumb", v["thumb.K"]),
        r=v["finger.r"], b=v["finger.b"], r_m=v["transmission.r_m"], J_m=v["transmission.J_m"],
        N=v["transmission.N"], abduction_ratio=v["transmission.abduction_ratio"],
        encoder_counts=v["transmission.encoder_counts"], tau_max=v["transmission.tau_max"],
        F_s=v["friction.F_s"], F_v=v["friction.F_v"], smooth_velocity=v["friction.smooth_velocity"],
        gravity=v["environment.gravity"], finger_lower=v["finger.lower"], finger_upper=v["finger.upper"],
        abduction_K=v["thumb.abduction_K"], thumb_base_mass=v["thumb.base_mass"], abduction_axis=v["thumb.abduction_axis"],
        abduction_lower=v["thumb.abduction_lower"], abduction_upper=v["thumb.abduction_upper"],
        finger_names=v["palm.finger_names"],
        finger_xy=np.column_stack([v["palm.finger_x"], v["palm.finger_y"]]),
        thumb_xyz=v["palm.thumb_xyz"], thumb_yaw=v["palm.thumb_yaw"], path=path, raw=raw, fingers=fingers,
        abduction_F_s=v.get("thumb.abduction_F_s"), abduction_F_v=v.get("thumb.abduction_F_v"),
        identification=ident, tendon_compliance=float(v.get("transmission.tendon_compliance", 0.0)),
        capstan=float(v.get("transmission.capstan", 0.0)), torque_delay=int(v.get("transmission.torque_delay", 0)),
        abduction_encoder_offset=float(v.get("thumb.abduction_encoder_offset", 0.0)),
        friction_law=v.get("friction.law", "tanh"), sigma0=float(v.get("friction.sigma0", SIGMA0)),
        sigma1=float(v.get("friction.sigma1", SIGMA1)),
        creep_kappa=float(v.get("friction.creep_kappa", CREEP_KAPPA)),
        creep_rate=float(v.get("friction.creep_rate", CREEP_RATE)),
        model_error=None if "friction.model_error" not in v else float(v["friction.model_error"]),
        observer_law=v.get("friction.observer_law"),
    )


# ----------------------------------------------------------------------------- writing
def _toml_value(x: Any) -> str:
    if isinstance(x, (tuple, list, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in x) + "]"
    if isinstance(x, str):
        return json.dumps(x)  # a TOML basic string: JSON's escapes are TOML's
    if isinstance(x, (bool, np.bool_)):
        raise ModelError(f"parameter value {x!r}: booleans are not parameters")
    return repr(float(x))


def params_toml(raw: dict[str, Param], header: str = "",
                identification: dict[str, dict[str, Any]] | None = None) -> str:
    """TOML text of a parameter set (``HandParams.raw``, and its ``identification`` records), in the
    schema's order; loads back to the same.

    Parameters
    ----------
    raw : dict of str to Param
        "section.field" -> :class:`Param` (``HandParams.raw``).
    header : str, optional
        Comment lines put at the top (control characters escaped; default none).
    identification : dict or None, optional
        Records of ``[identification.<chain>]`` {chain: {field: value}} (default None: none).

    Returns
    -------
    str
        The TOML text.
    """
    lines = [f"# {_header_line(h)}" for h in header.split("\n")] + ([""] if header else [])

    def section_lines(section: str, fields) -> None:
        lines.append(f"[{section}]")
        for key in fields:
            prm = raw.get(f"{section}.{key}")
            if prm is None:
                continue
            items = [f"value = {_toml_value(prm.value)}", f"unit = {_toml_value(prm.unit)}",
                     f"source = {_toml_value(prm.source)}"]
            if prm.reason:
                items.append(f"reason = {_toml_value(prm.reason)}")
            if prm.std is not None:
                items.append(f"std = {_toml_value(prm.std)}")
            if prm.description:
                items.append(f"description = {_toml_value(prm.description)}")
            lines.append(f"{key} = {{ " + ", ".join(items) + " }")
        lines.append("")

    names = raw["palm.finger_names"].value if "palm.finger_names" in raw else ()
    for section, fields in _SCHEMA.items():
        section_lines(section, fields)
        if section == "finger":  # the per-finger tables, in palm.finger_names order
            for nm in names:
                if any(k.startswith(f"finger.{nm}.") for k in raw):
                    section_lines(f"finger.{nm}", OVERRIDE_FIELDS)
    for chain, rec in (identification or {}).items():
        lines.append(f"[identification.{chain}]")
        for key in IDENTIFICATION_FIELDS:
            if key in rec:
                value = rec[key]
                text = ("true" if value else "false") if isinstance(value, bool) else (
                    "[" + ", ".join(json.dumps(str(x)) for x in value) + "]" if isinstance(value, list) else
                    json.dumps(value) if isinstance(value, str) else repr(float(value)))
                lines.append(f"{key} = {text}")
        lines.append("")
    return "\n".join(lines)


def with_values(params: HandParams, updates: dict[str, Param], header: str = "",
                identification: dict[str, dict[str, Any]] | None = None) -> HandParams:
    """``params`` with the entries ``updates`` ("section.field" -> :class:`Param`) replaced, validated
    exactly as a file is (the result is what :func:`load_params` reads from :func:`params_toml`);
    ``identification``: records of ``[identification.<chain>]`` set (per chain, replacing).

    Parameters
    ----------
    params : HandParams
        The parameters (not changed).
    updates : dict of str to Param
        "section.field" -> the new :class:`Param`.
    header : str, optional
        Comment lines put at the top (control characters escaped; default none).
    identification : dict or None, optional
        Records of ``[identification.<chain>]`` {chain: {field: value}}, each replacing the chain's (default None).

    Returns
    -------
    HandParams
        The updated parameters.

    Raises
    ------
    ModelError
        An unknown field, or a value the file's checks refuse.
    """
    raw = dict(params.raw)
    for name, prm in updates.items():
        section, _, key = name.partition(".")
        finger, _, field_ = key.partition(".")
        if not (section in _SCHEMA and key in _SCHEMA[section]) and not (
                section == "finger" and finger in params.finger_names and field_ in OVERRIDE_FIELDS):
            raise ModelError(f"{name}: unknown parameter field")
        raw[name] = prm
    ident = {**params.identification, **(identification or {})}
    text = params_toml(raw, header, ident)
    return _from_text(text, params.path or "<updated>")


def write_params(params: HandParams, path: str | Path, header: str = "") -> Path:
    """Write ``params`` as a parameter file (atomically: a temporary file renamed into place).

    Parameters
    ----------
    params : HandParams
        The parameters (their ``raw`` values and ``identification`` records).
    path : str or Path
        The file to write.
    header : str, optional
        Comment lines put at the top (control characters escaped; default none).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    text = params_toml(params.raw, header, params.identification)
    return atomic_write(path, text, "parameter file", ModelError)


def chain_params(params: HandParams, chain: str) -> HandParams:
    """``params`` as seen by one chain: for a finger, the hand whose shared ``[finger]`` values are that
    finger's (its ``[finger.<name>]`` values merged in, every finger's own table dropped), so that
    ``finger2``/``finger3`` built from it is that finger; for ``"thumb"`` or ``"finger"``, ``params``
    without per-finger values. Both the arrays and ``raw`` (what :func:`write_params` writes) change.

    Parameters
    ----------
    params : HandParams
        The hand's parameters.
    chain : str
        A finger's name, ``"thumb"`` or ``"finger"``.

    Returns
    -------
    HandParams
        The parameters as the chain sees them.

    Raises
    ------
    ModelError
        An unknown chain.
    """
    own = params.chain(chain)  # an unknown chain: ModelError
    raw = {k: prm for k, prm in params.raw.items() if not (k.startswith("finger.") and k.count(".") == 2)}
    finger = params.finger
    if chain in params.finger_names:
        finger = own
        for field_, prm in params.overrides(chain).items():
            base = params.raw.get(f"finger.{field_}")
            desc = prm.description or (base.description if base is not None else "")
            raw[f"finger.{field_}"] = Param(prm.value, prm.unit, prm.source, prm.reason, desc, prm.std)
    return dataclasses.replace(params, finger=finger, fingers={nm: finger for nm in params.finger_names}, raw=raw)
