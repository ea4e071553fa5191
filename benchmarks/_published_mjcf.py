"""Part ``published`` of ``benchmarks/foreign_hands.py`` (issue 51, items 1-3): MJCF files as MuJoCo users write them.

* MuJoCo's ``tendon_arm/arm26`` (its six muscles replaced by motors; written by ``tests/test_mjcf_spatial.py``):
  over its published 0-120 degrees (its tendons leave or change side of their wrapping cylinders: imported as their
  paths, :mod:`alpes_dyn.model.spatial_path`) and over 0-90 degrees with the three tendons that stay on their
  cylinders (one of them over both joints: polynomials), the import and its ratios, motor angles and forward dynamics
  against MuJoCo's (``ten_J`` read sparse, ``ten_length``, ``qacc``) at random states: the largest relative error
  (goal <= 1e-9);
* a Robotiq-like closed linkage (a four-bar closed by a ``<connect>``): the import's exit code and line;
* a joint equality with a fixed tendon (``tests/test_mjcf_import.py``'s TIED: the tied joint's springs, damping,
  armature, friction and a motor on it): the import, and its model against MuJoCo's projected on the coupling
  (G^T M G, G^T bias, G^T of the actuators' forces) at random states.
"""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

ROBOTIQ_LIKE = """<mujoco model="robotiq_like"><compiler angle="radian"/><worldbody>
  <body name="base"><inertial pos="0 0 0" mass="0.5" diaginertia="1e-3 1e-3 1e-3"/>
    <body name="driver" pos="0 0.01 0.05"><joint name="driver_joint" axis="1 0 0" range="0 0.8"/>
      <inertial pos="0 0.015 0.02" mass="0.02" diaginertia="4e-6 4e-6 1e-6"/>
      <body name="coupler" pos="0 0.03 0.04"><joint name="coupler_joint" axis="1 0 0" range="-1 1"/>
        <inertial pos="0 0 0.015" mass="0.01" diaginertia="1e-6 1e-6 3e-7"/></body></body>
    <body name="follower" pos="0 0.03 0.04"><joint name="follower_joint" axis="1 0 0" range="-1 1"/>
      <inertial pos="0 0.01 0.02" mass="0.015" diaginertia="2e-6 2e-6 5e-7"/></body></body>
  </worldbody>
  <equality><connect name="close" body1="coupler" body2="follower" anchor="0 0 0.03"/></equality>
  <actuator><motor name="fingers" joint="driver_joint" gear="1"/></actuator>
</mujoco>"""
"""A parallel gripper's finger as Robotiq's 2F-85 is modelled in MuJoCo Menagerie: a driven link and a follower, a
coupler closing the four-bar by a ``<connect>`` equality (dimensions of our own)."""


def _test_module(name: str):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).parents[1] / "tests" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _arm(model, xml: str, states: int, seed: int) -> dict[str, float]:
    """The largest errors of the arm's ratios, motor angles (relative to their largest) and forward dynamics
    (relative to |qacc|) against MuJoCo at random states over the ranges."""
    import mujoco

    from alpes_dyn.model.mjcf_spatial import tendon_jacobian

    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    g = m.actuator_gear[:, 0]
    d.qpos[:] = 0
    mujoco.mj_fwdPosition(m, d)
    L0 = d.ten_length.copy()
    rng = np.random.default_rng(seed)
    err = {"ratio": 0.0, "angle": 0.0, "qdd": 0.0}
    tr = model.transmission
    for _ in range(states):
        q = m.jnt_range[:, 0] + np.ptp(m.jnt_range, axis=1) * rng.random(m.njnt)
        d.qpos[:], d.qvel[:], d.ctrl[:] = q, rng.normal(size=m.nv), 0.5 * rng.normal(size=m.nu)
        mujoco.mj_forward(m, d)
        J = g[:, None] * tendon_jacobian(m, d)
        dL = g * (d.ten_length - L0)
        err["ratio"] = max(err["ratio"], float(np.max(np.abs(tr.ratio(q) - J)) / np.max(np.abs(J))))
        err["angle"] = max(err["angle"], float(np.max(np.abs(tr.motor_positions(q) - dL)) / np.max(np.abs(dL))))
        qdd = model.forward_dynamics(q, d.qvel.copy(), tr.joint_torque(d.ctrl.copy(), q))
        err["qdd"] = max(err["qdd"], float(np.max(np.abs(qdd - d.qacc)) / np.max(np.abs(d.qacc))))
    return err


