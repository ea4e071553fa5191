"""Bad input, table-driven: every CLI subcommand and every public API.

CLI rows: exit code 2, nothing on stdout, exactly one line on stderr (captured at the file-descriptor
level, so text printed by native libraries counts) containing the row's needle, no traceback, and no
file left behind in the working folder or next to an output file.

API rows: a typed error (a subclass of :class:`alpes_dyn.AlpesDynError`, and the row's class) whose
one-line message contains the row's needle.

To add a command or an API: add rows to ``CLI`` / ``API``; ``test_every_command_has_rows`` and
``test_every_public_api_has_rows`` fail until you do. Placeholders in CLI arguments (``{dir}``,
``{binary_toml}``...) name the files that :func:`bad_files` writes in the row's temporary folder.
"""

from __future__ import annotations

import argparse
import copy
import functools
import json
import math
import os
import re
import resource
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn import cli
from alpes_dyn.errors import AlpesDynError, InputError, ModelError, RecordingError
from alpes_dyn.model.params import default_params_path
from alpes_dyn.model.spec import TransmissionSpec

BASE_TOML = default_params_path().read_text(encoding="utf-8")
FINGER3 = ad.urdf_string("finger3")


def _with_p3_inertial(mass: str, inertia: str) -> str:
    """finger3's URDF with the inertial of its last phalanx p3 replaced."""
    out, n = re.subn(r'(<link name="p3">.*?<mass value=")[^"]*("/>\s*<inertia )[^/]*/>',
                     rf'\g<1>{mass}\g<2>{inertia}/>', FINGER3, flags=re.S)
    assert n == 1
    return out


