"""An MJCF file with new physical values written in, everything else kept as written: the identified robot handed
back to a MuJoCo user (``alpes-dyn identify ... --mjcf ROBOT.xml -o ident.toml`` writes ``ident.xml``;
:func:`~alpes_dyn.estimation.identification.identified_spec.identified_mjcf` maps a fit to the values here).

:func:`updated_mjcf` edits the file's own text: only the start tags of the elements whose values change differ
(and a comment before ``<mujoco>``), the rest byte for byte as written (comments, defaults, classes, geoms, meshes,
contacts, actuators, tendons, sites, sensors; the tags found at expat's byte offsets). The values go where the import
(:mod:`alpes_dyn.model.mjcf_import`) read them, each as an explicit attribute on the element (which overrides any
``<default>`` class, so MuJoCo takes it; an unnamed element, which the import names ``body3`` or ``joint2``, found by
its index in the file):

* a body's mass: ``<inertial mass>``, its inertia (``diaginertia`` or ``fullinertia``) times m / m0, m0 the compiled
  mass, its centre of mass and principal axes kept (what
  :func:`~alpes_dyn.estimation.identification.identified_spec.identified_urdf` does to the imported URDF's link);
  a body whose inertia MuJoCo takes from its geoms gets an ``<inertial>`` of its own with the compiled centre of
  mass, axes and inertia (scaled), which MuJoCo's default ``inertiafromgeom="auto"`` prefers to the geoms;
* a hinge's ``stiffness`` (N m/rad), ``springref`` (the spring's rest angle, written in the file's
  ``<compiler angle>`` unit: degrees unless ``angle="radian"``), ``damping`` (N m s/rad), ``frictionloss`` (N m),
  ``armature`` (kg m^2): the import maps them to the spec's ``[stiffness]``, ``[rest_angle]``, ``[viscous]``,
  ``[coulomb]``, ``[armature]`` as they are;
* a motor's rotor inertia J_m (kg m^2, the spec's ``rotor_inertia``, the import's tendon ``armature`` / gear^2):
  the ``armature`` J_m gear^2 of the tendon its actuator pulls; an actuator on a joint (whose rotor the import
  leaves in the joint's ``armature``) adds gear^2 J_m to that joint's armature as compiled.

Relative file names (``<include file>``, meshes, textures, height fields, skins, ``<compiler meshdir texturedir
assetdir>``) are rewritten to resolve from the output's folder as they did from the original's. The text is then
checked, before anything is written: MuJoCo compiles it from the output's folder (a temporary file there) into the
same tree (body, joint, geom, site, tendon, actuator counts, every body's pose and every joint's axis unchanged)
with each value asked for and every other mass, inertia and joint value as before; a body or joint that is not in
the file itself (an ``<include>``, a ``<replicate>``) or a compiler option that rescales masses
(``inertiafromgeom="true"``, ``settotalmass``) is refused with one line (:class:`~alpes_dyn.ModelError`) naming it.
"""

from __future__ import annotations

import math
import os
import posixpath
import tempfile
from pathlib import Path
from typing import Mapping, Sequence
from xml.sax.saxutils import escape

import numpy as np

from ..errors import ModelError
from ..fileio import decode_utf8, read_bytes
from .mjcf_import import _compile, _mj, _name

__all__ = ["JOINT_ATTRIBUTES", "check_origin", "updated_mjcf"]

JOINT_ATTRIBUTES: tuple[str, ...] = ("stiffness", "springref", "damping", "frictionloss", "armature")
"""The joint attributes :func:`updated_mjcf` writes (SI, ``springref`` in rad)."""