def _tied(model, xml: str, states: int, seed: int) -> dict[str, float]:
    """The largest relative errors of the tied model's A, bias and actuated torques against MuJoCo's full model
    projected on q_full = G q + o."""
    import mujoco

    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    G, o = np.array([[1, 0], [0, 1], [0, 0.8]]), np.array([0, 0, 0.05])
    rng = np.random.default_rng(seed)
    err = {"M": 0.0, "bias": 0.0, "actuator": 0.0}
    rel = lambda a, b: float(np.max(np.abs(a - b)) / np.max(np.abs(b)))  # noqa: E731
    for _ in range(states):
        q, v, u = rng.uniform(-0.8, 0.8, 2), rng.normal(size=2), rng.normal(size=2)
        d.qpos[:], d.qvel[:], d.ctrl[:] = G @ q + o, G @ v, u
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        err["M"] = max(err["M"], rel(model.inertia_matrix(q), G.T @ M @ G))
        err["bias"] = max(err["bias"], rel(model.coriolis_matrix(q, v) @ v + model.gravity_torque(q),
                                           G.T @ (d.qfrc_bias - d.qfrc_spring)))
        err["actuator"] = max(err["actuator"], rel(model.transmission.joint_torque(u, q), G.T @ d.qfrc_actuator))
    return err


def published(d: Path, states: int, seed: int, cli: Callable[..., tuple[float, dict[str, Any]]]) -> dict[str, Any]:
    """The part's figures (module doc); ``cli`` runs ``alpes-dyn`` as a new process (foreign_hands' ``cli``)."""
    import alpes_dyn as ad

    spatial, imp = _test_module("test_mjcf_spatial"), _test_module("test_mjcf_import")
    out: dict[str, Any] = {}
    (d / "arm26.xml").write_text(spatial.ARM26)
    wall, r = cli("import", "--model", str(d / "arm26.xml"), "--out-dir", str(d / "arm26"))
    model = ad.Model.from_urdf_file(r["urdf"], r["spec"])
    err = _arm(model, spatial.ARM26, states, seed)
    out["arm26_0_120"] = {"import_wall_s": wall, "paths": sum(mo.path is not None for mo in model.spec.motors),
                          "vs_mujoco": err, "goal_met": max(err.values()) <= 1e-9}
    xml = spatial.only(spatial.ARM26, "SE", "EE", "BE", ranges="0 90")
    (d / "arm90.xml").write_text(xml)
    wall, r = cli("import", "--model", str(d / "arm90.xml"), "--out-dir", str(d / "arm90"))
    model = ad.Model.from_urdf_file(r["urdf"], r["spec"])
    err = _arm(model, xml, states, seed)
    out["arm26_0_90"] = {"import_wall_s": wall, "tendons": ["SE", "EE", "BE"], "vs_mujoco": err,
                         "goal_met": max(err.values()) <= 1e-9}
    (d / "robotiq_like.xml").write_text(ROBOTIQ_LIKE)
    wall, r = cli("import", "--model", str(d / "robotiq_like.xml"), "--out-dir", str(d / "robotiq"), ok=(0, 2))
    out["robotiq_like"] = {"wall_s": wall, **r}
    (d / "tied.xml").write_text(imp.TIED)
    t0 = time.perf_counter()
    wall, r = cli("import", "--model", str(d / "tied.xml"), "--out-dir", str(d / "tied"))
    err = _tied(ad.Model.from_urdf_file(r["urdf"], r["spec"]), imp.TIED, states, seed)
    out["tied"] = {"import_wall_s": wall, "vs_mujoco": err, "goal_met": max(err.values()) <= 1e-9,
                   "check_s": time.perf_counter() - t0 - wall}
    return out


def table(p: dict[str, Any]) -> list[str]:
    """The part's lines of foreign_hands' table."""
    a, b, c, t = p["arm26_0_120"], p["arm26_0_90"], p["robotiq_like"], p["tied"]
    e, f, g = b["vs_mujoco"], t["vs_mujoco"], a["vs_mujoco"]
    return ["MJCF files as published (issue 51):",
            f"  arm26 over 0-120 deg ({a['paths']} tendons as paths): import {a['import_wall_s']:.1f} s; vs MuJoCo "
            f"ratio {g['ratio']:.1e}, motor angle {g['angle']:.1e}, qdd {g['qdd']:.1e} (relative; goal <= 1e-9: "
            f"{'met' if a['goal_met'] else 'NOT met'})",
            f"  arm26 over 0-90 deg (SE, EE, BE): import {b['import_wall_s']:.1f} s; vs MuJoCo ratio {e['ratio']:.1e}, "
            f"motor angle {e['angle']:.1e}, qdd {e['qdd']:.1e} (relative; goal <= 1e-9: "
            f"{'met' if b['goal_met'] else 'NOT met'})",
            f"  Robotiq-like four-bar: exit {c.get('exit', 0)} in {c['wall_s']:.1f} s: {c.get('error', 'imported')}",
            f"  joint equality + fixed tendon: import {t['import_wall_s']:.1f} s; vs MuJoCo projected M {f['M']:.1e}, "
            f"bias {f['bias']:.1e}, S^T u {f['actuator']:.1e} (goal <= 1e-9: {'met' if t['goal_met'] else 'NOT met'})"]
