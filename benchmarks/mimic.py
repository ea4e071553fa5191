"""Mimic joints (a URDF ``<mimic>``, q_k = a q_J + b) as constraints: agreement with independent references and the
cost of the forward dynamics, on Panda's gripper (example-robot-data: ``panda_finger_joint2`` mimics
``panda_finger_joint1``) and on a planar 3-link finger whose DIP mimics its PIP (a = 0.7, b = 0.1 rad).

Agreement (max |difference| over random states inside the limits):

* ``pinocchio_mimic``: the finger's forward dynamics against Pinocchio's own mimic model (``mimic=True``), CRBA and
  ``nonLinearEffects`` solved here, rad/s^2;
* ``full_tree``: Panda's A and forward dynamics against the whole tree's (``mimic`` off) projected,
  G^T A G and G^T b, solved here (kg m^2, rad/s^2);
* ``welded``: the finger with a = 0 against the same URDF with the DIP a fixed joint at b, rad/s^2;
* ``mujoco_projected``: the exported MJCF's M and bias (MuJoCo's own) projected, its forward dynamics, rad/s^2;
* ``mujoco_equality``: MuJoCo's constrained accelerations with the exported joint equality (a soft constraint),
  relative to the largest acceleration;
* ``adam``: the symbolic (ADAM) forward dynamics, rad/s^2.

Speed: ``Model.forward_dynamics`` on Panda with its mimic (Pinocchio's mimic model: CRBA, RNEA, a dense Cholesky
solve; ABA refuses mimic joints) against two baselines in the same process, the same ``Model`` with the finger a
free joint (ABA, the input checks alike) and Pinocchio's bare ABA on the whole tree (9 free joints), and the other
route measured (the whole tree's CRBA and bias projected by G, solved here).

    python benchmarks/mimic.py [--json] [--states 20] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

FINGER = """<?xml version="1.0"?><robot name="finger3m"><link name="base"/>
<link name="l1"><inertial><origin xyz="0 0 -0.02"/><mass value="0.05"/><inertia ixx="1e-5" iyy="1.2e-5" izz="0.5e-5"
 ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="l2"><inertial><origin xyz="0 0 -0.015"/><mass value="0.03"/><inertia ixx="5e-6" iyy="6e-6" izz="3e-6"
 ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="l3"><inertial><origin xyz="0.002 0 -0.01"/><mass value="0.02"/><inertia ixx="2.5e-6" iyy="3e-6" izz="1e-6"
 ixy="0" ixz="0" iyz="0"/></inertial></link><link name="tip"/>
<joint name="mcp" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>
 <limit lower="-1.5" upper="1.5" effort="1" velocity="10"/></joint>
<joint name="pip" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 -0.04"/><axis xyz="0 1 0"/>
 <limit lower="-1.5" upper="1.5" effort="1" velocity="10"/></joint>