ZERO_I = 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"'
URDFS = {
    "negmass_urdf": _with_p3_inertial("-0.023", 'ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"'),
    "massless_urdf": _with_p3_inertial("0.0", ZERO_I),  # p3 massless: joint j3 moves nothing
    "zero_mass_inertia_urdf": _with_p3_inertial("0.0", 'ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"'),
    "triangle_urdf": _with_p3_inertial("0.023", 'ixx="1e-7" ixy="0" ixz="0" iyy="1e-7" iyz="0" izz="1e-6"'),
    "indefinite_urdf": _with_p3_inertial("0.023", 'ixx="1e-6" ixy="2e-6" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"'),
    "nan_urdf": _with_p3_inertial("nan", ZERO_I),
    "no_limits_urdf": "<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
                      "<parent link='a'/><child link='b'/></joint></robot>",
    "truncated_urdf": FINGER3[: len(FINGER3) // 2],
    "twoleaf_urdf": FINGER3.replace("</robot>", '<link name="nail"/><joint name="nail_joint" type="fixed"><parent '
                                    'link="p3"/><child link="nail"/></joint></robot>'),  # two leaves: no default tip
    "continuous_urdf": FINGER3.replace('<joint name="j2" type="revolute">', '<joint name="j2" type="continuous">', 1),
    "planar_urdf": FINGER3.replace('<joint name="j2" type="revolute">', '<joint name="j2" type="planar">', 1),
    "zeroaxis_urdf": re.sub(r'(<joint name="j2".*?<axis xyz=")[^"]*"', r'\g<1>0 0 0"', FINGER3, count=1, flags=re.S),
    "nanaxis_urdf": re.sub(r'(<joint name="j2".*?<axis xyz=")[^"]*"', r'\g<1>0 nan 1"', FINGER3, count=1, flags=re.S),
    "inverted_limit_urdf": FINGER3.replace('lower="0.0" upper="1.5707963267948966"', 'lower="1.6" upper="0.0"', 1),
    "mimic_urdf": FINGER3.replace('<joint name="j2" type="revolute">', '<joint name="j2" type="revolute"><mimic joint="j1"/>',
                                  1),  # well formed: j2 follows j1 (a spec naming j2 is refused)
    "mimicself_urdf": FINGER3.replace('<joint name="j2" type="revolute">',
                                      '<joint name="j2" type="revolute"><mimic joint="j2"/>', 1),
    "mimicnan_urdf": FINGER3.replace('<joint name="j2" type="revolute">',
                                     '<joint name="j2" type="revolute"><mimic joint="j1" multiplier="nan"/>', 1),
    "mimicbig_urdf": FINGER3.replace('<joint name="j2" type="revolute">',
                                     '<joint name="j2" type="revolute"><mimic joint="j1" multiplier="1e300"/>', 1),
    "many_links_urdf": "<robot name='x'>" + "".join(f"<link name='l{i}'/>" for i in range(1001)) + "</robot>",
    "star_urdf": "<robot name='x'>" + "".join(f"<link name='l{i}'/>" for i in range(202))
                 + "".join(f"<joint name='j{i}' type='revolute'><parent link='l0'/><child link='l{i + 1}'/>"
                           "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>" for i in range(201))
                 + "</robot>",  # 201 joints on the base: Pinocchio's data would grow with their square
    "deep_urdf": "<robot name='x'>" + "".join(f"<link name='l{i}'><inertial><mass value='1'/><inertia ixx='1' "
                                              "ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link>"
                                              for i in range(102))
                 + "".join(f"<joint name='j{i}' type='revolute'><parent link='l{i}'/><child link='l{i + 1}'/>"
                           "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>" for i in range(101))
                 + "</robot>",
}
_MJCF_EQ = ('<mujoco><worldbody><body name="a"><joint name="j" range="-1 1"/><inertial pos="0 0 0" mass="1" '
            'diaginertia="1 1 1"/><body name="b"><joint name="k" range="-1 1"/><inertial pos="0 0 0" mass="1" '
            'diaginertia="1 1 1"/></body></body></worldbody><equality>{}</equality></mujoco>')
"""A two-hinge MJCF with the equality given (``.format``): the import reads joint couplings only."""
_MJCF_FLIP = ('<mujoco><worldbody><site name="s0" pos="-0.15 0 0"/><body><joint name="shoulder" axis="0 0 1" '
              'range="0 120"/><geom name="shoulder" type="cylinder" size=".1 .05"/><site name="in" pos="0 -0.05 0"/>'
              '<site name="s2" pos="0.15 -0.06 0"/></body></worldbody><tendon><spatial name="SE"><site site="s0"/>'
              '<geom geom="shoulder" sidesite="in"/><site site="s2"/></spatial></tendon><actuator><motor name="SE" '
              'tendon="SE"/></actuator></mujoco>')
"""MuJoCo's arm26 shoulder extensor (a motor for its muscle) with its side site moved inside the shoulder's cylinder:
over 0..120 degrees its tendon leaves the cylinder (no polynomial follows it), and its path is MuJoCo's Newton
iteration (``wrap_inside``, to 1e-6), which has no closed form: refused, the site and the geom named."""
_PATH = ('path = {{ frames = [{{ name = "b", pos = [0.0, 0.0, 0.0], joints = [{{ joint = "{}", axis = [0.0, 0.0, 1.0] '
         '}}] }}], points = [{{ site = "s0", pos = [0.1, 0.0, 0.0] }}, {{ site = "s1", frame = "b", pos = [0.0, 0.1, 0.0] }}] '
         '}}\n')
"""A spec's spatial-tendon ``path`` (``.format`` the joint it turns about): two sites, the second on a hinged body."""
_MJCF_BODY = '<body name="b{0}"><joint name="j{0}" range="-1 1"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'
_MJCF_DEEP = "<mujoco><worldbody>" + "".join(_MJCF_BODY.format(i) for i in range(500)) + "</body>" * 500 + (
    "</worldbody></mujoco>")
"""A chain of 500 bodies (deeper than the URDF's limit of 100; MuJoCo's own XML parser stops at 500)."""
_MJCF_SITES = ("<mujoco><worldbody>" + _MJCF_BODY.format(0) + "".join(f'<site name="s{i}"/>' for i in range(1001))
               + "</body></worldbody></mujoco>")
"""One body with 1001 sites: each site a URDF link, over the limit of 1000."""
_MJCF_FLAT = ("<mujoco><worldbody>" + "".join(_MJCF_BODY.format(i) + "</body>" for i in range(201))
              + "</worldbody></mujoco>")
"""201 one-hinge bodies on the world: the imported URDF's 201 moving joints, over the limit of 200."""
RECORDING_HEAD = "t,encoder_finger,torque_finger\n"
ARM_MJCF = """<mujoco model="arm"><compiler angle="radian"/><worldbody>
  <body name="a" pos="0 0 0.1"><joint name="ja" type="hinge" axis="0 1 0" range="-1 1" stiffness="0.3"/>
    <inertial pos="0.05 0 0" mass="0.2" diaginertia="1e-4 2e-4 3e-4"/><site name="tip" pos="0.1 0 0"/></body>
</worldbody><tendon><fixed name="t"><joint joint="ja" coef="0.01"/></fixed></tendon>
<actuator><motor name="m" tendon="t" gear="100"/></actuator></mujoco>"""
"""A one-hinge MJCF with a fixed tendon and its motor: what ``alpes-dyn import`` reads."""

ROBOT_URDF = FINGER3.replace('name="alpes_finger3"', 'name="tendon_robot"', 1)
"""A URDF robot for the rows of the commands on any robot: finger3's URDF with a spec of its own (ROBOT_SPEC)."""
ROBOT_SPEC = ('[[motor]]\nname = "flexor"\njoints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\n\n'
              "[stiffness]\nj1 = 0.04\nj2 = 0.05\nj3 = 0.06\n\n[viscous]\nj1 = 1e-4\nj2 = 1e-4\nj3 = 1e-4\n")


_LINK = ("<link name='{0}'><inertial><origin xyz='0.02 0 0'/><mass value='0.02'/><inertia ixx='1e-6' ixy='0' "
         "ixz='0' iyy='1e-6' iyz='0' izz='1e-6'/></inertial></link>")
_HINGE = ("<joint name='{0}' type='revolute'><parent link='palm'/><child link='{1}'/><origin xyz='0 {2} 0'/>"
          "<axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>")
BRANCHES_URDF = ("<robot name='branches'><link name='palm'/>" + _LINK.format("a") + _LINK.format("b")
                 + _HINGE.format("ja", "a", "-0.02") + _HINGE.format("jb", "b", "0.02") + "</robot>")
"""Two one-joint branches on a palm, for the sub-model's rows (Model.subtree, --chain on a URDF)."""
BRANCHES_SPEC = ('[[motor]]\nname = "fa"\njoints = { ja = 1.0 }\n\n[[motor]]\nname = "fb"\njoints = { jb = 1.0 }\n\n'
                 '[[motor]]\nname = "across"\njoints = { ja = 1.0, jb = 0.5 }\n\n[stiffness]\nja = 0.1\njb = 0.1\n')
"""Its spec: a motor per branch and one tendon ``across`` both (a sub-model of ``fa`` alone is refused)."""


ROBOT_CONTROL_SPEC = ('gravity = [0.0, 0.0, 9.81]\ntips = ["tip", "p1"]\n\n' + ROBOT_SPEC
                      + '\n[[motor]]\nname = "distal"\njoints = { j3 = 1.0 }\n')
"""The robot palm down (its rest inside the joint ranges), two motors, two tips: for ``control`` on a URDF."""


def _toml_field(field: str, entry: str) -> bytes:
    """The shipped parameter file with the entry of ``field`` (``section.key``) replaced by ``entry``."""
    section, key = field.split(".")
    lines = BASE_TOML.splitlines(keepends=True)
    start = lines.index(f"[{section}]\n")
    i = next(k for k in range(start + 1, len(lines)) if lines[k].startswith(f"{key} = "))
    lines[i] = f"{key} = {entry}\n"
    return "".join(lines).encode()


_RECORDINGS: dict[str, str] = {}


def _recordings() -> dict[str, str]:
    """CSV text of a valid 0.2 s identification recording of finger2 and of finger3 (made once)."""
    if not _RECORDINGS:
        import tempfile

        from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment
        from alpes_dyn.estimation.experiments.recording import write_recording

        with tempfile.TemporaryDirectory() as d:
            for m in ("finger2", "finger3"):
                path = write_recording(experiment(m, design=ExperimentDesign(duration=0.2)), Path(d) / f"{m}.csv")
                _RECORDINGS[m] = path.read_text()
    return _RECORDINGS


def _huge_encoder(text: str) -> str:
    """A recording whose encoder reads 1e15 counts from line 103 on (a fit on it diverged: 'theta: expected finite')."""
    lines = text.splitlines(keepends=True)
    j = lines[0].strip().split(",").index("encoder_finger")
    for i in range(102, len(lines)):
        cells = lines[i].rstrip("\n").split(",")
        cells[j] = "1e15"
        lines[i] = ",".join(cells) + "\n"
    return "".join(lines)


def bad_files(d: Path) -> dict[str, str]:
    """Write the broken inputs into ``d``; return {placeholder: path}."""
    files: dict[str, bytes] = {
        "binary_toml": bytes(range(256)) * 4,
        "latin1_toml": ("# r\xe9glage\n" + BASE_TOML).encode("latin-1"),
        "binary_urdf": b"\x89PNG\r\n\x1a\n" + bytes(range(256)),
        "latin1_urdf": FINGER3.replace("Generated", "G\xe9n\xe9r\xe9").encode("latin-1"),
        "negative_compliance_toml": BASE_TOML.replace(
            "[transmission]\n", '[transmission]\ntendon_compliance = { value = -0.1, unit = "rad/(N m)", '
            'source = "identified", reason = "a fit" }\n', 1).encode(),
        "negative_k_toml": BASE_TOML.replace("K = { value = [0.04, 0.05, 0.06]", "K = { value = [-0.04, 0.05, 0.06]",
                                             1).encode(),
        "pinky_toml": BASE_TOML.replace("[thumb]", '[finger.pinky]\nK = { value = [0.04, 0.05, 0.06], unit = "N m/rad", '
                                        'source = "report" }\n\n[thumb]', 1).encode(),
        "short_index_toml": BASE_TOML.replace("[thumb]", '[finger.index]\nK = { value = [0.04, 0.05], '
                                              'unit = "N m/rad", source = "report" }\n\n[thumb]', 1).encode(),
    }
    files.update({
        "params_toml": BASE_TOML.encode(),
        "xmlname_toml": BASE_TOML.replace('["index"', '["in<d&\\"ex"', 1).encode(),
        "bom_toml": b"\xef\xbb\xbf" + BASE_TOML.encode(),
        "bigint_toml": _toml_field("transmission.N", '{ value = ' + "9" * 401 + ', unit = "-", source = "report" }'),
        "deep_toml": BASE_TOML.encode() + b"\n[extra]\nx = " + b"[" * 100_000 + b"]" * 100_000 + b"\n",
        "half_count_toml": _toml_field("transmission.encoder_counts",
                                       '{ value = 4096.5, unit = "counts/rev", source = "report" }'),
        "mm_toml": _toml_field("finger.r", '{ value = 5.0, unit = "mm", source = "report" }'),
        "longcell_csv": (RECORDING_HEAD + "0," + "1" * 300 + ",0\n").encode(),
        "hugecell_csv": (RECORDING_HEAD + "0," + "1" * 200_000 + ",0\n").encode(),
        "nul_csv": (RECORDING_HEAD + "0,\0,0\n").encode(),
    })
    files["compliance_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ntendon_compliance = { value = nan, '
                                                 'unit = "rad/(N m)", source = "assumed", reason = "x" }\n', 1).encode()
    files["cable_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ntendon_compliance = { value = 3.0, '
                                            'unit = "rad/(N m)", source = "assumed", reason = "x" }\n', 1).encode()
    files["capstan_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ncapstan = { value = nan, '
                                              'unit = "-", source = "assumed", reason = "x" }\n', 1).encode()
    files["negative_capstan_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ncapstan = { value = -0.2, '
                                                       'unit = "-", source = "assumed", reason = "x" }\n', 1).encode()
    files["model_error_toml"] = BASE_TOML.replace("[friction]\n", '[friction]\nmodel_error = { value = -1.0, '
                                                  'unit = "F_s", source = "identified", reason = "x" }\n', 1).encode()
    files["model_error_unit_toml"] = BASE_TOML.replace("[friction]\n", '[friction]\nmodel_error = { value = 1.0, '
                                                       'unit = "N m", source = "identified", reason = "x" }\n', 1).encode()
    files["observer_law_toml"] = BASE_TOML.replace("[friction]\n", '[friction]\nobserver_law = { value = "dahl", '
                                                   'unit = "-", source = "identified", reason = "x" }\n', 1).encode()
    files["badident_toml"] = (BASE_TOML + "\n[identification.finger]\nconverged = 1\n").encode()
    files["untrusted_toml"] = (BASE_TOML + '\n[identification.finger]\nconverged = false\nstop = "lost basin"\n'
                               "trustworthy = false\n").encode()  # written by identify --force
    files["fitted_friction_toml"] = (BASE_TOML + "\n[identification.finger]\nfriction = true\n").encode()
    files["halfdelay_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ntorque_delay = { value = 1.5, '
                                                'unit = "samples", source = "identified", reason = "x" }\n', 1).encode()
    files["longdelay_toml"] = BASE_TOML.replace("[transmission]\n", '[transmission]\ntorque_delay = { value = 500, '
                                                'unit = "samples", source = "identified", reason = "x" }\n', 1).encode()
    files["countsoffset_toml"] = BASE_TOML.replace("[thumb]\n", 'encoder_offset = { value = 4.0, unit = "counts", '
                                                   'source = "identified", reason = "x" }\n\n[thumb]\n', 1).encode()
    rec3 = _recordings()["finger3"].splitlines()  # the unit mistakes of a recording (issue 49)
    files["midblank_csv"] = ("\n".join(rec3[:100] + [",,,,"] + rec3[100:]) + "\n").encode()  # a lost sample (52)
    files["ma_csv"] = _scaled_column(rec3, "torque_finger", 1e5)  # a current in mA, not N m
    files["rad_csv"] = _scaled_column(rec3, "encoder_finger", 2 * math.pi / 4096)  # the motor's angle in rad
    files["deg_csv"] = _scaled_column(rec3, "encoder_finger", 360 / 4096)  # ... in degrees
    files["ms_csv"] = _scaled_column(rec3, "t", 1e3)  # the time in ms
    files["macurrent_csv"] = _scaled_column([rec3[0].replace("torque_finger", "current_finger")] + rec3[1:],
                                            "current_finger", 1e5)  # a current in mA, read with a constant in N m/A
    # physical ranges (issue 19): an angle, a ratio, gravity of 1e300, a subnormal spring, an axis of 1e300
    files["angle_toml"] = _toml_field("finger.upper", '{ value = 1e300, unit = "rad", source = "report" }')
    files["ratio_toml"] = _toml_field("transmission.N", '{ value = 1e300, unit = "-", source = "report" }')
    files["gravity_toml"] = _toml_field("environment.gravity", '{ value = [0.0, 0.0, -1e300], unit = "m/s^2", '
                                        'source = "report" }')
    files["subk_toml"] = _toml_field("finger.K", '{ value = [1e-320, 0.05, 0.06], unit = "N m/rad", source = "report" }')
    files["axis_toml"] = _toml_field("thumb.abduction_axis", '{ value = [1e300, 0.0, 0.0], unit = "-", '
                                     'source = "report", reason = "x" }')
    files.update({k: v.encode() for k, v in URDFS.items()})
    files.update(robot_urdf=ROBOT_URDF.encode(), robot_toml=ROBOT_SPEC.encode(),
                 robotident_toml=(ROBOT_SPEC + "\n[identified.stiffness]\nj1 = 1e-5\nj9 = 1e-5\n").encode(),
                 robotstd_toml=(ROBOT_SPEC + "\n[identified.viscous]\nj1 = -1e-5\n").encode(),
                 robotrecord_toml=(ROBOT_SPEC + '\n[identified]\nsource = "cad"\n').encode(),
                 robottwo_toml=(ROBOT_SPEC + '\n[[motor]]\nname = "distal"\njoints = { j3 = 1.0 }\n').encode(),
                 robotrest_toml=(ROBOT_SPEC + "\n[rest_angle]\nj1 = 0.1\nj9 = 0.2\n").encode(),
                 robotcapstan_toml=ROBOT_SPEC.replace("joints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\n",
                                                      "joints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\ncapstan = -0.3\n",
                                                      1).encode(),
                 robotcapstanid_toml=(ROBOT_SPEC + "\n[identified.capstan]\nextensor = 0.01\n").encode(),
                 robotsheath_toml=ROBOT_SPEC.replace("joints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\n",
                                                     "joints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\ncapstan = 0.3\n",
                                                     1).encode(),
                 robotstops_toml=(ROBOT_SPEC + "\n[stops]\nstiffness = -2.0\n").encode(),
                 robotstopj_toml=(ROBOT_SPEC + "\n[stops.joints]\nj9 = { stiffness = 2.0 }\n").encode(),
                 robotctl_toml=ROBOT_CONTROL_SPEC.encode(), branches_urdf=BRANCHES_URDF.encode(),
                 branches_toml=BRANCHES_SPEC.encode(),
                 robotctrlchar_toml=ROBOT_SPEC.replace('name = "flexor"', 'name = "fl\\u0001exor"').encode(),
                 robotratio_toml=ROBOT_SPEC.replace("j1 = 2.0", "j1 = 1e300", 1).encode(),
                 robotsub_toml=ROBOT_SPEC.replace("j1 = 0.04", "j1 = 1e-320", 1).encode(),
                 robotcounts_toml=("encoder_counts = 4096.5\n" + ROBOT_SPEC).encode(),
                 robotempty_toml=b"# a spec with nothing in it\n", arm_xml=ARM_MJCF.encode(),
                 slide_xml=ARM_MJCF.replace('<joint name="ja" type="hinge"', '<joint name="ja" type="slide"').encode(),
                 norange_xml=ARM_MJCF.replace(' range="-1 1"', "").encode(), notxml_xml=b"not xml at all\n",
                 flip_xml=_MJCF_FLIP.encode(), deep_xml=_MJCF_DEEP.encode(), sites_xml=_MJCF_SITES.encode(),
                 flat_xml=_MJCF_FLAT.encode(),
                 nan_xml=ARM_MJCF.replace('<body name="a" pos="0 0 0.1">', '<body name="a" pos="nan 0 0.1">').encode(),
                 gear0_xml=ARM_MJCF.replace('gear="100"', 'gear="0"').encode(),
                 muscle_xml=ARM_MJCF.replace('<motor name="m" tendon="t" gear="100"/>',
                                             '<muscle name="m" tendon="t"/>').encode(),
                 loop_xml=_MJCF_EQ.format('<connect name="loop" body1="b" body2="world" anchor="0 0 0"/>').encode(),
                 geomass_xml=ARM_MJCF.replace('<compiler angle="radian"/>', '<compiler angle="radian" inertiafromgeom='
                                              '"true"/>').replace("<site ", '<geom size="0.01"/><site ').encode())
    k = np.arange(200)  # a valid finger3 recording (200 samples at 1 ms, true joints), for estimate --data
    rows = ["t,encoder_finger,torque_finger,true_q_j1,true_q_j2,true_q_j3"]
    rows += [f"{1e-3 * int(i)!r},{int(i % 7)},{0.02 + 1e-3 * float(np.sin(0.1 * i))!r},0.1,0.2,0.3" for i in k]
    files["replay_csv"] = ("\n".join(rows) + "\n").encode()
    files.update({f"rec{m[-1]}_csv": text.encode() for m, text in _recordings().items()})
    files["enchuge_csv"] = _huge_encoder(_recordings()["finger3"]).encode()
    lines = _recordings()["finger3"].splitlines()
    files["grav149_csv"] = "\n".join([lines[0] + ",gravity_x,gravity_y,gravity_z"]
                                     + [row + ",0,0,-14.9" for row in lines[1:]]).encode()  # 1.5 g: not the Earth's
    run_files = {"runfrac": lambda i: "0.5" if i == 7 else "0", "rundown": lambda i: "1" if i < 120 else "0",
                 "runshort": lambda i: "0" if i < 150 else "1", "runhuge": lambda i: "0" if i < 110 else "1e17",
                 "runtwo": lambda i: "0" if i < 101 else "1"}  # the run column's defects, and two good runs
    for name, run in run_files.items():
        files[f"{name}_csv"] = "\n".join([lines[0] + ",run"] + [row + "," + run(i) for i, row in enumerate(lines[1:])]
                                         ).encode()
    held_files = {"heldbad": lambda i: "2" if i == 7 else "0", "heldmid": lambda i: "1" if 50 <= i < 170 else "0"}
    for name, held in held_files.items():  # the held_out column's defects (the stiction ramp's mark)
        files[f"{name}_csv"] = "\n".join([lines[0] + ",held_out"] + [row + "," + held(i) for i, row in
                                                                     enumerate(lines[1:])]).encode()
    files["gravok_csv"] = "\n".join([lines[0] + ",gravity_x,gravity_y,gravity_z"]
                                     + [row + ",0,0,-9.81" for row in lines[1:]]).encode()  # a good one, hung level
    files["unders_csv"] = "\n".join(lines[:5] + [lines[5].replace(",", ",1_0", 1)] + lines[6:]).encode()
    files["current_csv"] = _recordings()["finger3"].replace("torque_finger", "current_finger", 1).encode()
    out = {}
    for name, data in files.items():
        ext = name.rsplit("_", 1)[1]
        p = d / f"{name.rsplit('_', 1)[0]}.{ext}"
        p.write_bytes(data)
        out[name] = str(p)
    (d / "dir").mkdir()
    (d / "file").write_text("not a directory\n")
    out.update(dir=str(d / "dir"), file=str(d / "file"), tmp=str(d))
    os.link(out["params_toml"], d / "hardlink.toml")  # the same file as params.toml under another name
    (d / "link.png").symlink_to(out["params_toml"])
    (d / "rl_level.csv").symlink_to(out["params_toml"])  # experiment --design-only --rig both -o rl.csv's first file
    (d / "linked").mkdir()
    (d / "linked" / "finger2.urdf").symlink_to(out["params_toml"])  # write_urdfs would replace the link
    os.mkfifo(d / "fifo.toml")  # a FIFO with no writer: opening it to read would block forever
    (d / "big.urdf").touch()
    os.truncate(d / "big.urdf", 16 * 1024**2 + 1)  # sparse: over the size limit without writing 16 MiB
    out.update(hardlink=str(d / "hardlink.toml"), link=str(d / "link.png"), fifo=str(d / "fifo.toml"),
               big_urdf=str(d / "big.urdf"), device=_device(d))
    return out


def _scaled_column(lines: list[str], column: str, scale: float) -> bytes:
    """A recording's CSV ``lines`` with ``column`` times ``scale`` (a unit mistake), as bytes."""
    j = lines[0].split(",").index(column)
    rows = [r.split(",") for r in lines[1:]]
    for r in rows:
        r[j] = repr(float(r[j]) * scale)
    return "\n".join([lines[0]] + [",".join(r) for r in rows]).encode() + b"\n"


def _device(d: Path) -> str:
    """A character device to write to: a private copy of /dev/null's node as root, else /dev/full itself."""
    try:
        os.mknod(d / "null", 0o600 | __import__("stat").S_IFCHR, os.makedev(1, 3))
        return str(d / "null")
    except (OSError, AttributeError):
        return "/dev/full"


@dataclass(frozen=True)
class Cli:
    """One bad command line: ``argv`` (placeholders in braces), a substring of the one stderr line."""

    argv: tuple[str, ...]
    needle: str
    fsize: int | None = None  # run in a subprocess whose files may not exceed this many bytes (a full disk)


def C(*argv: str, needle: str, fsize: int | None = None) -> Cli:
    return Cli(tuple(argv), needle, fsize)


CLI: dict[str, list[Cli]] = {
    "experiment": [
        # a URDF --model (issue 17): the Alpes-only options refused by name
        C("experiment", "--model", "{robot_urdf}", "-o", "{tmp}/r.csv",
          needle="--spec: the identification experiment on a URDF --model needs its transmission spec"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--chain", "index", "-o", "{tmp}/r.csv",
          needle="--chain: names a finger of the Alpes hand; a URDF --model's experiment excites every motor"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--perturb", "0.1", "-o", "{tmp}/r.csv",
          needle="--perturb: draws an Alpes parameter file; for a URDF --model give the perturbed robot's spec"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-params-out", "{tmp}/t.toml",
          "-o", "{tmp}/r.csv", needle="--true-params-out: goes with --perturb on an Alpes model"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--rig", "hanging", "-o", "{tmp}/r.csv",
          needle="--rig: hangs an Alpes hand fingers down"),
        C("experiment", "--rig", "sideways", "-o", "{tmp}/r.csv", needle="argument --rig: invalid choice: 'sideways'"),
        C("experiment", "--model", "hand", "--rig", "both", "-o", "{tmp}/r.csv", needle="--rig both: one finger at a time"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--params", "x.toml", "-o", "{tmp}/r.csv",
          needle="--params: applies to the Alpes models"),
        C("experiment", "--true-spec", "x.toml", "-o", "{tmp}/r.csv", needle="--true-spec: applies to a URDF --model"),
        C("experiment", "--spec", "x.toml", "-o", "{tmp}/r.csv", needle="--spec: applies to a URDF --model"),
        C("experiment", "--true-model", "x.urdf", "-o", "{tmp}/r.csv", needle="--true-model: applies to a URDF --model"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-model", "{tmp}/missing.urdf",
          "-o", "{tmp}/r.csv", needle="--true-model: URDF file"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--amplitude", "0", "-o", "{tmp}/r.csv",
          needle="--amplitude: expected a fraction in (0, 1], got 0.0"),
        C("experiment", "--amplitude", "1.5", "-o", "{tmp}/r.csv", needle="--amplitude: expected a fraction in (0, 1]"),
        C("experiment", "--amplitude", "nan", "-o", "{tmp}/r.csv", needle="--amplitude"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-spec", "{robottwo_toml}", "-o",
          "{tmp}/r.csv", needle="--true-spec: the true robot has joints j1, j2, j3 and motors flexor, distal; expected"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-spec", "{robotident_toml}", "-o",
          "{tmp}/r.csv", needle="identified.stiffness.j9: the spec has no stiffness value for joint 'j9'"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-spec", "{robotstd_toml}", "-o",
          "{tmp}/r.csv", needle="identified.viscous.j1: expected a standard error >= 0"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robotcapstan_toml}", "-o", "{tmp}/r.csv",
          needle="motor 'flexor'.capstan: expected a number >= 0, got -0.3"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-spec", "{robotcapstanid_toml}",
          "-o", "{tmp}/r.csv", needle="identified.capstan.extensor: unknown motor 'extensor' (motors: flexor)"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "-o", "{robot_toml}",
          needle="-o: '{robot_toml}' is the input of --spec"),
        C("experiment", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--true-spec", "{robotstd_toml}", "-o",
          "{robotstd_toml}", needle="-o: '{robotstd_toml}' is the input of --true-spec"),
        C("experiment", needle="the following arguments are required: -o/--output"),
        C("experiment", "--model", "finger5", "-o", "{tmp}/r.csv", needle="defined for one chain (finger2, finger3, thumb"),
        C("experiment", "--chain", "pinky", "-o", "{tmp}/r.csv",
          needle="chain: unknown finger 'pinky' (expected one of index, middle, ring, little)"),
        C("experiment", "--model", "thumb", "--chain", "index", "-o", "{tmp}/r.csv", needle="chain: only a finger model"),
        C("experiment", "--duration", "0.01", "-o", "{tmp}/r.csv", needle="duration: expected a whole number of at least 100"),
        C("experiment", "--perturb", "1.5", "-o", "{tmp}/r.csv", needle="--perturb: expected a fraction in [0, 1)"),
        C("experiment", "--stick-seconds", "-1", "-o", "{tmp}/r.csv",
          needle="--stick-seconds: expected 0 (no stiction ramp) or a duration in s up to 600, got -1.0"),
        C("experiment", "--stick-seconds", "nan", "-o", "{tmp}/r.csv", needle="--stick-seconds: expected 0"),
        C("experiment", "--stick-seconds", "0.05", "-o", "{tmp}/r.csv",
          needle="stick_seconds: expected a whole number of at least 100 samples of 0.001 s, got 0.05"),
        C("experiment", "--perturb", "nan", "-o", "{tmp}/r.csv", needle="--perturb: expected a fraction in [0, 1), got nan"),
        C("experiment", "--perturb", "1e-320", "-o", "{tmp}/r.csv", needle="--perturb: 1e-320 is a subnormal number"),
        C("experiment", "--true-params-out", "{tmp}/t.toml", "-o", "{tmp}/r.csv", needle="goes with --perturb"),
        C("experiment", "-o", "{tmp}", needle="is a directory"),
        C("experiment", "--params", "{latin1_toml}", "-o", "{tmp}/r.csv", needle="not UTF-8 text"),
        # the output policy: no output over an input or another output, nor a link, device, FIFO, directory
        C("experiment", "--perturb", "0.1", "-o", "{tmp}/r.csv", "--true-params-out", "{tmp}/r.csv",
          needle="--true-params-out: '{tmp}/r.csv' is also the output of -o"),
        C("experiment", "--perturb", "0.1", "-o", "{tmp}/r.csv", "--true-params-out", "{tmp}/./r.csv",
          needle="is also the output of -o"),
        C("experiment", "--params", "{params_toml}", "-o", "{params_toml}", needle="-o: '{params_toml}' is the input of "
          "--params; refusing to write over it"),
        # --design-only and --bench (issue 49): the torque alone, or the experiment on the MuJoCo stand-in
        C("experiment", "--design-only", "--bench", "mujoco", "-o", "{tmp}/t.csv",
          needle="--bench: runs the experiment on a hand; --design-only writes its torque alone"),
        C("experiment", "--design-only", "--perturb", "0.1", "-o", "{tmp}/t.csv",
          needle="--perturb: --design-only draws no true finger"),
        C("experiment", "--design-only", "--seed", "3", "-o", "{tmp}/t.csv", needle="--seed: --design-only has no noise"),
        # --design-only --rig both: one profile per rig beside -o (-o's name with _level, _hanging), each checked
        C("experiment", "--design-only", "--rig", "both", "-o", "{tmp}/rl.csv",
          needle="-o: '{tmp}/rl_level.csv' is a symbolic link; refusing to replace it"),
        C("experiment", "--design-only", "--rig", "both", "-o", "{tmp}/t.toml", needle="-o: "),
        C("experiment", "--design-only", "--model", "hand", "-o", "{tmp}/t.csv",
          needle="--model: --design-only is defined for finger2, finger3, thumb, got 'hand'"),
        C("experiment", "--design-only", "--duration", "0.01", "-o", "{tmp}/t.csv",
          needle="duration: expected a whole number of at least 100"),
        C("experiment", "--design-only", "--amplitude", "2", "-o", "{tmp}/t.csv", needle="--amplitude: expected a "
          "fraction in (0, 1]"),
        C("experiment", "--design-only", "-o", "{tmp}/t.toml", needle="-o"),
        C("experiment", "--design-only", "--params", "{params_toml}", "-o", "{params_toml}",
          needle="-o: '{params_toml}' is the input of --params; refusing to write over it"),
        C("experiment", "--bench", "mujoco", "--model", "hand", "-o", "{tmp}/r.csv",
          needle="--model: --bench mujoco is defined for finger2, finger3, thumb, got 'hand'"),
        C("experiment", "--bench", "mujoco", "--chain", "index", "-o", "{tmp}/r.csv",
          needle="--chain: the MuJoCo stand-in is one finger"),
        C("experiment", "--bench", "mujoco", "--true-params-out", "{tmp}/t.toml", "-o", "{tmp}/r.csv",
          needle="--true-params-out: goes with --perturb"),
        C("experiment", "--bench", "mujoco", "--rig", "both", "--model", "hand", "-o", "{tmp}/r.csv",
          needle="--model: --bench mujoco is defined for finger2, finger3, thumb, got 'hand'"),
        C("experiment", "--bench", "mujoco", "--rig", "both", "-o", "{params_toml}",
          needle="-o: '{params_toml}' has extension"),
        C("experiment", "--bench", "real", "-o", "{tmp}/r.csv", needle="argument --bench: invalid choice: 'real'"),
        C("experiment", "--bench", "mujoco", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "-o", "{tmp}/r.csv",
          needle="--spec: goes with a URDF --model's simulated experiment, not --bench mujoco"),
        C("experiment", "--params", "{params_toml}", "-o", "{hardlink}", needle="-o: '{hardlink}' is the input of "
          "--params"),  # the same inode under another name
        C("experiment", "-o", "{link}", needle="-o: '{link}' is a symbolic link; refusing to replace it"),
        C("experiment", "-o", "{fifo}", needle="-o: '{fifo}' is a FIFO (named pipe); only a regular file"),
        C("experiment", "-o", "{tmp}/newdir/", needle="-o: '{tmp}/newdir/' ends with '/'"),
        C("experiment", "-o", "{tmp}/r\0.csv", needle="-o: the file name"),
        # numbers checked before any allocation
        C("experiment", "--duration", "1e308", "-o", "{tmp}/r.csv", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("experiment", "--duration", "1e9", "-o", "{tmp}/r.csv", needle="--duration: 1e+09 s is outside the accepted range [1e-09, 1e+06] s"),
        C("experiment", "--params", "{fifo}", "-o", "{tmp}/r.csv", needle="is a FIFO (named pipe), expected a regular"),
    ],
    "identifiability": [
        C("identifiability", "--max-operations", "99999999999999999999",
          needle="max_operations: 99999999999999999999 is over the limit of 50000000"),
        C("identifiability", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--design", "scenario",
          needle="--design: scenario is the Alpes fingers' estimation scenario"),
        C("identifiability", "--model", "{robot_urdf}", needle="--spec: identifiability on a URDF --model needs"),
        C("identifiability", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--params", "x.toml",
          needle="--params: applies to the Alpes models"),
        C("identifiability", "--spec", "{robot_toml}", needle="--spec: applies to a URDF --model"),
        C("identifiability", "--model", "{robot_urdf}", "--spec", "{robotrecord_toml}",
          needle='identified.source: expected "identified", got \'cad\''),
        C("identifiability", "--model", "hand", needle="--model: identifiability is defined for one finger"),
        C("identifiability", "--design", "wiggle", needle="--design: unknown design 'wiggle'"),
        C("identifiability", "--parameters", "K_9", needle="unknown parameter 'K_9'"),
        C("identifiability", "--points", "0", needle="--points: expected an integer from 1 to 10000"),
        C("identifiability", "--seed", "-1", needle="--seed: expected an integer from 0 to 9223372036854775807"),
        C("identifiability", "--camera-times", "a", "--parameters", "K", needle="--camera-times: expected comma-separated"),
        C("identifiability", "--parameters", "K", "--duration", "0.01",
          needle="duration: expected a whole number of at least 100"),
        C("identifiability", "--parameters", "K", "--camera-times", "9", needle="camera_times: 9.0 is outside"),
        C("identifiability", "--output", "elbow", "--parameters", "K", needle="unknown output 'elbow'"),
        C("identifiability", "--parameters", "K", "--duration", "1e308", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("identifiability", "--parameters", "K", "--duration", "1e9", needle="--duration: 1e+09 s is outside the accepted range [1e-09, 1e+06] s"),
        C("identifiability", "--params", "{deep_toml}", needle="nested more than 32 deep"),
    ],
    "identify": [
        C("identify", "--data", "{grav149_csv}", "-o", "{tmp}/i.toml",
          needle="gravity has norm 14.9 m/s^2 at row 2; expected 9.81 m/s^2 within 10 %"),
        C("identify", "--data", "{unders_csv}", "-o", "{tmp}/i.toml", needle="line 6: not a number ('1_0"),
        C("identify", "--data", "{rec3_csv}", "{gravok_csv}", "-o", "{tmp}/i.toml",
          needle="join_runs: gravity is in some of the recordings only"),
        C("identify", "--data", "{rec3_csv}", "{gravok_csv}", "-o", "{gravok_csv}",
          needle="-o: '{gravok_csv}' is the input of --data"),
        C("identify", "--data", "{rec3_csv}", "{tmp}/none.csv", "-o", "{tmp}/i.toml", needle="cannot be read"),
        C("identify", "--data", "{rec3_csv}", "{rec3_csv}", "-o", "{tmp}/i.toml",
          needle="--data: '{rec3_csv}' is the same recording as '{rec3_csv}': a run fitted twice makes its standard "
          "errors sqrt(2) too small"),
        C("identify", "--data", "-o", "{tmp}/i.toml", needle="argument --data: expected at least one argument"),
        C("identify", "--data", "{rec3_csv}", "--drift", "torque", "-o", "{tmp}/i.toml",
          needle="argument --drift: expected None or a comma-separated choice of offset, gain, got 'torque'"),
        C("identify", "--data", "{rec3_csv}", "--drift", "gain,gain", "-o", "{tmp}/i.toml",
          needle="argument --drift: 'gain,gain' names a drift twice"),
        C("identify", "--data", "{rec3_csv}", "--drift", "offset,gain", "--excitation", "none", "-o", "{tmp}/i.toml",
          needle="drift: 'gain' needs the excitation's lines"),
        C("identify", "--data", "{rec3_csv}", "--drift", "-o", "{tmp}/i.toml", needle="argument --drift: expected one argument"),
        C("identify", "--data", "{runfrac_csv}", "-o", "{tmp}/i.toml",
          needle="column 'run' line 9: 0.5 is not an integer (the run's number)"),
        C("identify", "--data", "{rundown_csv}", "-o", "{tmp}/i.toml",
          needle="column 'run' decreases at line 122 (1 then 0): each run's samples together, the runs in order"),
        C("identify", "--data", "{runshort_csv}", "-o", "{tmp}/i.toml",
          needle="run 1 (from line 152) has 51 samples; each run needs at least 100"),
        C("identify", "--data", "{heldbad_csv}", "-o", "{tmp}/i.toml",
          needle="column 'held_out' line 9: 2 is not 0 or 1 (1: a sample held out of the fit"),
        C("identify", "--data", "{heldmid_csv}", "-o", "{tmp}/i.toml",
          needle="column 'held_out' line 52: the held-out samples must be the last of their run (run 0: a fitted "
          "sample follows them)"),
        C("identify", "--data", "{runhuge_csv}", "-o", "{tmp}/i.toml",
          needle="column 'run' line 112: 1e+17 is beyond the integers a float holds"),
        C("identify", "--data", "{rec3_csv}", "--torque-noise", "1e308", "-o", "{tmp}/i.toml",
          needle="--torque-noise: 1e+308 N m is outside the accepted range [0, 1e+06] N m"),
        C("identify", "--data", "{rec3_csv}", "--encoder-noise", "1_0", "-o", "{tmp}/i.toml",
          needle="--encoder-noise: invalid float value: '1_0'"),
        C("identify", "--model", "{robot_urdf}", "--data", "x.csv", needle="--spec: identification on a URDF --model"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--rotor-inertia",
          needle="--rotor-inertia: applies to the Alpes models; a URDF --model's rotor inertia is its spec's"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--params", "x.toml",
          needle="--params: applies to the Alpes models"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--parameters", "K",
          "--chain", "index", needle="--chain: unknown motor 'index' of the URDF --model (motors: flexor)"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robottwo_toml}", "--data", "x.csv", "--parameters",
          "K_1", "--chain", "distal", needle="--chain: the selection has no parameter of motor 'distal'"),
        C("identify", "--model", "{branches_urdf}", "--spec", "{branches_toml}", "--data", "{replay_csv}", "--chain",
          "across", "--parameters", "K", needle="recording: unknown column 'encoder_finger' for model 'branches'"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robottwo_toml}", "--data", "{replay_csv}", "--chain",
          "distal", "--parameters", "K", needle="recording: unknown column 'encoder_finger' for model 'tendon_robot'"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--data", "x.csv", "-o",
          "{tmp}/robot.toml", needle="-o's URDF: '{tmp}/robot.urdf' is the input of --model; refusing to write over it"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--parameters", "K_9",
          needle="unknown parameter 'K_9'"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robotident_toml}", "--data", "x.csv",
          needle="identified.stiffness.j9: the spec has no stiffness value"),
        C("identify", "--spec", "{robot_toml}", "--data", "x.csv", needle="--spec: applies to a URDF --model"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--mjcf", "{arm_xml}",
          needle="--mjcf: the identified MJCF is written beside -o FILE.toml (as FILE.xml); give -o"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "-o", "{tmp}/i.toml",
          "--mjcf", "{robot_toml}", needle="--mjcf: expected the MJCF file the --model was imported from (FILE.xml)"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "-o", "{tmp}/i.toml",
          "--mjcf", "{arm_xml}", needle="--mjcf: the model's joint 'j1' is not a hinge of '{arm_xml}'; not the MJCF "
          "the model was imported from"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "-o", "{tmp}/arm.toml",
          "--mjcf", "{arm_xml}", needle="-o's MJCF: '{arm_xml}' is the input of --mjcf; refusing to write over it"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "-o", "{tmp}/i.toml",
          "--mjcf", "{tmp}/none.xml", needle="--mjcf: '{tmp}/none.xml' is not a file"),
        C("identify", "--data", "x.csv", "-o", "{tmp}/i.toml", "--mjcf", "{arm_xml}",
          needle="--mjcf: applies to a URDF --model imported from that MJCF (alpes-dyn import)"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--effects", "rotor",
          needle="--effects: rotor applies to the Alpes models"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--effects", "lugre",
          needle="--effects: lugre applies to the Alpes models"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--effects", "creep",
          needle="--effects: creep applies to the Alpes models"),
        C("identify", "--data", "x.csv", "--effects", "creep,tilt", "--parameters", "K",
          needle="--effects: tilt with --parameters"),
        C("identify", "--data", "x.csv", "--effects", "lugre,compliance", "--parameters", "K",
          needle="--effects: compliance with --parameters"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "{robot_toml}", "-o",
          "{robot_toml}", needle="-o: '{robot_toml}' is the input of"),
        C("identify", needle="the following arguments are required: --data"),
        C("identify", "--data", "{tmp}/none.csv", needle="cannot be read"),
        C("identify", "--data", "{latin1_toml}", needle="not a UTF-8 text file"),
        C("identify", "--data", "{binary_toml}", needle="recording"),
        C("identify", "--model", "hand", "--data", "x.csv", needle="recording 'x.csv': cannot be read"),
        C("identify", "--chain", "pinky", "--data", "x.csv", needle="chain: unknown finger 'pinky'"),
        C("identify", "--model", "thumb", "--chain", "ring", "--data", "x.csv", needle="chain: only a finger model"),
        C("identify", "--data", "{latin1_toml}", "--parameters", "K_9", needle="unknown parameter 'K_9'"),
        C("identify", "--data", "x.csv", "--parameters", "K,tilt_z", needle="unknown parameter 'tilt_z'"),
        C("identify", "--data", "x.csv", "--parameters", "encoder_offset_index",
          needle="unknown parameter 'encoder_offset_index'"),
        C("identify", "--data", "x.csv", "--parameters", "J_m", needle="'J_m' selects nothing"),
        C("identify", "--data", "x.csv", "--parameters", "K,capstan_pinky", needle="unknown parameter 'capstan_pinky'"),
        C("identify", "--data", "x.csv", "--effects", "capstan", "--parameters", "K",
          needle="--effects: capstan with --parameters: name their parameters there"),
        C("identify", "--data", "x.csv", "--effects", "capstan,capstan", needle="effects: an effect is named twice"),
        C("identify", "--params", "{negative_capstan_toml}", "--data", "x.csv",
          needle="transmission.capstan: value must be >= 0"),
        C("identify", "--data", "x.csv", "--effects", "friction", needle="effects: unknown effect 'friction'"),
        C("identify", "--data", "x.csv", "--effects", "none", "--law-spread",
          needle="--law-spread: the friction law's spread is made by the rounds of --effects auto"),
        C("identify", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--data", "x.csv", "--parameters", "m",
          "--law-spread", needle="--law-spread: the friction law's spread is made by the rounds of --effects auto"),
        C("identify", "--data", "x.csv", "--effects", "tilt,tilt", needle="effects: an effect is named twice"),
        C("identify", "--data", "x.csv", "--effects", "none,stiction", needle="effects: 'none' goes alone"),
        C("identify", "--data", "x.csv", "--effects", "compliance", "--parameters", "K",
          needle="--effects: compliance with --parameters: name their parameters there"),
        C("identify", "--data", "x.csv", "--rotor-inertia", "--parameters", "J_m_thumb",
          needle="unknown parameter 'J_m_thumb'"),
        C("identify", "--data", "x.csv", "--parameters", "tilt,tilt_y", needle="tilt_y is selected twice"),
        C("identify", "--data", "x.csv", "--parameters", "K,m,friction,input_gain",
          needle="input_gain with every mass, spring and friction"),
        C("identify", "--data", "x.csv", "-o", "{tmp}", needle="is a directory"),
        C("identify", "--data", "x.csv", "--excitation", "a,b", needle="--excitation: expected comma-separated"),
        C("identify", "--data", "{params_toml}", "-o", "{params_toml}", needle="-o: '{params_toml}' is the input of "
          "--data"),
        C("identify", "--data", "{hardlink}", "-o", "{params_toml}", needle="is the input of --data"),
        C("identify", "--data", "x.csv", "--params", "{params_toml}", "-o", "{hardlink}",
          needle="-o: '{hardlink}' is the input of --params"),
        C("identify", "--data", "x.csv", "-o", "{link}", needle="is a symbolic link"),
        C("identify", "--data", "x.csv", "-o", "{device}", needle="is a character device; only a regular file"),
        C("identify", "--data", "x.csv", "-o", "{tmp}/out/", needle="ends with '/'"),
        C("identify", "--data", "{fifo}", needle="recording '{fifo}': is a FIFO (named pipe)"),  # never blocks
        C("identify", "--data", "/dev/zero", needle="recording '/dev/zero': is a character device"),
        C("identify", "--data", "{dir}", needle="is a directory"),
        C("identify", "--data", "{longcell_csv}", needle="a cell of 300 characters, over the limit of 256"),
        C("identify", "--data", "{hugecell_csv}", needle="hugecell.csv': a cell over the limit of 256 characters"),  # over csv's own limit
        C("identify", "--data", "{nul_csv}", needle="column 'encoder_finger' line 2: not a number"),
        C("identify", "--data", "{current_csv}", needle="column 'current_finger' needs a torque constant (N m/A: "
          "torque_constant, or --torque-constant"),
        C("identify", "--data", "{rec3_csv}", "--torque-constant", "0.05", needle="recording '{rec3_csv}': a torque "
          "constant is given but it has no current_<motor> column"),
        C("identify", "--data", "{current_csv}", "--torque-constant", "-1", needle="torque_constant: expected a "
          "positive number of N m/A, got -1.0"),
        C("identify", "--data", "{current_csv}", "--torque-constant", "inf", needle="torque_constant: expected a "
          "positive number of N m/A, got inf"),
        C("identify", "--data", "x.csv", "--torque-constant", "0.05 N m/A", needle="--torque-constant: invalid float"),
        C("identify", "--data", "{current_csv}", "--torque-constant", "0.05", "--validate", "{rec3_csv}",
          needle="recording '{rec3_csv}': a torque constant is given but it has no current_<motor> column"),
        C("identify", "--data", "{ma_csv}", needle="recording: column 'torque_finger': values up to"),
        C("identify", "--data", "{ma_csv}", needle="against tau_max 0.05 N m: a current in mA? the recording's torque "
          "is in N m"),
        C("identify", "--data", "{rad_csv}", needle="column 'encoder_finger': values not whole numbers swinging"),
        C("identify", "--data", "{deg_csv}", needle="the motor angle in degrees? the recording's encoder is in counts"),
        C("identify", "--data", "{ms_csv}", needle="sample period 1 s is outside [1e-6, 0.1] s: t in milliseconds?"),
        C("identify", "--data", "{macurrent_csv}", "--torque-constant", "0.05", needle="column 'current_finger': values "
          "up to"),
        C("identify", "--data", "{enchuge_csv}", needle="recording: column 'encoder_finger' line 103: 1e+15 counts is "
          "beyond what the joint ranges allow (0 to 6144 counts"),
        C("identify", "--data", "{rec3_csv}", "--validate", "{tmp}/none.csv", needle="cannot be read"),
        C("identify", "--data", "{rec3_csv}", "--validate", "{latin1_toml}", needle="not a UTF-8 text file"),
        C("identify", "--data", "{rec3_csv}", "--validate", "{rec3_csv}", needle="validation: 201 samples are too few"),
        C("identify", "--data", "{rec3_csv}", "--validate", "{dir}", needle="is a directory, expected a file"),
        C("identify", "--data", "{rec3_csv}", "--encoder-noise", "-1", needle="encoder_noise: expected a non-negative"),
        C("identify", "--data", "{rec3_csv}", "--encoder-noise", "nan", needle="encoder_noise: expected a non-negative"),
        C("identify", "--data", "x.csv", "--encoder-noise", "abc", needle="--encoder-noise: invalid float value"),
        C("identify", "--data", "{rec3_csv}", "-o", "{rec3_csv}", needle="-o: '{rec3_csv}' is the input of --data"),
        C("identify", "--data", "{rec3_csv}", "--validate", "{params_toml}", "-o", "{hardlink}",
          needle="-o: '{hardlink}' is the input of --validate"),
        C("identify", "--data", "{rec3_csv}", "--params", "{badident_toml}",
          needle="identification.finger.converged: expected true or false"),
    ],
    "sweep": [
        C("sweep", "--study", "monte", needle="--study: unknown study 'monte'"),
        C("sweep", "--draws", "1_0", needle="argument --draws: expected an integer >= 1, got '1_0'"),  # int() reads 10
        C("sweep", "--serial", "-o", "{tmp}/s.toml", needle="-o: '{tmp}/s.toml' has extension 'toml'; expected one of .csv"),
        C("experiment", "-o", "{tmp}/r.toml", needle="-o: '{tmp}/r.toml' has extension 'toml'; expected one of .csv"),
        C("codegen", "--out-dir", "{tmp}/" + "z" * 300, needle="--out-dir: the name 'zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz'... has "
          "300 bytes, over the 255 a file name may have"),  # os.stat raised: an internal error, exit 1
        C("experiment", "-o", "{tmp}/a\nb.csv", needle="-o: the name 'a\\nb.csv' holds a control character"),
        C("sweep", "--serial", "--seed", "1_0", needle="argument --seed: expected an integer from 0 to"),
        C("sweep", "-o", "{link}", needle="-o: '{link}' is a symbolic link; refusing to replace it"),
        C("sweep", "-o", "{device}", needle="is a character device"),
        C("sweep", "-o", "{tmp}/table/", needle="ends with '/'"),
        C("sweep", "--duration", "1e308", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("sweep", "--model", "hand", needle="--model: the robustness study is defined for one finger"),
        C("sweep", "--model", "thumb", needle="--model: the robustness study is defined for one finger"),
        C("sweep", "--spread", "1.5", needle="--spread: expected a fraction in [0, 1)"),
        C("sweep", "--spread", "nan", needle="--spread: expected a fraction in [0, 1)"),
        C("sweep", "--draws", "0", needle="--draws: expected an integer >= 1"),
        C("sweep", "--serial", "--workers", "3", needle="--serial: runs in this process"),
        C("sweep", "--scheduler", "tcp://x:1", "--workers", "3", needle="--workers: sizes a local cluster"),
        C("sweep", "--scheduler", "localhost", needle="scheduler: expected an address such as tcp://host:8786"),
        C("sweep", "--duration", "0.01", needle="duration: expected a whole number of at least 100"),
        C("sweep", "-o", "{dir}", needle="is a directory"),
        C("sweep", "--spec", "{robot_toml}", needle="--spec: applies to a URDF --model; the Alpes model 'finger3'"),
        C("sweep", "--model", "{robot_urdf}", needle="--spec: the robustness study on a URDF --model needs its"),
        C("sweep", "--model", "{robot_urdf}", "--spec", "{latin1_toml}", needle="not UTF-8 text"),
        C("sweep", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--spread", "2",
          needle="--spread: expected a fraction in [0, 1)"),
        C("sweep", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "-o", "{robot_toml}",
          needle="-o: '{robot_toml}' is the input of --spec; refusing to write over it"),
    ],
    "mjcf": [
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robotctrlchar_toml}",
          needle="motor.name: 'fl\\x01exor' holds a control character; a name is printable text"),
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robotsheath_toml}",
          needle="capstan: a tendon's sheath friction (mu theta) has no MJCF form"),
        C("mjcf", "--model", "finger3", "--tilt", "1e308", needle="--tilt: 1e+308 deg is outside the accepted range [-180, 180] deg"),
        C("mjcf", "--model", "finger7", needle="unknown model 'finger7'"),
        C("mjcf", "hand", "--model", "finger3", needle="--model: given with the positional model 'hand'; give "
          "--model only"),
        C("mjcf", "--model", "{arm_xml}", needle="--model: '{arm_xml}' is an MJCF file; 'alpes-dyn import --model"),
        C("mjcf", "--model", "finger3", "--json", "-o", "{dir}/", needle="-o: '{dir}' is a directory"),
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--scene", "block",
          needle="--scene: applies to the Alpes models (finger2, finger3, hand, thumb); a URDF model's block scene"),
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--tilt", "10",
          needle="--tilt: applies to the Alpes models (finger2, finger3, hand, thumb); a URDF model's gravity is"),
        C("mjcf", "--model", "hand", "--scene", "block", needle="scene 'block' is for one finger"),
        C("mjcf", "--model", "finger3", "-o", "/nonexistent/dir/x.xml", needle="-o: directory '/nonexistent/dir' of"),
        C("mjcf", "--model", "finger3", "--params", "{latin1_toml}", needle="not UTF-8 text"),
        C("mjcf", "--model", "finger3", "--stiction", "-1", needle="stiction: expected a positive time constant in s"),
        C("mjcf", "--model", "finger3", "--stiction", "abc", needle="argument --stiction: invalid float value"),
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--stiction", "-1",
          needle="stiction: expected a positive time constant in s"),
        C("mjcf", "--model", "finger3", "--tendon-stiffness", "0", needle="tendon_stiffness: expected a positive stiffness"),
        C("mjcf", "--model", "finger3", "--tendon-stiffness", "inf", needle="tendon_stiffness: expected a positive stiffness"),
        C("mjcf", "--model", "finger3", "--tendon-damping", "2", needle="tendon_damping: needs tendon_stiffness"),
        C("mjcf", "--model", "finger3", "--tendon-stiffness", "4e4", "--tendon-damping", "-1",
          needle="tendon_damping: expected a damping >= 0"),
        C("mjcf", "--model", "{triangle_urdf}", "--tilt", "3", needle="--tilt: applies to the Alpes models"),
        C("mjcf", "--model", "{triangle_urdf}", "--params", "x.toml", needle="--params: applies to the Alpes models"),
        C("mjcf", "--model", "{triangle_urdf}", "--spring", "none", needle="--spring: applies to the Alpes models"),
        C("mjcf", "--model", "{triangle_urdf}", needle="link 'p3' has an inertia that breaks the triangle inequality"),
        C("mjcf", "--model", "finger3", "--spec", "x.toml", needle="--spec: applies to a URDF model"),
        C("mjcf", "--model", "hand", "--tendon-rotor", "--rotor-inertia", needle="rotor_inertia: the rotor would be counted twice"),
        C("mjcf", "--model", "finger3", "--tendon-rotor", "--tendon-stiffness", "4e4",
          needle="tendon_rotor: the series-elastic tendon (tendon_stiffness) has its rotor already"),
        C("mjcf", "--model", "finger3", "--tilt", "nan", needle="--tilt: expected a finite angle in degrees"),
        C("mjcf", "--model", "finger3", "--tendon-dead-band", "1e-4", needle="tendon_dead_band: needs tendon_stiffness"),
        C("mjcf", "--model", "finger3", "--params", "{cable_toml}", "--tendon-stiffness", "4e4",
          needle="tendon_stiffness: 40000.0 N/m differs from the parameter file's cable"),
        C("mjcf", "--model", "finger3", "--tendon-stiffness", "4e4", "--tendon-dead-band=-1e-4",
          needle="tendon_dead_band: expected a cable's play >= 0 in m"),
        C("mjcf", "--model", "{triangle_urdf}", "--tendon-dead-band", "1e-4", needle="--tendon-dead-band: applies to the Alpes"),
        C("mjcf", "--model", "finger3", "-o", "{dir}/", needle="-o: '{dir}' is a directory"),
        C("mjcf", "--model", "finger3", "--params", "{params_toml}", "-o", "{params_toml}", needle="is the input of --params"),
        C("mjcf", "--model", "finger3", "-o", "{device}", needle="is a character device"),
        C("mjcf", "--model", "finger3", "--params", "{mm_toml}", needle="finger.r.unit: the value is read in 'm', got 'mm'"),
        C("mjcf", "--model", "hand", "--params", "{xmlname_toml}", needle="palm.finger_names: 'in<d&\"ex' is not a name"),
    ],
    "control": [
        C("control", "--controller", "pid", needle="unknown controller 'pid'"),
        C("control", "--params", "{untrusted_toml}", needle="--params: '{untrusted_toml}' is marked not trustworthy "
          "(finger: the fit did not converge (lost basin)); --force uses it anyway"),
        C("control", "--model", "hand", "--params", "{untrusted_toml}", needle="is marked not trustworthy"),
        C("control", "--plant-effects", "some", needle="--plant-effects: invalid choice: 'some'"),
        C("control", "--plant-effects", "none", "--stiction", needle="--plant-effects: 'none' with an effect's flag"),
        C("control", "--stiction", "-1", needle="--stiction: expected a positive time constant in s"),
        C("control", "--tendon-stiffness", "-5", needle="--tendon-stiffness: expected a positive stiffness in N/m"),
        C("control", "--tendon-stiffness", "3e4", "--tendon-damping", "-1",
          needle="--tendon-damping: expected a damping >= 0 in N s/m"),
        C("control", "--tendon-dead-band", "1e-5", needle="--tendon-dead-band: the cable's slack needs the "
          "series-elastic tendon"),
        C("control", "--tendon-rotor", "--tendon-stiffness", "3e4", needle="--tendon-rotor: the series-elastic tendon"),
        C("control", "--tilt", "1e308", needle="--tilt: 1e+308 deg is outside the accepted range [-180, 180] deg"),
        C("control", "--torque-constant-error", "0.7", needle="--torque-constant-error: expected a fraction in "
          "(-0.5, 0.5), got 0.7"),
        C("control", "--encoder-offset", "nan", needle="--encoder-offset: expected a finite number of counts"),
        C("control", "--torque-delay", "200", needle="--torque-delay: expected a whole number of samples from 0 to 100"),
        C("control", "--torque-delay", "1.5", needle="--torque-delay: invalid int value: '1.5'"),
        C("control", "--no-compensation", needle="--no-compensation: applies to a plant with effects"),
        C("control", "--controller", "sensorless", "--force-scale", "1.05",
          needle="--force-scale: applies to a plant with a real hand's effects"),
        C("control", "--controller", "sensor", "--plant-effects", "all", "--calibrate",
          needle="--calibrate: applies to the sensorless controller"),
        C("control", "--controller", "sensorless", "--plant-effects", "all", "--force-scale", "3",
          needle="--force-scale: expected a scale from 0.5 to 2"),
        C("control", "--controller", "sensorless", "--plant-effects", "all", "--force-scale", "nan",
          needle="--force-scale"),
        C("control", "--controller", "sensorless", "--plant-effects", "all", "--force-scale", "1.1", "--calibrate",
          needle="--force-scale: give it or --calibrate"),
        C("control", "--model", "hand", "--controller", "sensorless", "--plant-effects", "all", "--calibrate",
          needle="--calibrate: applies to a finger model"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--plant-effects", "all",
          needle="--plant-effects: a real hand's effects apply to the Alpes models"),
        C("control", "--reference", "square", needle="unknown reference 'square'"),
        C("control", "--log", "/nonexistent/x.csv", needle="--log: directory '/nonexistent'"),
        C("control", "--plot", "{tmp}/x.xyz", needle="--plot:"),
        C("control", "--model", "hand", "--reference", "ramp", needle="--reference: the hand's loops follow step"),
        C("control", "--model", "hand", "--duration", "1", needle="--duration: the hand's run needs at least"),
        C("control", "--model", "hand", "--plot", "{tmp}/x.xyz", needle="--plot:"),
        C("control", "--log", "{tmp}/x.png", "--plot", "{tmp}/x.png", needle="--plot: '{tmp}/x.png' is also the "
          "output of --log"),
        C("control", "--params", "{params_toml}", "--log", "{hardlink}", needle="--log: '{hardlink}' is the input of "
          "--params"),
        C("control", "--plant-params", "{params_toml}", "--log", "{params_toml}", needle="is the input of --plant-params"),
        C("control", "--log", "{link}", needle="--log: '{link}' is a symbolic link"),
        C("control", "--log", "{fifo}", needle="--log: '{fifo}' is a FIFO"),
        C("control", "--duration", "1e308", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("control", "--duration", "1e9", needle="--duration: 1e+09 s is outside the accepted range [1e-09, 1e+06] s"),
        C("control", "--duration", "0.5001", needle="duration: 0.5001 s leaves less than 0.05 s after the settling"),
        C("control", "--model", "hand", "--duration", "1e308", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("control", "--params", "{fifo}", needle="is a FIFO (named pipe)"),
        # a URDF --model (issue 17): its spec, the frame, the motor, the block's placement
        C("control", "--model", "{robot_urdf}", needle="--spec: control on a URDF --model needs its transmission spec"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robot_toml}", needle="--spec: the rest configuration "
          "(motors off) has joint 'j1' at -0.727 rad, outside its range [0, 1.571]"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}",
          needle="--motor: 'tendon_robot' has 2 motors (flexor, distal); name one"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--motor", "flexor",
          needle="--frame: motor 'flexor' moves 2 tip frames (tip, p1); name one"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--motor", "distal", "--frame", "p1",
          needle="--frame: motor 'distal' does not move 'p1' (the tips it moves: tip)"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--motor", "wrist",
          needle="--motor: unknown motor 'wrist' (motors: flexor, distal)"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--frame", "p3",
          needle="--frame: 'p3' is not a tip frame of 'tendon_robot' (tips: tip, p1"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--frame", "tip", "--motor", "flexor",
          "--contact-q", "2,0,0", needle="--contact-q: the block cannot be placed: joint 'j1' at 2 rad is outside"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--frame", "tip", "--motor", "flexor",
          "--contact-q", "0.1,0.2", needle="--contact-q: expected 3 finite joint angles (rad, j1, j2, j3)"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--frame", "tip", "--motor", "flexor",
          "--contact-q", "0,0,0", needle="--contact-q: the block cannot be placed: the frame at rest (motors off) is "
          "already at or past the block's face"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--contact-q", "a,b",
          needle="--contact-q: expected comma-separated numbers"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--tau-max", "0",
          needle="--tau-max: expected a positive number of N m"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--tau-max", "nan",
          needle="--tau-max: expected a positive number of N m"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--params", "x.toml",
          needle="--params: applies to the Alpes models"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--plant-params", "x.toml",
          needle="--plant-params: applies to the Alpes models"),
        C("control", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--frame", "tip", "--motor", "flexor",
          "--log", "{robotctl_toml}", needle="--log: '{robotctl_toml}' is the input of --spec"),
        C("control", "--model", "{tmp}/none.urdf", "--spec", "{robotctl_toml}", needle="none.urdf"),
        C("control", "--spec", "{robotctl_toml}", needle="--spec: applies to a URDF --model"),
        C("control", "--frame", "tip", needle="--frame: applies to a URDF --model; the Alpes 'finger3'"),
        C("control", "--model", "hand", "--motor", "index", needle="--motor: applies to a URDF --model"),
        C("control", "--contact-q", "0.1,0.2,0.3", needle="--contact-q: applies to a URDF --model"),
        C("control", "--tau-max", "0.1", needle="--tau-max: applies to a URDF --model"),
        C("control", "--model", "nofinger", needle="--model: the control scenario is defined for one finger"),
    ],
    "linearize": [
        C("linearize", "--output", "sum+sum", needle="output: 'sum_finger' is asked for twice in 'sum+sum'"),
        C("observability", "--output", "joints:j1,j1", needle="output: 'q_j1' is asked for twice"),
        C("linearize", "--u=1,2", needle="--u: input 'joint' of model 'finger3' has 3 entries"),
        C("linearize", "--model", "finger2", "--spec", "x.toml", needle="--spec: applies to a URDF --model"),
        C("linearize", "--q=nan,0,0", needle="--q: contains NaN or inf"),
        C("linearize", "--dt", "1e308", "--json", needle="--dt: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("linearize", "--dt", "1e-320", needle="--dt: 1e-320 s is a subnormal number (below 2.2e-308"),
    ],
    "(global)": [
        C(needle="the following arguments are required: command"),
        C("frobnicate", needle="invalid choice: 'frobnicate'"),
        C("--bogus", needle="the following arguments are required"),
        C("dynamics", *["--json"] * 1000, needle="1001 command-line arguments, over the limit of 1000"),
    ],
    "urdf": [
        C("urdf", "--model", "finger7", needle="unknown model 'finger7'"),
        C("urdf", "finger3", "--model", "hand", needle="--model: given with the positional model 'finger3'; give "
          "--model only"),
        C("urdf", "--model", "{arm_xml}", "--params", "{params_toml}", needle="--params: applies to the Alpes models"),
        C("urdf", "--model", "{slide_xml}", needle="--model: joint 'ja' is a slide joint"),
        C("urdf", "--model", "{tmp}/missing.xml", needle="--model: '{tmp}/missing.xml' is not a file"),
        C("urdf", "--model", "{arm_xml}", "-o", "{arm_xml}", needle="-o: '{arm_xml}' is the input of --model"),
        C("urdf", "--model", "hand", "--json", "-o", "{dir}", needle="-o: '{dir}' is a directory"),
        C("urdf", "--model", "{robot_urdf}", needle="is a URDF already; this command writes the Alpes models'"),
        C("urdf", "--model", "hand", "-o", "{dir}", needle="-o: '{dir}' is a directory"),
        C("urdf", "--model", "hand", "-o", "", needle="-o: empty file name"),
        C("urdf", "--model", "hand", "-o", "{tmp}/missing/hand.urdf", needle="-o: directory '{tmp}/missing' of"),
        C("urdf", "--model", "hand", "-o", "{file}/hand.urdf", needle="-o: '{file}' in '{file}/hand.urdf' is not a directory"),
        C("urdf", "--model", "hand", "-o", "{tmp}/hand.urdf", needle="-o: cannot write", fsize=4096),  # full disk
        C("urdf", "--model", "finger3", "--params", "{binary_toml}", needle="not UTF-8 text (byte 0x80 at offset 128)"),
        C("urdf", "--model", "finger3", "--params", "{latin1_toml}", needle="not UTF-8 text (byte 0xe9"),
        C("urdf", "--model", "finger3", "--params", "", needle="parameter file: empty file name"),
        C("urdf", "--model", "finger3", "--params", "{dir}", needle="is a directory"),
        C("urdf", "--model", "finger3", "--params", "{negative_k_toml}", needle="finger.K: value must be >= 0"),
        C("identify", "--params", "{negative_compliance_toml}", "--data", "x.csv",
          needle="transmission.tendon_compliance: value must be >= 0"),
        C("urdf", "--model", "hand", "-o", "{link}", needle="-o: '{link}' is a symbolic link; refusing to replace it"),
        C("urdf", "--model", "hand", "-o", "{fifo}", needle="-o: '{fifo}' is a FIFO (named pipe)"),
        C("urdf", "--model", "hand", "-o", "{device}", needle="is a character device; only a regular file is written"),
        C("urdf", "--model", "hand", "-o", "{tmp}/newdir/", needle="-o: '{tmp}/newdir/' ends with '/': it names a directory"),
        C("urdf", "--model", "hand", "-o", "{dir}/", needle="-o: '{dir}' is a directory"),
        C("urdf", "--model", "hand", "--params", "{params_toml}", "-o", "{params_toml}", needle="-o: '{params_toml}' is the input "
          "of --params"),
        C("urdf", "--model", "hand", "--params", "{params_toml}", "-o", "{hardlink}", needle="is the input of --params"),
        C("urdf", "--model", "finger3", "--params", "{fifo}", needle="parameter file '{fifo}': is a FIFO (named pipe)"),
        C("urdf", "--model", "finger3", "--params", "/dev/zero", needle="'/dev/zero': is a character device, expected a regular"),
        C("urdf", "--model", "finger3", "--params", "{compliance_toml}", needle="transmission.tendon_compliance: value must be finite"),
        C("urdf", "--model", "finger3", "--params", "{capstan_toml}", needle="transmission.capstan: value must be finite"),
        C("estimate", "--model", "finger3", "--params", "{model_error_toml}",
          needle="friction.model_error: value must be >= 0"),
        C("urdf", "--model", "finger3", "--params", "{model_error_unit_toml}",
          needle="friction.model_error.unit: the value is read in 'F_s', got 'N m'"),
        C("estimate", "--model", "finger3", "--params", "{observer_law_toml}",
          needle="friction.observer_law: expected one of smooth, stick, lugre, got 'dahl'"),
        C("urdf", "--model", "finger3", "--params", "{bigint_toml}", needle="transmission.N.value: integer of 401 digits, over the limit"),
        C("urdf", "--model", "finger3", "--params", "{deep_toml}", needle="arrays or tables nested more than 32 deep"),
        C("urdf", "--model", "finger3", "--params", "{half_count_toml}", needle="transmission.encoder_counts: value must be a "
          "whole number, got 4096.5"),
        C("urdf", "--model", "finger3", "--params", "{mm_toml}", needle="finger.r.unit: the value is read in 'm', got 'mm'"),
    ],
    "import": [
        C("import", "--out-dir", "{tmp}/out", needle="the following arguments are required: --model"),
        C("import", "--model", "{arm_xml}", needle="--out-dir: required: the directory import writes"),
        C("import", "--model", "{arm_xml}", "-o", "{tmp}/a", "--out-dir", "{tmp}/b", needle="-o: given with --out-dir; give --out-dir only"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}/out", "--hold", "jz",
          needle="--hold: unknown joint 'jz' (joints: ja)"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}/out", "--hold", "ja",
          needle="--hold: joint 'ja' is on tendon 't'; hold joints no tendon crosses"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}/out", "--hold", "ja,,jb",
          needle="--hold: expected comma-separated joint names, got 'ja,,jb'"),
        C("import", "--model", "finger3", "--out-dir", "{tmp}/out", needle="--model: import reads an MJCF file (FILE.xml), "
          "got 'finger3'; an Alpes model's MJCF: 'alpes-dyn mjcf --model finger3 -o FILE.xml'"),
        C("import", "--model", "{robot_urdf}", "--out-dir", "{tmp}/out", needle="is a URDF already; give it with its spec"),
        C("import", "--model", "{tmp}/missing.xml", "--out-dir", "{tmp}/out", needle="--model: '{tmp}/missing.xml' is not a "
          "file"),
        C("import", "--model", "{dir}", "--out-dir", "{tmp}/out", needle="--model: '{dir}' is not a file"),
        C("import", "--model", "{slide_xml}", "--out-dir", "{tmp}/out", needle="--model: joint 'ja' is a slide joint"),
        C("import", "--model", "{norange_xml}", "--out-dir", "{tmp}/out", needle="--model: joint 'ja' has no range"),
        C("import", "--model", "{notxml_xml}", "--out-dir", "{tmp}/out", needle="--model: MuJoCo cannot compile it"),
        C("import", "--model", "{flip_xml}", "--out-dir", "{tmp}/out", needle="--model: spatial tendon 'SE' (actuator 'SE'): "
          "its side site 'in' is inside its wrapping geom 'shoulder'"),
        C("import", "--model", "{nan_xml}", "--out-dir", "{tmp}/out", needle="--model: <body name='a'> pos='nan 0 0.1': a "
          "number is NaN"),
        C("import", "--model", "{deep_xml}", "--out-dir", "{tmp}/out", needle="--model: bodies nested over 100 deep, the limit"),
        C("import", "--model", "{sites_xml}", "--out-dir", "{tmp}/out", needle="--model: over 1000 bodies and sites, the limit"),
        C("import", "--model", "{flat_xml}", "--out-dir", "{tmp}/out", needle="--model: its tree (imported as a URDF): 201 "
          "moving joints, over the limit of 200"),
        C("import", "--model", "{gear0_xml}", "--out-dir", "{tmp}/out", needle="--model: actuator 'm' has gear 0; a motor's "
          "gear (its ratio) must be a non-zero number"),
        C("import", "--model", "{muscle_xml}", "--out-dir", "{tmp}/out", needle="--model: actuator 'm' is a muscle"),
        C("import", "--model", "{loop_xml}", "--out-dir", "{tmp}/out", needle="--model: equality 'loop' is a connect between "
          "'b' and 'world': a closed kinematic loop"),
        C("import", "--model", "{tmp}/.xml", "--out-dir", "{tmp}/out", needle="--model: the files written are named after "
          "the MJCF file; '.xml' gives no plain name"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}", needle="--out-dir: directory '{tmp}' is not empty; refusing to "
          "write over it"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{file}", needle="--out-dir: '{file}' exists and is not a directory"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}/missing/out", needle="--out-dir: directory '{tmp}/missing' of"),
        C("import", "--model", "{arm_xml}", "--out-dir", "", needle="--out-dir: expected a directory name, got ''"),
        C("import", "--model", "{arm_xml}", "--out-dir", "{tmp}/out", "--json", "--json", needle="--json: given 2 times"),
    ],
    "dynamics": [
        C("dynamics", "--model", "{arm_xml}", needle="--model: '{arm_xml}' is an MJCF file; 'alpes-dyn import --model "
          "{arm_xml} --out-dir DIR' writes its URDF and spec, then give --model DIR/arm.urdf --spec DIR/arm.toml"),
        C("dynamics", "--model", "{star_urdf}", needle="URDF: 201 moving joints, over the limit of 200"),
        C("dynamics", "--q=1_0,0,0", needle="--q: expected comma-separated numbers, got '1_0,0,0'"),
        C("dynamics", "--model", "finger9", needle="unknown model 'finger9'"),
        C("dynamics", "--q=0.1,0.2", needle="--q: model 'finger3' has 3 joints, got 2 values"),
        C("dynamics", "--q=0.1,x,0.2", needle="--q: expected comma-separated numbers"),
        C("dynamics", "--q=0.1,nan,0.2", needle="--q: contains NaN or inf"),
        C("dynamics", "--v=1e400,0,0", needle="--v: contains NaN or inf"),
        C("dynamics", "--tau=1e308,1e308,1e308", needle="--tau: 1e+308 N m (index 0) is outside the accepted range"),  # no numpy warning line
        C("dynamics", "--force=0,1", needle="--force: expected 3 values"),
        C("dynamics", "--tip", "nail", needle="unknown tip/frame 'nail'"),
        C("dynamics", "--spring", "cubic", needle="invalid choice: 'cubic'"),
        C("dynamics", "--params", "/nonexistent.toml", needle="cannot be read"),
        C("dynamics", "--params", "", needle="parameter file: empty file name"),
        C("dynamics", "--params", "{binary_toml}", needle="not UTF-8 text"),
        C("dynamics", "--model", "/nonexistent.urdf", needle="cannot be read"),
        C("dynamics", "--model", "{binary_urdf}", needle="not UTF-8 text (byte 0x89 at offset 0)"),
        C("dynamics", "--model", "{latin1_urdf}", needle="not UTF-8 text (byte 0xe9"),
        C("dynamics", "--model", "{negmass_urdf}", needle="link 'p3': mass must be >= 0 kg, got -0.023"),
        C("dynamics", "--model", "{massless_urdf}", needle="joint 'j3' moves no mass"),
        C("dynamics", "--model", "{continuous_urdf}", needle="joint 'j2' is continuous (unbounded); give it limits as a "
          "revolute joint"),
        C("dynamics", "--model", "{zeroaxis_urdf}", needle="joint 'j2' has the zero axis xyz='0 0 0'; give the "
          "direction it turns about"),
        C("dynamics", "--model", "{planar_urdf}", needle="joint 'j2' is planar (3 degrees of freedom); only revolute, "
          "prismatic and fixed joints"),
        C("dynamics", "--model", "{zero_mass_inertia_urdf}", needle="link 'p3': zero mass with a non-zero inertia"),
        C("dynamics", "--model", "{indefinite_urdf}", needle="not positive semidefinite"),
        C("dynamics", "--model", "{indefinite_urdf}", needle="link 'p3': inertia is not positive semidefinite"),
        C("dynamics", "--model", "{nan_urdf}", needle="link 'p3': mass: must be finite, got 'nan'"),
        C("dynamics", "--model", "{no_limits_urdf}", needle="does not specify limits"),  # urdfdom's stderr
        C("dynamics", "--model", "{truncated_urdf}", needle="URDF could not be parsed"),
        C("dynamics", "--model", "{fifo}", needle="URDF file '{fifo}': is a FIFO (named pipe)"),
        C("dynamics", "--model", "{big_urdf}", needle="16777217 bytes, over the limit of 16777216 bytes"),
        C("dynamics", "--model", "{mimicself_urdf}", needle="joint 'j2': <mimic joint='j2'> names the joint itself"),
        C("dynamics", "--model", "{mimicnan_urdf}", needle="joint 'j2': <mimic multiplier='nan'> is not a finite number"),
        C("control", "--tau-max", "1_0", needle="argument --tau-max: expected a positive number of N m, got '1_0'"),
        C("observability", "--order", "1_0", needle="--order: expected auto, report or a non-negative integer, got '1_0'"),
        C("dynamics", "--model", "{mimicbig_urdf}", needle="joint 'j2': <mimic multiplier='1e300'>: 1e+300 is outside "
          "the accepted range [-1e+06, 1e+06]"),
        C("dynamics", "--model", "{mimic_urdf}", "--spec", "{robot_toml}", needle="motor 'flexor'.joints: joint 'j2' "
          "is a mimic joint (URDF <mimic>: q_j2 = 1 q_j1 + 0) with no coordinate of its own; name 'j1'"),
        C("dynamics", "--model", "{many_links_urdf}", needle="URDF: 1001 links, over the limit of 1000"),
        C("dynamics", "--model", "{deep_urdf}", needle="joints deep, over the limit of 100"),
        C("dynamics", "--model", "{inverted_limit_urdf}", needle="joint 'j1': limit lower 1.6 is above upper 0"),
        C("dynamics", "--model", "{negmass_urdf}", "--spec", "{fifo}", needle="spec file '{fifo}': is a FIFO"),
        C("dynamics", "--model", "{negmass_urdf}", "--spec", "{deep_toml}", needle="nested more than 32 deep"),
        C("dynamics", "--model", "{twoleaf_urdf}", needle="names no tip and its URDF has 2 leaf frames (nail, tip); "
          'name it: tips = ["<frame>"] in the spec, or tip=<frame> (the command line\'s --tip)'),
        C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotrest_toml}",
          needle="rest_angle.j9: joint 'j9' has no spring (no [stiffness] value)"),
        C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotstops_toml}",
          needle="stops.stiffness: expected a number > 0, got -2"),
        C("mjcf", "--model", "{robot_urdf}", "--spec", "{robotstopj_toml}",
          needle="stops.joints.j9: unknown joint 'j9' (URDF joints: j1, j2, j3)"),
    ],
    "report": [
        C("report", "--points", "0", needle="--points: expected an integer from 1 to 10000, got 0"),
        C("report", "--points", "100000000", needle="--points: expected an integer from 1 to 10000"),
        C("report", "--points", "x", needle="--points: expected an integer from 1 to 10000, got 'x'"),
        C("report", "--seed", "-1", needle="--seed: expected an integer from 0 to 9223372036854775807, got -1"),
    ],
    "observability": [
        C("observability", "--points", "0", needle="--points: expected an integer from 1 to 10000, got 0"),
        C("observability", "--points", "10000001", needle="--points: expected an integer from 1 to 10000"),
        C("observability", "--seed", "-1", needle="--seed: expected an integer from 0 to 9223372036854775807"),
        C("observability", "--order", "x", needle="--order: expected auto, report or a non-negative integer"),
        C("observability", "--order", "-1", needle="--order: expected auto, report or a non-negative integer"),
        C("observability", "--model", "{negmass_urdf}", needle="mass must be >= 0"),
        C("observability", "--model", "{binary_urdf}", needle="not UTF-8 text"),
        C("observability", "--input", "torque", needle="invalid choice: 'torque'"),
        C("observability", "--order", "99999999999999999999", needle="--order: 99999999999999999999 is over the limit "
          "of 1000"),
        C("observability", "--order", "1001", needle="--order: 1001 is over the limit of 1000"),
    ],
    "codegen": [
        C("codegen", needle="--out-dir: required: the directory codegen writes"),
        C("codegen", "-o", "{tmp}/a", "--out-dir", "{tmp}/b", needle="-o: given with --out-dir; give --out-dir only"),
        C("codegen", "--friction", "--no-friction", "--out-dir", "{tmp}/c", needle="--no-friction: given with --friction; give one of them"),
        C("codegen", "--params", "{fitted_friction_toml}", "--controller", "sensor", "--out-dir", "{tmp}/c",
          needle="without --chain and friction (--params {fitted_friction_toml}'s fit had friction: --no-friction)"),
        C("codegen", "--params", "{untrusted_toml}", "--out-dir", "c_out", needle="--params: '{untrusted_toml}' is marked "
          "not trustworthy (finger: the fit did not converge (lost basin)); --force uses it anyway"),
        C("codegen", "--out-dir", "", needle="--out-dir: expected a directory name, got ''"),
        C("codegen", "--out-dir", "{tmp}", needle="--out-dir: directory '{tmp}' is not empty; refusing to write over it"),
        C("codegen", "--out-dir", "{params_toml}", needle="--out-dir: '{params_toml}' exists and is not a directory"),
        C("codegen", "--params", "{params_toml}", "--out-dir", "{hardlink}", needle="exists and is not a directory"),
        C("codegen", "--out-dir", "{device}", needle="exists and is not a directory"),
        C("codegen", "--out-dir", "{link}", needle="--out-dir: '{link}' is a symbolic link"),
        C("codegen", "--out-dir", "/nonexistent/c", needle="--out-dir: directory '/nonexistent' of '/nonexistent/c' does not exist"),
        C("codegen", "--out-dir", "{file}/c", needle="--out-dir: directory '{file}' of '{file}/c' does not exist"),
        C("codegen", "--model", "hand", "--out-dir", "{tmp}/c", needle="--model: the C export is defined for one chain"),
        C("codegen", "--model", "{robot_urdf}", "--out-dir", "{tmp}/c",
          needle="--spec: the C export on a URDF --model needs its transmission spec"),
        C("codegen", "--spec", "{robot_toml}", "--out-dir", "{tmp}/c", needle="--spec: applies to a URDF --model"),
        C("codegen", "--controller", "sensor", "--frame", "tip", "--out-dir", "{tmp}/c",
          needle="--frame: applies to a URDF --model"),
        C("codegen", "--motor", "flexor", "--out-dir", "{tmp}/c", needle="--motor: applies to a URDF --model"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--chain", "index", "--out-dir", "{tmp}/c",
          needle="--chain: names a finger of the Alpes hand"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--params", "x.toml", "--out-dir", "{tmp}/c",
          needle="--params: applies to the Alpes models"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--friction", "--out-dir", "{tmp}/c",
          needle="--friction: applies to the Alpes models; a URDF --model's observer has its --spec's friction"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--motor", "flexor", "--out-dir", "{tmp}/c",
          needle="--motor: names the force controller's tip frame or motor; give it with --controller"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--observer", "pf", "--out-dir", "{tmp}/c",
          needle="--observer: unknown observer 'pf'"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--controller", "pid", "--out-dir", "{tmp}/c",
          needle="--controller: unknown controller 'pid'"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--controller", "sensor", "--out-dir", "{tmp}/c",
          needle="--spec: the rest configuration (motors off) has joint 'j1' at -0.727 rad, outside its range"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--controller", "sensor", "--out-dir",
          "{tmp}/c", needle="--motor: 'tendon_robot' has 2 motors (flexor, distal); name one"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--controller", "pi", "--motor", "nope",
          "--out-dir", "{tmp}/c", needle="--motor: unknown motor 'nope'"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robotctl_toml}", "--controller", "pi", "--motor",
          "flexor", "--out-dir", "{tmp}/c", needle="--frame: motor 'flexor' moves 2 tip frames (tip, p1); name one"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--out-dir", "{robot_toml}",
          needle="exists and is not a directory"),
        C("codegen", "--model", "thumb", "--out-dir", "{tmp}/c", needle="friction: the thumb's scenario needs"),
        C("codegen", "--chain", "pinky", "--out-dir", "{tmp}/c", needle="chain: unknown finger 'pinky'"),
        C("codegen", "--model", "thumb", "--friction", "--chain", "index", "--out-dir", "{tmp}/c",
          needle="chain: only a finger model"),
        C("codegen", "--observer", "pf", "--out-dir", "{tmp}/c", needle="--observer: unknown observer 'pf'"),
        C("codegen", "--step", "--out-dir", "{tmp}/c", needle="--step: needs --controller (sensor, sensorless or pi)"),
        C("codegen", "--step", "--controller", "pid", "--out-dir", "{tmp}/c", needle="--controller: unknown controller 'pid'"),
        C("codegen", "--step", "--model", "thumb", "--controller", "sensor", "--out-dir", "{tmp}/c",
          needle="--step: the force step is exported for finger2, finger3, hand and a URDF --model with its --spec, "
                 "got --model 'thumb'"),
        C("codegen", "--step", "--model", "{robot_urdf}", "--controller", "pi", "--out-dir", "{tmp}/c",
          needle="--spec: the force step on a URDF --model needs its transmission spec"),
        C("codegen", "--step", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--controller", "pi", "--params",
          "{params_toml}", "--out-dir", "{tmp}/c", needle="--params: not with --step on a URDF --model"),
        C("codegen", "--step", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--controller", "pi", "--frame",
          "nowhere", "--out-dir", "{tmp}/c", needle="--frame:"),
        C("codegen", "--step", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--controller", "pi", "--motor",
          "nomotor", "--out-dir", "{tmp}/c", needle="--motor:"),
        C("codegen", "--step", "--model", "hand", "--out-dir", "{tmp}/c", needle="--step: needs --controller"),
        C("codegen", "--step", "--model", "hand", "--controller", "pi", "--chain", "index", "--out-dir", "{tmp}/c",
          needle="--chain: not with --step"),
        C("codegen", "--step", "--model", "hand", "--controller", "pi", "--out-dir", "{tmp}",
          needle="--out-dir: directory '{tmp}' is not empty"),
        C("codegen", "--step", "--model", "hand", "--controller", "pi", "--params", "{untrusted_toml}",
          "--out-dir", "{tmp}/c", needle="marked"),
        C("codegen", "--step", "--controller", "pi", "--friction", "--out-dir", "{tmp}/c",
          needle="--friction: not with --step (the step's EKF has the --params file's friction)"),
        C("codegen", "--step", "--controller", "pi", "--chain", "index", "--out-dir", "{tmp}/c",
          needle="--chain: not with --step"),
        C("codegen", "--step", "--controller", "pi", "--observer", "ukf", "--out-dir", "{tmp}/c",
          needle="--observer: not with --step (the step's observer is the EKF)"),
        C("codegen", "--step", "--controller", "pi", "--frame", "tip", "--out-dir", "{tmp}/c",
          needle="--frame: not with --step"),
        C("codegen", "--step", "--controller", "pi", "--out-dir", "{tmp}", needle="--out-dir: directory '{tmp}' is not empty"),
        C("codegen", "--step", "--controller", "pi", "--out-dir", "{params_toml}", needle="exists and is not a directory"),
        C("codegen", "--step", "--controller", "pi", "--params", "{untrusted_toml}", "--out-dir", "{tmp}/c",
          needle="--params: '{untrusted_toml}' is marked"),
        C("codegen", "--params", "", "--out-dir", "{tmp}/c", needle="parameter file: empty file name"),
        C("codegen", "--params", "{latin1_toml}", "--out-dir", "{tmp}/c", needle="not UTF-8 text"),
        C("codegen", "--params", "{fifo}", "--out-dir", "{tmp}/c", needle="is a FIFO (named pipe)"),
        C("codegen", "--params", "{negative_k_toml}", "--out-dir", "{tmp}/c", needle="finger.K: value must be >= 0"),
        C("codegen", "--params", "{tmp}/missing.toml", "--out-dir", "{tmp}/c",
          needle="parameter file '{tmp}/missing.toml': cannot be read"),
        C("codegen", "--json", "--spring", "none", "--out-dir", "{tmp}/c", needle="unrecognized arguments: --spring"),
        C("codegen", "--controller", "pid", "--out-dir", "{tmp}/c", needle="--controller: unknown controller 'pid'"),
        C("codegen", "--controller", "sensor", "--model", "thumb", "--friction", "--out-dir", "{tmp}/c",
          needle="--controller: the force controller is exported for finger2 and finger3"),
        C("codegen", "--controller", "pi", "--chain", "index", "--out-dir", "{tmp}/c",
          needle="--controller: the force controller is exported for finger2 and finger3"),
        C("codegen", "--controller", "sensor", "--friction", "--out-dir", "{tmp}/c",
          needle="without --chain and friction"),
        C("codegen", "--controller", "sensor", "--out-dir", "{tmp}", needle="--out-dir: directory '{tmp}' is not empty"),
        C("codegen", "--controller", "sensor", "--params", "{negative_k_toml}", "--out-dir", "{tmp}/c",
          needle="finger.K: value must be >= 0"),
    ],
    "estimate": [
        C("estimate", "--friction", "--no-friction", needle="--no-friction: given with --friction; give one of them"),
        C("estimate", "--data", "{rec3_csv}", "--no-friction", "--friction", needle="--no-friction: given with --friction"),
        C("codegen", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--no-friction", "--out-dir", "{tmp}/c",
          needle="--no-friction: applies to the Alpes models"),
        C("estimate", "--data", "{grav149_csv}", needle="gravity has norm 14.9 m/s^2"),
        # a file written by identify --force, refused with its reason (issue 49)
        C("estimate", "--params", "{untrusted_toml}", needle="--params: '{untrusted_toml}' is marked not trustworthy "
          "(finger: the fit did not converge (lost basin)); --force uses it anyway"),
        C("estimate", "--observer-params", "{untrusted_toml}", needle="--observer-params: '{untrusted_toml}' is marked "
          "not trustworthy"),
        C("estimate", "--data", "{rec3_csv}", "--params", "{untrusted_toml}", needle="--params: '{untrusted_toml}' is "
          "marked not trustworthy"),
        # the recording's unit mistakes, named (issue 49; they ran into a diverged filter)
        C("estimate", "--data", "{ma_csv}", needle="column 'torque_finger': values up to"),
        C("estimate", "--data", "{rad_csv}", needle="the motor angle in radians? the recording's encoder is in counts"),
        C("estimate", "--data", "{ms_csv}", needle="t in milliseconds? the recording's time is in s"),
        C("estimate", "--data", "{runtwo_csv}", "--model", "finger3",
          needle="recording: 2 runs (column 'run'); an observer runs on one: give one run's rows"),
        C("estimate", "--duration", "1_0", needle="--duration: invalid float value: '1_0'"),
        C("control", "--duration", "1_0", needle="--duration: expected a positive number of seconds, got '1_0'"),
        C("estimate", "--model", "{robot_urdf}", "--spec", "{robot_toml}",
          needle="--model: the simulated estimation scenario is the Alpes fingers'; on a URDF --model run the observer"),
        C("estimate", "--friction-free", needle="--friction-free: applies to a URDF --model on a recording"),
        C("estimate", "--data", "{replay_csv}", "--friction-free", needle="--friction-free: applies to a URDF --model"),
        C("estimate", "--data", "{replay_csv}", "--model", "{robot_urdf}",
          needle="--spec: the observer on a URDF --model needs its transmission spec"),
        C("estimate", "--data", "{replay_csv}", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--chain", "index",
          needle="--chain: unknown motor 'index' of the URDF --model (motors: flexor)"),
        C("estimate", "--data", "{replay_csv}", "--model", "{branches_urdf}", "--spec", "{branches_toml}", "--chain",
          "fa", needle="recording: unknown column 'encoder_finger' for model 'branches' (motors fa, fb, across"),
        C("estimate", "--data", "{replay_csv}", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--friction",
          needle="--friction: applies to the Alpes models"),
        C("estimate", "--data", "{replay_csv}", "--model", "{robot_urdf}", "--spec", "{robot_toml}", "--rotor-inertia",
          needle="--rotor-inertia: applies to the Alpes models"),
        C("estimate", "--data", "{replay_csv}", "--model", "{robot_urdf}", "--spec", "{robottwo_toml}",
          needle="motors"),
        C("estimate", "--data", "{tmp}/none.csv", needle="cannot be read"),
        C("estimate", "--data", "{latin1_toml}", needle="not a UTF-8 text file"),
        C("estimate", "--torque-constant", "0.05", needle="--torque-constant: applies to an observer on a recording"),
        C("estimate", "--data", "{current_csv}", needle="column 'current_finger' needs a torque constant"),
        C("estimate", "--data", "{current_csv}", "--torque-constant", "nan",
          needle="torque_constant: expected a positive number of N m/A, got nan"),
        C("estimate", "--data", "{enchuge_csv}", "--friction", needle="column 'encoder_finger' line 103: 1e+15 counts"),
        C("estimate", "--data", "{replay_csv}", "--model", "finger2", needle="unknown column 'true_q_j3'"),
        C("estimate", "--data", "{replay_csv}", "--torque-noise", "-1", needle="torque_noise: expected a non-negative"),
        C("estimate", "--data", "{replay_csv}", "--torque-noise", "nan", needle="torque_noise: expected a non-negative"),
        C("estimate", "--data", "{replay_csv}", "--observer", "pf", needle="--observer: unknown observer 'pf'"),
        C("estimate", "--data", "{replay_csv}", "--tilt", "0.1", needle="tilt: expected 2 finite numbers (rad)"),
        C("estimate", "--data", "{replay_csv}", "--tilt", "0,x", needle="--tilt"),
        C("estimate", "--data", "{replay_csv}", "--encoder-offset", "1,2", needle="encoder_offset: expected 1 finite"),
        C("estimate", "--tilt", "0,0", needle="--tilt: applies to an observer on a recording"),
        C("estimate", "--sigma-limit", "0", needle="--sigma-limit: expected degrees in (0, 180], got 0.0"),
        C("estimate", "--data", "{replay_csv}", "--sigma-limit", "nan",
          needle="--sigma-limit: expected degrees in (0, 180], got nan"),
        C("estimate", "--sigma-limit", "1e400", needle="--sigma-limit: expected degrees in (0, 180]"),
        C("estimate", "--torque-delay", "1", needle="--torque-delay: applies to an observer on a recording"),
        C("estimate", "--data", "{replay_csv}", "--torque-delay", "-1",
          needle="--torque-delay: expected a whole number of samples from 0 to 100"),
        C("estimate", "--data", "{replay_csv}", "--torque-delay", "101",
          needle="--torque-delay: expected a whole number of samples from 0 to 100"),
        C("estimate", "--data", "{replay_csv}", "--torque-delay", "1.5", needle="--torque-delay"),
        C("estimate", "--friction-law", "stick", needle="--friction-law: applies to an observer on a recording"),
        C("estimate", "--stops", needle="--stops: applies to an observer on a recording"),
        C("estimate", "--law-spread", needle="--law-spread: applies to an observer on a recording"),
        C("estimate", "--band-sigma", needle="--band-sigma: applies to an observer on a recording"),
        C("estimate", "--data", "{replay_csv}", "--band-sigma",
          needle="--band-sigma: the observer's model has no dry friction"),
        C("estimate", "--no-band-sigma", needle="--no-band-sigma: applies to an observer on a recording"),
        C("estimate", "--data", "{replay_csv}", "--band-sigma", "--no-band-sigma",
          needle="--no-band-sigma: give either --band-sigma (the default) or --no-band-sigma"),
        C("estimate", "--data", "{replay_csv}", "--friction-law", "dahl",
          needle="--friction-law: unknown friction law 'dahl' (expected one of smooth, stick, lugre)"),
        C("estimate", "--rotor-inertia", needle="--rotor-inertia: applies to an observer on a recording"),
        C("estimate", "--data", "{replay_csv}", "--model", "{triangle_urdf}", "--rotor-inertia",
          needle="--rotor-inertia: applies to the Alpes models"),
        C("estimate", "--encoder-offset", "0", needle="--encoder-offset: applies to an observer on a recording"),
        C("estimate", "--data", "{replay_csv}", "--log", "{replay_csv}", needle="--log: '{replay_csv}' is the input of --data"),
        C("estimate", "--data", "{replay_csv}", "--params", "{params_toml}", "--log", "{hardlink}",
          needle="--log: '{hardlink}' is the input of --params"),
        C("estimate", "--data", "{replay_csv}", "--log", "{link}", needle="--log: '{link}' is a symbolic link"),
        C("estimate", "--data", "{fifo}", needle="recording '{fifo}': is a FIFO (named pipe)"),
        C("estimate", "--data", "{replay_csv}", "--log", "{dir}", needle="is a directory"),
        C("estimate", "--data", "x.csv", "--mismatch", "0.1", needle="--mismatch: applies to the simulated scenario"),
        C("estimate", "--data", "x.csv", "--seed", "3", needle="--seed: applies to the simulated scenario"),
        C("estimate", "--data", "x.csv", "--observer-params", "o.toml", needle="the observer's model is --params"),
        C("estimate", "--disturbance", needle="--disturbance: applies to an observer on a recording (--data"),
        C("estimate", "--log", "e.csv", needle="--log: applies to an observer on a recording (--data"),
        C("estimate", "--torque-noise", "1e-3", needle="--torque-noise: applies to an observer on a recording"),
        C("estimate", "--torque-noise", "0", needle="--torque-noise: applies to an observer on a recording"),  # 0 == False
        C("estimate", "--plot", "{dir}", needle="--plot: '{dir}' is a directory"),
        C("estimate", "--plot", "", needle="--plot: empty file name"),
        C("estimate", "--plot", "out.xyz", needle="--plot: 'out.xyz' has extension 'xyz'; expected one of"),
        C("estimate", "--plot", "out", needle="--plot: 'out' has no extension"),
        C("estimate", "--plot", "{tmp}/missing/x.png", needle="--plot: directory"),
        C("estimate", "--plot", "{file}/x.png", needle="is not a directory"),
        C("estimate", "--duration", "1e12", needle="--duration: 1e+12 s is outside the accepted range [1e-09, 1e+06] s"),
        C("estimate", "--duration", "0.001", needle="duration: 0.001 s is shorter than two samples"),
        C("estimate", "--duration", "0.0015", needle="not a whole number of samples"),
        C("estimate", "--duration", "nan", needle="duration: expected a finite number"),
        C("estimate", "--duration", "-1", needle="duration: expected a positive number"),
        C("estimate", "--duration", "x", needle="--duration: invalid float value"),
        C("estimate", "--mismatch", "0.7", needle="mismatch: expected a fraction in (-0.5, 0.5)"),
        C("estimate", "--mismatch", "inf", needle="mismatch: expected a finite number"),
        C("estimate", "--params", "", needle="parameter file: empty file name"),
        C("estimate", "--params", "{latin1_toml}", needle="not UTF-8 text"),
        C("estimate", "--observer", "pf", needle="--observer: unknown observer 'pf'"),
        C("estimate", "--model", "hand", needle="--model: the estimation scenario is defined for one chain"),
        C("estimate", "--model", "thumb", needle="friction: the thumb's scenario needs friction=True (the command line's --friction;"),
        C("estimate", "--chain", "pinky", needle="chain: unknown finger 'pinky'"),
        C("estimate", "--model", "thumb", "--friction", "--chain", "index", needle="chain: only a finger model"),
        C("estimate", "--seed", "-1", needle="--seed: expected an integer from 0 to 9223372036854775807, got -1"),
        C("estimate", "--spring", "report", needle="spring: the scenario's torque profile"),
        C("estimate", "--true-params", "{latin1_toml}", needle="not UTF-8 text"),
        C("estimate", "--observer-params", "", needle="parameter file: empty file name"),
        C("estimate", "--observer-params", "x.toml", "--mismatch", "0.1", needle="either --mismatch or --observer-params"),
        C("estimate", "--duration", "1e308", needle="--duration: 1e+308 s is outside the accepted range [1e-09, 1e+06] s"),
        C("estimate", "--duration", "1e9", needle="--duration: 1e+09 s is outside the accepted range [1e-09, 1e+06] s"),
        C("estimate", "--plot", "{link}", needle="--plot: '{link}' is a symbolic link"),
        C("estimate", "--true-params", "{fifo}", needle="is a FIFO (named pipe)"),
        C("estimate", "--observer-params", "{bigint_toml}", needle="integer of 401 digits"),
    ],
}

