"""Checks of a URDF's text before Pinocchio's parser sees it: its size and depth (the parser recurses per
level), its joints' types, axes, limits and ``<mimic>`` elements (:func:`~alpes_dyn.model.mimic.read_mimics`), each
refused by name with one line."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

from ..errors import ModelError
from ..limits import MAX_NAME, MAX_URDF_DEPTH, MAX_URDF_JOINTS, MAX_URDF_LINKS
from .mimic import read_mimics

__all__ = ["check_urdf_structure", "check_joint"]

_OTHER_TYPES = {
    "continuous": "is continuous (unbounded); give it limits as a revolute joint (type=\"revolute\" with <limit "
                  "lower=... upper=... effort=... velocity=...>)",
    "floating": "is floating (6 degrees of freedom); only revolute, prismatic and fixed joints are supported "
                "(a fixed-base tree of 1-DoF joints)",
    "planar": "is planar (3 degrees of freedom); only revolute, prismatic and fixed joints are supported "
              "(a fixed-base tree of 1-DoF joints)",
}


def check_joint(j: ET.Element) -> None:
    """A ``<joint>`` element of a supported type (revolute, prismatic or fixed), and a moving joint's
    ``<axis xyz>`` finite and non-zero (URDF's default, absent: 1 0 0).

    Parameters
    ----------
    j : xml.etree.ElementTree.Element
        The ``<joint>`` element (one without a type, a ``<transmission>``'s reference, is passed over).

    Raises
    ------
    ModelError
        An unsupported type or a bad axis, naming the joint.
    """
    name, kind = j.get("name"), j.get("type")
    if kind is None:
        return  # a <transmission>'s or <gazebo>'s <joint> reference, not a joint (one without a type: urdfdom's)
    if kind in _OTHER_TYPES:
        raise ModelError(f"joint {name!r} {_OTHER_TYPES[kind]}")
    if kind not in ("revolute", "prismatic", "fixed"):
        raise ModelError(f"joint {name!r} has type {kind!r}; expected revolute, prismatic or fixed")
    axis = j.find("axis")
    if kind == "fixed" or axis is None or axis.get("xyz") is None:
        return
    text = str(axis.get("xyz"))
    try:
        v = [float(x) for x in text.split()]
    except ValueError:
        return  # Pinocchio's parser names it
    how = "turns about" if kind == "revolute" else "slides along"
    if len(v) == 3 and not all(math.isfinite(x) for x in v):
        raise ModelError(f"joint {name!r}: axis xyz={text!r} is not finite; give the direction it {how}, e.g. "
                         "xyz='0 0 1'")
    if len(v) == 3 and not any(v):
        raise ModelError(f"joint {name!r} has the zero axis xyz={text!r}; give the direction it {how}, e.g. "
                         "xyz='0 0 1'")


def check_urdf_structure(urdf: str) -> None:
    """Before Pinocchio's parser: at most :data:`~alpes_dyn.limits.MAX_URDF_LINKS` links and
    :data:`~alpes_dyn.limits.MAX_URDF_JOINTS` moving joints (Pinocchio's data grows with their square), a kinematic
    tree at most :data:`~alpes_dyn.limits.MAX_URDF_DEPTH` joints deep (the parser recurses per level:
    a 10,000-link chain crashes it), every joint limit with lower <= upper, every ``<mimic>`` element well formed
    (:func:`~alpes_dyn.model.mimic.read_mimics`: it names an independent joint of its type), every joint of a
    supported type (:func:`check_joint`) and every moving joint's axis non-zero.

    Parameters
    ----------
    urdf : str
        The URDF text.

    Raises
    ------
    ModelError
        The first of these checks that fails, one line.
    """
    n_links = len(re.findall(r"<\s*link[\s/>]", urdf))
    if n_links > MAX_URDF_LINKS:
        raise ModelError(f"URDF: {n_links} links, over the limit of {MAX_URDF_LINKS}")
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise ModelError(f"URDF could not be parsed: {exc}") from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise ModelError(f"URDF could not be parsed: {type(exc).__name__}") from None
    moving = [j for j in root.iter("joint") if j.get("type") not in ("fixed", None)]
    if len(moving) > MAX_URDF_JOINTS:
        raise ModelError(f"URDF: {len(moving)} moving joints, over the limit of {MAX_URDF_JOINTS}")
    for el in list(root.iter("joint")) + list(root.iter("link")):
        name = el.get("name") or ""
        if len(name) > MAX_NAME:  # a joint's name becomes a recording's column (true_q_<joint>), an MJCF name
            raise ModelError(f"URDF: {el.tag} name {name[:40]!r}... of {len(name)} characters, over the limit of "
                             f"{MAX_NAME}")
    parent_of: dict[str, str] = {}
    for j in root.iter("joint"):
        check_joint(j)
        p, c = j.find("parent"), j.find("child")
        if p is not None and c is not None:
            parent_of[str(c.get("link"))] = str(p.get("link"))
        lim = j.find("limit")
        if lim is not None and lim.get("lower") is not None and lim.get("upper") is not None:
            try:
                lo, hi = float(lim.get("lower", "")), float(lim.get("upper", ""))
            except ValueError:
                continue  # Pinocchio's parser names it
            if lo > hi:
                raise ModelError(f"joint {j.get('name')!r}: limit lower {lo:g} is above upper {hi:g}")
    read_mimics(root)
    depth: dict[str, int] = {}
    for leaf in parent_of:
        chain, link = [], leaf
        while link in parent_of and link not in depth:
            chain.append(link)
            link = parent_of[link]
            if len(chain) > MAX_URDF_DEPTH + 1:
                raise ModelError(f"URDF: a chain more than {MAX_URDF_DEPTH} joints deep (the limit), or a "
                                 "loop, below link " + repr(link))
        base = depth.get(link, 0)
        for k, name in enumerate(reversed(chain), start=1):
            depth[name] = base + k
        if depth.get(leaf, 0) > MAX_URDF_DEPTH:
            raise ModelError(f"URDF: link {leaf!r} is {depth[leaf]} joints deep, over the limit of {MAX_URDF_DEPTH}")