DIP
<joint name="tip_joint" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0 0 -0.02"/></joint>
</robot>"""
DIP_MIMIC = ('<joint name="dip" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 -0.03"/>'
             '<axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="10"/>'
             '<mimic joint="pip" multiplier="{a!r}" offset="{b!r}"/></joint>')
DIP_WELDED = ('<joint name="dip" type="fixed"><parent link="l2"/><child link="l3"/><origin xyz="0 0 -0.03" '
              'rpy="0 {b!r} 0"/></joint>')


def finger(a: float = 0.7, b: float = 0.1, welded: bool = False) -> str:
    return FINGER.replace("DIP", (DIP_WELDED if welded else DIP_MIMIC).format(a=a, b=b))


def _sym(M: np.ndarray) -> np.ndarray:
    return np.triu(M) + np.triu(M, 1).T


def agreement(states: int) -> dict[str, float]:
    import casadi as cs
    import mujoco
    import pinocchio as pin

    import alpes_dyn as ad
    from alpes_dyn.symbolic.dynamics import SymbolicDynamics

    rng = np.random.default_rng(0)
    out: dict[str, float] = {}
    m = ad.Model(finger())
    pm = pin.buildModelFromXML(finger(), mimic=True)
    pd = pm.createData()
    zero, welded = ad.Model(finger(0.0, 0.3)), ad.Model(finger(0.0, 0.3, welded=True))
    mj = mujoco.MjModel.from_xml_string(m.to_mjcf())
    d = mujoco.MjData(mj)
    sd = SymbolicDynamics(m, "adam")
    qs, vs, ts = (cs.SX.sym(s, 2) for s in "qvt")
    fd_sym = cs.Function("fd", [qs, vs, ts], [sd.forward_dynamics(qs, vs, ts, smooth=False)])
    G = m.mimic.G
    keys = ("pinocchio_mimic", "welded", "mujoco_projected", "mujoco_equality", "adam")
    worst = dict.fromkeys(keys, 0.0)
    for _ in range(states):
        q, v = m.random_state(rng)
        tau = rng.normal(scale=0.02, size=2)
        qdd = m.forward_dynamics(q, v, tau)
        ref = np.linalg.solve(_sym(pin.crba(pm, pd, q)), tau - pin.nonLinearEffects(pm, pd, q, v))
        worst["pinocchio_mimic"] = max(worst["pinocchio_mimic"], float(np.max(np.abs(qdd - ref))))
        worst["welded"] = max(worst["welded"], float(np.max(np.abs(zero.forward_dynamics(q, v, tau)
                                                                    - welded.forward_dynamics(q, v, tau)))))
        d.qpos[:], d.qvel[:] = m.mimic.full_q(q), m.mimic.full_v(v)
        d.qfrc_applied[:] = np.r_[tau, 0.0]  # on the independent joints (mcp, pip): G^T f = tau
        mujoco.mj_forward(mj, d)
        M = np.zeros((3, 3))
        mujoco.mj_fullM(mj, M, d.qM) if hasattr(d, "qM") else mujoco.mj_fullM(mj, d, M)
        proj = np.linalg.solve(G.T @ M @ G, tau - G.T @ (d.qfrc_bias - d.qfrc_passive))
        worst["mujoco_projected"] = max(worst["mujoco_projected"], float(np.max(np.abs(qdd - proj))))
        worst["mujoco_equality"] = max(worst["mujoco_equality"],
                                       float(np.max(np.abs(d.qacc - G @ qdd)) / np.max(np.abs(qdd))))
        worst["adam"] = max(worst["adam"], float(np.max(np.abs(np.asarray(fd_sym(q, v, tau)).ravel() - qdd))))
    out.update(worst)
    return out


def panda(states: int, repeat: int) -> dict[str, float]:
    import pinocchio as pin

    import alpes_dyn as ad

    urdf = ad.example_robot_urdf("panda").read_text()
    m = ad.Model(urdf)
    full = pin.buildModelFromXML(urdf)
    fd = full.createData()
    G, rng = m.mimic.G, np.random.default_rng(1)
    worst_A = worst_fd = 0.0
    xs = [m.random_state(rng) for _ in range(states)]
    taus = [rng.normal(size=m.n) for _ in range(states)]
    for (q, v), tau in zip(xs, taus):
        A = G.T @ _sym(pin.crba(full, fd, m.mimic.full_q(q))) @ G
        b = G.T @ pin.nonLinearEffects(full, fd, m.mimic.full_q(q), G @ v)
        worst_A = max(worst_A, float(np.max(np.abs(m.inertia_matrix(q) - A))))
        worst_fd = max(worst_fd, float(np.max(np.abs(m.forward_dynamics(q, v, tau) - np.linalg.solve(A, tau - b)))))
    full_x = [(m.mimic.full_q(q), G @ v, np.r_[tau, 0.0]) for (q, v), tau in zip(xs, taus)]

    def projected(q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        qf = m.mimic.full_q(q)
        A = G.T @ _sym(pin.crba(full, fd, qf)) @ G
        return np.linalg.solve(A, tau - G.T @ pin.nonLinearEffects(full, fd, qf, G @ v))

    def best(fn, args) -> float:  # s per call, best of `repeat` passes over the states
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            for _ in range(50):
                for a in args:
                    fn(*a)
            times.append((time.perf_counter() - t0) / (50 * len(args)))
        return min(times)

    free = ad.Model(urdf.replace('<mimic joint="panda_finger_joint1"/>', ""))  # the second finger a free joint
    assert free.n == full.nq
    aba = best(lambda q, v, t: pin.aba(full, fd, q, v, t), full_x)
    ours = best(m.forward_dynamics, [(q, v, t) for (q, v), t in zip(xs, taus)])
    unconstrained = best(free.forward_dynamics, full_x)
    proj = best(projected, [(q, v, t) for (q, v), t in zip(xs, taus)])
    return {"nq_full_tree": int(full.nq), "n_model": int(m.n), "A_vs_full_tree": worst_A, "fd_vs_full_tree": worst_fd,
            "us_aba_full_tree": aba * 1e6, "us_forward_dynamics": ours * 1e6, "us_projection_route": proj * 1e6,
            "us_model_without_mimic": unconstrained * 1e6, "ratio_vs_model_without_mimic": ours / unconstrained,
            "ratio_vs_aba": ours / aba, "ratio_projection_vs_aba": proj / aba}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--states", type=int, default=20, help="random states (default %(default)s)")
    ap.add_argument("--repeat", type=int, default=5, help="timing passes, best kept (default %(default)s)")
    a = ap.parse_args()
    rep = {"finger_mimic": agreement(a.states), "panda": panda(a.states, a.repeat)}
    if a.json:
        print(json.dumps(rep))
        return
    f, p = rep["finger_mimic"], rep["panda"]
    print("3-link finger, q_dip = 0.7 q_pip + 0.1 (max |difference|):")
    for k, unit in (("pinocchio_mimic", "rad/s^2"), ("welded", "rad/s^2 (a = 0, b = 0.3)"),
                    ("mujoco_projected", "rad/s^2"), ("mujoco_equality", "relative (MuJoCo's soft equality)"),
                    ("adam", "rad/s^2")):
        print(f"  {k:18s} {f[k]:10.3g}  {unit}")
    print(f"Panda: nq {p['nq_full_tree']} (the whole tree) -> {p['n_model']} (the model, its finger a mimic)")
    print(f"  A vs the whole tree projected  {p['A_vs_full_tree']:10.3g}  kg m^2")
    print(f"  qdd vs the whole tree projected {p['fd_vs_full_tree']:9.3g}  rad/s^2")
    print(f"  Model.forward_dynamics {p['us_forward_dynamics']:7.1f} us: {p['ratio_vs_model_without_mimic']:.2f} x the "
          f"same Model with the finger free (ABA, {p['us_model_without_mimic']:.1f} us), {p['ratio_vs_aba']:.2f} x "
          f"Pinocchio's bare ABA on the whole tree ({p['us_aba_full_tree']:.1f} us); the projection route "
          f"{p['us_projection_route']:.1f} us ({p['ratio_projection_vs_aba']:.2f} x the bare ABA)")


if __name__ == "__main__":
    main()
