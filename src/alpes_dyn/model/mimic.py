"""Mimic joints: a URDF ``<mimic joint="J" multiplier="a" offset="b">`` as a constraint, q_k = a q_J + b.

A joint that mimics another has no coordinate of its own: the model keeps the independent coordinates q (n,) and
the whole tree's q_full = G q + o (n_full,), with G = dq_full/dq (n_full, n) constant (a row of the identity for
an independent joint, a e_J for a mimic joint) and o the offsets (b on a mimic joint's row, 0 elsewhere). The
Lagrangian of the tree restricted to q_full = G q + o gives the reduced terms

    A_red(q) = G^T A(q_full) G,   C_red(q, qd) = G^T C(q_full, G qd) G,   G_red(q) = G^T g(q_full),

the tip Jacobian J(q_full) G, and the same for any generalized force (a joint torque on the mimic joint acts on q_J
scaled by a). The virtual work of the constraint's force vanishes, so nothing else changes: the independent joint
is the one its motor, spring and encoder see (the spec names it; a spec naming a mimic joint is refused, naming it).
The model's limits (``Model.lower``, ``upper``, the stops, ``random_state``) are the independent joints' own URDF
ranges: a mimic joint's range is not mapped onto the joint it follows (the MJCF export keeps it on the mimic
joint's hinge, where MuJoCo enforces it).

:class:`MimicCoupling` holds G, o and the whole tree's Pinocchio model (``pin.buildModelFromXML(urdf)``) for
the terms Pinocchio's own mimic model (``mimic=True``, the model's ``pin_model``) does not compute or gets wrong
in this wheel (4.1): ABA, the gravity derivatives and the potential energy are refused on a mimic model, and its
``computeCoriolisMatrix`` disagrees with its own ``nonLinearEffects`` (C qd + g - nle = 9.6e-7 N m on a 3-link
finger where the Coriolis torque nle - g is 1.4e-6 N m); its kinematics, CRBA, RNEA and frame Jacobians agree with
the projection to machine precision on a fresh ``Data`` (checked on every model built: the frames and A at a generic
configuration), but its CRBA adds to the coupled entries of A on every further call (:meth:`MimicCoupling.mass_matrix`
is the model's A).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..checks import urdf_number_problem
from ..errors import ModelError
from ..limits import check_physical

__all__ = ["MimicJoint", "MimicCoupling", "read_mimics", "refuse_mimic_names", "tree_model"]


@dataclass(frozen=True)
class MimicJoint:
    """A joint ``name`` that follows ``primary``: q_name = multiplier q_primary + offset (rad or m, unitless a)."""

    name: str
    primary: str
    multiplier: float = 1.0
    offset: float = 0.0


def _attr_number(j: ET.Element, m: ET.Element, attr: str, default: float) -> float:
    """``<mimic attr=...>`` of joint ``j`` as a float (``default`` when absent): a decimal number within the
    accepted range (:func:`~alpes_dyn.limits.check_physical`): a multiplier of magnitude at most 1e6 (either sign,
    0 allowed: the joint then stays at its offset), an offset at most 100 rad (a revolute joint) or 100 m (a
    prismatic one) either side; not subnormal. :class:`~alpes_dyn.ModelError` naming the joint."""
    text = m.get(attr)
    if text is None:
        return default
    where = f"joint {j.get('name')!r}: <mimic {attr}={text[:40]!r}>"
    problem = urdf_number_problem(text)
    if problem is not None:
        raise ModelError(f"{where} {problem}")
    x = float(text)
    unit = "-" if attr == "multiplier" else ("m" if j.get("type") == "prismatic" else "rad")
    return float(check_physical(x, where, unit, "any", ModelError))


def read_mimics(root: ET.Element) -> tuple[MimicJoint, ...]:
    """The ``<mimic>`` elements of a parsed URDF's moving joints (URDF's defaults: multiplier 1, offset 0), each
    checked: one per joint; it names a joint (``joint=``) that exists, moves, is of the same type and is not
    itself a mimic (a chain of mimics is refused: name the first joint); multiplier and offset decimal numbers
    within their ranges (:func:`_attr_number`). A fixed joint's ``<mimic>`` is ignored (it moves nothing).

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        The parsed URDF's ``<robot>`` element.

    Returns
    -------
    tuple of MimicJoint
        The mimic joints, in URDF order.

    Raises
    ------
    ModelError
        A ``<mimic>`` that is not as above, naming the joint.
    """
    kinds = {str(j.get("name")): j.get("type") for j in root.iter("joint") if j.get("type") is not None}
    out: list[MimicJoint] = []
    for j in root.iter("joint"):
        m = j.find("mimic")
        if m is None or j.get("type") in ("fixed", None):
            continue
        name, primary = str(j.get("name")), m.get("joint")
        if len(j.findall("mimic")) > 1:
            raise ModelError(f"joint {name!r}: {len(j.findall('mimic'))} <mimic> elements; a joint follows one joint")
        if not primary:
            raise ModelError(f"joint {name!r}: <mimic> has no joint= attribute (the joint it follows)")
        if primary == name:
            raise ModelError(f"joint {name!r}: <mimic joint={primary!r}> names the joint itself")
        if primary not in kinds:
            raise ModelError(f"joint {name!r}: <mimic joint={primary!r}> names no joint of the URDF")
        if kinds[primary] != j.get("type"):
            raise ModelError(f"joint {name!r} ({j.get('type')}): <mimic joint={primary!r}> follows a "
                             f"{kinds[primary]} joint; a mimic joint and the joint it follows must be of one type")
        out.append(MimicJoint(name, primary, _attr_number(j, m, "multiplier", 1.0),
                              _attr_number(j, m, "offset", 0.0)))
    mimic_names = {m.name for m in out}
    for m in out:
        if m.primary in mimic_names:
            raise ModelError(f"joint {m.name!r}: <mimic joint={m.primary!r}> follows a joint that is itself a mimic; "
                             "name the independent joint (with the multipliers and offsets composed)")
    return tuple(out)


def urdf_mimics(urdf: str) -> tuple[MimicJoint, ...]:
    """:func:`read_mimics` of URDF text (already checked by the model's URDF checks)."""
    if "mimic" not in urdf:
        return ()
    return read_mimics(ET.fromstring(urdf))


class MimicCoupling:
    """q_full = G q + o: the whole tree's coordinates from the independent ones (the module doc).

    Parameters
    ----------
    mimics : sequence of MimicJoint
        The mimic joints (:func:`read_mimics`).
    names : sequence of str
        The independent joints, in the model's order (the columns of G).
    full_names : sequence of str
        Every moving joint of the tree (the rows of G), e.g. the full Pinocchio model's order.
    full_model : pinocchio.Model or None, optional
        The whole tree's ``pinocchio.Model`` (``full_names`` its joints), or None (default; only the map, e.g. for
        ADAM).
    """

    def __init__(self, mimics: Sequence[MimicJoint], names: Sequence[str], full_names: Sequence[str],
                 full_model: Any = None) -> None:
        self.mimics: tuple[MimicJoint, ...] = tuple(mimics)
        self.names: tuple[str, ...] = tuple(names)
        self.full_names: tuple[str, ...] = tuple(full_names)
        col = {j: i for i, j in enumerate(self.names)}
        by_name = {m.name: m for m in self.mimics}
        G = np.zeros((len(self.full_names), len(self.names)))
        o = np.zeros(len(self.full_names))
        for r, j in enumerate(self.full_names):
            if j in by_name:
                m = by_name[j]
                G[r, col[m.primary]] = m.multiplier
                o[r] = m.offset
            else:
                G[r, col[j]] = 1.0
        G.flags.writeable = False
        o.flags.writeable = False
        self.G: np.ndarray = G
        """dq_full/dq (n_full, n), constant."""
        self.offset: np.ndarray = o
        """o (n_full,): q_full = G q + o (rad or m)."""
        self.full_model = full_model
        self.full_data = full_model.createData() if full_model is not None else None

    @property
    def mimic_names(self) -> tuple[str, ...]:
        """The mimic joints' names (URDF order)."""
        return tuple(m.name for m in self.mimics)

    def of(self, name: str) -> MimicJoint | None:
        """The :class:`MimicJoint` of joint ``name``, None for an independent joint.

        Parameters
        ----------
        name : str
            A joint's name.
        """
        return next((m for m in self.mimics if m.name == name), None)

    def full_q(self, q: np.ndarray) -> np.ndarray:
        """q_full = G q + o, (n_full,) (or (..., n_full) for q (..., n)).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,) or (..., n)
            The independent joint angles, rad (m for a prismatic joint).
        """
        return q @ self.G.T + self.offset

    def full_v(self, v: np.ndarray) -> np.ndarray:
        """qd_full = G qd, (n_full,).

        Parameters
        ----------
        v : numpy.ndarray, shape (n,) or (..., n)
            The independent joint velocities qd, rad/s (m/s for a prismatic joint).
        """
        return v @ self.G.T

    def project(self, M: np.ndarray) -> np.ndarray:
        """G^T M G (n, n) of a whole-tree matrix (n_full, n_full).

        Parameters
        ----------
        M : numpy.ndarray, shape (n_full, n_full)
            A matrix of the whole tree's coordinates (e.g. its mass matrix, kg m^2).
        """
        return self.G.T @ M @ self.G

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """A_red = G^T A(q_full) G, (n, n) symmetric, kg m^2 (the whole tree's CRBA, projected). Pinocchio 4.1's
        CRBA on its mimic model is right on a fresh ``Data`` only: each further call adds to the coupled entries
        (A[0, 1] of a 3-link finger whose DIP mimics its PIP: 4.66e-5, 7.30e-5, 9.95e-5 kg m^2 on three calls at
        q = 0), so the model's inertia comes from here.

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            The independent joint angles, rad (m for a prismatic joint).
        """
        import pinocchio as pin

        A = pin.crba(self.full_model, self.full_data, self.full_q(q))
        A = np.triu(A) + np.triu(A, 1).T  # CRBA fills the upper triangle
        return self.project(A)

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """G^T C(q_full, G qd) G, (n, n), N m s (Pinocchio's, Christoffel-consistent, on the whole tree).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            The independent joint angles, rad (m for a prismatic joint).
        v : numpy.ndarray, shape (n,)
            The independent joint velocities qd, rad/s.
        """
        import pinocchio as pin

        C = pin.computeCoriolisMatrix(self.full_model, self.full_data, self.full_q(q), self.full_v(v))
        return self.project(C)

    def gravity_jacobian(self, q: np.ndarray) -> np.ndarray:
        """G^T (dg/dq_full) G, (n, n), N m/rad (gravity only).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            The independent joint angles, rad (m for a prismatic joint).
        """
        import pinocchio as pin

        return self.project(pin.computeGeneralizedGravityDerivatives(self.full_model, self.full_data, self.full_q(q)))

    def potential_energy(self, q: np.ndarray) -> float:
        """The gravity potential energy of the whole tree at q_full (J).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            The independent joint angles, rad (m for a prismatic joint).
        """
        import pinocchio as pin

        return float(pin.computePotentialEnergy(self.full_model, self.full_data, self.full_q(q)))


def refuse_mimic_names(spec: Any, coupling: MimicCoupling) -> None:
    """:class:`~alpes_dyn.ModelError` where a :class:`~alpes_dyn.model.spec.TransmissionSpec` names a mimic joint
    (a motor's joint, a spring, friction, armature, rest-angle or stop row): it has no coordinate of its own, so its row
    is refused rather than moved onto the joint it follows (whose own values would then be ambiguous).

    Parameters
    ----------
    spec : TransmissionSpec
        The spec (:class:`~alpes_dyn.model.spec.TransmissionSpec`) whose joint rows are checked.
    coupling : MimicCoupling
        The model's mimic coupling.

    Raises
    ------
    ModelError
        A row naming a mimic joint, naming the row and the joint to name instead.
    """
    from .spec import JOINT_TABLES, REST_TABLE

    uses = [(f"motor {m.name!r}.joints", j) for m in spec.motors for j in m.joints]
    uses += [(f"{t}.{j}", j) for t in JOINT_TABLES + (REST_TABLE,) for j in getattr(spec, t)]
    uses += [(f"stops.joints.{j}", j) for j in (spec.stops or {}).get("joints", {})]
    for where, j in uses:
        m = coupling.of(j)
        if m is not None:
            raise ModelError(f"{where}: joint {j!r} is a mimic joint (URDF <mimic>: q_{j} = {m.multiplier:g} "
                             f"q_{m.primary} + {m.offset:g}) with no coordinate of its own; name {m.primary!r}")


def tree_model(model: Any) -> Any:
    """The Pinocchio model of ``model``'s whole tree: with mimic joints the one beside Pinocchio's mimic model (every
    joint its own coordinate, mimic joints included), else the model's own (the same joint ids).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.

    Returns
    -------
    pinocchio.Model
        The whole tree's model.
    """
    mimic = getattr(model, "mimic", None)
    return mimic.full_model if mimic is not None else model.pin_model