# issue 19's re-check: numbers outside their unit's accepted range, repeated options, the cache's folder, outputs
RANGE = "is outside the accepted range"
CLI["dynamics"] += [
    C("dynamics", "--q", "1e300,0,0", needle=f"--q: 1e+300 rad (index 0) {RANGE} [-100, 100] rad"),
    C("dynamics", "--v=0,-1e300,0", needle=f"--v: -1e+300 rad/s (index 1) {RANGE} [-10000, 10000] rad/s"),
    C("dynamics", "--force", "0,0,1e-320", needle="--force (index 2): 1e-320 N is a subnormal number"),
    C("dynamics", "--q", "0.1,0,0", "--q", "0.2,0,0", needle="--q: given 2 times; give it once"),
    C("dynamics", "--json", "--json", needle="--json: given 2 times; give it once"),
    C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotratio_toml}",
      needle=f"motor 'flexor'.joints.j1: 1e+300 {RANGE} [-1e+06, 1e+06]"),
    C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotsub_toml}", needle="stiffness.j1: 1e-320 N m/rad is a "
      "subnormal number"),
    C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotcounts_toml}",
      needle="encoder_counts: expected a whole number of counts per revolution, got 4096.5"),
    C("dynamics", "--model", "{robot_urdf}", "--spec", "{robotempty_toml}", needle="holds nothing (no [[motor]]"),
    C("dynamics", "--params", "{angle_toml}", needle=f"finger.upper: 1e+300 rad {RANGE} [-100, 100] rad"),
]
CLI["mjcf"] += [
    C("mjcf", "--model", "finger3", "--tendon-stiffness", "1e300", "-o", "{tmp}/m.xml",
      needle=f"--tendon-stiffness: 1e+300 N/m {RANGE} [1e-06, 1e+12] N/m"),
    C("mjcf", "--model", "finger3", "--stiction", "1e-320", "-o", "{tmp}/m.xml", needle="--stiction: 1e-320 s is a subnormal"),
    C("mjcf", "--model", "hand", "--params", "{ratio_toml}", "-o", "{tmp}/m.xml", needle=f"transmission.N: 1e+300 {RANGE}"),
]
CLI["linearize"] += [C("linearize", "--u", "1e300,0,0", needle=f"--u: 1e+300 N m (index 0) {RANGE}")]
CLI["experiment"] += [
    C("experiment", "--duration", "0.2", "-o", "{tmp}/a.csv", "-o", "{tmp}/b.csv", needle="-o: given 2 times"),
    C("experiment", "--perturb", "1e300", "-o", "{tmp}/r.csv", needle="--perturb: expected a fraction in [0, 1), got 1e+300"),
    C("experiment", "--seed", "9" * 400, "-o", "{tmp}/r.csv", needle="--seed: expected an integer from 0 to "
      "9223372036854775807"),
    C("experiment", "--model", "hand", "--chain", "index", "-o", "{tmp}/r.csv",
      needle="--chain: the hand's experiment drives every chain at once"),
    C("experiment", "--model", "hand", "--true-params-out", "{tmp}/t.toml", "-o", "{tmp}/r.csv",
      needle="--true-params-out: goes with --perturb"),
    C("experiment", "--model", "hand", "-o", "{tmp}/r.toml", needle="-o: '{tmp}/r.toml' has extension 'toml'"),
    C("identify", "--model", "hand", "--parameters", "K", "--data", "x.csv",
      needle="--parameters: with --model hand each chain fits its default selection"),
    C("identify", "--model", "hand", "--chain", "pinky", "--data", "{replay_csv}",
      needle="--chain: unknown chain 'pinky' of the hand"),
    C("identify", "--model", "hand", "--data", "{replay_csv}", needle="recording"),
]
CLI["control"] += [
    C("control", "--log", "{tmp}/x.png", needle="--log: '{tmp}/x.png' has extension 'png'; expected one of .csv"),
    C("control", "--tau-max", "1e300", needle=f"--tau-max: 1e+300 N m {RANGE} [1e-12, 1e+06] N m"),
]
CLI["estimate"] += [
    C("estimate", "--torque-constant", "1e300", "--data", "x.csv", needle=f"--torque-constant: 1e+300 N m/A {RANGE}"),
    C("estimate", "--encoder-offset", "1e300", "--data", "{replay_csv}", needle=f"--encoder-offset: 1e+300 rad {RANGE}"),
    C("estimate", "--log", "{tmp}/e.txt", "--data", "x.csv", needle="--log: '{tmp}/e.txt' has "
      "extension 'txt'"),
]
CLI["identifiability"] += [C("identifiability", "--camera-times", "0.5,1e300",
                             needle=f"--camera-times: 1e+300 s (index 1) {RANGE} [0, 1e+06] s")]
