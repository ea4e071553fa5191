"""The closed-loop engine (alpes_dyn.simulation.loop): the runner's timing and checks, each block alone (a sensor
against its closed form, a plant's step against its model, the observer against its filter), and the library's
scenarios as compositions of blocks reproducing the hand-written loops they replace (tests/legacy_loops.py) to the
last bit on fixed seeds."""

from __future__ import annotations

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.blocks import Observer, ObserverBank
from alpes_dyn.estimation.observers.observers import make_observer
from alpes_dyn.simulation.integrate import rk4_step_function, simulate
from alpes_dyn.simulation.loop import Block, Delay, Function, Source, run_loop
from alpes_dyn.simulation.plants import SimulatorPlant
from alpes_dyn.simulation.sensors import Encoder, ForceSensor, TorqueSensor
from alpes_dyn.symbolic.statespace import StateSpace

import legacy_loops as legacy


def same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


# ----------------------------------------------------------------------------- the runner
class Accumulate(Block):
    """x_k+1 = x_k + u_k (a period signal: the sum over the periods so far), y_k = x_k (a sample signal)."""

    inputs, update_inputs, outputs, period_outputs = (), ("u",), ("y",), ("x_next",)

    def start(self, n_periods, dt, final):
        self.x = 0.0

    def output(self, k, u):
        return {"y": self.x}

    def update(self, k, u):
        self.x += u["u"]
        return {"x_next": self.x}


def test_timing_of_sample_period_and_delayed_signals():
    u = np.arange(1.0, 6.0)
    log = run_loop([Source(u=u), Accumulate(), Delay("u", "u_prev", -1.0),
                    Function(lambda y, u_prev: y + u_prev, ("y", "u_prev"), "s")], 4, 0.1, final=True)
    assert log.mode == "step" and same(log.t, 0.1 * np.arange(5))
    assert same(log["u"], u) and same(log["y"], [0, 1, 3, 6, 10])  # y_k = the sum of u before t_k
    assert same(log["x_next"], [1, 3, 6, 10])  # a period signal: one row per period
    assert same(log["u_prev"], [-1, 1, 2, 3, 4]) and same(log["s"], log["y"] + log["u_prev"])
    assert log.period == {"x_next"}
    with pytest.raises(InputError, match="no signal 'nope'"):
        log["nope"]


def test_outputs_are_ordered_by_their_inputs_and_period_signals_read_the_previous_period():
    seen = []

    class Reader(Block):
        inputs, outputs = ("x_next", "f"), ("r",)

        def output(self, k, u):
            seen.append((u["x_next"], u["f"]))
            return {"r": 0.0}

    blocks = [Reader(), Function(lambda y: 2 * y, ("y",), "f"), Accumulate(), Source(u=np.ones(4))]
    blocks[2].initial = {"x_next": -5.0}
    run_loop(blocks, 3, 1.0)  # the reader listed first still reads f of the same sample
    assert seen == [(-5.0, 0.0), (1.0, 2.0), (2.0, 4.0)]


def test_composition_errors():
    src = Source(u=np.ones(3))
    with pytest.raises(InputError, match="'v': read by block 'function' but written by no block"):
        run_loop([src, Function(lambda v: v, ("v",), "w")], 2, 1.0)
    with pytest.raises(InputError, match="'u': written by two blocks"):
        run_loop([src, Source(u=np.ones(3))], 2, 1.0)
    with pytest.raises(InputError, match="algebraic loop through the outputs"):
        run_loop([Function(lambda a: a, ("a",), "b"), Function(lambda b: b, ("b",), "a")], 2, 1.0)
    with pytest.raises(InputError, match="'batch' needs an open loop"):
        run_loop([src, Accumulate()], 2, 1.0, mode="batch")
    with pytest.raises(InputError, match="u: expected at least 4 rows"):
        run_loop([src], 4, 1.0)
    with pytest.raises(InputError, match="written 1 times in 3 samples"):
        class Once(Block):
            outputs = ("o",)

            def output(self, k, u):
                return {"o": 1.0} if k == 0 else {}

        run_loop([Once()], 3, 1.0)


