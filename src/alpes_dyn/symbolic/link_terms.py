"""A few links' share of a tree's dynamics, on the branch from the base to them alone (issue 51: the whole hand sized).

:class:`~alpes_dyn.symbolic.parametric.ParametricDynamics` scales each fitted link's mass (with its inertia) by a
symbol, so it needs each such link's own terms: its mass matrix J^T I J, its velocity product and its centre of
mass. Only the joints between the base and the link move it, so they are computed on that branch alone (the URDF
cut to it, every other link massless) and placed in the whole model's rows: on the Shadow hand with its wrist free
(24 joints, 24 massive links) each link's recursion runs over at most 7 joints, not 24, and its terms carry the
branch's structural zeros (:func:`~alpes_dyn.symbolic.tree_sparsity.tree_pattern`). The terms are the same
functions of q as on the whole tree: a joint off the branch does not move the link. A URDF with ``<mimic>`` joints
keeps the whole tree (a mimic joint may follow a joint off the branch).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..model.mimic import urdf_mimics
from .tree_sparsity import sparse_dm

__all__ = ["branch_urdf", "LinkTerms"]

_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def branch_urdf(urdf: str, keep: set[str], joint_names: Sequence[str], cut: bool = True) -> tuple[str, list[str],
                                                                                                  float]:
    """The URDF with every link outside ``keep`` massless and, with ``cut``, only the links and joints between
    the base and the links of ``keep``.

    Parameters
    ----------
    urdf : str
        The tree's URDF.
    keep : set of str
        The links whose masses are kept.
    joint_names : sequence of str
        The model's moving joints, in its order.
    cut : bool, optional
        Drop every link and joint off the branches to ``keep`` (default True).

    Returns
    -------
    tuple of (str, list of str, float)
        The URDF, the moving joints left (in ``joint_names``' order) and the total mass of ``keep``, kg.
    """
    root = ET.fromstring(urdf)
    total = 0.0
    for link in root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        if link.get("name") in keep:
            total += float(inertial.find("mass").get("value"))
            continue
        inertial.find("mass").set("value", "0.0")
        inertia = inertial.find("inertia")
        if inertia is not None:
            for k in _INERTIA:
                inertia.set(k, "0.0")
    if not cut:
        return ET.tostring(root, encoding="unicode"), list(joint_names), total
    by_child = {j.find("child").get("link"): j for j in root.findall("joint") if j.find("child") is not None}
    links, joints = set(), set()
    for name in keep:  # (a loop over the kept links, up their branch)
        while name is not None and name not in links:
            links.add(name)
            j = by_child.get(name)
            if j is None:
                break
            joints.add(j.get("name"))
            name = j.find("parent").get("link")
    for el in list(root):
        if (el.tag == "link" and el.get("name") not in links) or (el.tag == "joint" and el.get("name") not in joints) \
                or el.tag == "transmission":
            root.remove(el)
    return ET.tostring(root, encoding="unicode"), [j for j in joint_names if j in joints], total


class _Shim:
    """What :class:`~alpes_dyn.symbolic.dynamics._Adam` reads of a model: a URDF, joint names, no gravity."""

    def __init__(self, urdf: str, joint_names: Sequence[str]) -> None:
        self.urdf, self.joint_names, self.gravity = urdf, tuple(joint_names), np.zeros(3)


class LinkTerms:
    """The mass matrix, velocity product C qd and centre of mass of the links ``keep`` alone (the others
    massless), computed on their branch (:func:`branch_urdf`) and given in the whole model's joints.

    Parameters
    ----------
    urdf : str
        The tree's URDF.
    keep : set of str
        The links.
    joint_names : sequence of str
        The model's moving joints, in its order (n).
    """

    def __init__(self, urdf: str, keep: set[str], joint_names: Sequence[str]) -> None:
        from .dynamics import _Adam

        self.n = len(joint_names)
        text, names, self.mass = branch_urdf(urdf, keep, joint_names, cut=not urdf_mimics(urdf))
        self.idx = [list(joint_names).index(j) for j in names]
        self._be = _Adam(_Shim(text, names)) if names else None
        self._P = sparse_dm(np.eye(self.n)[:, self.idx]) if self.idx else None  # (n, k) the branch's joints

    def mass_matrix(self, q: cs.SX) -> cs.SX:
        """(n, n) kg m^2: J^T I J of the links, zero off their branch's joints.

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            The model's joint angles, rad.
        """
        if self._be is None:
            return cs.SX(self.n, self.n)
        return cs.mtimes(self._P, cs.mtimes(self._be.mass_matrix(q[self.idx]), self._P.T))

    def bias(self, q: cs.SX, v: cs.SX) -> cs.SX:
        """(n,) N m: the links' C(q, qd) qd (no gravity).

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            The model's joint angles, rad.
        v : casadi.SX, shape (n,)
            The joint velocities qd, rad/s.
        """
        if self._be is None:
            return cs.SX(self.n, 1)
        return cs.mtimes(self._P, self._be.bias(q[self.idx], v[self.idx]))

    def com_position(self, q: cs.SX) -> Any:
        """(3,) m: the links' centre of mass at q (zeros where no joint moves them: no gravity torque).

        Parameters
        ----------
        q : casadi.SX, shape (n,)
            The model's joint angles, rad.
        """
        if self._be is None:
            return cs.SX.zeros(3)
        return self._be.com_position(q[self.idx])