CLI["identify"] += [C("identify", "--data", "x.csv", "--encoder-noise", "1e300",
                      needle=f"--encoder-noise: 1e+300 counts {RANGE} [0, 1e+09] counts"),
                    C("identify", "--data", "x.csv", "-o", "{tmp}/i.csv",
                      needle="-o: '{tmp}/i.csv' has extension 'csv'; expected one of .toml")]
CLI["experiment"] += [C("experiment", "--perturb", "0.1", "-o", "{tmp}/r.csv", "--true-params-out", "{tmp}/t.csv",
                        needle="--true-params-out: '{tmp}/t.csv' has extension 'csv'; expected one of .toml")]

CLI["experiment"] += [  # issue 52's silent cases
    C("experiment", "--model", "finger2", "--rig", "both", "--duration", "0.15", "-o", "{tmp}/r.csv",
      needle="duration: 0.15 s gives 75 samples to each of the 2 orientations; each needs at least 100")]
CLI["identify"] += [C("identify", "--model", "finger3", "--data", "{midblank_csv}", "--effects", "none",
                      needle="line 101 is empty between data rows (a lost sample")]
CLI["estimate"] += [C("estimate", "--model", "finger3", "--data", "{midblank_csv}",
                      needle="line 101 is empty between data rows (a lost sample")]

CLI_ROWS = [(cmd, row) for cmd, rows in CLI.items() for row in rows]


def test_every_command_has_rows():
    sub = next(a for a in cli.build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) <= set(CLI), f"commands without bad-input rows: {set(sub.choices) - set(CLI)}"


def _files_under(*dirs: Path) -> dict[str, tuple[int, int, int]]:
    """Every path under ``dirs`` with its (mode, size, mtime): a file written over, or replaced, counts."""
    out = {}
    for d in dirs:
        for p in d.rglob("*"):
            st = p.lstat()
            out[str(p)] = (st.st_mode, st.st_size, st.st_mtime_ns)
    return out


def _one_stderr_line(code: int, out: str, err: str, needle: str) -> None:
    assert code == 2, (code, err)
    assert out == ""
    assert err.endswith("\n") and err.count("\n") == 1, f"expected one stderr line, got {err!r}"
    assert needle in err, err
    assert "Traceback" not in err and "Warning" not in err


@pytest.mark.parametrize("cmd,row", CLI_ROWS, ids=[f"{c}:{' '.join(r.argv)[:120] or '-'}" for c, r in CLI_ROWS])
def test_cli_bad_input(cmd, row, tmp_path, monkeypatch, capfd):
    work = tmp_path / "work"
    work.mkdir()
    paths = bad_files(tmp_path)
    argv = [a.format(**paths) for a in row.argv]
    needle = row.needle.format(**paths)
    monkeypatch.chdir(work)
    before = _files_under(tmp_path)
    if row.fsize is None:
        code = cli.main(argv)
        out, err = capfd.readouterr()
    else:
        def limit() -> None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (row.fsize, row.fsize))

        env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), PYTHONDONTWRITEBYTECODE="1")
        r = subprocess.run([sys.executable, "-m", "alpes_dyn.cli", *argv], capture_output=True, text=True,
                           preexec_fn=limit, env=env, timeout=120)
        code, out, err = r.returncode, r.stdout, r.stderr
    _one_stderr_line(code, out, err, needle)
    assert _files_under(tmp_path) == before, "a file was left behind"


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"alpes-dyn {ad.__version__}"


def test_cli_warning_becomes_one_line(capfd, monkeypatch):
    """A numpy warning and native stderr text during a failing command end up in its one error line."""
    import warnings

    def noisy(args):
        os.write(2, b"Error:   something native\n   at line 1\n")
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        raise InputError("q: bad")

    parser = cli.build_parser

    def build():
        p = parser()
        sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
        sub.choices["dynamics"].set_defaults(func=noisy)
        return p

    monkeypatch.setattr(cli, "build_parser", build)
    code = cli.main(["dynamics"])
    out, err = capfd.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err == "alpes-dyn: error: q: bad [RuntimeWarning: overflow encountered in multiply (+2 more)]\n"


# ----------------------------------------------------------------------------- API
@dataclass(frozen=True)
class Api:
    """One bad call: the public name it exercises, the call (given the fixture namespace), the error."""

    api: str
    call: Callable[[Any], Any]
    error: type[AlpesDynError]
    needle: str


def _creep_of_constraint(*args):
    from alpes_dyn.model.friction import creep_of_constraint

    return creep_of_constraint(*args)


def A(api: str, call: Callable[[Any], Any], error: type[AlpesDynError], needle: str) -> Api:
    return Api(api, call, error, needle)


def _on_hand(name: str) -> Any:
    from alpes_dyn.estimation.experiments import on_hand

    return getattr(on_hand, name)


def _calibration(name: str) -> Any:
    from alpes_dyn.estimation.experiments import calibration

    return getattr(calibration, name)


def _check_command(*args: Any, **kw: Any) -> Any:
    from alpes_dyn.bench.interface import check_command

    return check_command(*args, **kw)


def _turned(name: str) -> Any:
    from alpes_dyn.estimation.experiments import turned

    return getattr(turned, name)


def _loopback(motors: tuple[str, ...] = ("finger",)) -> Any:
    from alpes_dyn.bench.interface import Loopback

    return Loopback(motor_names=motors)


def _branches():
    """The two-branch robot of :data:`BRANCHES_URDF` with its spec."""
    return ad.Model(BRANCHES_URDF, TransmissionSpec.from_toml(BRANCHES_SPEC))


class Ctx:
    """What the API rows work on: finger3, its state space, the broken files."""

    def __init__(self, d: Path) -> None:
        from alpes_dyn.symbolic.statespace import StateSpace

        self.d = d
        self.f = bad_files(d)
        self.m = ad.Model.alpes("finger3")
        self.ss = StateSpace(self.m, input="motor", output="encoder")
        self.z = np.zeros(3)


def _steploop(lifted=True, **kw):
    """A compiled loop of x_k+1 = 0.9 x_k + 0.05 w_k, its two numbers an input p (lifted) or literals."""
    import casadi as cs

    from alpes_dyn.simulation.codegen import CompiledStepLoop
    from alpes_dyn.symbolic.lifted import lift_constants

    x, w = cs.SX.sym("x"), cs.SX.sym("w")
    f = cs.Function("lin", [x, w], [0.9 * x + 0.05 * w])
    return CompiledStepLoop(lift_constants(f)[0] if lifted else f, "bad_lifted", threads=1, **kw)


def _ekf(c, **kw):
    from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter

    return ExtendedKalmanFilter(c.ss, 1e-3, **{"process_noise": 1e-9, "measurement_noise": 1e-7, **kw})


def _ukf(c, **kw):
    from alpes_dyn.estimation.observers.observers import UnscentedKalmanFilter

    return UnscentedKalmanFilter(c.ss, 1e-3, process_noise=1e-9, measurement_noise=1e-7, **kw)


def _sim_x0(c, x0):
    from alpes_dyn.simulation import simulate

    return simulate(c.m, x0, duration=0.01, dt=1e-3)


def _sim(c, **kw):
    from alpes_dyn.simulation import simulate

    return simulate(c.m, np.zeros(6), **{"duration": 0.01, "dt": 1e-3, **kw})


def _est(**kw):
    from alpes_dyn.estimation.observers.scenario import run_estimation

    return run_estimation("ekf", **kw)


def _rollout(c, **kw):
    from alpes_dyn.simulation import compile_rollout

    return compile_rollout(c.m, **{"dt": 1e-3, **kw})


def _design(**kw):
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign

    return ExperimentDesign(**{"duration": 0.2, "stick_seconds": 0.0, **kw})  # no stiction ramp: 0.2 s to simulate


def _exp(**kw):
    """finger2's experiment of :func:`_design` (0.2 s); without arguments the one recording every row that only needs
    a valid recording shares (simulated once per process, each row given its own copy)."""
    from alpes_dyn.estimation.experiments.experiment import experiment

    if not kw:
        return copy.deepcopy(_shared_exp())
    return experiment(**{"model": "finger2", "design": _design(), **kw})


@functools.lru_cache(maxsize=1)
def _shared_exp():
    """The recording of ``_exp()``, simulated once (the experiment trims its bias by hundreds of static balances:
    seconds, repeated by each identify row before this)."""
    from alpes_dyn.estimation.experiments.experiment import experiment

    return experiment(model="finger2", design=_design())


def _model_exp(nominal, **kw):
    from alpes_dyn.estimation.experiments.experiment import model_experiment

    return model_experiment(nominal, **{"design": _design(), **kw})


def _model_torque(nominal, **kw):
    from alpes_dyn.estimation.experiments.experiment import model_experiment_torque

    return model_experiment_torque(nominal, **{"design": _design(), **kw})


def _example_mjcf(name):
    from alpes_dyn.model.mjcf_import import example_mjcf_path

    return example_mjcf_path(name)


def _ident_urdf(names, urdf=None, value=0.05):
    """identified_urdf of a made-up fit of ``names`` on the URDF robot, every value ``value``."""
    import types

    from alpes_dyn.estimation.identification.identified_spec import identified_urdf

    p = len(names)
    res = types.SimpleNamespace(names=tuple(names), values=np.full(p, value), std=np.full(p, 1e-5),
                                recording_path=None, model=ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(ROBOT_SPEC)),
                                trustworthy=True)
    return identified_urdf(res, ROBOT_URDF if urdf is None else urdf)


def _ident_mjcf(c, names, value=0.05, base=None):
    """identified_mjcf of a made-up fit of ``names`` on the one-hinge MJCF (ARM_MJCF) imported, every value
    ``value``, into a file beside it."""
    import types
    import warnings

    from alpes_dyn.estimation.identification.identified_spec import identified_mjcf

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = ad.Model.from_mjcf(c.f["arm_xml"])
    p = len(names)
    res = types.SimpleNamespace(names=tuple(names), values=np.full(p, value), std=np.full(p, 1e-5),
                                recording_path=None, model=model, trustworthy=True)
    return identified_mjcf(res, model.spec if base is None else base, c.f["arm_xml"], c.d / "ident.xml")


def _update_mjcf(c, mjcf=None, out=None, **kw):
    """updated_mjcf of the one-hinge MJCF (or ``mjcf``) into a file beside it (or ``out``)."""
    from alpes_dyn.model.mjcf_update import updated_mjcf

    return updated_mjcf(c.f["arm_xml"] if mjcf is None else mjcf, c.d / "o.xml" if out is None else out, **kw)


def _ident_spec(names, base=None, masses="refuse"):
    """identified_spec of a made-up fit of ``names`` on the URDF robot (no fit run: the refusals come first)."""
    from alpes_dyn.estimation.identification.identification import IdentificationResult
    from alpes_dyn.estimation.identification.identified_spec import identified_spec

    spec = TransmissionSpec.from_toml(ROBOT_SPEC)
    p = len(names)
    z = np.zeros(p)
    res = IdentificationResult(names=tuple(names), values=z + 0.05, std=z + 1e-5, initial=z + 0.05, units=("",) * p,
                               correlation=np.eye(p), residual_rms=0.5, iterations=1, converged=True, seconds=0.0,
                               compile_seconds=0.0, states=np.zeros((1, 6)), node_times=np.zeros(1),
                               model=ad.Model(ROBOT_URDF, spec))
    return identified_spec(res, spec if base is None else base, masses)


def _replay(c, **kw):
    from alpes_dyn.estimation.experiments.recording import read_recording
    from alpes_dyn.estimation.observers.replay import estimate_recording

    kw = {"recording": read_recording(c.f["replay_csv"], c.m), "model": c.m, **kw}
    return estimate_recording(**kw)


def _pp(**kw):
    from alpes_dyn.estimation.experiments.experiment import perturbed_params

    return perturbed_params(**kw)


def _ident(c, recording=None, **kw):
    from alpes_dyn.estimation.identification.identification import identify

    if recording is None:
        recording = _exp()
    return identify(ad.Model.alpes("finger2", friction=True), recording, **kw)


def _ident3(path, **kw):
    from alpes_dyn.estimation.identification.identification import identify

    return identify(ad.Model.alpes("finger3", friction=True), path, **kw)


def _diverging():
    """A Recording object (no reader's range check) whose encoder jumps to 1e15 counts: the fit overflows, and
    identify names the column (its unit check made where a fit diverges)."""
    import dataclasses

    rec = _exp()
    enc = rec.encoder.copy()
    enc[100:] = 1e15
    return dataclasses.replace(rec, encoder=enc)


def _adq(name, *args):
    from alpes_dyn.estimation.identification import adequacy

    return getattr(adequacy, name)(*args)


def _pdyn(c, parameters):
    from alpes_dyn.symbolic.parametric import ParametricDynamics

    return ParametricDynamics(c.m, parameters)


def _idf(**kw):
    from alpes_dyn.analysis.identifiability import identifiability

    return identifiability(**{"system": "finger2", "parameters": "K", **kw})


def _fim(c, **kw):
    from alpes_dyn.analysis.identifiability import fisher_information

    kw = {"model": c.m, "parameters": "K", "U": np.full(10, 0.02), **kw}
    return fisher_information(**kw)


def _stops(model, **kw):
    from alpes_dyn.model.stops import JointStops

    return JointStops.of(model, **kw)


def _cable(*args, **kw):
    from alpes_dyn.symbolic.elastic_tendon import ElasticTendon
    return ElasticTendon.from_cable(*args, **kw)


def _tendon_of(model, **kw):
    from alpes_dyn.model.tendon import ElasticTendon
    return ElasticTendon.of(model, **kw)


def _model_mjcf(model, **kw):
    from alpes_dyn.model.mjcf_export import model_mjcf
    return model_mjcf(model, **kw)


def _tendon(*args):
    from alpes_dyn.symbolic.elastic_tendon import ElasticTendon
    return ElasticTendon(*args)


def _curved():
    """finger3's URDF with one motor whose ratio on j1 changes with q_1 (a ratio_curve)."""
    from alpes_dyn.model.spec import Motor, TransmissionSpec

    return ad.Model(FINGER3, TransmissionSpec(motors=(Motor("m", {"j1": 1.0, "j2": 1.0}, ratio_curve={"j1": (0.1,)}),),
                                              name="curved"))


def _ses(model, tendon, **kw):
    from alpes_dyn.symbolic.elastic_tendon import SeriesElasticSystem
    return SeriesElasticSystem(model, tendon, **kw)


def _nd(v, names):
    from alpes_dyn.analysis.identifiability import name_direction

    return name_direction(v, names)



def _harm():
    return __import__("alpes_dyn.estimation.identification.harmonics", fromlist=["x"])


def _realism():
    return __import__("alpes_dyn.studies.realism", fromlist=["x"])