# ----------------------------------------------------------------------------- sensors alone
def test_encoder_quantises_to_its_step_closed_form():
    cpr = 4096
    step = 2 * np.pi / cpr
    x = np.linspace(-1.0, 1.0, 201)
    enc = Encoder("x", "y", cpr)
    enc.start(200, 1e-3, True)
    y = enc.response({"x": x})["y"]
    assert same(y, np.round(x / step) * step)
    assert np.max(np.abs(y - x)) <= step / 2 + 1e-15
    assert np.allclose(y / step, np.round(y / step), rtol=0, atol=1e-9)  # whole counts
    counts = Encoder("x", "c", cpr, counts=True, offset=3.0)
    counts.start(200, 1e-3, True)
    assert same(counts.response({"x": x})["c"], np.round(x / step + 3.0))
    # the noise: noise_counts counts, drawn at the start from the sensor's own stream
    noisy = Encoder("x", "y", cpr, noise_counts=0.5, rng=np.random.default_rng(3))
    noisy.start(200, 1e-3, True)
    z = np.random.default_rng(3).standard_normal(201)
    assert same(noisy.response({"x": x})["y"], np.round((x + 0.5 * step * z) / step) * step)


def test_sensors_step_and_record_give_the_same_readings():
    x = np.linspace(0.0, 1.0, 11)
    for make in (lambda r: Encoder("x", "y", 1024, noise_counts=2.0, rng=r),
                 lambda r: TorqueSensor("x", "y", noise=0.01, gain=1.03, rng=r),
                 lambda r: ForceSensor("x", "y", noise=0.05, resolution=0.01, rng=r)):
        logs = [run_loop([Source(x=x), make(np.random.default_rng(1))], 10, 0.1, final=True, mode=m)
                for m in ("step", "batch")]
        assert logs[1].mode == "batch" and same(logs[0]["y"], logs[1]["y"])


def test_torque_and_force_sensors_closed_form():
    z = np.random.default_rng(5).standard_normal(4)
    tau = TorqueSensor("t", "m", noise=0.1, gain=1.5, rng=np.random.default_rng(5), timing="period")
    tau.start(4, 1e-3, False)
    assert same(tau.response({"t": np.arange(5.0)})["m"], 1.5 * np.arange(4.0) + 0.1 * z)
    f = ForceSensor("F", "Fm", resolution=0.25)
    f.start(3, 1e-3, True)
    assert same(f.response({"F": np.array([-0.3, 0.1, 0.13, 0.9])})["Fm"], [0.0, 0.0, 0.25, 1.0])
    assert f.output(0, {"F": -0.3})["Fm"] == 0.0 and f.output(1, {"F": 0.9})["Fm"] == 1.0


def test_sensor_noise_streams_are_independent_and_reproducible():
    """Each sensor on its own stream: adding a sensor changes no other's noise."""
    x = np.zeros(6)

    def run(extra: bool):
        blocks = [Source(x=x), Encoder("x", "a", 64, noise_counts=1.0, rng=np.random.default_rng([7, 0]))]
        if extra:
            blocks.append(TorqueSensor("x", "c", noise=1.0, rng=np.random.default_rng([7, 2])))
        blocks.append(TorqueSensor("x", "b", noise=1.0, rng=np.random.default_rng([7, 1])))
        return run_loop(blocks, 5, 1.0, final=True)

    one, two = run(False), run(True)
    assert same(one["a"], two["a"]) and same(one["b"], two["b"]) and not same(two["b"], two["c"])
    # one shared generator: the draws come in the order of the list
    rng = np.random.default_rng(4)
    log = run_loop([Source(x=x), TorqueSensor("x", "a", noise=1.0, rng=rng, draws=8),
                    TorqueSensor("x", "b", noise=1.0, rng=rng)], 5, 1.0, final=True)
    z = np.random.default_rng(4).standard_normal(14)
    assert same(log["a"], z[:6]) and same(log["b"], z[8:])
    with pytest.raises(InputError, match="reads 6 times but draws 3"):
        run_loop([Source(x=x), TorqueSensor("x", "a", noise=1.0, rng=rng, draws=3)], 5, 1.0, final=True)


