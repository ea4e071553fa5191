"""Dynamics with physical parameters as symbols: the base of identifiability and identification.

The rigid-body dynamics are linear in each body's inertial parameters (mass, first moment, inertia:
the regressor form of eq. 2.4). When body b's mass m_b is scaled by alpha_b = m_b / m_b^0 with its
inertia (the report's I_i = m_i L_i^2 / 3 scales with m_i; the centre of mass stays put), all ten of
its inertial parameters scale by alpha_b, hence

    A(q) = sum_b alpha_b A_b(q) + A_rest(q) + I_a,
    C(q, qd) qd = sum_b alpha_b c_b(q, qd) + c_rest(q, qd),
    G_gravity(q) = -sum_b alpha_b m_b^0 (d p_b / dq)^T g - m_rest (d p_rest / dq)^T g,

where A_b, c_b and p_b (centre of mass) are those of the URDF with only body b massive ("rest": the
bodies not parameterised), computed once by the symbolic backend (ADAM). Springs (eq. 2.14,
torsional), friction (eq. 2.6-2.7, smooth sign) and the input gain are linear in their parameters too.
The gravity vector g (base frame) may be an input (the hand's orientation changes during an
experiment) instead of the model's constant.

Parameters are named after the joint they belong to (``K_1`` for joint ``j1`` of a finger,
``K_index_j1`` on the hand):

===================== =========================================================== ==========
kind                  meaning                                                     unit
===================== =========================================================== ==========
``K``                 spring stiffness of a joint (torsional, eq. 2.14)           N m/rad
``m``                 mass of the body a joint moves, inertia scaled with it      kg
``F_s``               Coulomb friction of a joint (eq. 2.6)                       N m
``F_v``               viscous friction of a joint (eq. 2.6)                       N m s/rad
``input_gain``        scale of the known torques (r/r_m, the torque constant)     --
``J_m``               rotor inertia of a motor on its tendon, S^T diag(J_m) S     kg m^2
                      (eq. 2.8; ``J_m_<motor>``)
``encoder_offset``    the zero of a motor's encoder: y = S q + offset             rad
                      (``encoder_offset_<motor>``; output only, no dynamics)
``tilt``              the base (palm) turned by two small angles, ``tilt_x``      rad
                      about its x axis then ``tilt_y`` about its y axis
``tendon_compliance`` a motor's tendon stretch per N m of its recorded torque:    rad/(N m)
                      y_k = S q_k + offset + C tau_m,k-1, the torque held
                      before the reading (``tendon_compliance_<motor>``;
                      output only; the tendon's quasi-static limit)
``capstan``           mu theta of a motor's tendon-sheath friction: the joints    --
                      get S^T (u - (1 - exp(-mu theta)) |u| tanh(S qd / v_c))
                      (``capstan_<motor>``; :func:`~alpes_dyn.model.transmission.
                      capstan_torque`)
``sigma0``            the LuGre law's bristle stiffness, one for every joint      N m/rad
                      (eq. L1-L2 of :mod:`~alpes_dyn.model.friction`; a model
                      whose file's ``friction.law`` is ``lugre`` only)
``sigma1``            the LuGre law's bristle damping (likewise)                  N m s/rad
``creep_kappa``       the ``creep`` law's band inertia, in units of the joint's    --
                      own (eq. C1 of :class:`~alpes_dyn.model.friction.Creep`;
                      a model whose file's ``friction.law`` is ``creep`` only)
``creep_rate``        the ``creep`` law's band rate b (likewise)                   1/s
===================== =========================================================== ==========

The LuGre law. On a model whose parameter file has ``friction.law = "lugre"``
(:func:`~alpes_dyn.model.friction.lugre_of`) the friction has a state, the bristles z (n,) rad: the friction
torque is sigma0 z + sigma1 z' + F_v qd instead of F_s tanh(qd / v_s) + F_v qd (:meth:`ParametricDynamics.
forward_dynamics` with ``z``), z' = qd - sigma0 |qd| z / F_s (:meth:`ParametricDynamics.bristle_rate`), F_s, sigma0
and sigma1 symbols where selected (the kind ``friction`` selects all four with F_v).

Scaling. K, m, F_s, F_v, input_gain and J_m are positive and fitted as log theta
(:func:`~alpes_dyn.estimation.identification.identification.identify`); ``encoder_offset`` and ``tilt`` have the
nominal value 0, can be negative and are fitted as they are (:data:`ADDITIVE_KINDS`); so is
``tendon_compliance`` and ``capstan`` (nominal: the model's, 0 for a rigid tendon without sheath friction).

Tilt. With the base rotated by R = R_x(tilt_x) R_y(tilt_y) against the frame the gravity vector g is
given in (the recording's ``gravity_*`` columns, else the model's constant), the gravity in the base
frame is R^T g (:func:`tilted_gravity`). For a finger moving in its x-z plane (joint axes along -y),
g = (0, 0, -g0) gives R^T g = g0 (cos tilt_x sin tilt_y, -sin tilt_x, -cos tilt_x cos tilt_y): tilt_y
turns gravity within the finger's plane (a tilt about the joint axes), which changes the gravity
torques at first order; tilt_x moves part of gravity along the joint axes, where it exerts no torque,
and scales the in-plane part by cos tilt_x (second order): from a palm near level the encoder sees
tilt_y, and tilt_x only through 1 - cos tilt_x.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..errors import ModelError
from ..model.extras import spring_law
from ..model.friction import creep_of, lugre_of
from ..model.transmission import capstan_torque, capstan_velocity
from ..model.robot import Model
from .creep import band_inertia, creep_friction
from .dynamics import block_solve, sparse_dm
from .link_terms import LinkTerms

__all__ = ["KINDS", "ADDITIVE_KINDS", "OUTPUT_KINDS", "PhysicalParameter", "tilted_gravity", "common_scale", "parameter_catalogue", "select_parameters", "unseen_masses", "ParametricDynamics"]

KINDS: tuple[str, ...] = ("K", "m", "F_s", "F_v", "input_gain", "J_m", "encoder_offset", "tilt", "tendon_compliance",
                          "capstan", "sigma0", "sigma1", "creep_kappa", "creep_rate")
ADDITIVE_KINDS: tuple[str, ...] = ("encoder_offset", "tilt", "tendon_compliance", "capstan")
"""Kinds fitted as they are (nominal 0, either sign), not in log."""
OUTPUT_KINDS: tuple[str, ...] = ("encoder_offset", "tendon_compliance")
"""Kinds that change the measured output only, not the dynamics."""
_UNITS = {"K": "N m/rad", "m": "kg", "F_s": "N m", "F_v": "N m s/rad", "input_gain": "-", "J_m": "kg m^2",
          "encoder_offset": "rad", "tilt": "rad", "tendon_compliance": "rad/(N m)", "capstan": "-",
          "sigma0": "N m/rad", "sigma1": "N m s/rad", "creep_kappa": "-", "creep_rate": "1/s"}
_GROUPS = {"friction": ("F_s", "F_v", "sigma0", "sigma1", "creep_kappa", "creep_rate")}
_LAW_KINDS = {"sigma0": "lugre", "sigma1": "lugre", "creep_kappa": "creep", "creep_rate": "creep"}
"""The kinds of a friction law's own constants, and the law (the file's ``friction.law``) that has them."""
_ALWAYS = ("input_gain", "encoder_offset", "tilt", "tendon_compliance", "capstan")  # a kind selects these even at nominal 0


@dataclass(frozen=True)
class PhysicalParameter:
    """One physical parameter of a model: its name, kind, joint (or motor), nominal value and unit."""

    name: str
    kind: str
    joint: str | None
    nominal: float
    unit: str
    motor: str | None = None

    @property
    def additive(self) -> bool:
        """Fitted as it is (nominal 0, either sign), not in log: :data:`ADDITIVE_KINDS`."""
        return self.kind in ADDITIVE_KINDS


def _suffix(joint: str) -> str:
    """``j1`` -> ``1`` (the report's K_1), other names unchanged."""
    return joint[1:] if joint[:1] == "j" and joint[1:].isdigit() else joint


def _child_links(model: Model) -> dict[str, str]:
    """Joint name -> the URDF link it moves."""
    root = ET.fromstring(model.urdf)
    out = {}
    for j in root.iter("joint"):
        child = j.find("child")
        if child is not None and j.get("name") in model.joint_names:
            out[j.get("name")] = child.get("link")
    return out


def _link_masses(urdf: str) -> dict[str, float]:
    out = {}
    for link in ET.fromstring(urdf).iter("link"):
        mass = link.find("inertial/mass")
        out[link.get("name")] = float(mass.get("value")) if mass is not None else 0.0
    return out


def _check_model(model: Any) -> None:
    """:class:`~alpes_dyn.ModelError` naming the field where ``model`` is not a :class:`Model`."""
    if not isinstance(model, Model):
        raise ModelError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")


def parameter_catalogue(model: Model) -> list[PhysicalParameter]:
    """Every parameter of ``model`` that :class:`ParametricDynamics` can make symbolic, nominal values
    from the model (stiffness, masses, friction of its extras; input gain 1; each motor's rotor inertia
    J_m and encoder offset 0; the tilt angles 0; the LuGre law's sigma0 and sigma1 where the file's law is it).

    Parameters
    ----------
    model : alpes_dyn.Model
        The numeric model.

    Returns
    -------
    list of PhysicalParameter
        The parameters, by kind then joint (motor).

    Raises
    ------
    ModelError
        ``model`` not a :class:`~alpes_dyn.Model`.
    """
    _check_model(model)
    ex = model.extras
    links = _child_links(model)
    masses = _link_masses(model.urdf)
    out = []
    for kind in ("K", "m", "F_s", "F_v"):
        for i, j in enumerate(model.joint_names):
            nominal = {"K": ex.stiffness[i], "m": masses.get(links.get(j, ""), 0.0), "F_s": ex.coulomb[i],
                       "F_v": ex.viscous[i]}[kind]
            out.append(PhysicalParameter(f"{kind}_{_suffix(j)}", kind, j, float(nominal), _UNITS[kind]))
    out.append(PhysicalParameter("input_gain", "input_gain", None, 1.0, "-"))
    tr = model.transmission
    if tr is not None:
        for kind in ("J_m", "encoder_offset", "tendon_compliance", "capstan"):
            for k, mo in enumerate(tr.motor_names):
                nominal = {"J_m": float(tr.rotor_inertia[k]), "encoder_offset": 0.0,
                           "tendon_compliance": float(tr.tendon_compliance[k]), "capstan": float(tr.capstan[k])}[kind]
                out.append(PhysicalParameter(f"{kind}_{mo}", kind, None, nominal, _UNITS[kind], mo))
    out += [PhysicalParameter(f"tilt_{a}", "tilt", None, 0.0, "rad") for a in ("x", "y")]
    law = lugre_of(model)
    if law is not None:
        out += [PhysicalParameter(k, k, None, float(getattr(law, k)), _UNITS[k]) for k in ("sigma0", "sigma1")]
    creep = creep_of(model)
    if creep is not None:
        out += [PhysicalParameter(f"creep_{k}", f"creep_{k}", None, float(getattr(creep, k)), _UNITS[f"creep_{k}"])
                for k in ("kappa", "rate")]
    return out


def unseen_masses(model: Model) -> tuple[str, ...]:
    """The masses that the default selection holds: m_j of a joint j that no motor moves, nor any joint between it
    and the base (the link of a passive joint at the root, e.g. finger_edu's ab/adduction). Its weight and inertia
    act on those passive joints alone, whose only witness in the encoders is their coupling to the driven ones: the
    mass is seen together with the joint's spring (on finger_edu's 3 s experiment the Cramér-Rao bounds give it 2.9 %
    against 0.02 % for the other masses, correlated +0.99 with K of its joint) and the fit, freeing it, headed for
    m = 0 and lost its basin. A mimic joint counts as moved where its primary joint is. Empty without motors.

    Parameters
    ----------
    model : alpes_dyn.Model
        The numeric model.

    Returns
    -------
    tuple of str
        The masses' parameter names (``m_<joint>``).
    """
    _check_model(model)
    tr = model.transmission
    if tr is None:
        return ()
    moved = {j for j, col in zip(model.joint_names, np.asarray(tr.S).T) if np.any(col != 0)}
    if model.mimic is not None:
        moved |= {mj.name for mj in model.mimic.mimics if mj.primary in moved}
    pm = model.pin_model
    out = []
    for j in model.joint_names:
        jid, seen = pm.getJointId(j), False
        while jid > 0 and not seen:
            seen, jid = pm.names[jid] in moved, pm.parents[jid]
        if not seen:
            out.append(f"m_{_suffix(j)}")
    return tuple(out)


def select_parameters(model: Model, spec: str | Sequence[str] | None = None) -> tuple[PhysicalParameter, ...]:
    """Parameters chosen by ``spec``: a comma-separated string or a list of kinds (``K``, ``m``,
    ``F_s``, ``F_v``, ``friction`` = F_s and F_v, ``input_gain``, ``J_m``, ``encoder_offset``, ``tilt``)
    and/or names (``K_2``, ``m_1``, ``J_m_finger``, ``encoder_offset_finger``, ``tilt_y``).

    ``None`` gives K and m of every joint (but the masses of :func:`unseen_masses`, held), plus F_s and F_v (and a
    LuGre law's sigma0, sigma1) where the model has friction (never the rotor inertia, encoder offsets or tilt: those are asked for by name). A kind
    selects only the joints (motors) where its nominal value is non-zero (a joint without a spring has no K, a motor
    without rotor inertia no J_m); ``input_gain``, ``encoder_offset`` and ``tilt`` are always selected.

    Parameters
    ----------
    model : alpes_dyn.Model
        The numeric model.
    spec : str or sequence of str or None, optional
        The kinds and names, as above (default None: the default selection).

    Returns
    -------
    tuple of PhysicalParameter
        The selection, in the order asked.

    Raises
    ------
    ModelError
        An unknown name, a repeat, or an empty selection.
    """
    cat = parameter_catalogue(model)
    by_name = {p.name: p for p in cat}
    if spec is None:
        unseen = set(unseen_masses(model))
        items: list[str] = (["K"] + ([p.name for p in cat if p.kind == "m" and p.nominal != 0.0 and p.name not in unseen]
                                     if unseen else ["m"]) + (["friction"] if model.extras.has_friction else []))
    elif isinstance(spec, str):
        items = [s.strip() for s in spec.split(",")]
    else:
        items = list(spec)
    chosen: list[PhysicalParameter] = []
    for it in items:
        if not isinstance(it, str) or not it:
            raise ModelError(f"parameters: empty or non-string entry in {spec!r}")
        kinds = _GROUPS.get(it, (it,) if it in KINDS else ())
        if it in _LAW_KINDS and getattr(model.params, "friction_law", "tanh") != _LAW_KINDS[it]:
            raise ModelError(f"parameters: {it} is the {_LAW_KINDS[it]} law's; the model's friction.law is "
                             f"{getattr(model.params, 'friction_law', 'tanh')}")
        if kinds:
            new = [p for p in cat if p.kind in kinds and (p.kind in _ALWAYS or p.nominal != 0.0)]
        elif it in by_name:
            new = [by_name[it]]
        else:
            raise ModelError(f"parameters: unknown parameter {it!r} (kinds: {', '.join(KINDS + tuple(_GROUPS))}; "
                             f"names like {cat[0].name}, {cat[len(cat) // 4].name})")
        for p in new:
            if p in chosen:
                raise ModelError(f"parameters: {p.name} is selected twice in {spec!r}")
            chosen.append(p)
    if not chosen:
        raise ModelError(f"parameters: {spec!r} selects nothing on model {model.name!r} (no spring/friction?)")
    return tuple(chosen)


def tilted_gravity(g: Any, tilt_x: Any, tilt_y: Any, xp: Any = np) -> Any:
    """R^T g (3,), m/s^2: gravity g in the frame of a base turned by R = R_x(tilt_x) R_y(tilt_y) (rad)
    against the frame g is given in.

    Parameters
    ----------
    g : array_like or casadi.SX, shape (3,)
        Gravity, m/s^2.
    tilt_x : float or casadi.SX
        The base's tilt about x, rad.
    tilt_y : float or casadi.SX
        The base's tilt about y, rad.
    xp : module, optional
        ``numpy`` (default) or ``casadi``.
    """
    cx, sx, cy, sy = xp.cos(tilt_x), xp.sin(tilt_x), xp.cos(tilt_y), xp.sin(tilt_y)
    gx, gy, gz = g[0], g[1], g[2]
    a = gy * cx + gz * sx  # (R_x^T g)_y
    b = -gy * sx + gz * cx  # (R_x^T g)_z
    out = (cy * gx - sy * b, a, sy * gx + cy * b)
    return xp.vertcat(*out) if xp is not np else np.array(out, dtype=float)


def common_scale(model: Model, parameters: Sequence[PhysicalParameter]) -> bool:
    """True when ``parameters`` hold ``input_gain`` and every term of eq. 2.10 that scales with it: the mass of
    every body a joint moves, every non-zero spring, friction and rotor inertia (none held), no joint-side
    armature. Then theta -> c theta leaves qdd, hence the encoder, unchanged: only the ratios are seen. The
    torque constant's scale must come from something known -- the masses (the maker gives them) or a force
    sensor: fit ``input_gain`` with the masses held.

    Parameters
    ----------
    model : alpes_dyn.Model
        The numeric model.
    parameters : sequence of PhysicalParameter
        The selection.

    Returns
    -------
    bool
        Whether the selection is seen only up to a common scale.
    """
    names = {p.name for p in parameters}
    if "input_gain" not in names or np.any(model.extras.armature != 0):
        return False
    return all(p.name in names for p in parameter_catalogue(model)
               if p.kind in ("K", "m", "F_s", "F_v", "J_m") and p.nominal != 0.0)


class ParametricDynamics:
    """qdd(q, qd, Gamma; theta, g) of eq. 2.10 with the parameters ``theta`` as CasADi symbols.

    Parameters
    ----------
    model : alpes_dyn.Model
        The numeric model; parameters not selected keep its values.
    parameters : str or sequence of str or None, optional
        A selection for :func:`select_parameters` (default None: K, m, and friction if any).
    gravity_input : bool, optional
        Take the gravity vector g (3,), m/s^2, base frame, as an input (default False: the model's constant
        gravity).

    Attributes
    ----------
    parameters : tuple of PhysicalParameter
        The selected parameters (length p); ``names`` their names, ``nominal`` (p,) their nominal values.
    theta : casadi.SX, shape (p,)
        Symbol of the parameter values in their units.
    g : casadi.SX, shape (3,), or None
        The gravity input's symbol, m/s^2, or None.
    """

    def __init__(self, model: Model, parameters: str | Sequence[str] | None = None,
                 gravity_input: bool = False) -> None:
        self.model = model
        self.n = model.n
        self.parameters = select_parameters(model, parameters)
        self.names = tuple(p.name for p in self.parameters)
        self.nominal = np.array([p.nominal for p in self.parameters])
        self.p = len(self.parameters)
        self.theta = cs.SX.sym("theta", self.p)
        self.g = cs.SX.sym("g", 3) if gravity_input else None
        self.gravity_input = bool(gravity_input)
        links = _child_links(model)
        masses = _link_masses(model.urdf)
        self._mass_params = []  # (index in theta, nominal mass, backend)
        self._K = cs.DM(model.extras.stiffness)
        self._q_rest = np.asarray(model.extras.rest) if model.extras.has_rest else None  # rad, not fitted
        self._Fs = cs.DM(model.extras.coulomb)
        self._Fv = cs.DM(model.extras.viscous)
        self.lugre = lugre_of(model)  # the law with a state (module docstring), or None: the smooth sign
        self.creep = creep_of(model)  # the soft dry friction solved with the dynamics (symbolic.creep), or None
        self._dry = (np.asarray(model.extras.coulomb) > 0).astype(float)  # the joints with a bristle
        idx = {j: i for i, j in enumerate(model.joint_names)}
        parameterised = set()
        self._sel: dict[str, list[tuple[int, int]]] = {k: [] for k in KINDS}
        for k, prm in enumerate(self.parameters):
            if prm.kind == "m":
                link = links[prm.joint]
                if masses.get(link, 0.0) <= 0:
                    raise ModelError(f"parameters: {prm.name}: body {link!r} has no mass to scale")
                parameterised.add(link)
                self._mass_params.append((k, masses[link], LinkTerms(model.urdf, {link}, model.joint_names)))
            elif prm.kind in ("J_m", "encoder_offset", "tendon_compliance", "capstan"):
                self._sel[prm.kind].append((k, model.motor_index(prm.motor)))
            elif prm.kind in _LAW_KINDS:  # (the catalogue has them with their law only)
                self._sel[prm.kind].append((k, -1))
            elif prm.kind == "tilt":
                self._sel[prm.kind].append((k, "xy".index(prm.name[-1])))
            else:
                self._sel[prm.kind].append((k, idx[prm.joint] if prm.joint is not None else -1))
        rest = {name for name, mass in masses.items() if mass > 0} - parameterised
        self._rest = None
        if rest:
            terms = LinkTerms(model.urdf, rest, model.joint_names)
            self._rest = (terms.mass, terms)
        self._armature = np.asarray(model.extras.armature, dtype=float)
        tr = model.transmission
        self._S = sparse_dm(tr.S) if tr is not None else None
        self._Jm = cs.DM(tr.rotor_inertia) if tr is not None else None
        self._rotor = model.rotor_matrix if model._rotor else None
        self._curve = tr.curve if tr is not None else None
        self.smooth_velocity = float(model.extras.smooth_velocity)
        self._capstan = cs.DM(tr.capstan) if tr is not None else None
        self._capstan_velocity = capstan_velocity(tr.S, self.smooth_velocity) if tr is not None else None

    # ------------------------------------------------------------------ pieces
    def _vector(self, kind: str, base: cs.DM, theta: cs.SX) -> cs.SX:
        """A per-joint vector: the model's values with the selected entries replaced by theta's."""
        out = cs.SX(base)
        for k, i in self._sel[kind]:
            out[i] = theta[k]
        return out

    def inertia_matrix(self, q: cs.SX, theta: cs.SX) -> cs.SX:
        """A(q; theta) + I_a, (n, n), kg m^2, with the tree's structural zeros (:func:`~alpes_dyn.symbolic.tree_sparsity.
        tree_pattern`: the bodies' terms' own patterns, summed), so that :func:`block_solve` and the looped
        sensitivities solve a hand's fingers apart.

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        M = self._link_inertia(q, theta)
        if np.any(self._armature != 0):
            M = M + cs.diag(cs.DM(self._armature))
        if self._curve is not None and (self._sel["J_m"] or self._rotor is not None):  # rho(q)^T diag(J_m) rho(q)
            rho = self._curve.ratio(q, cs)
            M = M + cs.mtimes(rho.T, cs.mtimes(cs.diag(self._vector("J_m", self._Jm, theta)), rho))
        elif self._sel["J_m"]:  # S^T diag(J_m) S with J_m fitted (S sparse: the blocks stay apart)
            J = self._vector("J_m", self._Jm, theta)
            M = M + cs.mtimes(self._S.T, cs.mtimes(cs.diag(J), self._S))
        elif self._rotor is not None:
            M = M + sparse_dm(self._rotor)
        return M

    def _link_inertia(self, q: Any, theta: cs.SX) -> cs.SX:
        """A(q; theta) (n, n), kg m^2: the links' inertia alone (theta's masses and the rest of the links), without
        the armature and the rotors; structurally sparse as the tree."""
        M = cs.SX(self.n, self.n)  # (structurally empty: SX.zeros would make every entry a structural 0)
        for k, m0, be in self._mass_params:
            M = M + (theta[k] / m0) * be.mass_matrix(q)
        if self._rest is not None:
            M = M + self._rest[1].mass_matrix(q)
        return M

    def rotor_bias(self, q: cs.SX, v: cs.SX, theta: cs.SX) -> cs.SX | float:
        """rho(q)^T diag(J_m) (drho/dt) qd (n,), N m, the rotors' velocity product where the ratios change with q
        (:meth:`Transmission.rotor_bias <alpes_dyn.model.transmission.Transmission.rotor_bias>`); 0 otherwise.

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        if self._curve is None or not (self._sel["J_m"] or self._rotor is not None):
            return 0.0
        J = self._vector("J_m", self._Jm, theta)
        return cs.mtimes(self._curve.ratio(q, cs).T, J * self._curve.rate_product(q, v, cs))

    def bias_torque(self, q: cs.SX, v: cs.SX, theta: cs.SX, g: Any) -> cs.SX:
        """C(q, qd) qd + gravity torque (no springs) for gravity g (3,), N m; g turned by the tilt
        angles where they are selected (:func:`tilted_gravity`).

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        g : casadi.SX or array_like, shape (3,), or None
            Gravity, m/s^2, base frame (None: the model's).
        """
        g = cs.DM(self.model.gravity) if g is None else g
        if self._sel["tilt"]:
            angles: list[Any] = [0.0, 0.0]
            for k, i in self._sel["tilt"]:
                angles[i] = theta[k]
            g = tilted_gravity(g, angles[0], angles[1], cs)
        out = cs.SX.zeros(self.n)
        terms = [(theta[k] / m0, m0, be) for k, m0, be in self._mass_params]
        if self._rest is not None:
            terms.append((1.0, self._rest[0], self._rest[1]))
        for scale, mass, be in terms:
            com = be.com_position(q)  # at q_full on a mimic model: d com / dq is then J G (the reduced force)
            grav = -mass * cs.mtimes(cs.jacobian(com, q).T, g)
            out = out + scale * (be.bias(q, v) + grav)
        return out

    def passive_torque(self, q: cs.SX, v: cs.SX, theta: cs.SX, z: cs.SX | None = None, dry: bool = True) -> cs.SX:
        """Springs K (q - q_rest) (torsional; K fitted, the rest angles q_rest the model's, :func:`~alpes_dyn.model.extras.
        spring_law`) plus friction F_s tanh(qd / v_s) + F_v qd, (n,), N m; with the bristles ``z`` (n,) rad, the
        LuGre friction sigma0 z + sigma1 z' + F_v qd instead (eq. L2, z' of :meth:`bristle_rate`).

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        z : casadi.SX, shape (n,), or None, optional
            The bristle deflections, rad: the LuGre friction (default None: the smooth law).
        dry : bool, optional
            With the smooth law's dry term F_s tanh(qd / v_s) (default True); False leaves it out (the ``creep``
            law, whose dry friction :meth:`creep_torque` gives). Unused with ``z``.

        Returns
        -------
        casadi.SX, shape (n,)
            The springs' and friction's torque, N m.
        """
        K = self._vector("K", self._K, theta)
        Fv = self._vector("F_v", self._Fv, theta)
        if z is not None:
            s0, s1 = self._law("sigma0", theta), self._law("sigma1", theta)
            return spring_law(K, self._q_rest, q, cs) + s0 * z + s1 * self.bristle_rate(z, v, theta) + Fv * v
        Fs = self._vector("F_s", self._Fs, theta) if dry else 0.0
        return spring_law(K, self._q_rest, q, cs) + Fs * cs.tanh(v / self.smooth_velocity) + Fv * v

    def _law(self, kind: str, theta: cs.SX) -> Any:
        """The LuGre law's ``sigma0`` or ``sigma1``: theta's where selected, else the file's."""
        sel = self._sel[kind]
        return theta[sel[0][0]] if sel else float(getattr(self.lugre, kind))

    def bristle_terms(self, v: cs.SX, theta: cs.SX) -> tuple[cs.SX, cs.DM]:
        """(sigma0 |qd| / F_s (n,) 1/s, the bristles' relaxation rate of eq. L1 (0 on a joint without dry friction),
        the mask of the joints with a bristle (n,)).

        Parameters
        ----------
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        Fs = self._vector("F_s", self._Fs, theta)
        dry = cs.DM(self._dry)
        return dry * self._law("sigma0", theta) * cs.fabs(v) / (dry * Fs + (1 - dry)), dry

    def bristle_rate(self, z: cs.SX, v: cs.SX, theta: cs.SX) -> cs.SX:
        """z' = qd - sigma0 |qd| z / F_s (eq. L1), (n,) rad/s; 0 on a joint without dry friction.

        Parameters
        ----------
        z : casadi.SX, shape (n,)
            The bristle deflections, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        a, dry = self.bristle_terms(v, theta)
        return dry * v - a * z

    def encoder_offset(self, theta: cs.SX) -> cs.SX:
        """(m,) the encoder offsets, rad: y = S q + offset (zeros where not selected).

        Parameters
        ----------
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        m = self.model.transmission.n_motors if self.model.transmission is not None else 0
        return self._vector("encoder_offset", cs.DM.zeros(m), theta)

    def input_gain(self, theta: cs.SX) -> Any:
        """The input gain: theta's where selected, else 1 (dimensionless; it scales the joint torques).

        Parameters
        ----------
        theta : casadi.SX, shape (p,)
            The parameter values, in their units.
        """
        sel = self._sel["input_gain"]
        return theta[sel[0][0]] if sel else 1.0

    def input_torque(self, q: cs.SX, v: cs.SX, u: cs.SX, theta: cs.SX | None = None) -> cs.SX:
        """The joint torques (n,), N m, of the motor torques u (m,) through the tendons: S^T u, rho(q)^T u on ratios
        that change with q, less the tendons' sheath friction where a ``capstan`` is fitted or the model has one
        (:func:`~alpes_dyn.model.transmission.capstan_torque` at the motor velocities rho(q) v, rad/s). The
        transmission's :meth:`~alpes_dyn.model.transmission.Transmission.transmitted` with theta's values.

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        u : casadi.SX, shape (m,)
            Motor torques, N m.
        theta : casadi.SX, shape (p,), or None, optional
            The parameter values, in their units (default None: :attr:`theta`).
        """
        theta = self.theta if theta is None else theta
        tr = self.model.transmission
        rho = cs.DM(tr.S) if self._curve is None else self._curve.ratio(q, cs)
        if self._sel["capstan"] or tr.has_capstan:
            mu = self._vector("capstan", self._capstan, theta)
            u = capstan_torque(u, cs.mtimes(rho, v), mu, self._capstan_velocity, cs)
        return cs.mtimes(self._S.T, u) if self._curve is None else cs.mtimes(rho.T, u)

    def forward_dynamics(self, q: cs.SX, v: cs.SX, tau: cs.SX, theta: cs.SX | None = None, g: Any = None,
                         F_torque: cs.SX | None = None, z: cs.SX | None = None) -> cs.SX:
        """qdd (n,) of eq. 2.10 with joint torques ``input_gain * tau`` (+ ``F_torque``, e.g. J^T F); with the
        bristles ``z`` (n,) rad, the LuGre friction (:meth:`passive_torque`): M^-1 r of :meth:`dynamics_terms`.

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        tau : casadi.SX, shape (n,)
            Joint torques of the inputs, N m (scaled by the input gain).
        theta : casadi.SX, shape (p,), or None, optional
            The parameter values, in their units (default None: :attr:`theta`).
        g : casadi.SX or array_like, shape (3,), or None, optional
            Gravity, m/s^2, base frame (default None: the model's).
        F_torque : casadi.SX, shape (n,), or None, optional
            Further joint torques, N m, e.g. J^T F (default None).
        z : casadi.SX, shape (n,), or None, optional
            The bristle deflections, rad: the LuGre friction (default None: the smooth law).
        """
        return block_solve(*self.dynamics_terms(q, v, tau, theta, g, F_torque, z))

    def dynamics_terms(self, q: cs.SX, v: cs.SX, tau: cs.SX, theta: cs.SX | None = None, g: Any = None,
                       F_torque: cs.SX | None = None, z: cs.SX | None = None) -> tuple[cs.SX, cs.SX]:
        """(M (n, n), r (n,)) with M qdd = r, eq. 2.10: the inertia matrix and the torques but the inertial ones
        (``input_gain * tau`` + ``F_torque`` - bias - passive), as :meth:`forward_dynamics` solves them; what the
        sensitivities of a large model differentiate (:mod:`~alpes_dyn.simulation.variational`).

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            Joint angles, rad.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        tau : casadi.SX, shape (n,)
            Joint torques of the inputs, N m (scaled by the input gain).
        theta : casadi.SX, shape (p,), or None, optional
            The parameter values, in their units (default None: :attr:`theta`).
        g : casadi.SX or array_like, shape (3,), or None, optional
            Gravity, m/s^2, base frame (default None: the model's).
        F_torque : casadi.SX, shape (n,), or None, optional
            Further joint torques, N m, e.g. J^T F (default None).
        z : casadi.SX, shape (n,), or None, optional
            The bristle deflections, rad: the LuGre friction (default None: the smooth law).
        """
        theta = self.theta if theta is None else theta
        creep = self.creep is not None and z is None
        rhs = (self.input_gain(theta) * tau - self.bias_torque(q, v, theta, g)
               - self.passive_torque(q, v, theta, z, dry=not creep))
        if self._curve is not None:
            rhs = rhs - self.rotor_bias(q, v, theta)
        if F_torque is not None:
            rhs = rhs + F_torque
        M = self.inertia_matrix(q, theta)
        if creep:  # the soft dry friction of eq. C1, solved with M (symbolic.creep)
            rhs = rhs - self.creep_torque(M, rhs, v, theta)
        return M, rhs

    def creep_torque(self, M: cs.SX, r: cs.SX, v: cs.SX, theta: cs.SX) -> cs.SX:
        """The ``creep`` law's dry friction (n,), N m, with M qdd = r - it (:func:`~alpes_dyn.symbolic.creep.
        creep_friction`): its band inertia from the links' inertia at q = 0 (theta's masses; the rotors and the
        armature, which MuJoCo's constraint does not weigh on a joint, left out).

        Parameters
        ----------
        M : casadi.SX, shape (n, n)
            The inertia matrix at q, kg m^2.
        r : casadi.SX, shape (n,)
            Every torque on the joints but the dry friction's (input, bias, springs, viscous), N m.
        v : casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        theta : casadi.SX, shape (p,)
            The parameter values, in their units (the masses, F_s, and ``creep_kappa``/``creep_rate`` where
            selected).

        Returns
        -------
        casadi.SX, shape (n,)
            The dry friction tau_f of eq. C1, N m (subtracted from ``r``).
        """
        a = band_inertia(self._link_inertia(cs.DM.zeros(self.n), theta), self._creep_law("kappa", theta))
        return creep_friction(M, r, v, self._vector("F_s", self._Fs, theta), a, self._creep_law("rate", theta),
                              self._dry > 0)

    def _creep_law(self, kind: str, theta: cs.SX) -> Any:
        """The ``creep`` law's ``kappa`` or ``rate``: theta's where selected (``creep_kappa``/``creep_rate``), else
        the file's."""
        sel = self._sel["creep_" + kind]
        return theta[sel[0][0]] if sel else float(getattr(self.creep, kind))