API: list[Api] = [
    # Model construction and files
    A("Model", lambda c: ad.Model(FINGER3, gravity="abc"), ModelError, "gravity: expected 3 finite numbers"),
    A("Model", lambda c: ad.Model(FINGER3, gravity=[0.0, -9.81]), ModelError, "gravity: expected 3 finite numbers"),
    A("Model", lambda c: ad.Model(FINGER3, gravity=[0, 0, 1j]), ModelError, "gravity: complex values"),
    A("Model", lambda c: ad.Model(123), ModelError, "urdf: expected URDF text"),
    A("Model", lambda c: ad.Model(URDFS["negmass_urdf"]), ModelError, "link 'p3': mass must be >= 0 kg"),
    A("Model", lambda c: ad.Model(URDFS["massless_urdf"]), ModelError, "joint 'j3' moves no mass"),
    A("Model", lambda c: ad.Model(URDFS["continuous_urdf"]), ModelError,
      "joint 'j2' is continuous (unbounded); give it limits as a revolute joint"),
    A("Model", lambda c: ad.Model(URDFS["zeroaxis_urdf"]), ModelError, "joint 'j2' has the zero axis xyz='0 0 0'"),
    A("Model", lambda c: ad.Model(URDFS["nanaxis_urdf"]), ModelError, "joint 'j2': axis xyz='0 nan 1' is not finite"),
    A("Model", lambda c: ad.Model(URDFS["planar_urdf"]), ModelError, "joint 'j2' is planar"),
    A("Model", lambda c: ad.Model(URDFS["zero_mass_inertia_urdf"]), ModelError, "zero mass with a non-zero inertia"),
    A("Model", lambda c: ad.Model(URDFS["triangle_urdf"], check_inertia="strict"), ModelError, "triangle inequality"),
    A("Model", lambda c: ad.Model(URDFS["triangle_urdf"], check_inertia="loose"), ModelError,
      "check_inertia: unknown mode 'loose'"),
    A("Model", lambda c: ad.Model(URDFS["indefinite_urdf"], check_inertia="relaxed"), ModelError,
      "not positive semidefinite"),
    A("Model", lambda c: ad.Model(URDFS["no_limits_urdf"]), ModelError, "does not specify limits"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["binary_urdf"]), ModelError, "not UTF-8 text"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["latin1_urdf"]), ModelError, "not UTF-8 text (byte 0xe9"),
    A("Model", lambda c: ad.Model.from_urdf_file(""), ModelError, "URDF file: empty file name"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["dir"]), ModelError, "is a directory"),
    A("Model", lambda c: ad.Model.from_urdf_file(None), ModelError, "expected a file path"),
    A("Model", lambda c: ad.Model.alpes("finger4"), ModelError, "unknown model 'finger4'"),
    A("Model", lambda c: ad.Model.alpes("finger3", spring="linear"), ModelError, "unknown spring model"),
    A("Model", lambda c: ad.Model.alpes("finger3", params=c.f["binary_toml"]), ModelError, "not UTF-8 text"),
    A("Model", lambda c: ad.Model.alpes("finger3", params=""), ModelError, "parameter file: empty file name"),
    A("Model", lambda c: ad.Model.alpes("finger3", chain="pinky"), ModelError,
      "chain: unknown finger 'pinky' (expected one of index, middle, ring, little)"),
    A("Model", lambda c: ad.Model.alpes("hand", chain="index"), ModelError, "chain: only a finger model"),
    A("Model", lambda c: ad.Model.alpes("thumb", chain="thumb"), ModelError, "chain: only a finger model"),
    # Model evaluation
    A("Model", lambda c: c.m.forward_dynamics(c.z, c.z, c.z, F="abc"), InputError, "F: expected F_z or 3 numbers"),
    A("Model", lambda c: c.m.forward_dynamics(c.z, c.z, c.z, F=[0, 0, np.nan]), InputError, "F: contains NaN"),
    A("Model", lambda c: ad.Model.alpes("finger3", rotor_inertia=True).forward_dynamics(c.z, c.z, np.array([0, np.inf, 0])),
      InputError, "tau: contains NaN or inf"),
    A("Model", lambda c: ad.Model.alpes("finger3", rotor_inertia=True).forward_dynamics(np.array([np.nan, 0, 0]), c.z, c.z),
      InputError, "q: contains NaN or inf"),
    A("Model", lambda c: c.m.forward_dynamics(np.array([0.1 + 1j, 0, 0]), c.z, c.z), InputError,
      "q: complex values are not supported"),
    A("Model", lambda c: c.m.inertia_matrix([0.1j, 0, 0]), InputError, "q: complex values are not supported"),
    A("Model", lambda c: c.m.inverse_dynamics(c.z, c.z, "abc"), InputError, "a: expected 3 numbers"),
    A("Model", lambda c: c.m.gravity_torque(np.zeros(4)), InputError, r"q: expected shape (3,), got (4,)"),
    A("Model", lambda c: c.m.fingertip_jacobian(c.z, "nail"), ModelError, "unknown tip/frame 'nail'"),
    A("Model", lambda c: ad.Model(URDFS["twoleaf_urdf"]).fingertip_jacobian(c.z), ModelError,
      "tip: model 'alpes_finger3' names no tip and its URDF has 2 leaf frames (nail, tip); name it"),
    A("Model", lambda c: ad.Model(URDFS["twoleaf_urdf"]).default_tip, ModelError, 'tips = ["<frame>"] in the spec'),
    A("Model", lambda c: c.m.random_state("abc"), InputError, "rng: expected a numpy Generator"),
    A("Model", lambda c: c.m.random_state(-1), InputError, "rng: expected a numpy Generator"),
    A("Model", lambda c: c.m.random_state(0, speed=-1.0), InputError, "speed: expected a finite number >= 0"),
    A("Model", lambda c: c.m.random_state(0, size=-2), InputError, "size: expected an integer >= 0"),
    # JointExtras
    A("JointExtras", lambda c: ad.JointExtras(-np.ones(3), c.z, c.z, c.z), ModelError,
      "extras.stiffness: must be >= 0 (got -1 at index 0)"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, c.z, np.array([0, -0.1, 0])), ModelError,
      "extras.viscous: must be >= 0 (got -0.1 at index 1)"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, np.array([0, np.nan, 0]), c.z), ModelError,
      "extras.coulomb: contains NaN"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, -c.z - 1, c.z, c.z), ModelError, "extras.armature: must be >= 0"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, np.zeros(2), c.z, c.z), ModelError,
      "extras.armature: expected shape (3,)"),
    A("JointExtras", lambda c: ad.JointExtras(np.zeros((3, 1)), c.z, c.z, c.z), ModelError,
      "extras.stiffness: expected a 1-D array"),
    A("JointExtras", lambda c: ad.JointExtras(c.z + 1j, c.z, c.z, c.z), ModelError, "extras.stiffness: expected a 1-D"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, c.z, c.z, smooth_velocity=0.0), ModelError,
      "extras.smooth_velocity: expected a finite number > 0"),
    A("JointExtras", lambda c: ad.Model(FINGER3, extras=ad.JointExtras.zeros(2)), ModelError,
      "extras.stiffness: expected shape (3,)"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, c.z, c.z, rest=np.zeros(2)), ModelError,
      "extras.rest: expected shape (3,) like extras.stiffness (rest angles, rad), got shape (2,)"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, c.z, c.z, rest=np.array([0, np.inf, 0])), ModelError,
      "extras.rest: contains NaN or inf"),
    A("JointExtras", lambda c: ad.JointExtras(c.z, c.z, c.z, c.z, rest="abc"), ModelError, "extras.rest: expected shape"),
    # parameter files and URDF generation
    A("load_params", lambda c: ad.load_params(c.f["binary_toml"]), ModelError, "not UTF-8 text (byte 0x80"),
    A("load_params", lambda c: ad.load_params(c.f["latin1_toml"]), ModelError, "not UTF-8 text (byte 0xe9"),
    A("load_params", lambda c: ad.load_params(""), ModelError, "parameter file: empty file name"),
    A("load_params", lambda c: ad.load_params(c.f["dir"]), ModelError, "is a directory"),
    A("load_params", lambda c: ad.load_params(c.f["negative_k_toml"]), ModelError, "finger.K: value must be >= 0"),
    A("load_params", lambda c: ad.load_params(c.f["negative_compliance_toml"]), ModelError,
      "transmission.tendon_compliance: value must be >= 0 (got -0.1"),
    A("load_params", lambda c: ad.load_params(c.f["pinky_toml"]), ModelError, "finger.pinky: unknown key"),
    A("load_params", lambda c: ad.load_params(c.f["short_index_toml"]), ModelError,
      "finger.index.K: value must be a list of 3 numbers"),
    A("load_params", lambda c: ad.load_params(c.f["fifo"]), ModelError, "is a FIFO (named pipe), expected a regular"),
    A("load_params", lambda c: ad.load_params("/dev/zero"), ModelError, "'/dev/zero': is a character device"),
    A("load_params", lambda c: ad.load_params("x\0.toml"), ModelError, "parameter file: the file name 'x\\x00.toml' "
      "contains a NUL byte"),
    A("load_params", lambda c: ad.load_params(c.f["bigint_toml"]), ModelError, "integer of 401 digits"),
    A("load_params", lambda c: ad.load_params(c.f["deep_toml"]), ModelError, "nested more than 32 deep"),
    A("load_params", lambda c: ad.load_params(c.f["half_count_toml"]), ModelError,
      "transmission.encoder_counts: value must be a whole number, got 4096.5"),
    A("load_params", lambda c: ad.load_params(c.f["mm_toml"]), ModelError,
      "finger.r.unit: the value is read in 'm', got 'mm'"),
    A("load_params", lambda c: ad.load_params(c.f["halfdelay_toml"]), ModelError,
      "transmission.torque_delay: value must be a whole number, got 1.5"),
    A("load_params", lambda c: ad.load_params(c.f["longdelay_toml"]), ModelError,
      "transmission.torque_delay: 500 samples is outside the accepted range [0, 100] samples"),
    A("load_params", lambda c: ad.load_params(c.f["countsoffset_toml"]), ModelError,
      "finger.encoder_offset.unit: the value is read in 'rad', got 'counts'"),
    A("estimate_recording", lambda c: _replay(c, model=ad.Model.alpes("finger3", params=c.f["untrusted_toml"])),
      ModelError, "params: '{untrusted_toml}' is marked not trustworthy (finger: the fit did not converge (lost "
      "basin)); force=True uses it anyway"),
    A("run_control", lambda c: __import__("alpes_dyn.control", fromlist=["x"]).run_control(
        "sensor", params=c.f["untrusted_toml"], duration=0.6), ModelError, "params: '{untrusted_toml}' is marked not "
      "trustworthy"),
    A("scenario_filter", lambda c: __import__("alpes_dyn.estimation.cexport.cexport", fromlist=["x"]).scenario_filter(
        params=c.f["untrusted_toml"]), ModelError, "is marked not trustworthy"),
    A("block_controller", lambda c: __import__("alpes_dyn.control.cexport", fromlist=["x"]).block_controller(
        params=c.f["untrusted_toml"]), ModelError, "is marked not trustworthy"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["big_urdf"]), ModelError, "over the limit of 16777216 bytes"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["fifo"]), ModelError, "is a FIFO"),
    A("Model", lambda c: ad.Model.from_mjcf(c.f["big_urdf"]), ModelError, "mjcf '{big_urdf}': 16777217 bytes, over the"),
    A("Model", lambda c: ad.Model(URDFS["mimic_urdf"].replace('<mimic joint="j1"/>', '<mimic joint="j9"/>')),
      ModelError, "joint 'j2': <mimic joint='j9'> names no joint of the URDF"),
    A("Model", lambda c: ad.Model(URDFS["mimic_urdf"].replace('<joint name="j3" type="revolute">',
                                                              '<joint name="j3" type="revolute"><mimic joint="j2"/>')),
      ModelError, "joint 'j3': <mimic joint='j2'> follows a joint that is itself a mimic"),
    A("Model", lambda c: ad.Model(URDFS["mimic_urdf"].replace('<mimic joint="j1"/>', '<mimic/>')), ModelError,
      "joint 'j2': <mimic> has no joint= attribute"),
    A("Model", lambda c: ad.Model(URDFS["mimic_urdf"].replace('<mimic joint="j1"/>',
                                                              '<mimic joint="j1" offset="1e999"/>')),
      ModelError, "joint 'j2': <mimic offset='1e999'> is not a finite number"),
    A("Model", lambda c: ad.Model(FINGER3.replace('<joint name="j1" type="revolute">',
                                                  '<joint name="j1" type="revolute"><mimic joint="j2"/>', 1)),
      ModelError, "URDF could not be parsed by Pinocchio: The parent joint of the mimic joint is not in the kinematic "
      "tree ('j1' follows 'j2'; Pinocchio needs the joint followed before its mimic"),
    A("Model", lambda c: ad.Model(URDFS["mimic_urdf"], TransmissionSpec.from_toml('[stiffness]\nj2 = 0.1\n')),
      ModelError, "stiffness.j2: joint 'j2' is a mimic joint"),
    A("Model", lambda c: ad.Model.from_mjcf(_MJCF_EQ.format('<connect body1="a" body2="world" anchor="0 0 0"/>')),
      ModelError, "mjcf: equality 'equality0' is a connect between 'a' and 'world': a closed kinematic loop; the "
      "library models kinematic trees"),
    A("Model", lambda c: ad.Model.from_mjcf(_MJCF_EQ.format('<weld name="w" body1="b" body2="world"/>')),
      ModelError, "mjcf: equality 'w' is a weld between 'b' and 'world': a closed kinematic loop"),
    A("Model", lambda c: ad.Model.from_mjcf(_MJCF_FLIP), ModelError,
      "mjcf: spatial tendon 'SE' (actuator 'SE'): its side site 'in' is inside its wrapping geom 'shoulder' (MuJoCo "
      "then finds the path by Newton's method"),
    A("Model", lambda c: ad.Model.from_mjcf(_MJCF_EQ.format('<joint name="e" joint1="k" joint2="j" polycoef="0 1 2 0 0"/>')),
      ModelError, "mjcf: equality 'e' on joint 'k' is not a linear coupling of two joints"),
    A("Model", lambda c: ad.Model.from_mjcf(_MJCF_EQ.format('<joint joint1="k"/>')),
      ModelError, "mjcf: equality 'equality0' on joint 'k' is not a linear coupling of two joints"),
    A("Model", lambda c: ad.Model.from_mjcf(ARM_MJCF, hold="ja"), ModelError,
      "hold: expected a list of joint names, got 'ja'"),
    A("Model", lambda c: ad.Model.from_mjcf(ARM_MJCF, hold=["ja", 3]), ModelError,
      "hold: expected a list of joint names, got ['ja', 3]"),
    A("example_mjcf_path", lambda c: _example_mjcf("allegro"), ModelError,
      "unknown example MJCF 'allegro' (shipped: shadow_hand)"),
    A("example_mjcf_path", lambda c: _example_mjcf(3), ModelError, "unknown example MJCF 3 (shipped: shadow_hand)"),
    A("Model", lambda c: ad.Model(FINGER3, gravity=[True, False, True]), ModelError, "gravity: expected 3 finite"),
    A("simulate", lambda c: _sim(c, inputs=np.full(3, 1e-3 + 1e-3j)), InputError, "inputs: complex values"),
    A("simulate", lambda c: _sim(c, method="cvodes", rtol="x"), InputError, "rtol: expected a positive number, got 'x'"),
    A("simulate", lambda c: _sim(c, method="cvodes", atol=-1.0), InputError, "atol: expected a positive finite number"),
    A("simulate", lambda c: _sim(c, inputs=np.ma.masked_array(np.zeros((10, 3)), mask=np.eye(10, 3))), InputError,
      "inputs: masked values are not supported"),
    A("Model", lambda c: c.m.inertia_matrix(np.ma.masked_array([0.1, 0.2, 0.3], mask=[1, 0, 0])), InputError,
      "q: masked values are not supported"),
    A("Model", lambda c: ad.Model(URDFS["star_urdf"]), ModelError, "URDF: 201 moving joints, over the limit of 200"),
    A("simulate", lambda c: _sim(c, inputs=["0", "0", "0"]), InputError, "inputs: expected an array of numbers"),
    A("simulate", lambda c: _sim(c, inputs=np.zeros(3, bool)), InputError, "inputs: expected an array of numbers or a "
      "callable of time, got booleans"),
    A("simulate", lambda c: _sim(c, duration=1e308), InputError, "duration: 1e+308 s at dt = 0.001 s is more than 2^53"),
    A("simulate", lambda c: _sim(c, duration=10**400), InputError, "duration: expected a positive finite number"),
    A("simulate", lambda c: _sim(c, duration=True), InputError, "duration: expected a positive number of seconds"),
    A("StateSpace", lambda c: __import__("alpes_dyn.symbolic.statespace", fromlist=["x"]).StateSpace(
        c.m, output=["encoder", "encoder"]), InputError, "output: 'q_m_finger' is asked for twice"),
    A("StateSpace", lambda c: c.ss.linearize(np.zeros(6), np.zeros(1), dt=1e308), InputError,
      "dt: 1e+308 s is outside [1e-09, 1e+06] s"),
    A("compile_rollout", lambda c: _rollout(c, dt=1e-320), InputError, "dt: 9.99989e-321 s is outside [1e-09, 1e+06] s"),
    A("ExtendedKalmanFilter", lambda c: __import__("alpes_dyn.estimation.observers.observers", fromlist=["x"]).ExtendedKalmanFilter(
        c.ss, 1e300, process_noise=1e-9, measurement_noise=1e-7), InputError, "dt: 1e+300 s is outside"),
    A("fisher_information", lambda c: _fim(c, U=[10**400] * 10), InputError, "U: expected an array of numbers, got a "
      "number too large"),
    A("fisher_information", lambda c: _fim(c, U=[True] * 10), InputError, "U: expected an array of numbers, got "
      "booleans"),
    A("run_estimation", lambda c: _est(duration=10**400), InputError, "duration: 1000000000000000000"),
    A("write_urdfs", lambda c: ad.write_urdfs("a\0b"), InputError, "directory: the folder name 'a\\x00b' contains a NUL"),
    A("simulate", lambda c: _sim(c, dt=True), InputError, "dt: expected a positive number of seconds, got True"),
    A("simulate", lambda c: _sim(c, dt=10**400), InputError, "dt: expected a positive number of seconds"),
    A("simulate", lambda c: _sim(c, dt="1e-3"), InputError, "dt: expected a positive number of seconds, got '1e-3'"),
    A("simulate", lambda c: _sim_x0(c, np.zeros(6) + 1j), InputError, "x0: complex values are not supported"),
    A("compile_rollout", lambda c: _rollout(c).rollout(np.zeros(6) + 1j, np.zeros((5, 3))), InputError,
      "x0_batch: complex values are not supported"),
    A("compile_rollout", lambda c: _rollout(c).rollout(np.zeros(6), np.zeros((5, 3), bool)), InputError,
      "U_batch: expected an array of inputs, got booleans"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c).run(np.zeros(6), np.ones(6), np.zeros((5, 1)) + 1j, np.zeros((6, 1))),
      InputError, "W: complex values are not supported"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c).run(np.zeros(6), np.ones(6), np.zeros((5, 1)), [["a"]] * 6),
      InputError, "Y: expected an array of measurements"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c).run(np.zeros(6), [True] * 6, np.zeros((5, 1)), np.zeros((6, 1))),
      InputError, "P0: expected 6 variances or an (6, 6) covariance, got booleans"),
    A("Model", lambda c: ad.Model(URDFS["many_links_urdf"]), ModelError, "URDF: 1001 links, over the limit of 1000"),
    A("Model", lambda c: ad.Model(URDFS["deep_urdf"]), ModelError, "is 101 joints deep, over the limit of 100"),
    A("Model", lambda c: ad.Model(URDFS["inverted_limit_urdf"]), ModelError, "limit lower 1.6 is above upper 0"),
    A("Model", lambda c: ad.Model(FINGER3, spec=c.f["fifo"]), ModelError, "spec file '{fifo}': is a FIFO"),
    A("write_urdfs", lambda c: ad.write_urdfs(_linked_dir(c)), InputError, "finger2.urdf' is a symbolic link"),
    A("load_params", lambda c: ad.load_params(c.f["xmlname_toml"]), ModelError,
      "palm.finger_names: 'in<d&\"ex' is not a name: letters, digits and '_'"),
    A("write_params", lambda c: _write_params(c.f["link"]), ModelError, "is a symbolic link; refusing to replace it"),
    A("write_params", lambda c: _write_params(c.f["fifo"]), ModelError, "is a FIFO (named pipe); only a regular file"),
    A("write_recording", lambda c: _write_rec(c.f["device"]), RecordingError, "is a character device"),
    A("read_recording", lambda c: _read_rec(c.f["fifo"]), RecordingError, "recording '{fifo}': is a FIFO"),
    A("read_recording", lambda c: __import__("alpes_dyn.estimation.experiments.recording", fromlist=["x"]).read_recording(
        c.f["rec3_csv"], "finger3"), RecordingError,
      "model: expected an alpes_dyn Model (it names the columns), got str"),
    A("read_recording", lambda c: _read_rec(c.f["unders_csv"]), RecordingError, "not a number ('1_0"),
    A("read_recording", lambda c: _read_rec(c.f["runshort_csv"]), RecordingError, "each run needs at least 100"),
    A("read_recording", lambda c: _read_rec(c.f["ma_csv"]), RecordingError, "column 'torque_finger': values up to"),
    A("read_recording", lambda c: _read_rec(c.f["rad_csv"]), RecordingError, "the motor angle in radians?"),
    A("read_recording", lambda c: _read_rec(c.f["deg_csv"]), RecordingError, "the motor angle in degrees?"),
    A("read_recording", lambda c: _read_rec(c.f["ms_csv"]), RecordingError, "t in milliseconds?"),
    A("read_recording", lambda c: _read_rec(c.f["macurrent_csv"], 0.05), RecordingError,
      "column 'current_finger': values up to"),
    A("join_runs", lambda c: _join_runs([]), RecordingError, "join_runs: expected one or more Recordings"),
    A("join_runs", lambda c: _join_runs([_read_rec(c.f["rec3_csv"]), "b.csv"]), RecordingError,
      "join_runs: expected one or more Recordings"),
    A("join_runs", lambda c: _join_runs([_read_rec(c.f["rec3_csv"]), _slow(_read_rec(c.f["rec3_csv"]))]),
      RecordingError, "join_runs: sample period 0.002 s differs from the first recording's 0.001 s"),
    A("join_runs", lambda c: _join_runs([_read_rec(c.f["rec3_csv"]), _slow(_read_rec(c.f["rec3_csv"]), None)]),
      RecordingError, "join_runs: gravity is in some of the recordings only"),
    A("read_recording", lambda c: __import__("alpes_dyn.estimation.experiments.recording", fromlist=["x"]).read_recording(
        c.f["rec3_csv"], c.m, ignore_others_of="hand"), RecordingError,
      "ignore_others_of: expected an alpes_dyn Model or None, got str"),
    # a sub-model on some branches (Model.subtree)
    A("Model.subtree", lambda c: _branches().subtree("fc"), ModelError, "motors: unknown motor 'fc' (motors: fa, fb, "
      "across)"),
    A("Model.subtree", lambda c: _branches().subtree([]), ModelError, "motors: expected a motor name or a non-empty "
      "list of motor names, got []"),
    A("Model.subtree", lambda c: _branches().subtree(3), ModelError, "motors: expected a motor name or a non-empty "
      "list of motor names, got 3"),
    A("Model.subtree", lambda c: _branches().subtree(["fa", 1]), ModelError, "motors: expected a motor name"),
    A("Model.subtree", lambda c: _branches().subtree("fa"), ModelError, "motors fa: motor 'across' drives joint 'ja' "
      "of their branches and joint 'jb' of another branch"),
    A("Model.subtree", lambda c: ad.Model(FINGER3).subtree("finger"), ModelError, "motors: model 'alpes_finger3' has "
      "no spec with motors"),
    A("subtree_model", lambda c: __import__("alpes_dyn.model.subtree", fromlist=["x"]).subtree_model(
        ad.Model(BRANCHES_URDF.replace("<joint name='jb' type='revolute'>", "<joint name='jb' type='revolute'><mimic "
                                       "joint='ja'/>"), TransmissionSpec.from_toml('[[motor]]\nname = "fa"\njoints = '
                                                                                   '{ ja = 1.0 }\n')), "fa"),
      ModelError, "motors fa: mimic joint 'jb' follows 'ja', and joint 'ja' is in their branches, 'jb' in another"),
    A("read_recording", lambda c: _read_rec(c.f["grav149_csv"]), RecordingError, "gravity has norm 14.9 m/s^2"),
    A("read_recording", lambda c: _read_rec(c.f["longcell_csv"]), RecordingError, "a cell of 300 characters"),
    A("read_recording", lambda c: _read_rec(c.f["current_csv"], True), RecordingError,
      "torque_constant: expected a positive number of N m/A, got True"),
    A("read_recording", lambda c: _read_rec(c.f["current_csv"], "0.05"), RecordingError,
      "torque_constant: expected a positive number of N m/A, got '0.05'"),
    A("read_recording", lambda c: _read_rec(c.f["current_csv"], np.float64(0.0)), RecordingError,
      "torque_constant: expected a positive number of N m/A, got 0.0"),
    A("read_recording", lambda c: _read_rec(c.f["enchuge_csv"]), RecordingError,
      "column 'encoder_finger' line 103: 1e+15 counts is beyond what the joint ranges allow"),
    A("check_outputs", lambda c: _outputs([("-o", c.f["hardlink"])], [("--params", c.f["params_toml"])]), InputError,
      "-o: '{hardlink}' is the input of --params"),
    A("check_outputs", lambda c: _outputs([("-o", c.d / "a.csv"), ("--log", str(c.d) + "//a.csv")]), InputError,
      "--log: '{tmp}/a.csv' is also the output of -o"),
    A("check_outputs", lambda c: _outputs([("-o", c.f["tmp"] + "/nodir/")]), InputError, "ends with '/'"),
    A("atomic_write", lambda c: _atomic(c.f["device"]), InputError, "is a character device"),
    A("read_text", lambda c: _read_text(c.f["big_urdf"]), InputError, "over the limit of 16777216 bytes"),
    A("read_text", lambda c: _read_text(c.f["latin1_urdf"]), InputError, "not UTF-8 text (byte 0xe9"),
    A("load_toml", lambda c: _toml("a = " + "9" * 401), InputError, "x: a: integer of 401 digits"),
    A("load_toml", lambda c: _toml("a = " + "[" * 100_000), InputError, "x: arrays or tables nested more than 32"),
    A("ControlScenario", lambda c: _control_sc(duration=0.52), InputError, "leaves less than 0.05 s after the settling"),
    A("ControlScenario", lambda c: _control_sc(duration=1e9), InputError, "duration: 1e+09 s is over the limit"),
    A("ControlScenario", lambda c: _control_sc(frame="tip"), InputError, "frame: applies to a URDF + spec model"),
    A("ControlScenario", lambda c: _control_sc(motor="finger"), InputError, "motor: applies to a URDF + spec model"),
    A("ControlScenario", lambda c: _control_sc(tau_max=0.1), InputError, "tau_max: applies to a URDF + spec model"),
    A("ControlScenario", lambda c: _control_sc(model=_control_robot(c), tau_max=-1.0), InputError,
      "tau_max: expected a positive motor torque limit in N m, got -1.0"),
    A("ControlScenario", lambda c: _control_sc(model=_control_robot(c), params="x.toml"), InputError,
      "params: applies to the Alpes fingers"),
    A("ControlScenario", lambda c: _control_sc(model=42), InputError, "model: the control scenario is defined for one"),
    A("run_control", lambda c: _run_control(c, frame="p3"), InputError, "frame: 'p3' is not a tip frame"),
    A("run_control", lambda c: _run_control(c, motor="flexor", frame="tip", contact_q=(0.1, np.nan, 0.2)), InputError,
      "contact_q: expected 3 finite joint angles"),
    A("place_block", lambda c: _place(c, approach=1.0), InputError, "approach: expected a number in (0, 1)"),
    A("place_block", lambda c: _place(c, tip_radius=0.0), InputError, "tip_radius: expected a number in (0, inf) m"),
    A("place_block", lambda c: _place(c, contact_q="abc"), InputError, "contact_q: expected 3 joint angles"),
    A("place_block", lambda c: _place(c, contact_q=(0.0, 0.0, 2.0)), InputError,
      "contact_q: the block cannot be placed: joint 'j3' at 2 rad is outside its range"),
    A("place_block", lambda c: _place_on(ad.Model(ROBOT_URDF)), InputError,
      "spec: model 'tendon_robot' has no transmission"),
    A("place_block", lambda c: _place(c, spec=ROBOT_CONTROL_SPEC.replace("gravity = [0.0, 0.0, 9.81]\n", "")
                                      .replace("j1 = 0.04", "j1 = 0.0").replace("j1 = 2.0, ", "")), InputError,
      "spec: the rest configuration (motors off) cannot be found: static equilibrium: singular stiffness"),
    A("ExperimentDesign", lambda c: _design(duration=1e308).check(), InputError, "duration: 1e+308 s is over the limit"),
    A("observability", lambda c: ad.observability("finger2", max_operations=10**20), InputError,
      "max_operations: 100000000000000000000 is over the limit of 50000000"),
    A("observability", lambda c: ad.observability("finger2", order=10**20), InputError, "order: 100000000000000000000 "
      "is over the limit of 1000"),
    A("check_duration", lambda c: _check_duration(10**400), InputError, "d: expected a finite number of seconds"),
    A("check_duration", lambda c: _check_duration("5"), InputError, "d: expected a number of seconds, got str"),
    A("InputError", lambda c: _raise_np(), InputError, "x: got 0.1 and 3, True"),
    A("urdf_string", lambda c: ad.urdf_string("palm"), ModelError, "unknown model 'palm'"),
    A("layout", lambda c: ad.layout("palm"), ModelError, "unknown model 'palm'"),
    A("write_urdfs", lambda c: ad.write_urdfs(c.f["file"]), InputError, "exists and is not a folder"),
    A("write_urdfs", lambda c: ad.write_urdfs(""), InputError, "directory: expected a folder path"),
    A("write_urdfs", lambda c: ad.write_urdfs(c.d / "w", params=c.f["dir"]), ModelError, "is a directory"),
    A("urdf_string", lambda c: ad.urdf_string("finger3", params=42), ModelError, "expected a file path, got int"),
    A("example_robot_urdf", lambda c: ad.example_robot_urdf("r2d2"), ModelError,
      "unknown example-robot-data robot 'r2d2'"),
    A("Transmission", lambda c: c.m.transmission.motor_positions("abc"), InputError, "q: expected joint angles"),
    A("Transmission", lambda c: c.m.transmission.joint_torque([1j]), InputError, "tau_m: complex values"),
    A("Transmission", lambda c: c.m.transmission.quantize("x"), InputError, "q_m: expected motor angles"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, [-1e-7]), InputError,
      "rotor_inertia: expected 1 finite numbers >= 0"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, None, [np.nan]),
      InputError, "tendon_compliance: expected 1 finite numbers (rad/(N m))"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, None, [1.0])
      .encoder_angles(np.zeros(3), [1.0, 2.0]), InputError, "tau_m: expected last dimension 1"),
    A("torque_before", lambda c: __import__("alpes_dyn.model.transmission", fromlist=["x"]).torque_before(1.0),
      InputError, "tau_m: expected one row per sample, got shape ()"),
    A("acceleration_before", lambda c: __import__("alpes_dyn.model.transmission", fromlist=["x"])
      .acceleration_before(np.zeros((1, 2)), 1e-3), InputError, "qd_m: expected two samples or more along axis 0"),
    A("acceleration_before", lambda c: __import__("alpes_dyn.model.transmission", fromlist=["x"])
      .acceleration_before("fast", 1e-3), InputError, "qd_m: expected motor velocities, got a string"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, None, [1.0])
      .encoder_angles(np.zeros((2, 3)), np.zeros((2, 1)), np.zeros((3, 1))), InputError,
      "qdd_m: expected the shape of tau_m (2, 1), got (3, 1)"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'tendon_compliance = "x"\n'),
      ModelError, "motor 'a'.tendon_compliance: expected a number, got 'x'"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'capstan = -0.1\n'),
      ModelError, "motor 'a'.capstan: expected a number >= 0, got -0.1"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'capstan = nan\n'),
      ModelError, "motor 'a'.capstan: expected a finite number, got nan"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  '[identified.capstan]\nb = 0.01\n'),
      ModelError, "identified.capstan.b: unknown motor 'b' (motors: a)"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, capstan=[-0.1]),
      InputError, "capstan: expected 1 finite numbers >= 0 (mu theta, dimensionless), got [-0.1]"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, capstan=[0.1, 0.2]),
      InputError, "capstan: expected 1 finite numbers >= 0"),
    A("StateSpace", lambda c: __import__("alpes_dyn.symbolic.statespace", fromlist=["x"]).StateSpace(
        ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(ROBOT_SPEC.replace("j3 = 2.0 }\n", "j3 = 2.0 }\ncapstan = 0.2\n",
                                                                           1))), input="motor")
      .input_torque(np.zeros(3), np.ones(1)), InputError, "v: motor torques through tendons with sheath friction"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'ratio_curve = { j2 = [0.1] }\n'),
      ModelError, "motor 'a'.ratio_curve.j2: joint 'j2' is not one of the motor's joints (j1)"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'ratio_curve = { j1 = [] }\n'),
      ModelError, "motor 'a'.ratio_curve.j1: expected a list of 1 to 16 coefficients"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'ratio_curve = { j1 = [0.1, "x"] }\n'),
      ModelError, "motor 'a'.ratio_curve.j1: expected a number, got 'x'"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'ratio_curve = [0.1]\n'),
      ModelError, "motor 'a'.ratio_curve: expected a table joint name -> [c_1, ..., c_P]"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'path = [1]\n'),
      ModelError, "motor 'a'.path: expected a table, got [1]"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'path = { points = [] }\n'),
      ModelError, "motor 'a'.path.frames: expected an array of tables"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml('[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n'
                                                                  'ratio_curve = { j1 = [0.1] }\n' + _PATH.format("j1")),
      ModelError, "motor 'a'.path: a motor has a path or a ratio_curve, not both"),
    A("Model", lambda c: ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(
        '[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n' + _PATH.format("nope"))),
      ModelError, "motor 'a'.path: joint 'nope' is not a joint of the model"),
    A("Model", lambda c: ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(
        '[[motor]]\nname = "a"\njoints = { j1 = 2.0 }\n' + _PATH.format("j1"))),
      ModelError, "motor 'a'.joints.j1: the path's ratio at q = 0 is 0.07071067812, not 2"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.ones((1, 3)), np.ones((1, 3)), 4096.0, None, None,
                                                np.ones((1, 1, 3))).joint_torque([1.0]), InputError,
      "q: a transmission whose ratios change with the joints (ratio_curve) needs the joint angles"),
    A("Transmission", lambda c: ad.Transmission(("a",), np.eye(1, 3), np.ones((1, 3)), 4096.0, None, None,
                                                np.ones((1, 1, 3))), InputError,
      "ratio_curve: expected finite coefficients, only on a joint its motor drives"),
    A("fit_ratio_curve", lambda c: __import__("alpes_dyn.model.ratio_curve", fromlist=["x"])
      .fit_ratio_curve([0.0, 1.0], [1.0, 1.0], 2), InputError, "q, ratio: expected as many finite samples"),
    A("fit_ratio_curve", lambda c: __import__("alpes_dyn.model.ratio_curve", fromlist=["x"])
      .fit_ratio_curve([0.0, 1.0], [1.0, 1.0], 17), InputError, "degree: expected an integer in 1..16"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[identified.coulomb]\nj1 = 1e-5\n"),
      ModelError, "identified.coulomb.j1: the spec has no coulomb value for joint 'j1'"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[identified]\nresidual_rms = -1\n"),
      ModelError, "identified.residual_rms: expected a non-negative number"),
    A("TransmissionSpec", lambda c: TransmissionSpec(identified=[1]), ModelError, "identified: expected a table"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + '[rest_angle]\nj1 = "x"\n'), ModelError,
      "rest_angle.j1: expected a number, got 'x'"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[rest_angle]\nj1 = nan\n"), ModelError,
      "rest_angle.j1: expected a finite number, got nan"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[rest_angle]\nj9 = 0.1\n"), ModelError,
      "rest_angle.j9: joint 'j9' has no spring (no [stiffness] value); a rest angle is where a spring exerts no torque"),
    A("TransmissionSpec", lambda c: TransmissionSpec(rest_angle=[0.1]), ModelError,
      "rest_angle: expected a table joint name -> number"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops]\nstiffness = 0.0\n"), ModelError,
      "stops.stiffness: expected a number > 0, got 0"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops]\ndamping = -1e-3\n"), ModelError,
      "stops.damping: expected a number >= 0, got -0.001"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + '[stops]\nstiffness = "x"\n'), ModelError,
      "stops.stiffness: expected a number, got 'x'"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops]\nstifness = 2.0\n"), ModelError,
      "stops.stifness: unknown key (expected stiffness or damping)"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops]\n"), ModelError,
      "stops: an empty table; give stiffness, damping or joints"),
    A("TransmissionSpec", lambda c: TransmissionSpec(stops=[2.0]), ModelError,
      "stops: expected a table (stiffness, damping, joints), got [2.0]"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops]\njoints = 2.0\n"), ModelError,
      "stops.joints: expected a table joint name -> {{stiffness, damping}}, got 2.0"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops.joints]\nj1 = 2.0\n"), ModelError,
      "stops.joints.j1: expected a table with stiffness and/or damping, got 2.0"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops.joints]\nj1 = { k = 2.0 }\n"),
      ModelError, "stops.joints.j1.k: unknown key (expected stiffness or damping)"),
    A("TransmissionSpec", lambda c: TransmissionSpec.from_toml(ROBOT_SPEC + "[stops.joints]\nj1 = { damping = nan }\n"),
      ModelError, "stops.joints.j1.damping: expected a finite number, got nan"),
    A("TransmissionSpec", lambda c: ad.Model(FINGER3, TransmissionSpec(stops={"joints": {"j9": {"stiffness": 1.0}}})),
      ModelError, "stops.joints.j9: unknown joint 'j9'"),
    A("mjcf_recording", lambda c: _mjcf_recording(None, 3, np.zeros((5, 1))), InputError,
      "model: expected an alpes_dyn Model with motors, got int"),
    A("mjcf_recording", lambda c: _mjcf_recording(12, None, np.zeros((5, 1))), InputError,
      "mjcf: expected MJCF text or the path of its file, got int"),
    A("mjcf_recording", lambda c: _mjcf_recording({"timestep": 3e-4}, None, np.zeros((5, 1))), InputError,
      "timestep: 0.0003 s does not divide the sample period 0.001 s"),
    A("mjcf_recording", lambda c: _mjcf_recording({}, None, np.zeros((5, 2))), InputError,
      "torque: expected finite motor torques of shape (N+1, 1), got shape (5, 2)"),
    A("mjcf_recording", lambda c: _mjcf_recording({}, None, np.zeros((5, 1)), q0=[0.1]), InputError,
      "q0: expected 3 finite joint angles (rad), got [0.1]"),
    A("mjcf_recording", lambda c: _mjcf_recording({}, None, np.zeros((5, 1)), seed=-1), InputError,
      "seed: expected a non-negative integer, got -1"),
    A("mjcf_recording", lambda c: _mjcf_recording("{d}/missing.xml".format(d=c.d), None, np.zeros((5, 1))),
      InputError, "missing.xml"),
    A("mjcf_recording", lambda c: _mjcf_recording({}, None, np.zeros((5, 1)), gravity=np.full((5, 3), np.nan)),
      InputError, "gravity: expected finite gravity vectors (m/s^2) of shape (5, 3), one per sample, got shape (5, 3)"),
    A("JointStops", lambda c: _stops(ad.Model(FINGER3.replace('lower="0.0" upper="1.5707963267948966"',
                                                              'lower="-1e4" upper="1e4"'),
                                              TransmissionSpec(stops={"joints": {"j1": {"stiffness": 1.0}}}))),
      InputError, "stops.joints.j1: joint 'j1' has no finite limit (URDF limits beyond 1e3 or none): no stop to hold it"),
    A("TransmissionSpec", lambda c: ad.Model(FINGER3, TransmissionSpec(stiffness={"j1": 0.1, "j9": 0.1},
                                                                          rest_angle={"j9": 0.1})), ModelError,
      "stiffness.j9: unknown joint 'j9'"),
    A("JointStops", lambda c: _stops(ad.Model(FINGER3, gravity=[0.0, 0.0, 0.0])), InputError,
      "stops: nothing pushes model 'alpes_finger3' into its joint stops (no gravity torque, no spring resting beyond a "
      "limit) to size them by; pass stiffness= (N m/rad) and damping= (N m s/rad), or give them in the --spec "
      "file's [stops] table"),
    A("JointStops", lambda c: _stops(c.m, stiffness=-1.0), InputError,
      "stiffness: expected a positive number of N m/rad or 3 of them (one per joint) (or None: sized to the robot), "
      "got -1.0"),
    A("JointStops", lambda c: _stops(c.m, damping=float("nan")), InputError,
      "damping: expected a number >= 0 of N m s/rad"),
    A("JointStops", lambda c: _stops(c.m, stiffness="2"), InputError, "stiffness: expected a positive number"),
    A("JointStops", lambda c: _stops(c.m, stiffness=[1.0, 2.0]), InputError,
      "stiffness: expected a positive number of N m/rad or 3 of them (one per joint), got shape (2,)"),
    A("JointStops", lambda c: _stops(c.m, stiffness=[1.0, 0.0, 2.0]), InputError,
      "stiffness: expected a positive number of N m/rad or 3 of them (one per joint) (or None: sized to the robot), "
      "got [1.0, 0.0, 2.0]"),
    A("JointStops", lambda c: _stops(c.m, damping=np.array([1e-3, np.nan, 1e-3])), InputError,
      "damping: expected a number >= 0 of N m s/rad or 3 of them"),
    A("JointStops", lambda c: _stops(c.m, stiffness=["a", 1, 2]), InputError, "stiffness: expected a positive number"),
    A("JointStops", lambda c: _stops(c.m, per_joint="yes"), InputError, "per_joint: expected True or False, got 'yes'"),
    A("JointStops", lambda c: _stops(ad.Model(FINGER3, gravity=[0.0, 0.0, 0.0]), per_joint=True), InputError,
      "stops: nothing pushes model 'alpes_finger3' into its joint stops"),
    A("JointStops", lambda c: _stops(ad.Model(FINGER3, gravity=[0.0, 0.0, 0.0]), damping=1.0), InputError,
      "stops: nothing pushes model 'alpes_finger3'"),  # d given, k still to size
    A("TransmissionSpec", lambda c: TransmissionSpec(identified={"record": 3}), ModelError,
      "identified.record: expected a table"),
    # any robot's experiment and identified spec (issue 17)
    A("model_experiment", lambda c: _model_exp("finger3"), InputError, "nominal: expected an alpes_dyn Model, got str"),
    A("model_experiment", lambda c: _model_exp(c.m, truth=ad.Model.alpes("finger2")), InputError,
      "truth: expected the nominal's joints j1, j2, j3"),
    A("model_experiment", lambda c: _model_exp(c.m, truth=3), InputError, "truth: expected an alpes_dyn Model"),
    A("model_experiment", lambda c: _model_exp(c.m, seed=-1), InputError, "seed: expected an integer from 0 to 9223372036854775807, got -1"),
    A("model_experiment", lambda c: _model_exp(ad.Model(ROBOT_URDF)), InputError, "nominal: model 'tendon_robot' has "
      "no motors"),
    A("model_experiment", lambda c: _model_exp(c.m, design=_design(dt=0.0)), InputError, "dt: expected a sample period"),
    A("model_experiment_torque", lambda c: _model_torque("finger3"), InputError,
      "nominal: expected an alpes_dyn Model, got str"),
    A("model_experiment_torque", lambda c: _model_torque(c.m, truth=ad.Model.alpes("finger2")), InputError,
      "truth: expected the nominal's joints j1, j2, j3"),
    A("model_experiment_torque", lambda c: _model_torque(ad.Model(ROBOT_URDF)), InputError,
      "nominal: model 'tendon_robot' has no motors"),
    # the experiment on the hand (issue 49): bad settings refused before the hand moves
    A("run_experiment", lambda c: _on_hand("run_experiment")(_loopback(), c.m, _design(orientations=((0, 0, -9.81),
                                                                                                      (0, 0, 9.81)))),
      InputError, "orientations: the experiment on the hand runs in one orientation"),
    A("run_experiment", lambda c: _on_hand("run_experiment")(_loopback(), c.m, stages=(0.5, 0.2)), InputError,
      "stages: expected non-decreasing fractions in (0, 1]"),
    A("run_experiment", lambda c: _on_hand("run_experiment")(_loopback(), c.m, hold=0.0), InputError,
      "hold: expected a number above 0.1"),
    A("run_experiment", lambda c: _on_hand("run_experiment")(_loopback(), c.m, calibration=3), InputError,
      "calibration: expected a Calibration of the hand's motors (finger)"),
    A("run_experiment", lambda c: _on_hand("run_experiment")(3, c.m), InputError, "hw: expected a HardwareInterface"),
    A("run_experiment", lambda c: _on_hand("run_experiment")(_loopback(), c.m, path=c.d / "r.txt"), InputError,
      "path"),
    # the experiment turned (estimation.experiments.turned): refused before any hand is asked for
    A("run_turned", lambda c: _turned("run_turned")(3, c.m), InputError,
      "hand_in: expected a callable rig -> HardwareInterface, got int"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, rigs="level"), InputError,
      "rigs: expected a sequence of rigs (level, hanging), got 'level'"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, rigs=("level", "sideways")),
      InputError, "rigs: expected each one of level, hanging, got 'sideways'"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, rigs=("level", "level")),
      InputError, "rigs: each rig once, got ['level', 'level']"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), "finger3"), InputError,
      "nominal: expected an alpes_dyn Model, got str"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, calibration=None), InputError,
      "calibration: each rig is calibrated in its own orientation"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, path=c.d / "r.txt"), InputError,
      "path"),
    A("run_turned", lambda c: _turned("run_turned")(lambda rig: _loopback(), c.m, _design(orientations=(
        (0, 0, -9.81), (0, 0, 9.81)))), InputError, "design: expected one orientation to turn, got 2"),
    A("rig_design", lambda c: _turned("rig_design")("hanging", 2.0, design=_design()), InputError,
      "duration: give the design's duration in design (one of them)"),
    A("rig_design", lambda c: _turned("rig_design")("upside-down"), InputError,
      "rig: expected one of level, hanging, got 'upside-down'"),
    A("designed_torque", lambda c: _on_hand("designed_torque")("finger3"), InputError,
      "nominal: expected an alpes_dyn Model with motors, got str"),
    A("check_command", lambda c: _check_command([0.0], 1, 0.05, both_ways=[True, False]), InputError,
      "both_ways: expected one flag per motor (1)"),
    A("check_command", lambda c: _check_command([0.01, -0.01], 2, 0.05, both_ways=[True, False]), InputError,
      "command: motor torques must lie in [0, 0.05] N m"),
    A("calibrate", lambda c: _calibration("calibrate")(_loopback(), c.m, safe_torque=1.0), InputError,
      "safe_torque: expected a torque in (0, 0.05] N m"),
    A("calibrate", lambda c: _calibration("calibrate")(_loopback(), c.m, rate=-1.0), InputError,
      "rate: expected a ramp rate"),
    A("calibrate", lambda c: _calibration("calibrate")(_loopback(), c.m, speed=math.nan), InputError,
      "speed: expected a positive encoder speed"),
    A("calibrate", lambda c: _calibration("calibrate")(_loopback(("a", "b")), c.m), InputError,
      "hw: its motors a, b are not the model's finger"),
    A("load_calibration", lambda c: _calibration("load_calibration")(c.f["params_toml"]), InputError,
      "not a calibration file"),
    A("model_experiment_torque", lambda c: _model_torque(c.m, design="4 s"), InputError, "design: expected"),
    A("identified_spec", lambda c: _ident_spec(("K_1",), base="x"), ModelError, "base: expected a TransmissionSpec"),
    A("identified_spec", lambda c: _ident_spec(("K_1", "m_2")), ModelError,
      "identified spec: m_2: a spec file holds no masses"),
    A("identified_spec", lambda c: _ident_spec(("K_1", "m_2"), masses="spec"), ModelError,
      "masses: expected 'refuse' or 'urdf', got 'spec'"),
    A("identified_urdf", lambda c: _ident_urdf(("K_1",)), ModelError,
      "identified urdf: the fit has no mass (--parameters m or m_<joint>)"),
    A("identified_urdf", lambda c: _ident_urdf(("m_2",), urdf="<robot"), ModelError, "urdf: not XML"),
    A("identified_urdf", lambda c: _ident_urdf(("m_2",), value=float("nan")), ModelError,
      "identified urdf: m_2 = nan kg is not a positive mass; not written"),
    A("identified_spec", lambda c: _ident_spec(("K_1",), base=TransmissionSpec.from_toml(
        ROBOT_SPEC.replace('"flexor"', '"tendon"'))), ModelError, "base: the spec's motors tendon do not hold the fitted"),
    A("identified_mjcf", lambda c: _ident_mjcf(c, ("m_ja",), value=-0.1), ModelError,
      "identified mjcf: m_ja = -0.1 kg is not a positive mass; not written"),
    A("identified_mjcf", lambda c: _ident_mjcf(c, ("K_ja",), base="x"), ModelError,
      "base: expected a TransmissionSpec, got str"),
    A("updated_mjcf", lambda c: _update_mjcf(c, masses={"b": 0.1}), ModelError, "mjcf: no body 'b' in the MJCF"),
    A("updated_mjcf", lambda c: _update_mjcf(c, masses={"a": float("inf")}), ModelError,
      "masses: a: inf kg is not a positive mass"),
    A("updated_mjcf", lambda c: _update_mjcf(c, joints={"ja": {"spring": 1.0}}), ModelError,
      "joints: ja: unknown attribute 'spring'"),
    A("updated_mjcf", lambda c: _update_mjcf(c, joints={"ja": {"damping": -1.0}}), ModelError,
      "joints: ja: damping = -1.0 is not a finite value"),
    A("updated_mjcf", lambda c: _update_mjcf(c, joints={"jz": {"damping": 1.0}}), ModelError,
      "mjcf: no joint 'jz' in the MJCF"),
    A("updated_mjcf", lambda c: _update_mjcf(c, rotors={"m": float("nan")}), ModelError,
      "rotors: m: nan kg m^2 is not a rotor inertia"),
    A("updated_mjcf", lambda c: _update_mjcf(c, out=c.d / "none" / "o.xml"), ModelError,
      "out: the folder of '{tmp}/none/o.xml' is not a directory"),
    A("updated_mjcf", lambda c: _update_mjcf(c, mjcf=c.f["notxml_xml"]), ModelError, "mjcf: MuJoCo cannot compile it"),
    A("updated_mjcf", lambda c: _update_mjcf(c, mjcf=c.d / "none.xml"), ModelError, "is not a file"),
    A("updated_mjcf", lambda c: _update_mjcf(c, mjcf=c.f["geomass_xml"], masses={"a": 0.1}), ModelError,
      '<compiler inertiafromgeom="true">: MuJoCo takes every mass from the geoms'),
    # state space, observability
    A("StateSpace", lambda c: ad.StateSpace(c.m, output=lambda q, xp: "abc"), ModelError,
      "output function: returned str 'abc'"),
    A("StateSpace", lambda c: ad.StateSpace(c.m, output=lambda q, xp: 1 / 0), ModelError,
      "output function failed on a CasADi symbol: division by zero"),
    A("StateSpace", lambda c: ad.StateSpace(c.m, output=np.array([[1.0, np.nan, 0.0]])), ModelError,
      "output matrix: contains NaN or inf"),
    A("StateSpace", lambda c: ad.StateSpace(c.m, output=np.array([["a", "b", "c"]], dtype=object)), ModelError,
      "output: expected a preset name, a matrix or a callable"),
    A("StateSpace", lambda c: ad.StateSpace(c.m, input="tendon"), ModelError, "unknown input 'tendon'"),
    A("observability", lambda c: ad.observability("finger3", seed=-1), InputError, "seed: expected an integer >= 0"),
    A("experiment", lambda c: _exp(seed=-1), InputError, "seed: expected an integer from 0 to 9223372036854775807, got -1"),
    A("experiment", lambda c: _exp(design=_design(duration=True)), InputError, "duration: expected a real number, got bool"),
    A("experiment", lambda c: _exp(design=_design(dt="0.001")), InputError, "dt: expected a real number, got str"),
    A("experiment", lambda c: _exp(design=_design(substeps=True)), InputError, "substeps: expected an integer in [1, 64]"),
    A("experiment", lambda c: _exp(design=_design(frequencies=(1j,))), InputError, "frequencies: complex values"),
    A("experiment", lambda c: _exp(design=_design(orientations=((0.0, 0.0, -14.9),))), InputError,
      "orientations: gravity vector [0.0, 0.0, -14.9] has norm 14.9 m/s^2; expected 9.81 m/s^2 within 10 %"),
    A("experiment", lambda c: _exp(design={"duration": 0.2}), InputError, "design: expected an ExperimentDesign, got dict"),
    A("experiment", lambda c: _exp(true_params=c.f["params_toml"], path=c.f["params_toml"]), InputError,
      "path: '{params_toml}' is the input of true_params; refusing to write over it"),
    A("experiment", lambda c: _exp(path=c.f["tmp"] + "/newdir/"), InputError, "path: '{tmp}/newdir/' ends with '/'"),
    A("experiment", lambda c: _exp(path=c.f["link"]), InputError, "path: '{link}' is a symbolic link"),
    A("write_recording", lambda c: __import__("alpes_dyn.estimation.experiments.recording", fromlist=["x"]).write_recording(
        _exp(), c.f["tmp"] + "/newdir/"), InputError, "ends with '/'"),
    A("experiment", lambda c: _exp(model="hand"), InputError, "defined for one chain"),
    A("experiment", lambda c: _exp(model="finger3", chain="pinky"), ModelError, "chain: unknown finger 'pinky'"),
    A("experiment", lambda c: _exp(model="thumb", chain="index"), ModelError, "chain: only a finger model"),
    A("experiment", lambda c: _exp(design=_design(frequencies=(600.0,))), InputError, "below Nyquist"),
    A("experiment", lambda c: _exp(design=_design(orientations=((0.0, 0.0),))), InputError, "orientations"),
    A("experiment", lambda c: _exp(design=_design(dither=-1.0)), InputError, "dither: expected a number in [0, 100]"),
    A("experiment", lambda c: _exp(design=_design(dither=float("nan"))), InputError, "dither: expected a number"),
    A("experiment", lambda c: _exp(design=_design(dither_frequency=600.0)), InputError,
      "dither_frequency: expected a frequency below Nyquist and off the multisine's lines, got 600.0 Hz"),
    A("experiment", lambda c: _exp(design=_design(dither_frequency=11.3)), InputError,
      "dither_frequency: expected a frequency below Nyquist and off the multisine's lines, got 11.3 Hz"),
    A("experiment", lambda c: _exp(design=_design(stick_seconds=-1.0)), InputError,
      "stick_seconds: expected 0 (no stiction ramp) or a duration in s up to 600, got -1.0"),
    A("experiment", lambda c: _exp(design=_design(stick_seconds=0.05)), InputError,
      "stick_seconds: expected a whole number of at least 100 samples of 0.001 s, got 0.05"),
    A("experiment", lambda c: _exp(design=_design(stick_seconds="6")), InputError,
      "stick_seconds: expected a real number, got str"),
    A("experiment", lambda c: _exp(design=_design(stick_swing=float("nan"))), InputError,
      "stick_swing: expected a number in [0, 100] (times each motor's breakaway torque), got nan"),
    A("experiment", lambda c: _exp(design=_design(stick_swing=1e3)), InputError, "stick_swing: expected a number in"),
    A("perturbed_params", lambda c: _pp(spread=1.0), InputError, "spread: expected a fraction in [0, 1)"),
    A("perturbed_params", lambda c: _pp(kinds=("L",)), InputError, "kinds: unknown kind 'L'"),
    A("perturbed_params", lambda c: _pp(chains=("pinky",)), InputError,
      "chains: unknown chain 'pinky' (expected one of index, middle, ring, little, thumb)"),
    A("identify", lambda c: _ident(c, interval=0.0), InputError, "interval: expected a positive number"),
    A("identify", lambda c: _ident(c, interval=1e308), InputError, "interval: 1e+308 s must hold 2 to"),
    A("identify", lambda c: _ident(c, interval=True), InputError, "interval: expected a positive number, got True"),
    A("identify", lambda c: _ident(c, drift="torque"), InputError,
      "drift: expected None or a comma-separated choice of offset, gain, got 'torque'"),
    A("identify", lambda c: _ident(c, drift=1), InputError,
      "drift: expected None or a comma-separated choice of offset, gain, got 1"),
    A("identify", lambda c: _ident(c, drift=""), InputError,
      "drift: expected None or a comma-separated choice of offset, gain, got ''"),
    A("identify", lambda c: _ident(c, drift=["offset", "offset"]), InputError, "names a drift twice"),
    A("identify", lambda c: _ident(c, drift="gain"), InputError, "drift: 'gain' needs the excitation's lines"),
    A("identify", lambda c: _ident3(c.f["runtwo_csv"], interval=0.15),
      InputError, "interval: 150 samples is longer than run 0 (101 samples): each run needs at least one whole"),
    A("identify", lambda c: _ident(c, substeps=10**9), InputError, "substeps: expected an integer from 1 to 1000"),
    A("sweep", lambda c: __import__("alpes_dyn.studies.sweep", fromlist=["x"]).sweep(
        lambda seed: {"x": 1.0}, 1, options=5, serial=True), InputError, "options: expected a dict of keyword arguments"),
    A("sweep", lambda c: __import__("alpes_dyn.studies.sweep", fromlist=["x"]).sweep(
        lambda seed: {"x": 1.0}, 1, options={"seed": 3}, serial=True), InputError, "options: 'seed' is each draw's own"),
    A("harmonic_ratio", lambda c: _harm().harmonic_ratio(np.zeros(100), [20.0], 0.0), InputError,
      "dt: expected a positive time step in s, got 0.0"),
    A("intermodulation", lambda c: _harm().intermodulation([20.0, -1.0], 500.0), InputError,
      "lines: expected positive frequencies in Hz, got [20.0, -1.0]"),
    A("intermodulation", lambda c: _harm().intermodulation([], 500.0), InputError, "lines: expected positive"),
    A("sweep", lambda c: __import__("alpes_dyn.studies.sweep", fromlist=["x"]).sweep(
        lambda seed: {"x": 1.0}, seeds=[3, 3], serial=True), InputError, "seeds: a seed is given twice"),
    A("sweep", lambda c: __import__("alpes_dyn.studies.sweep", fromlist=["x"]).sweep(
        lambda seed: {"x": 1.0}, 2, flat=None, serial=True), InputError, "flat: expected True or False, got None"),
    A("realism_row", lambda c: _realism().realism_row(1, cable=(-1.0, 0.0)), InputError,
      "cable: expected (k_t > 0 N/m, c_t >= 0 N s/m), got (-1.0, 0.0)"),
    A("realism_draw", lambda c: _realism().realism_draw(1, case="bogus"), InputError,
      "case: expected one of none, stiction, tendon, rotor, tilt, kt, offset, slack, delay, all, got 'bogus'"),
    A("parse_seeds", lambda c: _realism().parse_seeds("320-301"), InputError,
      "seeds: expected a range a-b with 0 <= a <= b, got '320-301'"),
    A("parse_seeds", lambda c: _realism().parse_seeds("1,x"), InputError,
      "seeds: expected non-negative integers or ranges a-b, comma-separated, got '1,x'"),
    A("parse_seeds", lambda c: _realism().parse_seeds("3,1-4"), InputError, "seeds: a seed is named twice"),
    A("realism_draw", lambda c: _realism().realism_draw(1, rig="upside"), InputError,
      "rig: expected one of level, hanging, got 'upside'"),
    A("adapted_experiment", lambda c: _adapted(rig="upside"), InputError,
      "rig: expected one of auto, level, hanging, both, got 'upside'"),
    A("realism_row", lambda c: _realism().realism_row(1, adapt="sideways"), InputError,
      "adapt: expected one of auto, level, hanging, both, none, got 'sideways'"),
    A("plant_experiment", lambda c: _realism().plant_experiment(None, 1, None, None, adapt="sideways"), InputError,
      "adapt: expected one of auto, level, hanging, both, none, got 'sideways'"),

    A("realism_draw", lambda c: _realism().realism_draw(1, chain="pinky"), InputError,
      "chain: unknown chain 'pinky' (expected one of index, middle, ring, little, thumb)"),
    A("realism_draw", lambda c: _realism().realism_draw(1, duration=-4.0), InputError, "duration"),
    A("rig_design", lambda c: _realism().rig_design("level", duration=float("nan")), InputError, "duration"),
    A("identify", lambda c: _ident(c, max_iterations=True), InputError, "max_iterations: expected a positive integer"),
    A("identify", lambda c: _ident(c, excitation="abc"), InputError, "excitation: expected frequencies in Hz, got a string"),
    A("identify", lambda c: _ident(c, excitation=[1j]), InputError, "excitation: complex values are not supported"),
    A("identify", lambda c: _ident(c, recording=_exp(design=_design(duration=0.5)),
                                   validation=_exp(design=_design(duration=0.5))), RecordingError,
      "validation: the same samples as the recording fitted"),
    A("identify", lambda c: _ident(c, interval=10.0), InputError, "interval: 10 s must hold 2 to"),
    A("identify", lambda c: _ident(c, parameters="K_7"), ModelError, "unknown parameter 'K_7'"),
    A("identify", lambda c: _ident(c, parameters="K,tilt_w"), ModelError, "unknown parameter 'tilt_w'"),
    A("identify", lambda c: _ident(c, parameters="input_gain,m,K,friction"), ModelError,
      "the encoder sees only their ratios"),
    A("identify", lambda c: _ident(c, torque_noise=-1.0), InputError, "torque_noise: expected a non-negative"),
    A("identify", lambda c: _ident(c, start={"K_9": 0.05}), InputError, "start: 'K_9' is not a parameter of this fit"),
    A("identify", lambda c: _ident(c, start={"m_1": -0.01}), InputError, "start: m_1 = -0.01: expected a finite number > 0"),
    A("identify", lambda c: _ident(c, start={"m_1": True}), InputError, "start: m_1 = True: expected a finite number"),
    A("identify", lambda c: _ident(c, start={"K_1": float("nan")}), InputError, "start: K_1 = nan: expected a finite"),
    A("identify", lambda c: _ident(c, start=[0.05]), InputError, "start: expected a mapping of parameter names"),
    A("identify", lambda c: _ident(c, kkt="qr"), InputError, "kkt: expected 'sparse', 'superlu' or 'dense', got 'qr'"),
    A("identify", lambda c: _ident(c, excitation=(0.0,)), InputError, "excitation: expected positive frequencies"),
    A("identify", lambda c: _ident(c, recording=c.f["latin1_toml"]), RecordingError, "not a UTF-8 text file"),
    A("identify", lambda c: _ident(c, recording=_diverging()), RecordingError, "column 'encoder_finger' line 102: "
      "1e+15 counts is beyond what the joint ranges allow"),
    A("estimate_recording", lambda c: _replay(c, model="finger3"), InputError, "model: expected an alpes_dyn.Model"),
    A("estimate_recording", lambda c: _replay(c, observer="pf"), InputError, "observer: expected one of ekf"),
    A("estimate_recording", lambda c: _replay(c, torque_delay=1.5), InputError,
      "torque_delay: expected a whole number of samples from 0 to 100, got 1.5"),
    A("estimate_recording", lambda c: _replay(c, torque_delay=True), InputError, "torque_delay: expected a whole number"),
    A("estimate_recording", lambda c: _replay(c, recording=c.f["latin1_toml"]), RecordingError, "not a UTF-8 text"),
    A("estimate_recording", lambda c: _replay(c, recording=42), InputError, "recording: expected a Recording"),
    A("estimate_recording", lambda c: _replay(c, disturbance="yes"), InputError, "disturbance: expected True or False"),
    A("estimate_recording", lambda c: _replay(c, stops="on"), InputError, "stops: expected True or False"),
    A("estimate_recording", lambda c: _replay(c, disturbance_walk=-1.0), InputError, "disturbance_walk: expected a"),
    A("estimate_recording", lambda c: _replay(c, transient=0.5), InputError, "must be shorter than the recording's"),
    A("estimate_recording", lambda c: _replay(c, encoder_offset=[0.1, 0.2]), InputError,
      "encoder_offset: expected 1 finite numbers (rad)"),
    A("estimate_recording", lambda c: _replay(c, tilt="flat"), InputError, "tilt: expected 2 finite numbers (rad)"),
    A("estimate_recording", lambda c: _replay(c, tilt=[0.0, np.nan]), InputError, "tilt: expected 2 finite numbers"),
    A("estimate_recording", lambda c: _replay(c, encoder_noise_counts=float("inf")), InputError,
      "encoder_noise_counts: expected a non-negative"),
    A("estimate_recording", lambda c: _replay(c, model=ad.Model.alpes("finger2")), RecordingError,
      "recording: made for motors ['finger'] and joints ['j1', 'j2', 'j3'], not the model's"),
    A("identify", lambda c: _ident(c, validation=c.f["latin1_toml"]), RecordingError, "not a UTF-8 text file"),
    A("identify", lambda c: _ident(c, validation=c.f["rec2_csv"]), RecordingError, "validation: 201 samples are too few"),
    A("identify", lambda c: _ident(c, encoder_noise=-1.0), InputError, "encoder_noise: expected a non-negative"),
    A("identify", lambda c: _ident(c, encoder_noise=True), InputError, "encoder_noise: expected a non-negative"),
    A("whiteness", lambda c: _adq("whiteness", np.zeros(5)), InputError, "residual: expected (N,) or (N, m) samples"),
    A("whiteness", lambda c: _adq("whiteness", np.r_[np.zeros(99), np.nan]), InputError, "residual: expected finite"),
    A("whiteness", lambda c: _adq("whiteness", np.zeros(100), 60), InputError, "lags: expected an integer from 1 to 49"),
    A("cross_correlation", lambda c: _adq("cross_correlation", np.zeros(100), np.zeros(99)), InputError,
      "input: expected 100 samples, got 99"),
    A("fit_percent", lambda c: _adq("fit_percent", np.arange(5.0), np.arange(4.0)), InputError, "yhat: expected shape"),
    A("sensor_floor", lambda c: _adq("sensor_floor", np.arange(20.0), 0.0, -1.0), InputError,
      "encoder_noise: expected a non-negative number of counts"),
    A("sensor_floor", lambda c: _adq("sensor_floor", np.arange(20.0), math.inf), InputError,
      "torque_explained: expected a non-negative number"),
    A("load_params", lambda c: ad.load_params(c.f["badident_toml"]), ModelError,
      "identification.finger.converged: expected true or false, got 1"),
    A("identifiability", lambda c: _idf(points=0), InputError, "points: expected an integer from 1 to 10000"),
    A("identifiability", lambda c: _idf(seed=-1), InputError, "seed: expected an integer >= 0"),
    A("identifiability", lambda c: _idf(parameters="K_9"), ModelError, "unknown parameter 'K_9'"),
    A("identifiability", lambda c: _idf(coordinates="polar"), InputError, "coordinates: expected 'log' or 'absolute'"),
    A("identifiability", lambda c: _idf(theta=[0.04, -1.0]), InputError, "theta: K_2 must be a finite positive"),
    A("identifiability", lambda c: _idf(theta=[1.0]), InputError, "theta: expected 2 values"),
    A("identifiability", lambda c: _idf(order=-1), InputError, "order: expected an integer >= 0"),
    A("identifiability", lambda c: _idf(system=3), ModelError, "system: expected a Model or an Alpes model name"),
    A("identifiability", lambda c: _idf(system=c.m, friction=True), ModelError, "friction: only with a model name"),
    A("fisher_information", lambda c: _fim(c, U=None), InputError, "U: the motor torques of the experiment are"),
    A("fisher_information", lambda c: _fim(c, U=np.zeros((10, 2))), InputError, "U: expected 1 motor torque column"),
    A("fisher_information", lambda c: _fim(c, U=[np.nan] * 10), InputError, "U: contains NaN or inf"),
    A("fisher_information", lambda c: _fim(c, U="abc"), InputError, "U: expected an array of numbers"),
    A("fisher_information", lambda c: _fim(c, U=np.zeros(1)), InputError, "U: expected at least 2 sample periods"),
    A("fisher_information", lambda c: _fim(c, G=np.zeros((3, 3))), InputError, "G: expected (3,) or (10, 3)"),
    A("fisher_information", lambda c: _fim(c, dt=0.0), InputError, "dt: expected a positive"),
    A("fisher_information", lambda c: _fim(c, initial_state="free"), InputError, "initial_state: expected one of"),
    A("fisher_information", lambda c: _fim(c, encoder_noise_counts=-1.0), InputError,
      "encoder_noise_counts: expected a non-negative number"),
    A("fisher_information", lambda c: _fim(c, camera_times=(0.5,)), InputError,
      "camera_times: 0.5 is not a sample time in [0, 0.01] s"),
    A("fisher_information", lambda c: _fim(c, camera_times=("x",)), InputError, "camera_times: expected times in s"),
    A("fisher_information", lambda c: _fim(c, parameters="K_9"), ModelError, "unknown parameter 'K_9'"),
    A("fisher_information", lambda c: _fim(c, model="finger3"), ModelError, "model: expected an alpes_dyn Model"),
    A("fisher_information", lambda c: _fim(c, counts_per_rev=-1), InputError,
      "counts_per_rev: expected a positive number"),
    A("name_direction", lambda c: _nd([0, 0], ("K_1", "m_1")), InputError, "v: expected a finite, non-zero"),
    A("name_direction", lambda c: _nd([1, 0, 0], ("K_1", "m_1")), InputError, "v: expected 2 components"),
    A("ParametricDynamics", lambda c: _pdyn(c, "m_9"), ModelError, "unknown parameter 'm_9'"),
    A("ParametricDynamics", lambda c: _pdyn(c, "friction"), ModelError, "selects nothing"),
    A("ParametricDynamics", lambda c: _pdyn(c, "J_m"), ModelError, "'J_m' selects nothing"),
    A("ParametricDynamics", lambda c: _pdyn(c, "encoder_offset_thumb"), ModelError,
      "unknown parameter 'encoder_offset_thumb'"),
    A("check_observability", lambda c: ad.check_observability("finger3", seed=-1), InputError,
      "seed: expected an integer >= 0"),
    A("check_observability", lambda c: ad.check_observability("finger3", max_operations=0), InputError,
      "max_operations"),
    A("observability", lambda c: ad.observability("finger3", points=10_001), InputError, "points: at most 10000"),
    A("observability", lambda c: ad.observability("finger3", points=0), InputError, "points: expected a positive"),
    A("observability", lambda c: ad.observability("finger3", seed=1.5), InputError, "seed: expected an integer"),
    # simulation and compiled rollouts
    A("simulate", lambda c: _sim(c, duration=1e12), InputError, "duration: 1000000000000000 steps of 6 states"),
    A("simulate", lambda c: _sim(c, dt=0.0), InputError, "dt: expected a positive finite number"),
    A("simulate", lambda c: _sim(c, dt="abc"), InputError, "dt: expected a positive number"),
    A("simulate", lambda c: _sim(c, method="euler"), InputError, "method: unknown integration method 'euler'"),
    A("simulate", lambda c: _sim(c, inputs=lambda t: "abc"), InputError, "inputs: the callable must return 3"),
    A("compile_rollout", lambda c: _rollout(c, threads="a"), InputError, "threads: expected an integer from 1 to 64"),
    A("compile_rollout", lambda c: _rollout(c, threads=0), InputError, "threads: expected an integer from 1 to 64"),
    A("compile_rollout", lambda c: _rollout(c, dt=float("nan")), InputError, "dt: expected a positive finite"),
    A("CompiledStepLoop", lambda c: _steploop(parameters=[1.0]), InputError,
      "parameters: expected 2 numbers, the step's input p, got '[1.0]'"),
    A("CompiledStepLoop", lambda c: _steploop(parameters=None), InputError, "parameters: expected 2 numbers"),
    A("CompiledStepLoop", lambda c: _steploop(parameters=[[0.9, 0.05]]), InputError, "parameters: expected 2 numbers"),
    A("CompiledStepLoop", lambda c: _steploop(parameters=["a", "b"]), InputError, "parameters: expected 2 numbers"),
    A("CompiledStepLoop", lambda c: _steploop(parameters=[np.inf, 0.0]), InputError, "parameters: contains NaN or inf"),
    A("CompiledStepLoop", lambda c: _steploop(lifted=False, parameters=[1.0]), InputError,
      "parameters: the step (x, w) -> x_next takes none"),
    A("batch_step_caller", lambda c: __import__("alpes_dyn.estimation.observers.blocks", fromlist=["x"]).batch_step_caller(
        _ekf(c).filter_step_p, "bad", False, [1.0, 2.0]), InputError,
      "numbers, the step's input p, got '[1.0, 2.0]'"),
    A("lift_constants", lambda c: __import__("alpes_dyn.symbolic.lifted", fromlist=["x"]).lift_constants("f"),
      ModelError, "lift_constants: expected an SX casadi.Function, got str"),
    A("compile_rollout", lambda c: _rollout(c).rollout(np.zeros(6), np.broadcast_to(0.0, (1, 10**9, 3))), InputError,
      "U_batch: 1 trajectories of 1000000000 steps would take about"),
    # observers and the estimation scenario
    A("UnscentedKalmanFilter", lambda c: _ukf(c, kappa=-6), InputError, "kappa: alpha^2 (nz + kappa) must be > 0"),
    A("UnscentedKalmanFilter", lambda c: _ukf(c, beta=float("nan")), InputError, "beta: expected a finite number"),
    A("UnscentedKalmanFilter", lambda c: _ukf(c, alpha="x"), InputError, "alpha: expected a finite number"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c, process_noise=[np.nan] * 6), InputError,
      "process_noise: contains NaN or inf"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c, measurement_noise=-1.0), InputError,
      "measurement_noise: covariance must be positive semidefinite"),
    A("ExtendedKalmanFilter", lambda c: _ekf(c).run(np.zeros(6), np.ones(6), np.zeros((10**9, 1)), np.zeros((1, 1))),
      InputError, "W: 1000000000 samples of 6 states and their covariance would take about"),
    A("run_estimation", lambda c: _est(dt=0), InputError, "dt: expected a positive number of seconds, got 0"),
    A("run_estimation", lambda c: _est(dt=float("nan")), InputError, "dt: expected a finite number, got nan"),
    A("run_estimation", lambda c: _est(duration=1e12), InputError, "duration: 1e+12 s at dt = 0.001 s"),
    A("run_estimation", lambda c: _est(duration=0.001), InputError, "shorter than two samples"),
    A("run_estimation", lambda c: _est(duration="5"), InputError, "duration: expected a number, got '5'"),
    A("run_estimation", lambda c: _est(seed=-1), InputError, "seed: expected an integer >= 0, got -1"),
    A("run_estimation", lambda c: _est(substeps="a"), InputError, "substeps: expected an integer >= 1"),
    A("run_estimation", lambda c: _est(params=""), ModelError, "parameter file: empty file name"),
    A("run_estimation", lambda c: _est(params=c.f["latin1_toml"]), ModelError, "not UTF-8 text"),
    A("run_estimation", lambda c: _est(model="hand"), InputError, "model: the estimation scenario"),
    A("run_estimation", lambda c: _est(model="thumb"), InputError, "friction: the thumb's scenario needs friction=True"),
    A("run_estimation", lambda c: _est(chain="pinky"), ModelError, "chain: unknown finger 'pinky'"),
    # The whole hand's force loops (run_hand_control checks its settings before building anything)
    A("run_hand_control", lambda c: _hand("pid"), InputError, "controller: unknown controller 'pid'"),
    A("run_hand_control", lambda c: _hand(levels={"index": (0.2, 0.3)}), InputError,
      "levels: no reference for chain 'middle'"),
    A("run_hand_control", lambda c: _hand(levels={**_hand_levels(), "pinky": (0.2, 0.3)}), InputError,
      "levels: unknown chain 'pinky'"),
    A("run_hand_control", lambda c: _hand(levels={**_hand_levels(), "thumb": (0.2, float("nan"))}), InputError,
      "levels: 'thumb' expects two positive forces (before, after) in N"),
    A("run_hand_control", lambda c: _hand(levels=[0.2, 0.3]), InputError, "levels: expected a dict chain"),
    A("run_hand_control", lambda c: _hand(thumb_abduction=2.0), InputError,
      "thumb_abduction: 2 rad is outside the ab/adduction range"),
    A("run_hand_control", lambda c: _hand(step_time=5.0), InputError, "step_time: expected settle + 0.25 s <= step_time"),
    A("run_hand_control", lambda c: _hand(duration=float("nan")), InputError, "duration: expected a finite number"),
    A("run_hand_control", lambda c: _hand(abduction_kp="1"), InputError, "abduction_kp: expected a finite number"),
    A("run_hand_control", lambda c: _hand(abduction_kd=-0.01), InputError, "abduction_kd: expected a number >= 0"),
    A("run_hand_control", lambda c: _hand(substeps=0), InputError, "substeps: expected a positive integer, got 0"),
    A("run_hand_control", lambda c: _hand(ramp_s=-1.0), InputError, "ramp_s: expected a number >= 0"),
    A("run_hand_control", lambda c: _hand(ramp_s=2.0), InputError, "ramp_s: the ramp ends after the run"),
    A("grasp_levels", lambda c: _grasp_levels({"index": 0.5}), InputError,
      "limits: expected a positive force (N) for chain 'middle'"),
    A("grasp_levels", lambda c: _grasp_levels({k: float("nan") for k in _hand_levels()}), InputError,
      "limits: expected a positive force (N) for chain 'index', got nan"),
    A("run_hand_control", lambda c: _hand(params=c.f["latin1_toml"]), ModelError, "not UTF-8 text"),
    A("chain_frame", lambda c: _chain_frame("pinky"), InputError, "chain: unknown chain 'pinky'"),
    A("chain_model", lambda c: _chain_model("thumb2"), InputError, "chain: unknown chain 'thumb2'"),
    A("cylinder_normal", lambda c: _cyl_normal(c, (0, 0, 0)), InputError, "normal: expected a non-zero 3-vector"),
    A("cylinder_normal", lambda c: _cyl_normal(c, (0, np.nan, 1)), InputError, "normal: expected a non-zero 3-vector"),
    # the MJCF export's realism options
    A("mjcf_string", lambda c: _mjcf(stiction=0.0), InputError, "stiction: expected a positive time constant"),
    A("mjcf_string", lambda c: _mjcf(timestep=True), InputError, "timestep: expected a positive number of seconds"),
    A("mjcf_string", lambda c: _mjcf(contact_q=[0.1, 0.2]), InputError, "contact_q: places the block of scene='block'"),
    A("mjcf_string", lambda c: _mjcf(contact_q=[0.1, 0.2, 1j], scene="block"), InputError, "contact_q: complex values"),
    A("mjcf_string", lambda c: _mjcf(block_tilt=float("nan"), scene="block"), InputError,
      "block_tilt: expected a finite angle in rad"),
    A("mjcf_string", lambda c: _mjcf(tilt=4.0), InputError, "tilt: expected a finite angle in rad within [-pi, pi]"),
    A("mjcf_string", lambda c: _mjcf(stiction="0.5 ms"), InputError, "stiction: expected a positive time constant"),
    A("mjcf_string", lambda c: _mjcf(tendon_stiffness=-4e4), InputError, "tendon_stiffness: expected a positive"),
    A("mjcf_string", lambda c: _mjcf(tendon_stiffness=True), InputError, "tendon_stiffness: expected a positive"),
    A("mjcf_string", lambda c: _mjcf(tendon_stiffness=4e4, tendon_damping=np.nan), InputError,
      "tendon_damping: expected a damping >= 0"),
    A("mjcf_string", lambda c: _mjcf(tendon_damping=1.0), InputError, "tendon_damping: needs tendon_stiffness"),
    A("mjcf_string", lambda c: _mjcf(tendon_rotor="yes"), InputError, "tendon_rotor: expected True or False"),
    A("mjcf_string", lambda c: _mjcf(tendon_rotor=True, rotor_inertia=True), InputError, "counted twice"),
    A("mjcf_string", lambda c: _mjcf(tendon_stiffness=4e4, rotor_inertia=True), InputError, "counted twice"),
    A("mjcf_string", lambda c: _mjcf(tilt=float("inf")), InputError, "tilt: expected a finite angle in rad"),
    A("mjcf_string", lambda c: _mjcf(tendon_stiffness=4e4, tendon_dead_band=np.inf), InputError,
      "tendon_dead_band: expected a cable's play >= 0"),
    A("mjcf_string", lambda c: _mjcf(tendon_dead_band=1e-4), InputError, "tendon_dead_band: needs tendon_stiffness"),
    # the series-elastic tendon with its rotor as a state (symbolic.elastic_tendon), its cable in the MJCF export
    A("model_mjcf", lambda c: _model_mjcf(c.m, tendon=[1.0]), InputError, "tendon: expected an ElasticTendon"),
    A("ElasticTendon.of", lambda c: _tendon_of(c.m), InputError, "tendon_compliance: motor 'finger' has a rigid"),
    A("SeriesElasticSystem", lambda c: __import__("alpes_dyn.symbolic.elastic_tendon", fromlist=["x"]).SeriesElasticSystem(
        ad.Model.alpes("finger2", params=_sheathed()), __import__("alpes_dyn.model.tendon", fromlist=["x"]).ElasticTendon(
            [10.0], [0.0], [0.0])), InputError, "tendons have sheath friction (capstan); the series-elastic tendon"),
    A("ElasticTendon.from_cable", lambda c: _cable(1, "4e4", 0.002), InputError, "cable_stiffness: expected numbers of N/m, got a string"),
    A("ElasticTendon.from_cable", lambda c: _cable(1, 4e4, 0.002, dead_band=[1e-4, 2e-4]), InputError,
      "dead_band: expected 1 finite non-negative numbers"),
    A("ElasticTendon", lambda c: _tendon(1.0, -1.0, 0.0), InputError, "damping: expected 1 finite non-negative"),
    A("SeriesElasticSystem", lambda c: _ses(c.m, _tendon(1.0, 0.0, 0.0), rotor_inertia=np.nan), InputError,
      "rotor_inertia: expected 1 finite positive"),
    A("SeriesElasticSystem", lambda c: _ses(_curved(), _tendon(1.0, 0.0, 0.0)), InputError,
      "model: 'curved''s ratios change with q (ratio_curve); the series-elastic tendon is built for constant ratios"),
    A("model_mjcf", lambda c: _curved().to_mjcf(), ModelError,
      "model: 'curved''s ratios change with q (ratio_curve or path); the MJCF export writes fixed tendons"),
    A("SeriesElasticSystem", lambda c: _ses(c.m, _tendon(1.0, 0.0, 0.0), smooth="yes"), InputError,
      "smooth: expected True or False"),
    A("SeriesElasticSystem.simulate", lambda c: _ses(c.m, _tendon(1.0, 0.0, 0.0)).simulate(np.zeros(8), [[0.0, 1.0]],
                                                                                              1e-3, 50),
      InputError, "u: expected (N, 1) finite motor torques"),
    A("SeriesElasticSystem.equilibrium", lambda c: _ses(c.m, _tendon(1.0, 0.0, 0.0)).equilibrium([0.01j]), InputError,
      "u: complex values are not supported"),
    # MuJoCo recording plants and the experiment's torque
    A("mujoco_recording", lambda c: _mjrec(model="hand"), InputError, "model: a recording plant is one chain"),
    A("mujoco_recording", lambda c: _mjrec(torque=np.zeros((10, 2))), InputError,
      "torque: expected finite motor torques of shape (N+1, 1), got shape (10, 2)"),
    A("mujoco_recording", lambda c: _mjrec(torque=np.full((10, 1), np.nan)), InputError, "torque: expected finite"),
    A("mujoco_recording", lambda c: _mjrec(dt=0.0), InputError, "dt: expected a sample period in (0, 0.1] s"),
    A("mujoco_recording", lambda c: _mjrec(timestep=3e-4), InputError, "does not divide the sample period"),
    A("mujoco_recording", lambda c: _mjrec(timestep=2e-3), InputError, "timestep: expected a MuJoCo step in (0, dt]"),
    A("mujoco_recording", lambda c: _mjrec(integrator="euler"), InputError, "integrator: unknown integrator 'euler'"),
    A("mujoco_recording", lambda c: _mjrec(seed=-1), InputError, "seed: expected a non-negative integer"),
    A("mujoco_recording", lambda c: _mjrec(torque_noise=-1.0), InputError, "torque_noise: expected a non-negative"),
    A("mujoco_recording", lambda c: _mjrec(q0=[0.1, 0.2]), InputError, "q0: expected 3 finite joint angles (rad)"),
    A("mujoco_recording", lambda c: _mjrec(true_params=c.f["latin1_toml"]), ModelError, "not UTF-8 text"),
    A("mujoco_recording", lambda c: _mjrec(true_params=_sheathed(), effects=_eff(tendon_stiffness=1e4)), InputError,
      "capstan: the MuJoCo plant puts the tendons' sheath friction on a rigid tendon"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(torque_constant_error=0.7)), InputError,
      "torque_constant_error: expected a fraction in (-0.5, 0.5)"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(encoder_offset=np.nan)), InputError,
      "encoder_offset: expected a finite number of counts"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(stiction=-1.0)), InputError, "stiction: expected a positive"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(tendon_rotor=True, tendon_stiffness=1e4)), InputError,
      "tendon_rotor: the series-elastic tendon"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(torque_delay=1.5)), InputError,
      "torque_delay: expected a whole number of samples from 0 to 100"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(torque_delay=-1)), InputError,
      "torque_delay: expected a whole number of samples"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(tendon_dead_band=1e-5)), InputError,
      "tendon_dead_band: the cable's slack needs the series-elastic tendon"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(soft_stiction=True, stiction=5e-4)), InputError,
      "soft_stiction: MuJoCo's default dry-friction constraint, or stiction's time constant, not both"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(soft_stiction="yes")), InputError,
      "soft_stiction: expected True or False"),
    A("friction_row", lambda c: _friction_row("slippery"), InputError, "case: expected one of soft, soft_3x"),
    A("held_out_ramp", lambda c: _held_out_ramp("slippery"), InputError, "case: expected one of soft, soft_3x"),
    A("check_observer_law", lambda c: _check_observer_law("tanh"), ModelError,
      "friction.observer_law: expected one of smooth, stick, lugre, got 'tanh'"),
    A("creep_of_constraint", lambda c: _creep_of_constraint(-0.02, 0.9, 0.95), ModelError,
      "solreffriction: expected a finite number > 0 s"),
    A("creep_of_constraint", lambda c: _creep_of_constraint(0.02, np.nan, 0.95), ModelError,
      "solimpfriction: expected a finite number > 0"),
    A("creep_of_constraint", lambda c: _creep_of_constraint(0.02, 0.9, 1.0), ModelError,
      "solimpfriction: expected impedances in (0, 1)"),
    A("PlantEffects", lambda c: _mjrec(effects=_eff(tendon_stiffness=1e4, tendon_dead_band=-1e-5)), InputError,
      "tendon_dead_band: expected a cable's play >= 0"),
    A("experiment_torque", lambda c: _exptorque(model="hand"), InputError, "defined for one chain"),
    A("experiment_torque", lambda c: _exptorque(true_gravity=[0.0, -9.81]), InputError,
      "true_gravity: expected 3 finite numbers"),
    A("experiment_torque", lambda c: _exptorque(design=_design(orientations=((0, 0, -9.81), (9.81, 0, 0))),
                                                true_gravity=[0.0, 0.0, -9.81]),
      InputError, "true_gravity: expected 3 finite numbers (m/s^2) per orientation (2)"),
    A("mujoco_recording", lambda c: _mjrec(gravity=np.zeros((199, 3))), InputError,
      "gravity: expected finite gravity vectors (m/s^2) of shape (200, 3)"),
    A("mujoco_recording", lambda c: _mjrec(gravity=np.full((200, 3), np.nan)), InputError,
      "gravity: expected finite gravity vectors"),
    A("line_basis", lambda c: _line_basis([0, 990]), InputError,
      "excitation: 2 frequencies are too many for 11 samples in the segment from t = 0.99 s"),
    A("check_plot_path", lambda c: _plot_path(c.f["dir"]), InputError, "--plot: '{dir}' is a directory"),
    A("check_plot_path", lambda c: _plot_path("x.xyz"), InputError, "--plot: 'x.xyz' has extension 'xyz'"),
    A("recording_filter", lambda c: _recfilt("finger3"), InputError, "model: expected an alpes_dyn Model with motors"),
    A("recording_filter", lambda c: _recfilt(c.m, observer="pf"), InputError, "observer: unknown observer 'pf'"),
    A("recording_filter", lambda c: _recfilt(c.m, dt=0.0), InputError, "dt: expected a positive number of seconds"),
    A("recording_filter", lambda c: _recfilt(c.m, dt=float("nan")), InputError, "dt: expected a non-negative number"),
    A("recording_filter", lambda c: _recfilt(c.m, torque_noise=-1.0), InputError,
      "torque_noise: expected a non-negative number of N m"),
    A("recording_filter", lambda c: _recfilt(c.m, encoder_noise_counts="1"), InputError,
      "encoder_noise_counts: expected a non-negative number of counts"),
    A("recording_filter", lambda c: _recfilt(c.m, u0=[0.1, 0.2]), InputError, "u0: expected 1 finite numbers (N m)"),
    A("robot_controller", lambda c: _robctl("sensor", "finger3"), InputError, "model: expected an alpes_dyn Model"),
    A("robot_controller", lambda c: _robctl("sensor", ad.Model(ROBOT_URDF)), InputError,
      "model: 'tendon_robot' has no transmission spec"),
    A("robot_controller", lambda c: _robctl("pid", _ctl_robot(c)), InputError, "controller: unknown controller 'pid'"),
    A("robot_controller", lambda c: _robctl("pi", _ctl_robot(c), motor="nope"), InputError, "motor: unknown motor"),
    A("robot_controller", lambda c: _robctl("pi", _ctl_robot(c), motor="flexor", frame="nope"), InputError,
      "frame: "),
    A("robot_controller", lambda c: _robctl("pi", _ctl_robot(c), motor="flexor", frame="tip", tau_max=-1.0),
      InputError, "tau_max: expected a positive motor torque limit in N m, got -1.0"),
    A("drawn_spec", lambda c: _drawn(c, 1.5), InputError, "spread: expected a fraction in [0, 1), got 1.5"),
    A("drawn_spec", lambda c: _drawn(c, True), InputError, "spread: expected a fraction in [0, 1), got True"),
]