# ----------------------------------------------------------------------------- plants and observers alone
@pytest.fixture(scope="module")
def finger():
    return ad.Model.alpes("finger3")


def test_simulator_plant_steps_its_model(finger):
    n = finger.n
    x0 = np.r_[0.3, 0.8, 0.7, np.zeros(n)]
    u = np.full((6, 1), 0.0222) + 0.001 * np.arange(6)[:, None]
    plant = SimulatorPlant(finger, x0, substeps=2, u="tau")
    step_log = run_loop([Source(tau=u), plant], 5, 1e-3, final=True, mode="step")
    batch_log = run_loop([Source(tau=u), plant], 5, 1e-3, final=True)
    assert batch_log.mode == "batch"
    ss = StateSpace(finger, input="motor", output="encoder")
    f = rk4_step_function(ss, 0.5e-3)
    x = x0
    for k in range(5):  # one period: two RK4 steps of the model with the torque held
        x = np.array(f(f(x, u[k]), u[k])).reshape(-1)
        assert same(step_log["x"][k + 1], x)
    sim = simulate(finger, x0, np.repeat(u[:5], 2, axis=0), 5e-3, 0.5e-3, input="motor", joint_range="ignore")
    assert same(batch_log["x"], sim.x[::2]) and same(step_log["x"], batch_log["x"])
    assert same(step_log["q_m"], finger.transmission.encoder_angles(sim.x[::2, :n], u))


def test_mujoco_plant_steps_mujoco(finger):
    """One period of the block: the controls set, ``substeps`` mj_step calls; its signals MuJoCo's qpos and
    sensordata (the period sensor read after the steps), as on a twin MjData stepped by hand."""
    mujoco = pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf import joint_permutation, load_mujoco, mjcf_string
    from alpes_dyn.simulation.plants import MujocoPlant

    mj = load_mujoco(mjcf_string("finger3", ad.load_params(), friction=True, scene="block"))
    d, twin = mujoco.MjData(mj), mujoco.MjData(mj)
    perm = joint_permutation(mj, finger.joint_names)
    for dd in (d, twin):
        dd.qpos[perm] = [0.3, 0.8, 0.7]
        mujoco.mj_forward(mj, dd)
    u = np.array([0.0, 0.01, 0.02, 0.03])
    plant = MujocoPlant(mj, d, substeps=3, joints={"q": finger.joint_names}, actuators={"tau": "finger"},
                        sensors={"q_m": "encoder_finger"}, period_sensors={"tau_applied": "torque_finger"})
    log = run_loop([Source(tau=u), plant], 4, 3 * mj.opt.timestep)
    enc, frc = mj.sensor("encoder_finger").adr[0], mj.sensor("torque_finger").adr[0]
    for k in range(4):
        assert same(log["q"][k], twin.qpos[perm]) and log["q_m"][k] == twin.sensordata[enc]
        twin.ctrl[0] = u[k]
        for _ in range(3):
            mujoco.mj_step(mj, twin)
        assert log["tau_applied"][k] == twin.sensordata[frc]
    assert log["tau_applied"][-1] == pytest.approx(0.03)  # the actuator's force over the last period


def test_observer_block_is_its_filter_and_a_bank_is_its_observers(finger):
    ss = StateSpace(finger, input="motor", output="encoder")
    rng = np.random.default_rng(0)
    y = 1.0 + 0.01 * rng.standard_normal((21, 1))
    u = 0.02 + 0.001 * rng.standard_normal((20, 1))
    ekf = make_observer("ekf", ss, 1e-3, process_noise=1e-8, measurement_noise=1e-6, input_noise=1e-8)
    z0, P0 = np.zeros(6), np.full(6, 0.1)
    est = ekf.run(z0, P0, u, y)
    blocks = [Source(y=y), Source("torque", period=True, u=u), Observer(ekf, z0, P0, known=("u",), measurement="y")]
    for mode in ("batch", "step"):
        log = run_loop(blocks, 20, 1e-3, final=True, mode=mode)
        assert same(log["z"], est.z) and same(log["P"], est.P), mode
    # two observers of one model advanced together: each as alone
    obs = [Observer(ekf, z0 + i, P0, known=("u",), measurement="y", estimate=f"z{i}", covariance=None)
           for i in range(2)]
    bank = run_loop(blocks[:2] + [ObserverBank(obs, compiled=False)], 20, 1e-3, final=True)
    for i in range(2):
        alone = run_loop(blocks[:2] + [Observer(ekf, z0 + i, P0, known=("u",), measurement="y")], 20, 1e-3,
                         final=True, mode="step")
        assert same(bank[f"z{i}"], alone["z"])