_FILES = {"include": ("file",), "model": ("file",), "mesh": ("file",), "hfield": ("file",), "skin": ("file",),
          "texture": ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")}
_DIR_OF = {"mesh": "meshdir", "hfield": "meshdir", "skin": "meshdir", "texture": "texturedir"}


def _f(x: float) -> str:
    return repr(float(x))


class _Node:
    """An element of the file: its tag, attributes (as read), byte span of its start tag, parent and children."""

    __slots__ = ("tag", "attrs", "start", "end", "parent", "children", "edits")

    def __init__(self, tag: str, attrs: dict, start: int, parent: "_Node | None") -> None:
        self.tag, self.attrs, self.start, self.end, self.parent = tag, attrs, start, start, parent
        self.children: list[_Node] = []
        self.edits: dict[str, str] = {}

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.edits.get(key, self.attrs.get(key, default))

    def iter(self, tag: str):
        if self.tag == tag:
            yield self
        for c in self.children:
            yield from c.iter(tag)


def _parse(data: bytes) -> _Node:
    """The element tree of an XML document with each start tag's byte span (expat's offsets)."""
    from xml.parsers import expat

    p = expat.ParserCreate()
    p.ordered_attributes = False
    stack: list[_Node] = []
    top: list[_Node] = []

    def start(tag, attrs):
        node = _Node(tag, attrs, p.CurrentByteIndex, stack[-1] if stack else None)
        (stack[-1].children if stack else top).append(node)
        stack.append(node)

    p.StartElementHandler = start
    p.EndElementHandler = lambda tag: stack.pop()
    try:
        p.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(f"mjcf: not XML ({exc})") from None
    root = top[0]
    for node in _all(root):
        node.end = _tag_end(data, node.start)
    return root


def _all(node: _Node):
    yield node
    for c in node.children:
        yield from _all(c)


def _tag_end(data: bytes, i: int) -> int:
    """The index just past the ``>`` closing the start tag at ``i`` (quotes respected)."""
    quote = None
    for k in range(i + 1, len(data)):
        c = data[k:k + 1]
        if quote:
            if c == quote:
                quote = None
        elif c in (b'"', b"'"):
            quote = c
        elif c == b">":
            return k + 1
    raise ModelError("mjcf: not XML (an unterminated tag)")


def _edited_tag(tag: bytes, edits: dict[str, str]) -> bytes:
    """A start tag's text with ``edits`` (attribute: value, already escaped) replacing or appending attributes."""
    import re

    for key, value in edits.items():
        pat = re.compile(rb"(\s" + re.escape(key.encode()) + rb"\s*=\s*)(\"[^\"]*\"|'[^']*')")
        v = b'"' + value.encode() + b'"'
        if pat.search(tag):
            tag = pat.sub(lambda mo: mo.group(1) + v, tag, count=1)
        else:
            close = len(tag) - (2 if tag.endswith(b"/>") else 1)
            tag = tag[:close].rstrip() + b" " + key.encode() + b"=" + v + tag[len(tag[:close].rstrip()):]
    return tag


def _elements(root: _Node, tag: str) -> list[_Node]:
    """The ``tag`` elements of the file's ``<worldbody>`` trees, in document order."""
    return [e for w in root.iter("worldbody") for e in w.iter(tag)]


def _find(elements: list[_Node], name: str, prefix: str, what: str, path: str) -> _Node:
    """The element named ``name``, or for the import's name of an unnamed one (``body3``) the element at that
    index (the compiled ids in document order; the compile check after the edit confirms it)."""
    hits = [e for e in elements if e.get("name") == name]
    if len(hits) == 1:
        return hits[0]
    if not hits and name.startswith(prefix) and name[len(prefix):].isdigit():
        unnamed = int(name[len(prefix):]) - (1 if prefix == "body" else 0)  # body ids count the world
        if 0 <= unnamed < len(elements) and elements[unnamed].get("name") is None:
            return elements[unnamed]
    raise ModelError(f"mjcf: {what} {name!r} is not written in {path} itself (an <include>d file or a "
                     "<replicate>?); the values are written into the file's own elements")


def _angle_scale(root: _Node) -> float:
    """Radians to the file's angle unit (``<compiler angle>``, MuJoCo's default degrees)."""
    unit = "degree"
    for c in root.iter("compiler"):
        unit = c.get("angle", unit)
    return 1.0 if unit == "radian" else 180.0 / math.pi


def _check_compiler(root: _Node, path: str) -> None:
    for c in root.iter("compiler"):
        if c.get("inertiafromgeom") == "true":
            raise ModelError(f'mjcf: {path} has <compiler inertiafromgeom="true">: MuJoCo takes every mass from the '
                             "geoms, a body's <inertial> is ignored; the masses cannot be written")
        total = c.get("settotalmass")
        if total is not None and total.strip() not in ("-1", "0"):
            raise ModelError(f"mjcf: {path} has <compiler settotalmass>: MuJoCo rescales every mass; the masses "
                             "cannot be written")


def _relocate(root: _Node, source: Path, out: Path) -> None:
    """Relative file names rewritten to resolve from ``out``'s folder as they did from ``source``'s."""
    rel = os.path.relpath(source.resolve().parent, out.resolve().parent).replace(os.sep, "/")
    if rel == ".":
        return
    dirs = set()
    for c in root.iter("compiler"):
        for key in ("meshdir", "texturedir", "assetdir"):
            v = c.get(key)
            if v is not None:
                dirs.add(key)
                if not posixpath.isabs(v):
                    c.edits[key] = escape(posixpath.join(rel, v), {'"': "&quot;"})
    if "assetdir" in dirs:
        dirs |= {"meshdir", "texturedir"}
    for tag, keys in _FILES.items():
        if _DIR_OF.get(tag) in dirs:
            continue  # resolved from the (relocated) directory
        for e in root.iter(tag):
            for key in keys:
                v = e.get(key)
                if v is not None and not posixpath.isabs(v):
                    e.edits[key] = escape(posixpath.join(rel, v), {'"': "&quot;"})


def _set_mass(body: _Node, m, b: int, mass: float) -> str | None:
    """Body ``b`` (element ``body``) given mass ``mass`` [kg], its inertia times mass / m0 (module doc); the text
    of an ``<inertial>`` element to insert where the body has none (else None)."""
    if not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
        raise ModelError(f"masses: {body.get('name')}: {mass!r} kg is not a positive mass")
    m0 = float(m.body_mass[b])
    if not m0 > 0:
        raise ModelError(f"mjcf: body {body.get('name')!r} has no mass to scale")
    ratio = mass / m0
    inertial = [c for c in body.children if c.tag == "inertial"]
    if not inertial:  # MuJoCo's inertia from the geoms, written out (scaled) as the body's own
        return (f'<inertial pos="{" ".join(map(_f, m.body_ipos[b]))}" quat="{" ".join(map(_f, m.body_iquat[b]))}" '
                f'mass="{_f(mass)}" diaginertia="{" ".join(_f(x * ratio) for x in m.body_inertia[b])}"/>')
    inertial[0].edits["mass"] = _f(mass)
    for key in ("diaginertia", "fullinertia"):
        v = inertial[0].get(key)
        if v is not None:
            inertial[0].edits[key] = " ".join(_f(float(x) * ratio) for x in v.split())
    return None


def _targets(mujoco, m, masses, joints, rotors):
    """The compiled values asked for: ({body id: mass}, {(array, index): value}) and the joint / tendon edits."""
    O = mujoco.mjtObj
    jid = {_name(mujoco, m, O.mjOBJ_JOINT, j, "joint"): j for j in range(m.njnt)}
    bid = {_name(mujoco, m, O.mjOBJ_BODY, b, "body"): b for b in range(1, m.nbody)}
    aid = {_name(mujoco, m, O.mjOBJ_ACTUATOR, a, "motor"): a for a in range(m.nu)}
    for what, names, known in (("body", masses, bid), ("joint", joints, jid), ("actuator", rotors, aid)):
        for n in names:
            if n not in known:
                raise ModelError(f"mjcf: no {what} {n!r} in the MJCF ({what}s: {', '.join(list(known)[:8])}"
                                 f"{' ...' if len(known) > 8 else ''})")
    edits: dict[str, dict[str, float]] = {j: dict(v) for j, v in joints.items()}
    tendons: dict[int, float] = {}
    for a, J in rotors.items():
        if not (isinstance(J, (int, float)) and math.isfinite(J) and J >= 0):
            raise ModelError(f"rotors: {a}: {J!r} kg m^2 is not a rotor inertia (finite, >= 0)")
        i, gear = aid[a], float(m.actuator_gear[aid[a], 0])
        if m.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_TENDON:
            tendons[int(m.actuator_trnid[i, 0])] = J * gear**2
        elif m.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT:
            jn = _name(mujoco, m, O.mjOBJ_JOINT, int(m.actuator_trnid[i, 0]), "joint")
            base = edits.get(jn, {}).get("armature", float(m.dof_armature[m.jnt_dofadr[jid[jn]]]))
            edits.setdefault(jn, {})["armature"] = base + J * gear**2
        else:
            raise ModelError(f"rotors: actuator {a!r} acts neither on a joint nor on a tendon")
    for j, attrs in edits.items():
        for key, v in attrs.items():
            if key not in JOINT_ATTRIBUTES:
                raise ModelError(f"joints: {j}: unknown attribute {key!r} (written: {', '.join(JOINT_ATTRIBUTES)})")
            if not (isinstance(v, (int, float)) and math.isfinite(v) and (v >= 0 or key == "springref")):
                raise ModelError(f"joints: {j}: {key} = {v!r} is not a finite value (>= 0 but springref)")
    return bid, jid, edits, tendons


def updated_mjcf(mjcf: str | Path, out: str | Path, *, masses: Mapping[str, float] | None = None,
                 joints: Mapping[str, Mapping[str, float]] | None = None, rotors: Mapping[str, float] | None = None,
                 note: Sequence[str] = ()) -> str:
    """The text of the MJCF file ``mjcf`` with new values (module doc), to be written at ``out`` (its folder: the
    relative file names are rewritten for it, and MuJoCo's check compiles the text there; nothing else is written).

    Parameters
    ----------
    mjcf : str or Path
        The MJCF file.
    out : str or Path
        Where the text is to be written (its folder must exist).
    masses : mapping of str to float or None, optional
        {body: mass, kg} (default None: none).
    joints : mapping of str to mapping or None, optional
        {joint: {attribute of :data:`JOINT_ATTRIBUTES`: value}} (SI, ``springref`` in rad; default None: none).
    rotors : mapping of str to float or None, optional
        {actuator: J_m, kg m^2} (default None: none).
    note : sequence of str, optional
        Lines of an XML comment put before ``<mujoco>`` (``--`` escaped; default none).

    Returns
    -------
    str
        The updated MJCF text.

    Raises
    ------
    ModelError
        One line for an MJCF or a value that cannot be written (module doc).
    """
    mujoco = _mj()
    path, out = Path(mjcf), Path(out)
    if not path.is_file():
        raise ModelError(f"mjcf: {str(mjcf)!r} is not a file")
    if not out.resolve().parent.is_dir():
        raise ModelError(f"out: the folder of {str(out)!r} is not a directory")
    data = read_bytes(path, "mjcf", ModelError)
    m = _compile(path)
    bid, jid, edits, tendons = _targets(mujoco, m, dict(masses or {}), dict(joints or {}), dict(rotors or {}))
    root = _parse(data)
    if masses:
        _check_compiler(root, str(mjcf))
    inserts: dict[int, bytes] = {}  # byte offset: text inserted there
    bodies, jelems = _elements(root, "body"), _elements(root, "joint")
    for name, mass in (masses or {}).items():
        e = _find(bodies, name, "body", "body", str(mjcf))
        new = _set_mass(e, m, bid[name], mass)
        if new is not None:  # on a line of its own after the body's start tag, indented as its first child
            first = e.children[0].start if e.children else e.end
            gap = data[e.end:first]
            indent = gap[gap.rfind(b"\n"):] if b"\n" in gap else b" "
            inserts[e.end] = indent + new.encode()
    scale = _angle_scale(root)
    for name, attrs in edits.items():
        e = _find(jelems, name, "joint", "joint", str(mjcf))
        for key, v in attrs.items():
            e.edits[key] = _f(v * scale if key == "springref" else v)
    tnames = {t: _name(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t, "tendon") for t in tendons}
    telems = [e for t in root.iter("tendon") for e in t.children if e.tag in ("fixed", "spatial")]
    for t, arm in tendons.items():
        _find(telems, tnames[t], "tendon", "tendon", str(mjcf)).edits["armature"] = _f(arm)
    _relocate(root, path, out)
    comment = "".join(f"<!-- {line.replace('--', '- -')} -->\n" for line in note).encode()
    inserts[root.start] = comment + inserts.get(root.start, b"")
    pieces = [(e.start, e.end, _edited_tag(data[e.start:e.end], e.edits)) for e in _all(root) if e.edits]
    pieces += [(i, i, t) for i, t in inserts.items()]
    out_data = data
    for a, b, t in sorted(pieces, key=lambda x: (x[0], x[1]), reverse=True):  # from the end: offsets stay valid
        out_data = out_data[:a] + t + out_data[b:]
    new_text = decode_utf8(out_data, "mjcf", ModelError)
    _check_compiled(mujoco, m, _compile_at(new_text, out), {bid[b]: float(v) for b, v in (masses or {}).items()},
                    {jid[j]: a for j, a in edits.items()}, tendons)
    return new_text


def _compile_at(text: str, out: Path):
    """MuJoCo's model of ``text`` compiled from ``out``'s folder (a temporary file there, removed)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{out.stem[:80]}.", suffix=".check.xml", dir=out.resolve().parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        try:
            return _mj().MjModel.from_xml_path(tmp)
        except ValueError as exc:
            raise ModelError(f"mjcf: MuJoCo cannot compile the updated MJCF from {str(out.resolve().parent)!r} "
                             f"({str(exc).splitlines()[0]})") from None
    finally:
        Path(tmp).unlink(missing_ok=True)


def _check_compiled(mujoco, m, n, masses: dict[int, float], edits: dict[int, dict[str, float]],
                    tendons: dict[int, float]) -> None:
    """The updated model ``n`` is ``m``'s tree with the values asked for and every other as before (module doc)."""
    sizes = {"nbody": "bodies", "njnt": "joints", "ngeom": "geoms", "nsite": "sites", "ntendon": "tendons",
             "nu": "actuators", "neq": "equalities", "nsensor": "sensors"}
    for s, what in sizes.items():
        if getattr(n, s) != getattr(m, s):
            raise ModelError(f"mjcf: the updated MJCF compiles to {getattr(n, s)} {what}, the original to "
                             f"{getattr(m, s)}")
    want = {k: np.array(getattr(m, k), dtype=float) for k in
            ("body_mass", "body_inertia", "jnt_stiffness", "qpos_spring", "dof_damping", "dof_frictionloss",
             "dof_armature", "body_pos", "body_quat", "jnt_axis")}
    for b, mass in masses.items():
        want["body_inertia"][b] *= mass / want["body_mass"][b]
        want["body_mass"][b] = mass
    field = {"stiffness": ("jnt_stiffness", False), "springref": ("qpos_spring", None),
             "damping": ("dof_damping", True), "frictionloss": ("dof_frictionloss", True),
             "armature": ("dof_armature", True)}
    for j, attrs in edits.items():
        for key, v in attrs.items():
            arr, dof = field[key]
            i = int(m.jnt_dofadr[j]) if dof else int(m.jnt_qposadr[j]) if dof is None else j
            want[arr][i] = v  # (a springref in degrees back in rad to rounding: rtol 1e-12)
    if hasattr(m, "tendon_armature"):
        want["tendon_armature"] = np.array(m.tendon_armature, dtype=float)
        for t, arm in tendons.items():
            want["tendon_armature"][t] = arm
    for k, w in want.items():
        got = np.array(getattr(n, k), dtype=float)
        bad = np.argwhere(~np.isclose(got, w, rtol=1e-12, atol=1e-15 if k == "body_quat" else 0.0))
        if bad.size:
            i = tuple(bad[0])
            raise ModelError(f"mjcf: the updated MJCF compiles to {k}{list(i)} = {got[i]!r}, not {w[i]!r} (a compiler "
                             "option or a class MuJoCo applies after the file's own attribute?)")


def check_origin(model, mjcf: str | Path) -> None:
    """That ``model`` (a :class:`~alpes_dyn.Model`) was imported from the MJCF file ``mjcf``: each of its joints a
    hinge of the MJCF, each of its URDF's links with a mass a body of the same mass (to 1e-9); else
    :class:`~alpes_dyn.ModelError` naming the first that differs (before a fit whose values are to be written
    into that file).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.
    mjcf : str or Path
        The MJCF file.

    Raises
    ------
    ModelError
        The first joint or link that differs, named.
    """
    import xml.etree.ElementTree as ET

    mujoco = _mj()
    m = _compile(mjcf)
    O = mujoco.mjtObj
    hinges = {_name(mujoco, m, O.mjOBJ_JOINT, j, "joint") for j in range(m.njnt)
              if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE}
    for j in model.joint_names:
        if j not in hinges:
            raise ModelError(f"mjcf: the model's joint {j!r} is not a hinge of {str(mjcf)!r}; not the MJCF the model "
                             "was imported from")
    bodies = {_name(mujoco, m, O.mjOBJ_BODY, b, "body"): float(m.body_mass[b]) for b in range(1, m.nbody)}
    for link in ET.fromstring(model.urdf).iter("link"):
        mass = link.find("inertial/mass")
        if mass is None or not float(mass.get("value", 0)) > 0:
            continue
        name, value = link.get("name"), float(mass.get("value"))
        if name not in bodies or not math.isclose(bodies[name], value, rel_tol=1e-9):
            was = f"{bodies[name]:.6g} kg" if name in bodies else "no such body"
            raise ModelError(f"mjcf: link {name!r}: {value:.6g} kg in the model's URDF, {was} in {str(mjcf)!r}; not "
                             "the MJCF the model was imported from")