def _recfilt(model, **kw):
    from alpes_dyn.estimation.observers.replay import recording_filter

    return recording_filter(model, **kw)


def _robctl(kind, model, **kw):
    from alpes_dyn.control.cexport import robot_controller

    return robot_controller(kind, model, **kw)


def _ctl_robot(c):
    return ad.Model(ROBOT_URDF, c.f["robotctl_toml"])


def _drawn(c, spread):
    from alpes_dyn.model.spec import load_spec
    from alpes_dyn.studies.sweep import drawn_spec

    return drawn_spec(load_spec(c.f["robot_toml"]), spread, 0)


def _linked_dir(c):
    return c.d / "linked"


def _write_params(path):
    from alpes_dyn.model.params import write_params

    return write_params(ad.load_params(), path)


def _write_rec(path):
    from alpes_dyn.estimation.experiments.recording import write_recording

    return write_recording(_exp(), path)


def _slow(rec, gravity=False):
    """``rec`` at twice its sample period (``gravity`` False), or with gravity columns (None)."""
    import dataclasses

    if gravity is None:
        return dataclasses.replace(rec, gravity=np.tile([0.0, 0.0, -9.81], (rec.n_samples, 1)))
    return dataclasses.replace(rec, t=2 * rec.t)


def _join_runs(recs):
    from alpes_dyn.estimation.experiments.recording import join_runs

    return join_runs(recs)


