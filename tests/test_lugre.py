"""The LuGre friction law (alpes_dyn.model.friction, symbolic.lugre, simulation.lugre, the observers' "lugre") against
independent references.

References: the bristle ODE integrated by scipy's solve_ivp (its steady state F_s sign(v) / sigma0 and the sign law's
torque F_s sign(v) + F_v v; its presliding stiffness sigma0); finger3 with the law written here in numpy on
Pinocchio's frictionless forward dynamics, integrated by solve_ivp (Radau), against the library's RK4 rollout; and
an EKF on MuJoCo's stiff stick-slip (``frictionloss``, 0.5 ms ``solreffriction``), which the library did not write,
where the smooth tanh law drifts off the stuck joints.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import alpes_dyn as ad
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.estimation.observers.discrete import DiscreteModel
from alpes_dyn.model.friction import LuGre, lugre_of, lugre_rate, lugre_steady, lugre_torque
from alpes_dyn.model.params import Param, load_params, params_toml, with_values
from alpes_dyn.simulation.lugre import lugre_substeps, simulate_lugre
from alpes_dyn.symbolic.statespace import StateSpace

FS, FV = 5e-4, 1e-4


def bristle_ode(t, y, v, sigma0):
    """dz/dt of eq. L1 (g = F_s), written here."""
    return [v - sigma0 * abs(v) * y[0] / FS]


@pytest.mark.parametrize("v", [0.3, -0.05, 2.0])
def test_steady_state_is_the_sign_law(v):
    """Sliding at a constant v, z settles at F_s sign(v) / sigma0 and the torque at F_s sign(v) + F_v v."""
    law = LuGre()
    sol = solve_ivp(bristle_ode, (0, 0.5), [0.0], args=(v, law.sigma0), method="Radau", rtol=1e-10, atol=1e-14)
    z_ref = sol.y[0, -1]
    z, tau = lugre_steady(np.array([v]), np.array([FS]), np.array([FV]), law.sigma0)
    np.testing.assert_allclose(z, [z_ref], rtol=1e-6)
    np.testing.assert_allclose(z, [np.sign(v) * FS / law.sigma0], rtol=1e-9)
    zdot = lugre_rate(z, np.array([v]), np.array([FS]), law.sigma0)
    np.testing.assert_allclose(zdot, [0.0], atol=1e-12)
    np.testing.assert_allclose(lugre_torque(z, zdot, np.array([v]), np.array([FV]), law), tau, rtol=1e-12)
    np.testing.assert_allclose(tau, [FS * np.sign(v) + FV * v], rtol=1e-12)


def test_presliding_stiffness_is_sigma0():
    """From an unloaded bristle, a joint that yields by dq << F_s / sigma0 gets a friction torque sigma0 dq: the
    stiffness of a stuck joint (solve_ivp of eq. L1 over a slow creep)."""
    law = LuGre()
    v, T = 1e-4, 0.01  # dq = 1e-6 rad, a thousandth of the presliding displacement
    sol = solve_ivp(bristle_ode, (0, T), [0.0], args=(v, law.sigma0), method="Radau", rtol=1e-12, atol=1e-16)
    z = sol.y[0, -1]
    zdot = lugre_rate(np.array([z]), np.array([0.0]), np.array([FS]), law.sigma0)
    tau = lugre_torque(np.array([z]), zdot, np.array([0.0]), np.array([FV]), law)
    np.testing.assert_allclose(tau / (v * T), [law.sigma0], rtol=2e-3)


def test_rollout_matches_scipy_on_finger3():
    """finger3 from rest under a step of joint torque, its bristles loaded then sliding: the RK4
    rollout against solve_ivp (LSODA) of the law written here in numpy on Pinocchio's frictionless dynamics (springs
    and gravity), within 1e-3 degree."""
    model = ad.Model.alpes("finger3", friction=True)
    free = ad.Model.alpes("finger3", friction=False)
    law = LuGre()
    n, dt, N = 3, 1e-3, 200
    q_eq = np.array([0.4, 0.6, 0.5])
    tau = free.gravity_torque(q_eq) + np.array([3e-3, 1e-3, 3e-4])

    def rhs(s, y):
        q, v, z = y[:n], y[n:2 * n], y[2 * n:]
        zd = v - law.sigma0 * np.abs(v) * z / FS
        f = law.sigma0 * z + law.sigma1 * zd + FV * v
        return np.r_[v, free.forward_dynamics(q, v, tau - f), zd]

    sol = solve_ivp(rhs, (0, N * dt), np.r_[q_eq, np.zeros(2 * n)], method="LSODA", t_eval=dt * np.arange(N + 1),
                    rtol=1e-10, atol=1e-13)
    ref = sol.y.T
    res = simulate_lugre(model, np.r_[q_eq, np.zeros(n)], np.tile(tau, (N, 1)), dt, law)
    moved = np.ptp(ref[:, :n], axis=0)
    assert moved[0] > 1e-2 and moved.min() > FS / law.sigma0  # every joint slid (the coupled ones dragged along)
    np.testing.assert_allclose(np.degrees(res.q), np.degrees(ref[:, :n]), atol=1e-3)
    np.testing.assert_allclose(res.z, ref[:, 2 * n:], atol=1e-5)  # 1 % of F_s / sigma0: the split step's O(h)


def test_parameter_file_law_round_trip(tmp_path):
    """friction.law / sigma0 / sigma1 written and read back; the model's law follows the file; tanh without them."""
    p = load_params()
    assert p.friction_law == "tanh" and lugre_of(ad.Model.alpes("finger3", friction=True)) is None
    why = "a presliding displacement of 0.5 mrad"
    q = with_values(p, {"friction.law": Param("lugre", "-", "assumed", why),
                        "friction.sigma0": Param(1.0, "N m/rad", "assumed", why),
                        "friction.sigma1": Param(4e-3, "N m s/rad", "assumed", why)})
    assert (q.friction_law, q.sigma0, q.sigma1) == ("lugre", 1.0, 4e-3)
    path = tmp_path / "lugre.toml"
    path.write_text(params_toml(q.raw))
    m = ad.Model.alpes("finger3", friction=True, params=path)
    assert lugre_of(m) == LuGre(1.0, 4e-3)
    dm = DiscreteModel(StateSpace(m, input="motor", output="encoder"), 1e-3, substeps=2, friction_law="lugre")
    assert dm.nz == 9 and dm.names[-3:] == tuple(f"bristle_{j}" for j in m.joint_names) and dm.law.sigma0 == 1.0


