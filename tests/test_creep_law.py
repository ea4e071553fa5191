"""The ``creep`` friction law (model.friction.Creep, symbolic.creep): MuJoCo's default (soft) ``frictionloss``.

References independent of the law's code: MuJoCo's own accelerations and motion on the soft plant of a drawn
finger3 (the friction study's ``soft`` case), and the smooth law's distance from them.
"""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

from alpes_dyn.bench.effects import PlantEffects
from alpes_dyn.control.plants import mujoco_recording
from alpes_dyn.errors import ModelError
from alpes_dyn.model.friction import CREEP_KAPPA, CREEP_RATE, Creep, creep_of
from alpes_dyn.model.params import Param, with_values
from alpes_dyn.model.robot import Model
from alpes_dyn.studies.realism import FINGER3
from alpes_dyn.studies.realism_friction import validation_torque
from alpes_dyn.symbolic.parametric import ParametricDynamics

SEED = 10001
DT = 1e-3


def _model(law: str) -> Model:
    true = FINGER3.true_params(SEED)
    return Model.alpes("finger3", friction=True, params=with_values(true, {"friction.law": Param(law, "-", "assumed",
                                                                                                 "test")}))


def _simulate(model: Model, q0: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N+1, n) joint angles of ParametricDynamics from rest at q0 under the motor torque u (N+1, 1): RK4 at 0.1 ms."""
    pd = ParametricDynamics(model)
    n = model.n
    x, uu = cs.SX.sym("x", 2 * n), cs.SX.sym("u", 1)
    tau = pd.input_torque(x[:n], x[n:], uu, pd.theta)
    f = cs.Function("f", [x, uu], [cs.vertcat(x[n:], pd.forward_dynamics(x[:n], x[n:], tau, cs.DM(pd.nominal)))])
    h, xk = DT / 10, x
    for _ in range(10):
        k1 = f(xk, uu)
        k2 = f(xk + h / 2 * k1, uu)
        k3 = f(xk + h / 2 * k2, uu)
        k4 = f(xk + h * k3, uu)
        xk = xk + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    sim = cs.Function("step", [x, uu], [xk]).expand().mapaccum(len(u) - 1)
    X = np.array(sim(np.r_[q0, np.zeros(n)], u[:-1].T)).T
    return np.vstack([q0, X[:, :n]])


def test_creep_law_follows_mujoco_soft_friction():
    """Open loop over the study's validation run (the estimate scenario, then a ramp through the stick band):
    the creep law with the plant's true values and MuJoCo's default constants stays within 0.05 degree of MuJoCo's
    soft plant on every joint; the smooth law (its fixed v_s) drifts more than ten times as far."""
    u = validation_torque(DT, 1)[:4001]  # 4 s: the scenario's sines
    true = FINGER3.true_params(SEED)
    rec = mujoco_recording("finger3", true, u, DT, effects=PlantEffects(soft_stiction=True), seed=1)
    qt = rec.true_q
    err = {law: np.degrees(np.sqrt(np.mean((_simulate(_model(law), qt[0], u) - qt) ** 2, axis=0)))
           for law in ("creep", "tanh")}
    assert err["creep"].max() < 0.05, err
    assert err["tanh"].max() > 10 * err["creep"].max(), err


def test_creep_law_from_the_file():
    """friction.law = "creep" reads the law's constants (defaults MuJoCo's: kappa d/(1-d) at d = 0.9, b = 2/(0.95 t_c)
    at t_c = 0.02 s) and refuses a bad one naming its field."""
    m = _model("creep")
    law = creep_of(m)
    assert law is not None and law.kappa == pytest.approx(9.0) and law.rate == pytest.approx(2 / (0.95 * 0.02))
    assert (CREEP_KAPPA, CREEP_RATE) == (law.kappa, law.rate)
    assert creep_of(_model("tanh")) is None
    with pytest.raises(ModelError, match="friction.creep_rate"):
        Creep(9.0, -1.0)
    with pytest.raises(ModelError, match="friction.creep_kappa"):
        Creep(float("nan"), 1.0)
    with pytest.raises(ModelError, match="friction.creep_kappa"):  # the file's field, read as a file is
        with_values(FINGER3.true_params(SEED), {"friction.creep_kappa": Param(-1.0, "-", "assumed", "test")})


def test_library_simulator_reads_the_creep_file():
    """The library's own simulator (simulate, SymbolicDynamics: the observers' dynamics) on a creep file follows
    MuJoCo's soft plant as the fit's ParametricDynamics does (0.05 degree over 2 s of the scenario's torque)."""
    from alpes_dyn.simulation.integrate import simulate

    u = validation_torque(DT, 1)[:2001]
    rec = mujoco_recording("finger3", FINGER3.true_params(SEED), u, DT, effects=PlantEffects(soft_stiction=True),
                           seed=1)
    qt = rec.true_q
    res = simulate(_model("creep"), np.r_[qt[0], np.zeros(3)], u[:-1], duration=2.0, dt=DT, input="motor",
                   joint_range="ignore")
    assert np.degrees(np.abs(res.x[:, :3] - qt).max()) < 0.05


def test_mjcf_export_writes_the_creep_law():
    """A creep file's MJCF (the Alpes writer) holds its band as MuJoCo's soft constraint: a joint under a constant
    torque below F_s creeps at tau / (a b) with a = kappa / dof_invweight0 (MuJoCo's own measurement, non-default
    kappa and b)."""
    import mujoco

    from alpes_dyn.model.mjcf import mjcf_string

    true = FINGER3.true_params(SEED)
    p = with_values(true, {"friction.law": Param("creep", "-", "assumed", "test"),
                           "friction.creep_kappa": Param(4.0, "-", "assumed", "test"),
                           "friction.creep_rate": Param(50.0, "1/s", "assumed", "test")})
    mj = mujoco.MjModel.from_xml_string(mjcf_string("finger3", p, friction=True, contact=False))
    mj.opt.gravity[:] = 0.0
    mj.jnt_stiffness[:] = 0.0
    mj.dof_damping[:] = 0.0  # the friction alone
    mj.jnt_limited[:] = 0
    j = mj.joint("j3").dofadr[0]
    d = mujoco.MjData(mj)
    tau = 0.5 * mj.dof_frictionloss[j]
    d.qfrc_applied[j] = tau
    for _ in range(int(1.5 / mj.opt.timestep)):  # the band's slowest mode settled (its time constant 0.2 s)
        mujoco.mj_step(mj, d)
    assert d.qvel[j] == pytest.approx(tau / (4.0 / mj.dof_invweight0[j] * 50.0), rel=1e-3)