def _read_rec(path, torque_constant=None):
    from alpes_dyn.estimation.experiments.recording import read_recording

    return read_recording(path, ad.Model.alpes("finger3"), torque_constant)


def _outputs(outputs, inputs=()):
    from alpes_dyn.fileio import check_outputs

    return check_outputs(outputs, inputs)


def _atomic(path):
    from alpes_dyn.fileio import atomic_write

    return atomic_write(path, "x", "out")


def _read_text(path):
    from alpes_dyn.fileio import read_text

    return read_text(path, "text")


def _toml(text):
    from alpes_dyn.fileio import load_toml

    return load_toml(text, "x")


def _control_sc(**kw):
    from alpes_dyn.control import ControlScenario

    return ControlScenario(**kw).check()


def _control_robot(c, spec: str = ROBOT_CONTROL_SPEC):
    return ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(spec))


def _run_control(c, **kw):
    from alpes_dyn.control import run_control

    return run_control("pi", model=_control_robot(c), duration=1.0, **kw)


def _place(c, spec: str = ROBOT_CONTROL_SPEC, **kw):
    return _place_on(_control_robot(c, spec), **({"motor": "flexor", "frame": "tip"} | kw))


def _place_on(model, **kw):
    from alpes_dyn.model.block_scene import place_block

    return place_block(model, **kw)


def _check_duration(x):
    from alpes_dyn.limits import check_duration

    return check_duration(x, "d")


def _raise_np():
    raise InputError(f"x: got {np.float64(0.1)!r} and {np.int64(3)!r}, {np.bool_(True)!r}")


def _hand(controller="sensor", **kw):
    from alpes_dyn.control import run_hand_control

    return run_hand_control(controller, **kw)


def _grasp_levels(limits):
    from alpes_dyn.control import grasp_levels

    return grasp_levels(limits)


def _hand_levels():
    from alpes_dyn.control import HAND_LEVELS

    return dict(HAND_LEVELS)


def _chain_frame(chain):
    from alpes_dyn.control import chain_frame

    return chain_frame(ad.load_params(), chain)


def _chain_model(chain):
    from alpes_dyn.control import chain_model

    return chain_model(ad.load_params(), chain)


def _cyl_normal(c, axis):
    from alpes_dyn.control import cylinder_normal

    return cylinder_normal(c.m, np.zeros(3), (0.0, 0.0, 0.05), axis)


def _friction_row(case):
    from alpes_dyn.studies.realism_friction import friction_row

    return friction_row(case, 0)


def _held_out_ramp(case):
    from alpes_dyn.studies.realism_friction import held_out_ramp

    return held_out_ramp(case, 0, None)


def _check_observer_law(law):
    from alpes_dyn.model.friction import check_observer_law

    return check_observer_law(law)


def _mjrec(**kw):
    from alpes_dyn.control.plants import mujoco_recording

    kw = {"model": "finger3", "true_params": None, "torque": np.full((200, 1), 0.02), **kw}
    return mujoco_recording(kw.pop("model"), kw.pop("true_params"), kw.pop("torque"), **kw)


def _sheathed():
    """The shipped parameters with a sheath friction (mu theta 0.2) on the tendons."""
    from alpes_dyn.model.params import Param, with_values

    return with_values(ad.load_params(), {"transmission.capstan": Param(0.2, "-", "assumed", "test", "sheath")})


def _eff(**kw):
    from alpes_dyn.control.plants import PlantEffects

    return PlantEffects(**kw)


def _adapted(**kw):
    from alpes_dyn.estimation.experiments.adapt import adapted_experiment

    return adapted_experiment(kw.pop("model", "finger3"), design=_design(), **kw)


def _line_basis(starts):
    from alpes_dyn.estimation.identification.torque_lines import line_basis

    return line_basis(1e-3 * np.arange(1001), (0.7, 3.1), starts)


def _exptorque(**kw):
    from alpes_dyn.estimation.experiments.experiment import experiment_torque

    return experiment_torque(kw.pop("model", "finger3"), **kw)


def _mjcf(**kw):
    from alpes_dyn.model.mjcf import mjcf_string

    return mjcf_string("finger3", **kw)


def _plot_path(p):
    from alpes_dyn.estimation.observers.scenario import check_plot_path

    return check_plot_path(p)


def _cexport(c, what, *a, **kw):
    from alpes_dyn.estimation.cexport import cexport

    return getattr(cexport, what)(*a, **kw)


def _fcexport(what, *a, **kw):
    from alpes_dyn.control import cexport

    return getattr(cexport, what)(*a, **kw)


API.extend([
    A("c_sources", lambda c: _cexport(c, "c_sources", c.ss), InputError, "filt: expected a KalmanFilter, got StateSpace"),
    A("c_sources", lambda c: _cexport(c, "c_sources", _ekf(c), prefix="2x"), InputError, "prefix: expected a C identifier"),
    A("c_sources", lambda c: _cexport(c, "c_sources", _ekf(c), code="fast"), InputError,
      "code: expected 'sparse' or 'casadi', got 'fast'"),
    A("c_sources", lambda c: _cexport(c, "c_sources", _ekf(c), code="sparse", chains="yes"), InputError,
      "chains: expected True or False, got 'yes'"),
    A("c_sources", lambda c: _cexport(c, "c_sources", _ekf(c), code="casadi", chains=True), InputError,
      "chains: the model's code by block is the 'sparse' code's"),
    A("c_sources", lambda c: _cexport(c, "c_sources", _ukf(c), code="sparse"), InputError,
      "code: 'sparse' is the EKF's; the ukf is exported as 'casadi'"),
    A("write_c_observer", lambda c: _cexport(c, "write_c_observer", _ekf(c), c.d), InputError,
      "is not empty; refusing to write over it"),
    A("write_c_observer", lambda c: _cexport(c, "write_c_observer", _ekf(c), c.f["params_toml"]), InputError,
      "exists and is not a directory"),
    A("scenario_filter", lambda c: _cexport(c, "scenario_filter", "pf"), InputError, "unknown observer 'pf'"),
    A("scenario_filter", lambda c: _cexport(c, "scenario_filter", "ekf", "hand"), InputError,
      "model: the estimation scenario is defined for one finger or the thumb"),
    A("read_main_output", lambda c: _cexport(c, "read_main_output", "1 2 3\n", 6), InputError,
      "main.c output: expected lines of 42 numbers"),
    A("write_sources", lambda c: _cexport(c, "write_sources", {"../x.c": ""}, c.d / "new"), InputError,
      "files: '../x.c' is not a plain file name"),
    A("check_output_directory", lambda c: _cexport(c, "check_output_directory", ""), InputError,
      "-o: expected a directory name"),
    A("controller_c_sources", lambda c: _fcexport("controller_c_sources", c.m), InputError,
      "ctl: expected a ForceController, got Model"),
    A("block_controller", lambda c: _fcexport("block_controller", "pid"), InputError, "unknown controller 'pid'"),
    A("block_controller", lambda c: _fcexport("block_controller", "sensor", "hand"), InputError,
      "defined for finger2 and finger3 on the block"),
    A("read_force_output", lambda c: _fcexport("read_force_output", "1\n"), InputError,
      "force_main.c output: expected two numbers per line"),
    A("step_c_sources", lambda c: _cstep("step_c_sources", c.m), InputError, "step: expected a ForceStep, got Model"),
    A("write_c_step", lambda c: _cstep("write_c_step", _pi_step(), c.d), InputError,
      "is not empty; refusing to write over it"),
    A("write_c_step", lambda c: _cstep("write_c_step", _pi_step(), c.f["params_toml"]), InputError,
      "exists and is not a directory"),
    A("read_step_output", lambda c: _cstep("read_step_output", "1 2\n", 1, 4), InputError,
      "main.c output: expected lines of 6 numbers"),
])


def _cstep(what, *a, **kw):
    from alpes_dyn.control import cstep

    return getattr(cstep, what)(*a, **kw)


def _pi_step():
    from alpes_dyn.control.step import ForceStep

    return ForceStep("finger2", controller="pi", compiled=False)



def _loop(what: str, *a, **kw):
    from alpes_dyn.simulation import loop, plants, sensors

    mod = next(m for m in (loop, sensors, plants) if hasattr(m, what))
    return getattr(mod, what)(*a, **kw)


def _eblock(what: str, *a, **kw):
    from alpes_dyn.estimation.observers import blocks

    return getattr(blocks, what)(*a, **kw)


def _compensation(**kw):
    from alpes_dyn.control.realism_loop import Compensation

    return Compensation(**kw).check()


def _cblock(what: str, *a, **kw):
    from alpes_dyn.control import blocks

    return getattr(blocks, what)(*a, **kw)


def _src(n=3):
    return _loop("Source", u=np.ones(n))


# the closed-loop engine: the runner, its blocks
API.extend([
    A("run_loop", lambda c: _loop("run_loop", [_src()], 0, 1e-3), InputError, "n_periods: expected an integer >= 1"),
    A("run_loop", lambda c: _loop("run_loop", [_src()], 2, float("nan")), InputError, "dt: expected a positive number"),
    A("run_loop", lambda c: _loop("run_loop", [_src()], 2, 1e-3, mode="fast"), InputError,
      "mode: expected one of auto, step, batch"),
    A("run_loop", lambda c: _loop("run_loop", [_src(), "encoder"], 2, 1e-3), InputError,
      "blocks: expected Block objects, got str at position 1"),
    A("run_loop", lambda c: _loop("run_loop", [_src(), _src()], 2, 1e-3), InputError, "'u': written by two blocks"),
    A("run_loop", lambda c: _loop("run_loop", [_loop("Function", lambda v: v, ("v",), "w")], 2, 1e-3), InputError,
      "'v': read by block 'function' but written by no block"),
    A("run_loop", lambda c: _loop("run_loop", [_src(2)], 2, 1e-3, final=True), InputError, "u: expected at least 3 rows"),
    A("Source", lambda c: _loop("Source"), InputError, "Source: expected at least one signal"),
    A("Function", lambda c: _loop("Function", 3, ("a",), "b"), InputError, "fn: expected a callable, got int"),
    A("Function", lambda c: _loop("Function", abs, ("",), "b"), InputError, "inputs: expected signal names"),
    A("Encoder", lambda c: _loop("Encoder", "q", "y", 0), InputError, "counts_per_rev: expected a positive number"),
    A("Encoder", lambda c: _loop("Encoder", "q", "y", 4096, noise_counts=-1), InputError,
      "noise_counts: expected a non-negative number of counts"),
    A("Encoder", lambda c: _loop("Encoder", "q", "y", 4096, offset=float("inf")), InputError,
      "offset: expected a finite number of counts"),
    A("Encoder", lambda c: _loop("Encoder", "q", "y", 4096, rng=0), InputError,
      "rng: expected a numpy.random.Generator or None, got int"),
    A("Encoder", lambda c: _loop("Encoder", "q", "y", 4096, timing="later"), InputError,
      "timing: expected one of sample, period"),
    A("TorqueSensor", lambda c: _loop("TorqueSensor", "t", "m", gain=0.0), InputError, "gain: expected a positive"),
    A("TorqueSensor", lambda c: _loop("TorqueSensor", "t", "m", shape=3), InputError, "shape: expected a tuple of sizes"),
    A("TorqueSensor", lambda c: _loop("run_loop", [_loop("Source", t=np.ones((3, 2))), _loop("TorqueSensor", "t", "m")],
                                      2, 1e-3), InputError, "shape: sensor 'm' reads 't' of shape (2,), not its shape ()"),
    A("TorqueSensor", lambda c: _loop("run_loop", [_loop("Source", t=np.ones((3, 2))), _loop("TorqueSensor", "t", "m")],
                                      2, 1e-3, mode="step"), InputError, "shape: sensor 'm' reads 't' of shape (2,)"),
    A("TorqueSensor", lambda c: _loop("TorqueSensor", "t", "m", noise="big"), InputError,
      "std: expected a non-negative number"),
    A("TorqueSensor", lambda c: _loop("TorqueSensor", "t", "m", draws=-2), InputError,
      "draws: expected an integer >= 0 or None"),
    A("ForceSensor", lambda c: _loop("ForceSensor", "F", "Fm", resolution=0), InputError,
      "resolution: expected a positive number of N"),
    A("ForceSensor", lambda c: _loop("ForceSensor", "", "Fm"), InputError, "signal, reading: expected signal names"),
    A("SimulatorPlant", lambda c: _loop("SimulatorPlant", c.ss, np.zeros(6)), InputError,
      "model: expected an alpes_dyn.Model with a tendon transmission"),
    A("SimulatorPlant", lambda c: _loop("SimulatorPlant", c.m, np.zeros(6), substeps=0), InputError,
      "substeps: expected an integer >= 1"),
    A("SimulatorPlant", lambda c: _loop("SimulatorPlant", c.m, np.zeros(5)), InputError, "x0"),
    A("MujocoPlant", lambda c: _mj_plant(sensors={"F": "no_such_sensor"}), InputError,
      "sensors: the MuJoCo model has no sensor"),
    A("MujocoPlant", lambda c: _mj_plant(actuators={"tau": "no_such_motor"}), InputError,
      "actuators: the MuJoCo model has no actuator"),
    A("Observer", lambda c: _eblock("Observer", c.ss, np.zeros(6), np.ones(6)), InputError,
      "filt: expected a KalmanFilter"),
    A("Observer", lambda c: _eblock("Observer", _ekf(c), np.zeros(5), np.ones(6)), InputError, "z0"),
    A("ObserverBank", lambda c: _eblock("ObserverBank", []), InputError, "observers: expected a non-empty list"),
    A("RecordingPlayback", lambda c: _eblock("RecordingPlayback", "rec.csv"), InputError,
      "recording: expected a Recording, got str"),
    A("ForceLoop", lambda c: _cblock("ForceLoop", c.m), InputError, "controller: expected a ForceController, got Model"),
    A("SensorlessForce", lambda c: _cblock("SensorlessForce", c.m, 1.5), InputError, "alpha: expected a number in (0, 1]"),
    A("SensorlessForce", lambda c: _cblock("SensorlessForce", c.ss, 0.5), InputError, "model: expected an alpes_dyn.Model"),
    A("SensorlessForce", lambda c: _cblock("SensorlessForce", c.m, 0.5, scale=0.0), InputError,
      "scale: expected a positive number, got 0.0"),
    A("Compensation", lambda c: _compensation(force_scale=True), InputError, "force_scale: expected a number in [0.5, 2]"),
    A("Compensation", lambda c: _compensation(force_scale={"thumb": float("nan")}), InputError,
      "force_scale: expected a number in [0.5, 2] (or a dict chain -> number), got nan"),
    A("force_input", lambda c: _cblock("force_input", "F", "w", (0.0, 1.0)), InputError, "normal: expected 3 numbers"),
    A("EncoderPD", lambda c: _cblock("EncoderPD", 0.5, 1.0, 0.1, 0.0), InputError, "alpha: expected a number in (0, 1]"),
])


def _force_step(*a, **kw):
    """A ForceStep (Python's filter); without arguments the one finger3 step the rows of bad samples share (each
    refused before it advances)."""
    from alpes_dyn.control import ForceStep

    if not a and not kw:
        return _shared_force_step()
    return ForceStep(*a, **{"compiled": False, **kw})


@functools.lru_cache(maxsize=1)
def _shared_force_step():
    from alpes_dyn.control import ForceStep

    return ForceStep(compiled=False)


def _bench(hw_kw=None, **kw):
    from alpes_dyn.bench import Loopback
    from alpes_dyn.control import run_on_bench

    return run_on_bench(Loopback(**(hw_kw or {})), _force_step("finger3", controller="pi"),
                        kw.pop("reference", 0.3), kw.pop("duration", 0.01), **kw)


# the force loop's public step (issue 49): its construction, one sample, the loop through a hardware interface
API.extend([
    A("ForceStep", lambda c: _force_step(controller="pid"), InputError, "controller: unknown controller 'pid'"),
    A("ForceStep", lambda c: _force_step("hand"), InputError, "model: the force step is defined for one finger"),
    A("ForceStep", lambda c: _force_step(gains={"kq": 1.0}), InputError, "gains: unknown setting(s) 'kq'"),
    A("ForceStep", lambda c: _force_step(gains={"release_s": -0.05}), InputError,
      "release_s: expected a non-negative number of seconds or None, got -0.05"),
    A("ForceStep", lambda c: _force_step(compensation=1), InputError, "compensation: expected a Compensation"),
    A("ForceStep", lambda c: _force_step(dt=-1e-3), InputError, "dt: expected a positive number of seconds"),
    A("ForceStep", lambda c: _force_step(tau_max=0.1), InputError, "tau_max: applies to a URDF + spec model"),
    A("ForceStep", lambda c: _force_step(params=c.f["negative_k_toml"]), ModelError, "finger.K: value must be >= 0"),
    A("ForceStep.step", lambda c: _force_step().step([0.0, 0.0], [0.0], 0.1, 0.2), InputError,
      "counts: expected 1 encoder counts, got shape (2,)"),
    A("ForceStep.step", lambda c: _force_step().step([float("nan")], [0.0], 0.1, 0.2), InputError,
      "counts: expected finite encoder counts"),
    A("ForceStep.step", lambda c: _force_step().step([0.0], [0.0], None, 0.2), InputError,
      "force: the sensor controller needs the fingertip force"),
    A("ForceController.tuned", lambda c: __import__("alpes_dyn.control", fromlist=["x"]).ForceController.tuned(
        "pid", c.m, (0.0, 0.0, 1.0), 1e-3, 0.05), InputError, "controller: unknown controller 'pid'"),
    A("run_on_bench", lambda c: _bench({"period": 2e-3}), InputError, "period: the hardware's period 0.002 s"),
    A("run_on_bench", lambda c: _bench({"tau_max": 0.01}), InputError, "tau_max: the step commands up to 0.05 N m"),
    A("run_on_bench", lambda c: _bench(duration=float("nan")), InputError, "duration: expected a positive number"),
    A("run_on_bench", lambda c: _bench(reference=[0.1]), InputError, "reference: expected one force per tick"),
])


def _mj_plant(**kw):
    pytest.importorskip("mujoco")
    import mujoco

    from alpes_dyn.model.mjcf import load_mujoco, mjcf_string

    mj = load_mujoco(mjcf_string("finger3", ad.load_params(), friction=True, scene="block"))
    return _loop("MujocoPlant", mj, mujoco.MjData(mj), **kw)

# Public names that take no user input of their own (records returned by the library, constants, errors)
NOT_CALLED = {"AlpesDynError", "InputError", "ModelError", "RecordingError", "HandParams", "ObservabilityReport", "MODELS",
              "SPRING_MODELS"}


def _spec(**kw):
    from alpes_dyn.model.spec import Motor, TransmissionSpec

    motor = kw.pop("motor", None)
    return TransmissionSpec(motors=(Motor("m", **motor),) if motor else (), **kw)


def _checked_design(**kw):
    return _design(**kw).check()


API.extend([  # issue 19's re-check: every number of a file, a spec and the API within its unit's accepted range
    A("load_params", lambda c: ad.load_params(c.f["angle_toml"]), ModelError,
      "finger.upper: 1e+300 rad is outside the accepted range [-100, 100] rad"),
    A("load_params", lambda c: ad.load_params(c.f["ratio_toml"]), ModelError,
      "transmission.N: 1e+300 is outside the accepted range [1e-06, 1e+06]"),
    A("load_params", lambda c: ad.load_params(c.f["gravity_toml"]), ModelError,
      "environment.gravity: -1e+300 m/s^2 (index 2) is outside the accepted range [-100, 100] m/s^2"),
    A("load_params", lambda c: ad.load_params(c.f["subk_toml"]), ModelError,
      "finger.K (index 0): 1e-320 N m/rad is a subnormal number"),
    A("load_params", lambda c: ad.load_params(c.f["axis_toml"]), ModelError,
      "thumb.abduction_axis: value must be a unit vector (norm 1e+300)"),
    A("Model", lambda c: ad.Model.from_urdf_file(c.f["robot_urdf"], c.f["robotratio_toml"]), ModelError,
      "motor 'flexor'.joints.j1: 1e+300 is outside the accepted range"),
    A("Model", lambda c: ad.Model(FINGER3, gravity=[0.0, 0.0, -1e300]), ModelError,
      "gravity: -1e+300 m/s^2 (index 2) is outside the accepted range [-100, 100] m/s^2"),
    A("Model", lambda c: _spec(motor=dict(joints={"j1": 10**400})), ModelError,
      "motor 'm'.joints.j1: expected a finite number, got an integer of 401 digits"),
    A("Model", lambda c: _spec(motor=dict(joints={"j1": 1.0}, rotor_inertia=1e300)), ModelError,
      "motor 'm'.rotor_inertia: 1e+300 kg m^2 is outside the accepted range [0, 10000] kg m^2"),
    A("Model", lambda c: _spec(stiffness={"j1": 1e-320}), ModelError, "stiffness.j1: 1e-320 N m/rad is a subnormal"),
    A("Model", lambda c: _spec(gravity=(0.0, 0.0, 1e300)), ModelError,
      "gravity: 1e+300 m/s^2 is outside the accepted range [-100, 100] m/s^2"),
    A("Model", lambda c: _spec(encoder_counts=4096.5), ModelError, "encoder_counts: expected a whole number"),
    A("Model", lambda c: _mjcf(tendon_stiffness=1e300), InputError,
      "tendon_stiffness: 1e+300 N/m is outside the accepted range [1e-06, 1e+12] N/m"),
    A("Model", lambda c: _mjcf(timestep=10**400), InputError, "timestep: expected a positive number of seconds"),
    A("Model", lambda c: _mjcf(stiction=1e-320), InputError, "stiction: 1e-320 s is a subnormal number"),
    A("Model", lambda c: _mjcf(scene="block", block_friction=1e300), InputError,
      "block_friction: 1e+300 is outside the accepted range [0, 1e+06]"),
    A("read_recording", lambda c: _read_rec(c.f["current_csv"], torque_constant=1e300), RecordingError,
      "torque_constant: 1e+300 N m/A is outside the accepted range [1e-09, 1000] N m/A"),
    A("read_recording", lambda c: _read_rec(c.f["current_csv"], torque_constant=10**400), RecordingError,
      "torque_constant: expected a positive number of N m/A"),
    A("Model", lambda c: _ekf(c, process_noise=1e300), InputError, "process_noise: an entry of 1e+300 is over the "
      "limit of 1e+12"),
    A("Model", lambda c: _ekf(c, measurement_noise=1e-320), InputError, "measurement_noise: 1e-320 is a subnormal"),
    A("Model", lambda c: _checked_design(amplitude_fraction=10**400), InputError,
      "amplitude_fraction: expected a real number, got an integer too large for a float"),
    A("Model", lambda c: _checked_design(dither=1e-320), InputError, "dither: 1e-320 is a subnormal number"),
    A("experiment", lambda c: _exp(seed=10**400), InputError, "seed: expected an integer from 0 to 9223372036854775807"),
    # a name becomes a recording's column (at most 256 characters) and an MJCF name: at most 128 characters
    A("Model", lambda c: ad.Model(FINGER3.replace('"j3"', '"' + "j" * 300 + '"')), ModelError,
      "URDF: joint name 'jjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjjj'... of 300 characters, over the limit of 128"),
    A("Model", lambda c: _spec(motor=dict(joints={"j1": 1.0}), name="r" * 200), ModelError,
      "name: 'rrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrrr'... has 200 characters, over the limit of 128"),
])


def _mimic(attrs: str) -> str:
    """finger3 whose j2 follows j1 with the ``<mimic>`` attributes ``attrs`` (or elements, with a leading '>')."""
    return FINGER3.replace('<joint name="j2" type="revolute">', f'<joint name="j2" type="revolute"><mimic {attrs}/>', 1)


def _sweep_api():
    return __import__("alpes_dyn.studies.sweep", fromlist=["x"])


def _one(seed: int, x: float = 1.0) -> dict:
    return {"x": x * seed}


def _replay_rec3(c, **kw):
    from alpes_dyn.estimation.observers.replay import estimate_recording

    return estimate_recording(c.f["rec3_csv"], c.m, **kw)


API.extend([  # issue 19's third re-check: mimic attributes, the hot paths' bound, sweep, the replay's numbers
    A("Model", lambda c: ad.Model(_mimic('joint="j1" offset="1e7"')), ModelError,
      "joint 'j2': <mimic offset='1e7'>: 1e+07 rad is outside the accepted range [-100, 100] rad"),
    A("Model", lambda c: ad.Model(_mimic('joint="j1" offset="1e-320"')), ModelError,
      "<mimic offset='1e-320'>: 1e-320 rad is a subnormal number"),
    A("Model", lambda c: ad.Model(_mimic('joint="j1" multiplier="1_0"')), ModelError,
      "joint 'j2': <mimic multiplier='1_0'> is not a finite number (write a decimal number"),
    A("Model", lambda c: ad.Model(_mimic('joint="j1" multiplier="2 "')), ModelError,  # urdfdom refuses it too
      "joint 'j2': <mimic multiplier='2 '> has a blank after the number (URDF readers refuse it"),
    A("Model", lambda c: ad.Model(_mimic('joint="j1"/><mimic joint="j3" multiplier="2"')), ModelError,
      "joint 'j2': 2 <mimic> elements; a joint follows one joint"),
    A("Model", lambda c: c.m.forward_dynamics(np.array([1e300, 0.0, 0.0]), c.z, c.z), InputError,
      "q: 1e+300 (index 0) is over the numeric hot paths' bound of 2^40 = 1.1e12 in magnitude"),
    A("Model", lambda c: c.m.forward_dynamics(c.z, np.array([0.0, 0.0, -1e13]), c.z), InputError,
      "v: -1e+13 (index 2) is over the numeric hot paths' bound"),
    A("Model", lambda c: c.m.forward_dynamics(c.z, c.z, [0.0, 2e12, 0.0]), InputError,
      "tau: 2e+12 (index 1) is over the numeric hot paths' bound"),
    A("Model", lambda c: c.m.inertia_matrix(np.array([0.0, 1e15, 0.0])), InputError, "q: 1e+15 (index 1) is over"),
    A("StateSpace", lambda c: c.ss.f(np.array([1e13, 0, 0, 0, 0, 0.0]), np.zeros(1)), InputError,
      "x: 1e+13 (index 0) is over the numeric hot paths' bound"),
    A("compile_rollout", lambda c: _rollout(c).rollout(np.array([0, 0, 1e13, 0, 0, 0.0]), np.zeros((2, 3))),
      InputError, "x0_batch: 1e+13 (index 2) is over the numeric hot paths' bound"),
    A("sweep", lambda c: _sweep_api().sweep(_one, 1, options={"y": 2.0}, serial=True), InputError,
      "options: _one takes no argument 'y' (its arguments: seed, x)"),
    A("sweep", lambda c: _sweep_api().sweep(_one, 1, serial=True, workers=3), InputError,
      "workers: serial already says where the draws run"),
    A("sweep", lambda c: _sweep_api().sweep(_one, 1, scheduler="tcp://127.0.0.1:1", workers=3), InputError,
      "workers: scheduler already says where the draws run"),
    A("sweep", lambda c: _sweep_api().sweep(lambda seed: {"names": ["a", "b"]}, 1, serial=True), InputError,
      "fn: result 'names' (seed 0): expected numbers"),
    A("sweep", lambda c: _sweep_api().sweep(lambda seed: {"c": [1 + 2j]}, 1, serial=True), InputError,
      "fn: result 'c' (seed 0): complex values are not supported"),
    A("sweep", lambda c: _sweep_api().sweep(lambda seed: {"r": [[1.0, 2.0], [3.0]]}, 1, serial=True), InputError,
      "fn: result 'r' (seed 0): expected numbers"),
    A("sweep", lambda c: _sweep_api().sweep(lambda seed: {1: 2.0}, 1, serial=True), InputError,
      "fn: a draw's result has the key 1, expected a string (seed 0)"),
    A("sweep", lambda c: _sweep_api().sweep(_one, 1, serial=True).table(["nope"]), InputError,
      "columns: 'nope' is not a column (columns: seed, x)"),
    A("estimate_recording", lambda c: _replay_rec3(c, torque_noise=1e300), InputError,
      "torque_noise: 1e+300 N m is outside the accepted range [0, 1e+06] N m"),
    A("estimate_recording", lambda c: _replay_rec3(c, tilt=[1e300, 0.0]), InputError,
      "tilt: 1e+300 rad (index 0) is outside the accepted range [-100, 100] rad"),
    A("estimate_recording", lambda c: _replay_rec3(c, encoder_offset=[1e-320]), InputError,
      "encoder_offset: 1e-320 rad is a subnormal number"),
    A("estimate_recording", lambda c: _replay_rec3(c, compiled="yes"), InputError, "compiled: expected True or False"),
    A("read_recording", lambda c: __import__("alpes_dyn.estimation.experiments.recording", fromlist=["x"]).read_recording(3, c.m),
      RecordingError, "recording: expected a file path, got int"),
    A("write_sources", lambda c: __import__("alpes_dyn.fileio", fromlist=["x"]).write_directory(
        {"a\0.c": "int x;"}, c.f["tmp"] + "/cg"), InputError, "files: 'a\\x00.c' is not a plain file name"),
    A("write_sources", lambda c: __import__("alpes_dyn.fileio", fromlist=["x"]).write_directory(
        {"a.c": b"int x;"}, c.f["tmp"] + "/cg"), InputError, "files: 'a.c''s content is bytes, expected str"),
])


