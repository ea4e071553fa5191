"""Kinematic description: the URDF of the Alpes models, generated from the parameter file.

Four models (report Fig. 2.1, 3.1 and Section 1.1):

* ``finger2`` -- the report's two-phalanx simplification (phalanges 1 and 2 of Table 1.2);
* ``finger3`` -- one complete finger;
* ``hand`` -- the 15-DoF tree: four 3-phalanx fingers, the thumb's ab/adduction joint and its two
  flexion phalanges, root frame ``palm`` at the middle of the palm;
* ``thumb`` -- the hand's thumb alone on its fixed palm: the same links, joints (``thumb_abd``,
  ``thumb_j1``, ``thumb_j2``), frames and root frame ``palm`` as in ``hand``, so that gravity in the
  palm frame is the hand's and its dynamics are the thumb's block of the hand's (the chains of a
  hand on a fixed palm are dynamically independent).

A finger model can be built from one finger of the hand (``chain=``: a name of ``palm.finger_names``):
its parameters are then the shared ``[finger]`` values with that finger's own ``[finger.<name>]``
values (:func:`~alpes_dyn.model.params.chain_params`); the hand uses each finger's own values.

Conventions (report Section 2.2): a finger moves in its x-z plane, its joint axes point along -y so
that a positive q turns +x toward +z, gravity acts along -z of the base frame. In ``finger2`` and
``finger3`` joint 1 sits at the base origin and the finger lies along +x at q = 0, so the fingertip
Jacobian is exactly the report's closed form. Each chain ends in a fixed ``*tip`` frame.

The URDF inertial of phalanx i is about its COM: I_i - m_i d_i^2 with d_i = L_i - s_i (the table's
I_i is about the joint axis; with s_i = L_i/2 this is the report's I_i - m_i s_i^2).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path


from ..errors import InputError, ModelError
from ..fileio import atomic_write
from .params import ChainParams, HandParams, chain_params, load_params

__all__ = ["MODELS", "FINGER_MODELS", "model_params", "ChainLayout", "Layout", "urdf_string", "layout", "write_urdfs", "example_robot_urdf"]

MODELS: tuple[str, ...] = ("finger2", "finger3", "hand", "thumb")
FINGER_MODELS: tuple[str, ...] = ("finger2", "finger3")


@dataclass(frozen=True)
class ChainLayout:
    """One tendon-driven chain: its flexion joints (proximal first), their springs and its tip frame.

    ``abduction`` is the name of an extra directly driven joint (the thumb's), else ``""``.
    """

    name: str
    joints: tuple[str, ...]
    stiffness: tuple[float, ...]
    tip: str
    abduction: str = ""


@dataclass(frozen=True)
class Layout:
    """What the URDF cannot hold about an Alpes model: its chains, springs and transmission."""

    model: str
    chains: tuple[ChainLayout, ...]
    abduction_stiffness: float = 0.0
    chain: str | None = None  # the hand's chain whose parameters a finger model has (None: the shared [finger])

    @property
    def tips(self) -> tuple[str, ...]:
        return tuple(c.tip for c in self.chains)


def _f(x: float) -> str:
    return repr(float(x))


def _v(xs) -> str:
    return " ".join(_f(x) for x in xs)


def _phalanx_link(name: str, L: float, m: float, d: float, I_com: float, radius: float) -> str:
    ixx = 0.5 * m * radius**2
    return (
        f'  <link name="{name}">\n'
        f"    <inertial>\n"
        f'      <origin xyz="{_v((d, 0, 0))}" rpy="0.0 0.0 0.0"/>\n'
        f'      <mass value="{_f(m)}"/>\n'
        f'      <inertia ixx="{_f(ixx)}" ixy="0.0" ixz="0.0" iyy="{_f(I_com)}" iyz="0.0" izz="{_f(I_com)}"/>\n'
        f"    </inertial>\n"
        f"    <visual>\n"
        f'      <origin xyz="{_v((L / 2, 0, 0))}" rpy="0.0 1.5707963267948966 0.0"/>\n'
        f'      <geometry><cylinder radius="{_f(radius)}" length="{_f(L)}"/></geometry>\n'
        f"    </visual>\n"
        f"  </link>\n"
    )


def _revolute(name: str, parent: str, child: str, xyz, rpy, axis, lower: float, upper: float) -> str:
    return (
        f'  <joint name="{name}" type="revolute">\n'
        f'    <parent link="{parent}"/>\n'
        f'    <child link="{child}"/>\n'
        f'    <origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>\n'
        f'    <axis xyz="{_v(axis)}"/>\n'
        f'    <limit lower="{_f(lower)}" upper="{_f(upper)}" effort="1.0" velocity="20.0"/>\n'
        f"  </joint>\n"
    )


def _fixed(name: str, parent: str, child: str, xyz) -> str:
    return (
        f'  <joint name="{name}" type="fixed">\n'
        f'    <parent link="{parent}"/>\n'
        f'    <child link="{child}"/>\n'
        f'    <origin xyz="{_v(xyz)}" rpy="0.0 0.0 0.0"/>\n'
        f"  </joint>\n"
    )


def _chain(prefix: str, parent: str, ch: ChainParams, n: int, origin, rpy, lower: float, upper: float) -> str:
    """Links and joints of an n-phalanx planar chain hanging from ``parent``."""
    out = []
    prev, xyz, rot = parent, origin, rpy
    d, I_com = ch.com_from_joint, ch.I_com
    for i in range(n):
        link = f"{prefix}p{i + 1}"
        out.append(_phalanx_link(link, ch.L[i], ch.m[i], d[i], I_com[i], ch.radius))
        out.append(_revolute(f"{prefix}j{i + 1}", prev, link, xyz, rot, (0, -1, 0), lower, upper))
        prev, xyz, rot = link, (ch.L[i], 0, 0), (0, 0, 0)
    out.append(f'  <link name="{prefix}tip"/>\n')
    out.append(_fixed(f"{prefix}tip_joint", prev, f"{prefix}tip", (ch.L[n - 1], 0, 0)))
    return "".join(out)


def _finger_chain(f: ChainParams, n: int) -> ChainParams:
    return ChainParams(L=f.L[:n], s=f.s[:n], m=f.m[:n], I=f.I[:n], K=f.K[:n], radius=f.radius)


def _thumb_parts(p: HandParams) -> list[str]:
    """Links and joints of the thumb on the palm: its base (ab/adduction body) and two phalanges."""
    t = p.thumb
    rb = t.radius
    ib = 0.4 * p.thumb_base_mass * rb**2
    return [
        '  <link name="thumb_base">\n    <inertial>\n      <origin xyz="0.0 0.0 0.0" rpy="0.0 0.0 0.0"/>\n'
        f'      <mass value="{_f(p.thumb_base_mass)}"/>\n'
        f'      <inertia ixx="{_f(ib)}" ixy="0.0" ixz="0.0" iyy="{_f(ib)}" iyz="0.0" izz="{_f(ib)}"/>\n'
        "    </inertial>\n  </link>\n",
        _revolute("thumb_abd", "palm", "thumb_base", p.thumb_xyz, (0, 0, p.thumb_yaw), p.abduction_axis,
                  p.abduction_lower, p.abduction_upper),
        _chain("thumb_", "thumb_base", t, 2, (0, 0, 0), (0, 0, 0), p.finger_lower, p.finger_upper),
    ]


def model_params(model: str, params: HandParams | str | Path | None = None, chain: str | None = None) -> HandParams:
    """The parameters ``model`` is built from.

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3``, ``hand`` or ``thumb``.
    params : HandParams or str or Path or None, optional
        The parameters, or a parameter file (default None: the shipped one).
    chain : str or None, optional
        For a finger model, a finger's name of the hand: that finger's parameters
        (:func:`~alpes_dyn.model.params.chain_params`); only for finger models (``"thumb"`` is a model of its
        own). Default None: the file's finger.

    Returns
    -------
    HandParams
        The parameters.

    Raises
    ------
    ModelError
        An unknown model, a ``chain`` for a model that is not a finger, or an unknown finger.
    """
    check_model_name(model)
    p = params if isinstance(params, HandParams) else load_params(params)
    if chain is None:
        return p
    if model not in FINGER_MODELS:
        raise ModelError(f"chain: only a finger model ({', '.join(FINGER_MODELS)}) is built from one chain of the "
                         f"hand, not {model!r} (the thumb is model 'thumb')")
    if not isinstance(chain, str) or chain not in p.finger_names:
        raise ModelError(f"chain: unknown finger {chain!r} (expected one of {', '.join(p.finger_names)})")
    return chain_params(p, chain)


def check_model_name(model: str) -> str:
    if model not in MODELS:
        raise ModelError(f"unknown model {model!r} (expected one of {', '.join(MODELS)})")
    return model


def urdf_string(model: str, params: HandParams | str | Path | None = None, chain: str | None = None) -> str:
    """URDF text of an Alpes model built from a parameter file; deterministic: the checked-in ``urdf/*.urdf``
    files equal it for the shipped parameter file.

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3``, ``hand`` or ``thumb``.
    params : HandParams or str or Path or None, optional
        The parameters, or a parameter file (default: the shipped one).
    chain : str or None, optional
        A finger model as that finger of the hand (:func:`model_params`).

    Returns
    -------
    str
        The URDF.
    """
    p = model_params(model, params, chain)
    head = f'<?xml version="1.0"?>\n<!-- Generated by alpes_dyn from {Path(p.path).name}; do not edit. -->\n'
    lo, hi = p.finger_lower, p.finger_upper
    if model in FINGER_MODELS:
        n = 2 if model == "finger2" else 3
        body = '  <link name="base"/>\n' + _chain("", "base", _finger_chain(p.finger, n), n, (0, 0, 0), (0, 0, 0),
                                                  lo, hi)
        return head + f'<robot name="alpes_{model}">\n{body}</robot>\n'
    parts = ['  <link name="palm"/>\n']
    if model == "hand":
        for name, (x, y) in zip(p.finger_names, p.finger_xy):
            parts.append(_chain(f"{name}_", "palm", _finger_chain(p.chain(name), 3), 3, (x, y, 0.0), (0, 0, 0), lo, hi))
    parts += _thumb_parts(p)
    return head + f'<robot name="alpes_{model}">\n' + "".join(parts) + "</robot>\n"


def layout(model: str, params: HandParams | str | Path | None = None, chain: str | None = None) -> Layout:
    """Chains, springs (report's K_i) and tips of an Alpes model, by joint name.

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3``, ``hand`` or ``thumb``.
    params : HandParams or str or Path or None, optional
        The parameters, or a parameter file (default: the shipped one).
    chain : str or None, optional
        A finger model as that finger of the hand (:func:`urdf_string`).

    Returns
    -------
    Layout
        The model's layout.
    """
    p = model_params(model, params, chain)
    if model in FINGER_MODELS:
        n = 2 if model == "finger2" else 3
        joints = tuple(f"j{i + 1}" for i in range(n))
        return Layout(model, (ChainLayout("finger", joints, tuple(p.finger.K[:n]), "tip"),), chain=chain)
    chains = [
        ChainLayout(name, tuple(f"{name}_j{i + 1}" for i in range(3)), tuple(p.chain(name).K), f"{name}_tip")
        for name in (p.finger_names if model == "hand" else ())
    ]
    chains.append(ChainLayout("thumb", ("thumb_j1", "thumb_j2"), tuple(p.thumb.K), "thumb_tip", abduction="thumb_abd"))
    return Layout(model, tuple(chains), abduction_stiffness=p.abduction_K)


def write_urdfs(directory: str | Path, params: HandParams | str | Path | None = None) -> list[Path]:
    """Write ``<model>.urdf`` for every model into ``directory`` (created if needed), each file atomically
    (:func:`alpes_dyn.fileio.atomic_write`).

    Parameters
    ----------
    directory : str or Path
        The folder.
    params : HandParams or str or Path or None, optional
        The parameters, or a parameter file (default: the shipped one).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    InputError
        ``directory`` is a file or cannot be created or written."""
    if not isinstance(directory, (str, os.PathLike)) or not str(directory).strip():
        raise InputError(f"directory: expected a folder path, got {directory!r}")
    if "\0" in str(directory):
        raise InputError(f"directory: the folder name {str(directory)[:80]!r} contains a NUL byte")
    d = Path(directory)
    if d.exists() and not d.is_dir():
        raise InputError(f"directory: {str(d)!r} exists and is not a folder")
    p = params if isinstance(params, HandParams) else load_params(params)
    texts = {m: urdf_string(m, p) for m in MODELS}  # all generated before anything is written
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"directory: {str(d)!r} cannot be created ({exc.strerror or exc})") from None
    out = []
    for m, text in texts.items():
        out.append(atomic_write(d / f"{m}.urdf", text, "directory"))
    return out


def example_robot_urdf(robot: str, urdf: str | None = None) -> Path:
    """Path of a URDF shipped by ``example-robot-data`` (6.x has no Python module).

    Parameters
    ----------
    robot : str
        A folder name without ``_description`` (``"ur"``, ``"panda"``, ``"double_pendulum"``...).
    urdf : str or None, optional
        A file by name (default: the first one, by name, preferring the ``urdf/`` folder).

    Returns
    -------
    Path
        The URDF file.
    """
    import sys
    import sysconfig

    roots = {Path(sysconfig.get_paths()["purelib"]), Path(sysconfig.get_paths()["platlib"])}
    roots |= {Path(p) for p in sys.path if p.endswith("site-packages")}
    for root in sorted(roots):
        base = root / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if not base.is_dir():
            continue
        folder = base / f"{robot}_description"
        if not folder.is_dir():
            names = sorted(p.name.removesuffix("_description") for p in base.iterdir() if p.is_dir())
            raise ModelError(f"unknown example-robot-data robot {robot!r} (have: {', '.join(names)})")
        files = sorted(folder.rglob("*.urdf"), key=lambda f: (f.parent.name != "urdf", f.name))
        if urdf is not None:
            files = [f for f in files if f.name in (urdf, f"{urdf}.urdf")]
        if not files:
            raise ModelError(f"example-robot-data robot {robot!r}: no URDF {urdf!r} in {folder}")
        return files[0]
    raise ModelError("example-robot-data is not installed (pip install example-robot-data)")