@pytest.mark.parametrize("field, entry, needle", [
    ("friction.law", {"value": "dahl", "unit": "-", "source": "assumed", "reason": "r"},
     "friction.law: expected one of tanh, lugre, creep, got 'dahl'"),
    ("friction.law", {"value": 3, "unit": "-", "source": "assumed", "reason": "r"}, "friction.law: expected one of"),
    ("friction.sigma0", {"value": -1.0, "unit": "N m/rad", "source": "assumed", "reason": "r"},
     "friction.sigma0: value must be > 0"),
    ("friction.sigma0", {"value": 0.0, "unit": "N m/rad", "source": "assumed", "reason": "r"},
     "friction.sigma0: value must be > 0"),
    ("friction.sigma0", {"value": "x", "unit": "N m/rad", "source": "assumed", "reason": "r"},
     "friction.sigma0: value must be a number"),
    ("friction.sigma0", {"value": 1.0, "unit": "N m/deg", "source": "assumed", "reason": "r"},
     "friction.sigma0.unit: the value is read in 'N m/rad'"),
    ("friction.sigma1", {"value": float("nan"), "unit": "N m s/rad", "source": "assumed", "reason": "r"},
     "friction.sigma1: value must be finite"),
])
def test_bad_file_values(tmp_path, field, entry, needle):
    """A bad law or bristle constant in the file: one ModelError line naming the field."""
    import tomllib

    data = load_params().raw
    text = params_toml(data)
    key = field.split(".")[1]
    val = entry["value"]
    lit = '"dahl"' if isinstance(val, str) and val == "dahl" else ('"x"' if isinstance(val, str) else
                                                                  ("nan" if val != val else repr(val)))
    line = f'{key} = {{ value = {lit}, unit = "{entry["unit"]}", source = "assumed", reason = "r" }}\n'
    text = text.replace("[friction]\n", "[friction]\n" + line)
    tomllib.loads(text)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ModelError, match="^" + needle.replace("(", r"\(").replace(".", r"\.")) as e:
        load_params(path)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("kw, needle", [
    ({"sigma0": -1.0}, "friction.sigma0: expected a finite number > 0 N m/rad"),
    ({"sigma0": float("inf")}, "friction.sigma0: expected a finite number > 0"),
    ({"sigma1": 0.0}, "friction.sigma1: expected a finite number > 0 N m s/rad"),
    ({"sigma1": "a"}, "friction.sigma1: expected a finite number > 0"),
    ({"sigma0": True}, "friction.sigma0: expected a finite number > 0"),
])
def test_bad_law_values(kw, needle):
    with pytest.raises(ModelError, match=needle):
        LuGre(**kw)