# ----------------------------------------------------------------------------- the scenarios reproduce the old loops
@pytest.mark.parametrize("observer, kw", [
    ("ekf", dict(seed=0, duration=0.3)), ("ukf", dict(seed=1, duration=0.2, mismatch=0.1)),
    ("ekf-params", dict(seed=2, duration=0.3, mismatch=0.05)), ("ekf", dict(seed=3, duration=0.2, model="finger2")),
    ("ekf", dict(seed=0, duration=0.2, model="thumb", friction=True))])
def test_run_estimation_reproduces_the_hand_written_scenario(observer, kw):
    from alpes_dyn.estimation.observers.scenario import run_estimation

    new, old = run_estimation(observer, **kw), legacy.legacy_estimation(observer, **kw)
    assert same(new.x_true, old["x_true"]) and same(new.y, old["y"]) and same(new.u_meas, old["u_meas"])
    assert same(new.estimate.z, old["z"]) and same(new.estimate.P, old["P"]) and same(new.rmse, old["rmse"])
    assert same(np.reshape([[v["estimate"], v["true"]] for v in new.parameters.values()], (-1, 2)), old["gains"])


CONTROL_FIELDS = ("F_true", "F_meas", "F_hat", "q_true", "q_hat", "tau_cmd", "tau_meas")


@pytest.mark.parametrize("controller, kw", [
    ("sensor", dict(seed=0, compiled=False)), ("sensorless", dict(seed=1, compiled=False)), ("pi", dict(seed=2)),
    ("sensor", dict(seed=3, model="finger2", reference="sine", compiled=False))])
def test_run_control_reproduces_the_hand_written_loop(controller, kw):
    pytest.importorskip("mujoco")
    from alpes_dyn.control.finger_loop import run_control

    kw = dict(duration=0.8, settle=0.2, step_times=(0.3, 0.55), **kw)
    # the hand-written loop's EKF is frictionless (version 0.2's design): the same asked of run_control
    new, old = run_control(controller, observer_friction=False, **kw), legacy.legacy_control(controller, **kw)
    for f in CONTROL_FIELDS:
        assert same(getattr(new, f), old[f]), f