API.extend([  # issue 19's fourth re-check: the sub-model's and the effects' arguments
    A("subtree_model", lambda c: __import__("alpes_dyn.model.subtree", fromlist=["x"]).subtree_model("hand.urdf", "fa"),
      ModelError, "model: expected an alpes_dyn Model, got str"),
    A("closed_motors", lambda c: __import__("alpes_dyn.model.subtree", fromlist=["x"]).closed_motors(None, "fa"),
      ModelError, "model: expected an alpes_dyn Model, got NoneType"),
    A("branch_joints", lambda c: __import__("alpes_dyn.model.subtree", fromlist=["x"]).branch_joints(object(), "fa"),
      ModelError, "model: expected an alpes_dyn Model, got object"),
    A("unseen_masses", lambda c: __import__("alpes_dyn.symbolic.parametric", fromlist=["x"]).unseen_masses("finger3"),
      ModelError, "model: expected an alpes_dyn Model, got str"),
    A("select_parameters", lambda c: __import__("alpes_dyn.symbolic.parametric", fromlist=["x"]).select_parameters(
        None, "K"), ModelError, "model: expected an alpes_dyn Model, got NoneType"),
    A("parse_effects", lambda c: _parse_effects(5), InputError,
      "effects: expected a comma-separated string or a list of effect names, got int 5"),
    A("parse_effects", lambda c: _parse_effects({"rotor"}), InputError,
      "effects: expected a comma-separated string or a list of effect names, got set"),
    A("parse_effects", lambda c: _parse_effects(["rotor", None]), InputError,
      "effects: expected a comma-separated string or a list of effect names, got list"),
    A("parse_effects", lambda c: _parse_effects([]), InputError, "effects: an empty list (give 'none' for the rigid"),
    A("parse_effects", lambda c: _parse_effects("none,stiction"), InputError, "effects: 'none' goes alone"),
    # a trailing '/' after a file's name (Path() dropped it: the file was read)
    A("read_recording", lambda c: _read_rec(c.f["rec3_csv"] + "/"), RecordingError,
      "recording '{rec3_csv}/': a path through a file that is not a directory"),
    A("load_params", lambda c: ad.load_params(c.f["rec3_csv"] + "/"), ModelError, "a path through a file"),
    # a column of another branch, ignored for the sub-model, still an encoder in counts
    A("read_recording", lambda c: _read_branch_fa({"encoder_fb": 1e12}), RecordingError,
      "column 'encoder_fb' line 52: 1e+12 counts is beyond what the joint ranges allow"),
])


def _read_branch_fa(override: dict[str, float]):
    """A recording of both branches of :data:`BRANCHES_URDF` (without the tendon across them) read for the
    sub-model of motor fa, row 50 (line 52) of the columns ``override`` set to their values."""
    import tempfile

    from alpes_dyn.estimation.experiments.recording import read_recording

    whole = ad.Model(BRANCHES_URDF, TransmissionSpec.from_toml(BRANCHES_SPEC.split("[[motor]]\nname = \"across\"")[0]
                                                               + "[stiffness]\nja = 0.1\njb = 0.1\n"))
    rng = np.random.default_rng(0)
    cols = {"t": np.arange(200) * 1e-3}
    for m in ("fa", "fb"):
        cols[f"encoder_{m}"] = np.round(rng.uniform(-50, 50, 200))
        cols[f"torque_{m}"] = rng.normal(0, 1e-3, 200)
    for k, v in override.items():
        cols[k][50] = v
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "r.csv"
        path.write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(cols[k][i])) for k in cols)
                                                             for i in range(200)) + "\n")
        return read_recording(path, whole.subtree("fa"), ignore_others_of=whole)



def _parse_effects(text):
    from alpes_dyn.estimation.identification.effects import parse_effects

    return parse_effects(text)


def _excursion(fn, recording, *args):
    from alpes_dyn.estimation.experiments import excursion

    return getattr(excursion, fn)(recording, *args)


def _rec_of(counts):
    from alpes_dyn.estimation.experiments.recording import Recording

    enc = np.asarray(counts, dtype=float).reshape(-1, 1)
    return Recording(t=np.arange(enc.shape[0]) * 1e-3, encoder=enc, torque=np.zeros_like(enc), motor_names=("m",),
                     joint_names=("j",))


_P3_I = 'ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"'


def _p3_inertial_origin(xyz: str) -> str:
    """finger3's URDF with the ``<origin xyz>`` of its last phalanx p3's inertial replaced."""
    out, n = re.subn(r'(<link name="p3">\s*<inertial>\s*<origin xyz=")[^"]*"', rf'\g<1>{xyz}"', FINGER3)
    assert n == 1
    return out


API.extend([  # issue 19's sixth re-check: an inertial urdfdom cannot read (Pinocchio then builds the link massless)
    A("Model", lambda c: ad.Model(_with_p3_inertial("0.023 ", _P3_I)), ModelError,
      "link 'p3': mass: '0.023 ' has a blank after the number (URDF readers refuse it"),
    A("Model", lambda c: ad.Model(_with_p3_inertial("2_3e-2", _P3_I)), ModelError,
      "link 'p3': mass: '2_3e-2' is not a finite number (write a decimal number"),
    A("Model", lambda c: ad.Model(_with_p3_inertial("0.023", _P3_I.replace('ixx="1e-6"', 'ixx="1e-6 "'))), ModelError,
      "link 'p3': inertia ixx: '1e-6 ' has a blank after the number"),
    A("Model", lambda c: ad.Model(_with_p3_inertial("0.023", _P3_I.replace('ixy="0" ', ''))), ModelError,
      "link 'p3': inertia ixy: missing (URDF readers then drop the link's whole inertial"),
    A("Model", lambda c: ad.Model(FINGER3.replace('<mass value="0.023"/>', '<mass/>', 1)), ModelError,
      "link 'p3': mass: missing"),
    A("Model", lambda c: ad.Model(_p3_inertial_origin("0.01 0")), ModelError,
      "link 'p3': inertial origin xyz='0.01 0': expected 3 numbers, got 2"),
    A("Model", lambda c: ad.Model(_p3_inertial_origin("0.01 0 0x0")), ModelError,
      "link 'p3': inertial origin xyz: expected a number, got '0x0'"),
    A("check_inertials", lambda c: __import__("alpes_dyn.model.inertial", fromlist=["x"]).check_inertials(
        _with_p3_inertial("inf", _P3_I)), ModelError, "link 'p3': mass: must be finite, got 'inf'"),
])


API.extend([  # the encoder excursion check of experiment and identify (issue 17)
    A("encoder_excursions", lambda c: _excursion("encoder_excursions", "rec.csv"), InputError,
      "recording: expected a Recording with encoder counts (N, motors), got str"),
    A("small_excursions", lambda c: _excursion("small_excursions", _rec_of([0, 5]), -1.0), InputError,
      "threshold: expected a number of counts >= 0, got -1.0"),
    A("small_excursions", lambda c: _excursion("small_excursions", _rec_of([0, 5]), float("nan")), InputError,
      "threshold: expected a number of counts >= 0, got nan"),
    A("small_excursions", lambda c: _excursion("small_excursions", _rec_of([0, 5]), "30"), InputError,
      "threshold: expected a number of counts >= 0, got '30'"),
    A("small_excursions", lambda c: _excursion("small_excursions", _rec_of([0, 5]), True), InputError,
      "threshold: expected a number of counts >= 0, got True"),
    A("excursion_report", lambda c: _excursion("excursion_report", None), InputError,
      "recording: expected a Recording with encoder counts (N, motors), got NoneType"),
    A("warn_small_excursions", lambda c: _excursion("warn_small_excursions", _rec_of([0, 5]), -2), InputError,
      "threshold: expected a number of counts >= 0, got -2"),
    # the stops each joint gets (alpes-dyn dynamics' table)
    A("stop_table", lambda c: _stop_table("finger3"), InputError, "model: expected an alpes_dyn Model, got str"),
    A("stop_table", lambda c: _stop_table(ad.Model.alpes("finger3"), per_joint="yes"), InputError,
      "per_joint: expected True or False, got 'yes'"),
])


def _mjcf_recording(mjcf, model, torque, **kw):
    """mjcf_recording on ROBOT_URDF + ROBOT_SPEC (model None) and its MJCF (mjcf a dict: model_mjcf's keywords)."""
    from alpes_dyn.control.plants import mjcf_recording

    robot = ad.Model(ROBOT_URDF, TransmissionSpec.from_toml(ROBOT_SPEC))
    text = robot.to_mjcf(**mjcf) if isinstance(mjcf, dict) else mjcf
    return mjcf_recording(text, robot if model is None else model, torque, **kw)


def _stop_table(model, **kw):
    from alpes_dyn.model.stops import stop_table

    return stop_table(model, **kw)


def test_hot_path_below_its_bound_is_newton():
    """Below 2^40 the hot path gives what eq. 2.10 gives, however large: Gamma = 1e11 N m on finger3 against a
    dense solve of A qdd = Gamma - nle - k q (Pinocchio's CRBA and RNEA, numpy's solve); and the bound is the
    magnitude of one entry (three entries of 9e11, whose norm is 1.6e12 > 2^40, pass: the exact check decides)."""
    import pinocchio as pin

    m = ad.Model.alpes("finger3")
    q, v, tau = np.array([0.3, 0.5, 0.2]), np.array([0.1, -0.2, 0.3]), np.array([1e11, 0.0, -1e11])
    A = pin.crba(m.pin_model, m.pin_model.createData(), q)
    A = np.triu(A) + np.triu(A, 1).T
    nle = pin.rnea(m.pin_model, m.pin_model.createData(), q, v, np.zeros(3))
    np.testing.assert_allclose(m.forward_dynamics(q, v, tau), np.linalg.solve(A, tau - nle - m.spring_torque(q)),
                               rtol=1e-9)
    big = np.full(3, 9e11)
    assert np.linalg.norm(big) > 2.0**40
    np.testing.assert_allclose(m.inverse_dynamics(q, v, big) - m.inverse_dynamics(q, v, np.zeros(3)), A @ big,
                               rtol=1e-9)


def test_sweep_api_output_in_a_read_only_folder(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(InputError, match="is not writable"):
            _sweep_api().sweep(_one, 1, serial=True).to_csv(ro / "s.csv")
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)


def _ratio_model(curve: tuple[float, ...]) -> ad.Model:
    """finger3's URDF with one motor whose ratio on j1 is 1 + curve(q_1) (joint range [0, pi/2])."""
    from alpes_dyn.model.spec import Motor

    return ad.Model(FINGER3, TransmissionSpec(motors=(Motor("m", {"j1": 1.0, "j2": 1.0}, ratio_curve={"j1": curve}),),
                                              name="curved"))


def _steep_run() -> Any:
    """A steep ratio curve (1 + 50 q_1^3) simulated under a constant motor torque: j1 leaves its range, the curve
    beyond it crosses 0 and the state diverges."""
    from alpes_dyn.simulation.integrate import simulate

    m = _ratio_model((0.0, 0.0, 50.0))
    return simulate(m, np.zeros(2 * m.n), np.array([0.05]), duration=1.0, input="motor")


API.extend([  # issue 52's silent cases
    A("ExperimentDesign", lambda c: __import__("alpes_dyn.estimation", fromlist=["x"]).ExperimentDesign(
        duration=0.15, orientations=((0.0, 0.0, -9.81), (9.81, 0.0, 0.0))).check(),
      InputError, "duration: 0.15 s gives 75 samples to each of the 2 orientations; each needs at least 100"),
    A("Model", lambda c: _ratio_model((-2.0,)), ModelError,
      "motor 'm'.ratio_curve.j1: the ratio is 0 at q = 0.5 rad, inside the joint's range [0, 1.5708] rad"),
    A("Model", lambda c: _ratio_model((-4.0, 4.0)), ModelError,  # touching 0 (a double root) is 0 too
      "motor 'm'.ratio_curve.j1: the ratio is 0 at q = 0.5 rad"),
    A("simulate", lambda c: _steep_run(), InputError,
      "after joint 'j1' left its range [0, 1.5708] rad at t = "),
])


def test_every_public_api_has_rows():
    public = set(ad.__all__) - NOT_CALLED
    covered = {row.api for row in API}
    assert public <= covered, f"public names without bad-input rows: {sorted(public - covered)}"


@pytest.fixture(scope="module")
def ctx(tmp_path_factory):
    return Ctx(tmp_path_factory.mktemp("bad_api"))


@pytest.mark.parametrize("row", API, ids=[f"{r.api}:{i}" for i, r in enumerate(API)])
def test_api_bad_input(ctx, row):
    before = _files_under(ctx.d)
    with pytest.raises(row.error) as e:
        row.call(ctx)
    assert isinstance(e.value, AlpesDynError)
    msg = str(e.value)
    assert "\n" not in msg and msg.strip() == msg and msg
    assert row.needle.format(**ctx.f) in msg, msg
    assert _files_under(ctx.d) == before, "a file was left behind"


# ----------------------------------------------------------------------------- the process: signals, streams, compiler
def _env(**kw: str) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), PYTHONDONTWRITEBYTECODE="1", **kw)


_WRITER = """
import sys, time
from alpes_dyn.fileio import atomic_path
with atomic_path(sys.argv[1], "-o") as tmp:
    tmp.write_text("half of the new content")
    print("writing", flush=True)
    time.sleep(60)
"""


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT", "SIGHUP"])
def test_signal_mid_write_leaves_old_file_and_no_temp(tmp_path, sig):
    """A process stopped by a signal while it writes: the old file intact, no ``.NAME.*.tmp`` left behind."""
    import signal

    dest = tmp_path / "out.toml"
    dest.write_text("old content\n")
    signum = getattr(signal, sig)
    # the signal's default disposition in the child, whatever the runner's (under nohup SIGHUP is ignored, and
    # the ignored disposition is inherited: the writer then rightly sleeps through it)
    p = subprocess.Popen([sys.executable, "-c", _WRITER, str(dest)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=_env(), preexec_fn=lambda: signal.signal(signum, signal.SIG_DFL))
    assert p.stdout.readline() == "writing\n"
    assert len(list(tmp_path.iterdir())) == 2  # the temporary file exists while writing
    p.send_signal(signum)
    p.wait(timeout=30)
    assert p.returncode != 0
    if sig != "SIGINT":  # died by the signal, as without alpes_dyn's handler
        assert p.returncode == -getattr(signal, sig)
    assert [x.name for x in tmp_path.iterdir()] == ["out.toml"]
    assert dest.read_text() == "old content\n"


def _slow_cc(tmp_path: Path, seconds: float) -> Path:
    """A C compiler that first records its TMPDIR, then waits, then runs gcc."""
    cc = tmp_path / "slowcc"
    cc.write_text(f"#!/bin/sh\necho \"$TMPDIR\" > {tmp_path}/tmpdir.txt\nsleep {seconds}\nexec gcc \"$@\"\n")
    cc.chmod(0o755)
    return cc


def test_compiler_temp_files_in_the_build_folder(tmp_path):
    """gcc's own temporary files go into the cache's build folder (TMPDIR), removed with it."""
    from alpes_dyn.simulation.buildcache import build_library

    cache = tmp_path / "cache"
    lib, compiled, _, handle = build_library("int alpes_one(void) { return 1; }\n", "one", str(_slow_cc(tmp_path, 0)),
                                             ("-O0", "-shared", "-fPIC"), cache)
    assert compiled and handle.alpes_one() == 1
    tmpdir = Path((tmp_path / "tmpdir.txt").read_text().strip())
    assert tmpdir.parent == cache and tmpdir.name.startswith(".build@one_")
    assert not tmpdir.exists()  # the build folder is gone after the build
    assert sorted(p.name for p in cache.iterdir() if p.name.startswith(".build@")) == []


_BUILDER = """
import sys
from pathlib import Path
from alpes_dyn.simulation.buildcache import build_library
build_library("int alpes_one(void) { return 1; }\\n", "one", sys.argv[1], ("-O0", "-shared", "-fPIC"), Path(sys.argv[2]))
"""


def test_sigterm_during_compile_removes_the_build_folder(tmp_path):
    import signal
    import time

    cache = tmp_path / "cache"
    p = subprocess.Popen([sys.executable, "-c", _BUILDER, str(_slow_cc(tmp_path, 60)), str(cache)], env=_env(),
                         stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while not (tmp_path / "tmpdir.txt").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert any(x.name.startswith(".build@") for x in cache.iterdir())
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=30)
    assert p.returncode == -signal.SIGTERM
    assert [x.name for x in cache.iterdir() if not x.name.endswith(".lock")] == []


def test_cache_needs_a_home_or_alpes_dyn_cache(monkeypatch):
    from alpes_dyn.simulation import CompilerError, cache_dir

    monkeypatch.delenv("ALPES_DYN_CACHE", raising=False)
    for home in ("", "relative/home"):
        monkeypatch.setenv("HOME", home)
        with pytest.raises(CompilerError, match="set ALPES_DYN_CACHE") as e:
            cache_dir()
        assert "\n" not in str(e.value)
    monkeypatch.setenv("ALPES_DYN_CACHE", "/some/cache")
    assert cache_dir() == Path("/some/cache")


def test_cc_that_does_not_exist_is_an_error_naming_cc(monkeypatch):
    from alpes_dyn.simulation import CompilerError
    from alpes_dyn.simulation.codegen import _compiler

    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.raises(CompilerError, match=r"^CC: the C compiler '/nonexistent/cc' is not found"):
        _compiler()
    monkeypatch.delenv("CC")
    assert Path(_compiler()).name in ("gcc", "cc")  # unset: the system's gcc


def _cli(*argv: str, **kw: Any) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "alpes_dyn.cli", *argv], text=True, timeout=120,
                          **{"env": _env(), **kw})


def test_stdout_broken_pipe_is_one_line_exit_2():
    p = subprocess.Popen([sys.executable, "-m", "alpes_dyn.cli", "urdf", "--model", "hand"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=_env())
    p.stdout.close()  # the reader is gone before the first byte (``| head -c0``)
    err = p.stderr.read()
    assert p.wait(timeout=60) == 2
    assert err == "alpes-dyn: error: stdout: broken pipe (the reader closed it before the end of the output)\n"


def test_stdout_on_a_full_device_is_one_line_exit_2():
    with open("/dev/full", "w") as full:
        for argv in (("dynamics", "--json"), ("--help",)):
            r = _cli(*argv, stdout=full, stderr=subprocess.PIPE)
            assert r.returncode == 2, r.stderr
            assert r.stderr == "alpes-dyn: error: stdout: cannot write the output (No space left on device)\n"


def test_closed_stderr_keeps_the_exit_code():
    """``2>&-``: nothing to write the error line to; the exit code still tells (2 bad input, 0 success)."""
    close2 = lambda: os.close(2)  # noqa: E731
    bad = _cli("dynamics", "--q", "1", capture_output=True, preexec_fn=close2)
    assert bad.returncode == 2 and bad.stdout == ""
    good = _cli("dynamics", "--json", stdout=subprocess.PIPE, preexec_fn=close2)
    assert good.returncode == 0 and json.loads(good.stdout)["model"] == "finger3"


def test_help_on_an_ascii_terminal():
    r = _cli("identifiability", "--help", capture_output=True, env=_env(PYTHONIOENCODING="ascii"))
    assert r.returncode == 0 and r.stderr == ""
    assert "Cram\\xe9r-Rao" in r.stdout


def test_byte_order_mark_accepted(tmp_path):
    """A UTF-8 BOM (as Windows editors write) is read as nothing: TOML, spec, CSV."""
    from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
    from alpes_dyn.model.spec import load_spec

    files = bad_files(tmp_path)
    from alpes_dyn.model.params import params_toml

    assert params_toml(ad.load_params(files["bom_toml"]).raw) == params_toml(ad.load_params().raw)
    shipped = Path(ad.__file__).parent / "data" / "allegro_hand_spec.toml"
    (tmp_path / "bom_spec.toml").write_bytes(b"\xef\xbb\xbf" + shipped.read_bytes())
    assert load_spec(tmp_path / "bom_spec.toml") == load_spec(shipped)
    rec = _exp()
    path = write_recording(rec, tmp_path / "rec.csv")
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    m = ad.Model.alpes("finger2")
    a, b = read_recording(path, m), read_recording(bom, m)
    assert np.array_equal(a.t, b.t) and np.array_equal(a.encoder, b.encoder)


def test_header_with_control_characters_reads_back(tmp_path):
    """A recording name with control characters (ESC, NUL, a line separator) in a written file's header:
    escaped, so the file stays TOML that loads back to the same values."""
    from alpes_dyn.model.params import params_toml, write_params

    p = ad.load_params()
    path = write_params(p, tmp_path / "p.toml", header="from rec\x00\x1b[31m\u2028.csv\rnext")
    head = path.read_text().splitlines()[0]
    assert head == "# from rec\\x00\\x1b[31m\\u2028.csv\\x0dnext"
    assert params_toml(ad.load_params(path).raw) == params_toml(p.raw)


def test_recording_row_limit(tmp_path, monkeypatch):
    """Rows are counted before the CSV is parsed (the limit lowered here to 50: a real one is 20 million)."""
    from alpes_dyn.estimation.experiments import recording

    path = recording.write_recording(_exp(), tmp_path / "rec.csv")  # 201 rows
    monkeypatch.setattr(recording, "MAX_CSV_ROWS", 50)
    with pytest.raises(RecordingError, match=r"rec.csv': more than 50 rows \(the limit of a recording\)$"):
        recording.read_recording(path, ad.Model.alpes("finger2"))
    monkeypatch.setattr(recording, "MAX_CSV_ROWS", 201)
    assert recording.read_recording(path, ad.Model.alpes("finger2")).t.shape == (201,)


def test_long_file_name_written(tmp_path):
    """A legal 250-character file name: the temporary name next to it must fit as well."""
    from alpes_dyn.fileio import atomic_write

    dest = tmp_path / ("r" * 246 + ".csv")
    assert atomic_write(dest, "x\n").read_text() == "x\n"
    assert [p.name for p in tmp_path.iterdir()] == [dest.name]


def test_unix_epoch_time_stamps_accepted(tmp_path):
    """t in Unix-epoch seconds (~1.7e9 s, resolution ~0.24 us): uniform to its float resolution, accepted;
    a real jitter of 1 % of a period still refused."""
    import dataclasses

    from alpes_dyn.estimation.experiments.recording import read_recording, write_recording

    rec = _exp()
    m = ad.Model.alpes("finger2")
    epoch = write_recording(dataclasses.replace(rec, t=rec.t + 1.7e9), tmp_path / "epoch.csv")
    back = read_recording(epoch, m)
    assert np.allclose(back.t - 1.7e9, rec.t, atol=1e-6) and np.array_equal(back.encoder, rec.encoder)
    t = rec.t + 1.7e9
    t[5] += 1e-5
    with pytest.raises(RecordingError, match="t is not uniformly sampled"):
        write_recording(dataclasses.replace(rec, t=t), tmp_path / "jitter.csv")


def test_json_is_strict(capfd):
    """Non-finite numbers never reach JSON: written as null (here: no NaN/Infinity token parses)."""
    def refuse(token):
        raise AssertionError(f"non-JSON token {token}")

    assert cli._json_safe({"a": [1.0, float("nan")], "b": {"c": float("inf")}}) == {"a": [1.0, None], "b": {"c": None}}
    assert cli.main(["observability", "--model", "finger2", "--json"]) == 0
    json.loads(capfd.readouterr().out, parse_constant=refuse)


def test_numpy_reprs_are_plain_in_warnings_and_cli_lines():
    """``np.float64(0.1)`` (a ``{x!r}`` of a numpy value) reads ``0.1`` in alpes_dyn's warnings too, and in any
    line the command line prints (a warning of another library, an internal error)."""
    import warnings

    from alpes_dyn.cli.common import UntrustedFitWarning, _one_line
    from alpes_dyn.estimation.identification.adequacy import AdequacyWarning
    from alpes_dyn.model.stops import JointRangeWarning

    for cls in (JointRangeWarning, AdequacyWarning, UntrustedFitWarning):
        with pytest.warns(cls) as caught:
            warnings.warn(cls(f"q = {np.float64(0.1)!r} at {np.int64(3)!r}, {np.bool_(True)!r}"))
        assert str(caught[0].message) == "q = 0.1 at 3, True"
        assert issubclass(cls, UserWarning)
    assert _one_line(f"x {np.float64(2.5)!r}\n{np.float32(1.5)!r}") == "x 2.5 1.5"


def test_closed_stdout_is_one_line_exit_2():
    """``>&-``: no stdout at all (sys.stdout is None): one line on stderr and exit 2, not an AttributeError."""
    r = _cli("dynamics", "--json", capture_output=True, preexec_fn=lambda: os.close(1))
    assert r.returncode == 2, r.stderr
    assert r.stderr == "alpes-dyn: error: stdout: closed (nowhere to write the output)\n"


def test_unreachable_scheduler_is_one_input_error(monkeypatch):
    """A --scheduler that does not answer (Dask's OSError after its timeout) is an InputError naming it."""
    import distributed

    from alpes_dyn.studies.sweep import sweep

    def refuse(address, timeout=None):
        raise OSError(f"Timed out trying to connect to {address} after 10 s")

    monkeypatch.setattr(distributed, "Client", refuse)
    with pytest.raises(InputError, match=r"^scheduler: cannot connect to 'tcp://127.0.0.1:1' \(OSError: Timed out"):
        sweep(lambda seed: {"x": 1.0}, 1, scheduler="tcp://127.0.0.1:1")


def test_experiment_on_the_file_true_params_out_wrote():
    """``experiment --params TRUE.toml`` on the finger ``--perturb 0.2 --seed 11`` drew: its springs spread the joints
    so that the bias putting their mean mid-range leaves j1 out of range; the bias then moves to where every joint's
    static equilibrium (solved here again, on the finger itself) is in range, instead of refusing the file."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, excitation, perturbed_params

    true = perturbed_params(spread=0.2, seed=11)
    finger = ad.Model.alpes("finger3", friction=True, params=true)
    design = ExperimentDesign(duration=0.2)
    bias, amp = excitation(finger, design)
    q = finger.static_equilibrium(finger.transmission.joint_torque(np.array([bias])), np.zeros(3))
    assert np.all(q >= finger.lower + design.margin) and np.all(q <= finger.upper - design.margin), q
    assert amp > 0


def test_cache_folder_checked_before_a_compiling_command(tmp_path, monkeypatch, capfd):
    """The compiled-code cache's folder is checked before a compiling command starts: a symbolic link, a file, a
    folder without a write bit (root too), a relative path are one line and exit 2 -- not a silent fall-back to
    uncompiled code; a command that never compiles does not look at it."""
    from alpes_dyn.simulation.codegen import CacheFolderError, check_cache_folder

    (tmp_path / "folder").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "folder")
    (tmp_path / "file").write_text("x")
    (tmp_path / "ro").mkdir(mode=0o555)
    cases = {str(tmp_path / "link"): "is a symbolic link", str(tmp_path / "file"): "is not a folder",
             str(tmp_path / "ro"): "is a folder that cannot be written",
             str(tmp_path / "ro" / "new"): "cannot be created", "relative/cache": "is not an absolute path"}
    for path, needle in cases.items():
        monkeypatch.setenv("ALPES_DYN_CACHE", path)
        code = cli.main(["estimate", "--duration", "0.2"])
        out, err = capfd.readouterr()
        _one_stderr_line(code, out, err, needle)
        assert "ALPES_DYN_CACHE" in err
    assert cli.main(["dynamics", "--json"]) == 0  # dynamics compiles nothing: the bad cache is not its business
    capfd.readouterr()
    with pytest.raises(CacheFolderError, match="is a symbolic link"):
        check_cache_folder(tmp_path / "link", "cache")
    assert check_cache_folder(tmp_path / "folder" / "new", "cache") == tmp_path / "folder" / "new"
    assert not (tmp_path / "folder" / "new").exists()  # checked, not created


def test_output_in_a_read_only_folder_refused_to_root_too(tmp_path):
    from alpes_dyn.fileio import check_output_path

    ro = tmp_path / "ro"
    ro.mkdir(mode=0o555)
    with pytest.raises(InputError, match=r"-o: directory '.*ro' is not writable"):
        check_output_path(str(ro / "out.csv"), "-o")
    assert check_output_path(str(tmp_path / "out.csv"), "-o") == tmp_path / "out.csv"


def test_bad_max_bytes_refused_by_every_command(monkeypatch, capfd):
    """$ALPES_DYN_MAX_BYTES is read at the start of every command, also one that sizes no array (dynamics)."""
    monkeypatch.setenv("ALPES_DYN_MAX_BYTES", "abc")
    code = cli.main(["dynamics"])
    out, err = capfd.readouterr()
    _one_stderr_line(code, out, err, "ALPES_DYN_MAX_BYTES: expected a number of bytes >= 1, got 'abc'")


def _recording_edited(column: str, cell: Callable[[int, str], str] | None) -> str:
    """finger3's recording with ``column``'s cells replaced by ``cell(row index, old cell)``, or dropped (None)."""
    lines = _recordings()["finger3"].splitlines()
    j = lines[0].split(",").index(column)
    out = []
    for i, line in enumerate(lines):
        cells = line.split(",")
        if cell is None:
            del cells[j]
        elif i > 0:
            cells[j] = cell(i - 1, cells[j])
        out.append(",".join(cells))
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("column, cell, needle", [  # issue 19's fifth re-check: estimate --data's recordings
    ("torque_finger", lambda i, v: "1e-320", "column 'torque_finger' line 2: 1e-320 is a subnormal number"),
    ("encoder_finger", lambda i, v: "-5e-324" if i == 7 else v, "column 'encoder_finger' line 9: -5e-324 is a subnormal"),
    ("true_q_j2", lambda i, v: "nan", "column 'true_q_j2' line 2: NaN or inf"),  # the RMSE silently dropped
    ("true_q_j2", lambda i, v: "" if i == 3 else v, "column 'true_q_j2' is empty at line 5 (only q_* and force_z"),
    ("true_q_j2", None, "true_q_* has no column for joint 'j2': the true angles of every joint, or none"),
    ("t", lambda i, v: repr(1e12 + 1e-3 * i), "t reaches 1e+12 s, where a float holds time only to 0.00012 s"),
])
def test_recording_cells_that_were_read_as_nonsense(tmp_path, column, cell, needle):
    """A subnormal reading, true angles missing somewhere (estimate --data then said 'no true_q_* columns'), time
    stamps that cannot hold the sample period: one RecordingError naming the column, as for the other defects."""
    path = tmp_path / "r.csv"
    path.write_text(_recording_edited(column, cell))
    with pytest.raises(RecordingError, match=re.escape(needle)):
        _read_rec(path)


def test_recording_without_true_angles_and_epoch_seconds_still_read(tmp_path):
    """The same reader accepts the recording with no true_q_* at all (a real rig's) and t in Unix-epoch seconds."""
    no_true = "\n".join(",".join(line.split(",")[:3]) for line in _recordings()["finger3"].splitlines()) + "\n"
    (tmp_path / "real.csv").write_text(no_true)
    rec = _read_rec(tmp_path / "real.csv")
    assert rec.true_q is None and rec.t.shape == (201,)
    (tmp_path / "epoch.csv").write_text(_recording_edited("t", lambda i, v: repr(1.7e9 + float(v))))
    assert np.allclose(_read_rec(tmp_path / "epoch.csv").t - 1.7e9, rec.t, atol=1e-6)


def test_urdf_inertial_numbers_read_as_urdfdom_reads_them():
    """Why the inertials' numbers are checked by urdfdom's grammar: Pinocchio's own build of a mass with a blank
    after it gives the link no mass at all, without an error (the dynamics silently changed). What urdfdom accepts
    is accepted and gives the same model: a blank before a number, blanks around an origin's three numbers."""
    import pinocchio as pin
    from alpes_dyn.fileio import native_stderr_to
    with native_stderr_to([]):  # urdfdom prints its errors on the process's stderr
        raw = pin.buildModelFromXML(_with_p3_inertial("0.023 ", _P3_I))
    assert raw.inertias[raw.getJointId("j3")].mass == 0.0  # the link's 0.023 kg gone
    q = np.array([0.3, 0.5, 0.7])
    clean = ad.Model(FINGER3)
    padded = ad.Model(_p3_inertial_origin(" 0.012  0.0 0.0 ").replace('<mass value="0.023"/>',
                                                                       '<mass value=" 0.023"/>', 1))
    assert np.array_equal(padded.inertia_matrix(q), clean.inertia_matrix(q))
    assert np.array_equal(padded.gravity_torque(q), clean.gravity_torque(q))