def test_bad_simulation_inputs():
    model = ad.Model.alpes("finger3", friction=True)
    x0 = np.r_[0.4, 0.6, 0.5, 0, 0, 0]
    with pytest.raises(InputError, match="inputs: contains NaN or inf"):
        simulate_lugre(model, x0, np.full((3, 3), np.nan), 1e-3)
    with pytest.raises(InputError, match=r"inputs: expected shape \(N, 3\)"):
        simulate_lugre(model, x0, np.zeros((3, 2)), 1e-3)
    with pytest.raises(InputError, match="substeps: expected an integer"):
        simulate_lugre(model, x0, np.zeros((3, 3)), 1e-3, substeps=0)
    with pytest.raises(InputError, match="z0"):
        simulate_lugre(model, x0, np.zeros((3, 3)), 1e-3, z0=[0.0])
    with pytest.raises(InputError, match="law: expected a LuGre"):
        simulate_lugre(model, x0, np.zeros((3, 3)), 1e-3, law=0.5)
    assert lugre_substeps(model, LuGre(), 1e-3) >= 4


@pytest.fixture(scope="module")
def stuck_recording():
    """finger2 on MuJoCo with stiff stick-slip (0.5 ms solreffriction) and 10 times the file's F_s (a 3 degree dead
    band per joint), a torque that ramps up, holds, ramps half-way down and holds (4 s): the joints stay stuck away
    from their frictionless rest (the plant of tests/test_stick_observer.py)."""
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.estimation.experiments.draws import perturbed_params
    from alpes_dyn.model.mjcf import STICTION_TIMECONST

    p = perturbed_params(spread=0.2, seed=9002)
    p = dataclasses.replace(p, finger=dataclasses.replace(p.finger, F_s=10 * p.finger.F_s))
    t = 1e-3 * np.arange(4001)
    u = np.interp(t, [0, 0.3, 0.8, 1.8, 2.3, 4.0], [0.020, 0.020, 0.028, 0.028, 0.024, 0.024])[:, None]
    rec = mujoco_recording("finger2", p, u, 1e-3, effects=PlantEffects(stiction=STICTION_TIMECONST), seed=10002)
    # the file's law: LuGre with the presliding displacement F_s / sigma0 at 1 mrad of this friction
    p = dataclasses.replace(p, friction_law="lugre", sigma0=10 * p.sigma0)
    return rec, ad.Model.alpes("finger2", friction=True, params=p)


def test_ekf_holds_stuck_joints_on_mujoco(stuck_recording):
    """The EKF with the true file on MuJoCo's stick-slip: the smooth tanh law creeps back to the frictionless rest
    (over 1 degree RMS on every joint); the LuGre law, the file's default, holds the stuck joints within 0.4 degree
    (0.27 measured, the UKF's too; the stick law's time stepping 0.03, tests/test_stick_observer.py)."""
    from alpes_dyn.estimation.observers.replay import estimate_recording

    rec, model = stuck_recording
    smooth = np.degrees(estimate_recording(rec, model, "ekf", friction_law="smooth").rmse)
    res = estimate_recording(rec, model, "ekf")
    lugre = np.degrees(res.rmse)
    assert np.all(smooth > 1.0), smooth
    assert np.all(lugre < 0.4), lugre
    assert res.settings["friction_law"] == "lugre" and res.estimate.z.shape[1] == 6
    assert res.settings["torque_window_samples"] == 10
    ukf = np.degrees(estimate_recording(rec, model, "ukf").rmse)  # the same law through sigma points
    assert np.all(ukf < 0.4), ukf


