"""What MuJoCo's default (soft) ``frictionloss`` is on a drawn finger3 (issue 50): the creep velocity under a
constant torque below F_s and the friction force against the velocity, against the Huber-row law of
:func:`alpes_dyn.estimation.identification.creep.soft_constraint_friction` (added inertia a = 1/R, viscous a b).

    PYTHONPATH=src python benchmarks/soft_friction_law.py [--seed 10001]

Prints, per joint: F_s, MuJoCo's dof_invweight0 w, the band's added inertia a = d/(1-d)/w and its ratio to the
joint's own 1/w, the steady creep velocity measured under 0.5 F_s against tau/(a b), the band v_c = F_s/(a b),
and the friction's steady force at velocities through the band (a velocity servo far above it), normalised.
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np

from alpes_dyn.bench.effects import PlantEffects
from alpes_dyn.bench.mujoco_plant import plant_mjcf
from alpes_dyn.model.mjcf import joint_permutation
from alpes_dyn.studies.realism import FINGER3

B = 2.0 / (0.95 * 0.02)  # 1/s: MuJoCo's default solreffriction (0.02 s, ratio 1), d_max 0.95
KAPPA = 0.9 / (1 - 0.9)  # d/(1-d) at the default impedance 0.9


def plant(seed: int):
    true = FINGER3.true_params(seed)
    xml = plant_mjcf("finger3", true, PlantEffects(soft_stiction=True))
    mj = mujoco.MjModel.from_xml_string(xml)
    mj.opt.gravity[:] = 0.0
    mj.jnt_stiffness[:] = 0.0  # no spring: a constant torque meets the friction alone
    mj.dof_damping[:] = 0.0
    mj.jnt_limited[:] = 0
    return mj, FINGER3.alpes(params=true)


def creep(mj, dofs, j: int, tau: float, seconds: float = 0.3) -> float:
    """Steady velocity of dof j under a constant torque tau (rad/s), from rest at qpos0."""
    d = mujoco.MjData(mj)
    d.qfrc_applied[dofs[j]] = tau
    n = int(seconds / mj.opt.timestep)
    for _ in range(n):
        mujoco.mj_step(mj, d)
    return float(d.qvel[dofs[j]])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=10001)
    a = ap.parse_args()
    mj, model = plant(a.seed)
    perm = joint_permutation(mj, model.joint_names)
    dofs = np.array([mj.jnt_dofadr[i] for i in perm]) if len(perm) else perm
    Fs = mj.dof_frictionloss[dofs]
    w = mj.dof_invweight0[dofs]
    added = KAPPA / w
    print(f"seed {a.seed}: timestep {mj.opt.timestep:g} s, integrator {mj.opt.integrator}, nv {mj.nv}, "
          f"b = {B:.1f} /s, kappa = {KAPPA:.1f}")
    d0 = mujoco.MjData(mj)
    mujoco.mj_forward(mj, d0)
    Mfull = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, d0, Mfull)
    for j, name in enumerate(model.joint_names):
        v_c = Fs[j] / (added[j] * B)
        meas = [creep(mj, dofs, j, f * Fs[j]) for f in (0.25, 0.5, 0.9)]
        pred = [f * Fs[j] / (added[j] * B) for f in (0.25, 0.5, 0.9)]
        slide = creep(mj, dofs, j, 1.5 * Fs[j], 0.05)
        print(f"{name}: F_s {Fs[j]:.3g} N m, w {w[j]:.4g}, M_jj {Mfull[dofs[j], dofs[j]]:.3g}, "
              f"a {added[j]:.3g} kg m^2 (= {added[j] * w[j]:.1f} / w, {added[j] / Mfull[dofs[j], dofs[j]]:.2f} M_jj), "
              f"v_c {v_c:.3g} rad/s; creep at 0.25/0.5/0.9 F_s: measured {np.round(meas, 4).tolist()} "
              f"predicted tau/(a b) {np.round(pred, 4).tolist()}; at 1.5 F_s after 50 ms {slide:.3g} rad/s (sliding)")
    # steady force against velocity: the joint held at a constant velocity (qvel reset each step), the others free
    print("steady friction force / F_s against v / v_c (joint held at v; efc_force of its friction row):")
    for j, name in enumerate(model.joint_names):
        v_c = Fs[j] / (added[j] * B)
        row = []
        for r in (0.1, 0.3, 0.6, 0.9, 1.0, 1.5, 3.0):
            d = mujoco.MjData(mj)
            d.qvel[dofs[j]] = r * v_c
            mujoco.mj_forward(mj, d)
            # at rest otherwise: the friction row of dof j, no applied torque: the row's force saturates or not
            rows = [i for i in range(d.nefc) if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
                    and d.efc_id[i] == dofs[j]]
            row.append(float(-d.efc_force[rows[0]] / Fs[j]))
        print(f"  {name}: v/v_c 0.1 0.3 0.6 0.9 1 1.5 3 -> {np.round(row, 3).tolist()}")


if __name__ == "__main__":
    main()