@pytest.mark.parametrize("controller", ["sensor", "sensorless", "pi"])
def test_run_hand_control_reproduces_the_hand_written_loops(controller):
    """run_hand_control's step is the user's HandForceStep (the one step object of the simulation and the bench);
    the hand-written loop's numbers kept: the PI's to the last bit; with the EKFs, in free motion (0.55 s, before
    any contact), the plant's, the sensors' and the commands to the last bit, the joint estimates within 2e-3 rad
    (6e-4 rad seen: the step's EKF takes this tick's FlexiForce reading as the force over the period before, the
    hand-written loop the previous tick's; in free motion the reading is its noise, 0 or one 4.3 mN step)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.hand_loop import run_hand_control

    kw = dict(seed=4, duration=0.55, step_time=0.3, settle=0.05, compiled=False)
    new, old = run_hand_control(controller, **kw), legacy.legacy_hand(controller, **kw)
    assert same(new.q_abduction, old["q_abduction"])
    for c, r in new.chains.items():
        for f in CONTROL_FIELDS:
            if controller == "pi" or f not in ("q_hat", "F_hat"):
                assert same(getattr(r, f), old[f"{f}_{c}"]), (c, f)
            else:
                np.testing.assert_allclose(getattr(r, f), old[f"{f}_{c}"], rtol=0, atol=2e-3, err_msg=f"{c} {f}")


def test_run_hand_control_in_contact_keeps_the_hand_written_loops_numbers():
    """The sensor loops through contact (2.3 s: every fingertip on the cylinder by 1.5 s, the step at 2.0 s): each
    chain's force held over the last 0.2 s of each level within 2 mN of the hand-written loop's (1.4e-4 N seen),
    its joint estimates within 0.01 rad (4.5e-3 seen) and its commands within 5e-3 N m (1.8e-3 seen: the little
    finger's contact, one sample apart) at every sample, the ab/adduction within 2e-3 rad. Two differences of
    timing: the EKF's force input (this tick's reading, the loop's the previous tick's) and the contact normal of the
    controller and the sensorless estimate (the cylinder's at the previous sample's estimate, what the C step takes
    as its input; the loop's at this sample's)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.hand_loop import run_hand_control

    kw = dict(seed=4, duration=2.3, step_time=2.0, settle=1.7)
    new, old = run_hand_control("sensor", **kw), legacy.legacy_hand("sensor", **kw)
    np.testing.assert_allclose(new.q_abduction, old["q_abduction"], rtol=0, atol=2e-3)
    for c, r in new.chains.items():
        for lo in (1.8, 2.1):
            k = (r.t >= lo) & (r.t < lo + 0.2)
            assert abs(r.F_true[k].mean() - old[f"F_true_{c}"][k].mean()) < 2e-3, c
        np.testing.assert_allclose(r.q_hat, old[f"q_hat_{c}"], rtol=0, atol=1e-2, err_msg=c)
        np.testing.assert_allclose(r.tau_cmd, old[f"tau_cmd_{c}"], rtol=0, atol=5e-3, err_msg=c)


def test_recording_plant_and_replay_reproduce_the_hand_written_ones(finger):
    pytest.importorskip("mujoco")
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.estimation.observers.replay import estimate_recording

    t = 1e-3 * np.arange(301)
    u = (0.0222 + 0.002 * np.sin(2 * np.pi * 1.3 * t))[:, None]
    eff = PlantEffects(torque_constant_error=0.03, encoder_offset=2.0)
    rec = mujoco_recording("finger3", None, u, effects=eff, seed=5)
    old = legacy.legacy_mujoco_recording("finger3", None, u, effects=eff, seed=5)
    assert same(rec.encoder, old["encoder"]) and same(rec.torque, old["torque"]) and same(rec.true_q, old["true_q"])
    model = ad.Model.alpes("finger3", friction=True)
    for disturbance in (False, True):
        new = estimate_recording(rec, model, disturbance=disturbance)
        ref = legacy.legacy_estimate_recording(rec, model, disturbance=disturbance)
        assert same(new.estimate.z, ref["z"]) and same(new.estimate.P, ref["P"])


def test_the_estimation_scenario_stepped_gives_its_whole_record_run(monkeypatch):
    """The open loop of run_estimation evaluated block by block (auto) and sample by sample (step): the same bits."""
    from alpes_dyn.estimation.observers import scenario
    from alpes_dyn.simulation import loop

    modes = []

    def run(*a, mode="auto", **kw):
        log = loop.run_loop(*a, mode=mode, **kw)
        modes.append(log.mode)
        return log

    monkeypatch.setattr(scenario, "run_loop", run)
    batch = scenario.run_estimation("ekf", duration=0.2, seed=6)
    monkeypatch.setattr(scenario, "run_loop", lambda *a, **kw: run(*a, **{**kw, "mode": "step"}))
    step = scenario.run_estimation("ekf", duration=0.2, seed=6)
    assert modes == ["batch", "step"]
    for a, b in ((batch.x_true, step.x_true), (batch.y, step.y), (batch.u_meas, step.u_meas),
                 (batch.estimate.z, step.estimate.z), (batch.estimate.P, step.estimate.P)):
        assert same(a, b)