def test_mujoco_dcmotor_lugre_is_the_same_law():
    """The MJCF export writes the file's LuGre law as MuJoCo 4's passive dcmotor per joint (its own implementation
    of the law, a bristle activation): finger3 released from rest under a motor torque on MuJoCo (10 us steps)
    against simulate_lugre, within 0.02 degree over a swing of 20-50 degrees, the bristles within 2e-4 rad (a fifth of
    F_s / sigma0, where they load and reverse: the split step's O(h) against MuJoCo's own integration)."""
    mujoco = pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf_export import model_mjcf

    p = dataclasses.replace(load_params(), friction_law="lugre")
    m = ad.Model.alpes("finger3", friction=True, params=p)
    xml = model_mjcf(m, timestep=1e-5)
    assert xml.count("<dcmotor") == 3 and "frictionloss" not in xml
    mj = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(mj)
    assert mj.nu == 1 and mj.na == 3  # the motor's control only; a bristle per joint
    q0, u0, N = np.array([0.4, 0.6, 0.5]), 0.024, 300
    d.qpos[:] = q0
    d.ctrl[0] = u0
    Q, Z = [], []
    for _ in range(N):  # 300 samples of 100 MuJoCo steps
        mujoco.mj_step(mj, d, nstep=100)
        Q.append(d.qpos.copy())
        Z.append(d.act.copy())
    res = simulate_lugre(StateSpace(m, input="motor", output="encoder"), np.r_[q0, np.zeros(3)],
                         np.full((N, 1), u0), 1e-3, substeps=8)
    assert np.ptp(res.q, axis=0).min() > np.radians(20)
    np.testing.assert_allclose(np.degrees(res.q[1:]), np.degrees(np.array(Q)), atol=0.02)
    np.testing.assert_allclose(res.z[1:], np.array(Z), atol=2e-4)


def test_c_export_of_the_lugre_observer_equals_the_filter(tmp_path):
    """The observer's C export (estimation.cexport) of a LuGre EKF on finger2, compiled with the system compiler,
    gives the filter's numbers over 300 steps of a torque that sticks and slips."""
    import shutil
    import subprocess

    from alpes_dyn.estimation.cexport.cexport import main_input, read_main_output, write_c_observer
    from alpes_dyn.estimation.observers.observers import make_observer

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    m = ad.Model.alpes("finger2", friction=True, params=dataclasses.replace(load_params(), friction_law="lugre"))
    ss = StateSpace(m, input="motor", output="encoder")
    span = m.extras.coulomb / lugre_of(m).sigma0
    filt = make_observer("ekf", ss, 1e-3, friction_law="lugre", substeps=4,
                         process_noise=[1e-18] * 2 + [4e-8] * 2 + list((1e-3 * span) ** 2),
                         measurement_noise=[2e-7], input_noise=[2.5e-7])
    q0 = m.static_equilibrium(ss.B @ [0.02])
    z0, P0 = np.r_[q0, 0.0, 0.0, 0.0, 0.0], np.r_[1e-4, 1e-4, 1.0, 1.0, span**2]
    t = 1e-3 * np.arange(300)
    W = (0.02 + 0.003 * np.sin(2 * np.pi * 4 * t))[:, None]
    y0 = np.asarray(ss.h(np.r_[q0, 0.0, 0.0])).reshape(-1)
    Y = y0 + np.r_[0.0, np.cumsum(np.full(300, 2e-5))][:, None]  # the encoder creeping on: (301, 1)
    est = filt.run(z0, P0, W, Y)
    d = write_c_observer(filt, tmp_path / "ekf", z0=z0, P0=P0)["main.c"].parent
    exe = d / "alpes_ekf_main"
    subprocess.run([cc, "-O1", "-std=c99", "-o", str(exe), str(d / "main.c"), str(d / "alpes_ekf.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=600)
    (tmp_path / "in.txt").write_text(main_input(z0, P0, Y[0], W, Y[1:]))
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    Z, P = read_main_output(out, filt.nz)
    assert Z.shape == est.z.shape == (301, 6)
    np.testing.assert_allclose(Z, est.z, rtol=0, atol=1e-10)
    np.testing.assert_allclose(P, est.P, rtol=0, atol=1e-10)
