"""The public step of the force loop (issue 49, item 3): :class:`alpes_dyn.control.ForceStep` and
:func:`alpes_dyn.control.run_on_bench`.

References: the block composition that :func:`run_control` ran before it used the step (the library's blocks --
ForceLoop, the EKF as an Observer, force_input, SensorlessForce and the compensation's blocks of
``_effect_signals``, as :func:`run_hand_control` still composes them per chain), on the MuJoCo plant with every
effect of a real hand; the readings logged by that composition replayed through a ForceStep built by its public
constructor (what a user's loop does); a loopback plant whose force is proportional to the command.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from alpes_dyn import InputError
from alpes_dyn.bench import Loopback, Reading
from alpes_dyn.control import DEFAULT_GAINS, ForceController, ForceStep, SensorlessForce, run_control, run_on_bench
from alpes_dyn.control.realism_loop import NO_COMPENSATION, Compensation
from alpes_dyn.model.params import Param, load_params, with_values

P = load_params()
RUN = dict(levels=(0.2, 0.6, 0.6), step_times=(0.3, 0.7), duration=0.7, settle=0.2, compiled=False)


def _effects():
    from alpes_dyn.control.plants import PlantEffects

    return PlantEffects(stiction=5e-4, tendon_stiffness=3.95e4, tendon_damping=12.6, tilt=math.radians(3.0),
                        torque_constant_error=0.05, encoder_offset=4.0, tendon_dead_band=P.r_m * math.radians(0.5),
                        torque_delay=1)


@pytest.fixture(scope="module")
def ident():
    """An identified-like file: the shipped finger3 with the cable's compliance (the notch and the stretch act)."""
    return with_values(P, {"transmission.tendon_compliance": Param(1.0 / (3.95e4 * P.r_m**2), "rad/(N m)",
                                                                   "identified", "test", "")})


def _composition(sc):
    """The loop of ``sc`` composed of the library's blocks as run_control composed it before the step (the
    encoder in rad): its log (every signal)."""
    from alpes_dyn.control.blocks import ForceLoop, force_input
    from alpes_dyn.control.finger_loop import _alpes_setup, _effect_signals
    from alpes_dyn.control.controller import reference_profile
    from alpes_dyn.control.step import force_ekf
    from alpes_dyn.estimation.observers.blocks import Observer, step_caller
    from alpes_dyn.simulation.loop import Delay, Source, run_loop
    from alpes_dyn.simulation.plants import MujocoPlant
    from alpes_dyn.simulation.sensors import Encoder, ForceSensor, TorqueSensor

    s = _alpes_setup(sc)
    d, kind, N = s.design, sc.controller, int(round(sc.duration / sc.dt))
    model, rng = d.model, np.random.default_rng(sc.seed)
    fx = _effect_signals(sc, model, d.params)
    ctl = ForceController(kind, model, d.normal, sc.dt, d.tau_max, **d.gains, **fx["controller"])
    F_ref = reference_profile(sc.reference, sc.dt * np.arange(N), sc.levels, sc.sine, sc.step_times)
    blocks = [Source("reference", F_ref=F_ref),
              MujocoPlant(s.mj, s.data, substeps=sc.substeps, joints={"q": model.joint_names},
                          actuators={fx["applied"]: s.actuator}, sensors={"q_m": s.encoders, "F_touch": s.touch},
                          period_sensors={"tau_applied": s.torques}),
              Encoder("q_m", "y", model.transmission.counts_per_rev, noise_counts=sc.encoder_noise_counts, rng=rng,
                      draws=N + 1, offset=fx["offset"]),
              TorqueSensor("tau_applied", fx["reading"], noise=sc.torque_noise, rng=rng, timing="period",
                           gain=fx["gain"]),
              ForceSensor("F_touch", "F_meas", noise=sc.force_noise, resolution=sc.force_resolution, rng=rng),
              ForceLoop(ctl, force="F_fb" if kind == "sensorless" else "F_meas", estimate="z"), *fx["blocks"]]
    ekf, z0, P0 = force_ekf(d.observer_model or model, sc.dt, kind, torque_noise=sc.torque_noise,
                            force_noise=sc.force_noise, encoder_noise_counts=sc.encoder_noise_counts,
                            force_resolution=sc.force_resolution)
    blocks += [force_input("F_fb_prev" if kind == "sensorless" else "F_meas", "w_F", d.normal),
               Observer(ekf, z0, P0, known=(fx["torque"], "w_F"), measurement=fx["measurement"], covariance=None,
                        first_update=False, step=step_caller(ekf.filter_step_p, "t", False, ekf.model.values))]
    if kind == "sensorless":
        blocks += [SensorlessForce(model, sc.dt / (sc.force_filter_s + sc.dt), normal=d.normal,
                                   torque=fx["torque"], scale=fx["force_scale"]), Delay("F_fb", "F_fb_prev", 0.0)]
    return run_loop(blocks, N, sc.dt)


@pytest.mark.parametrize("kind", ["sensor", "sensorless"])
def test_run_control_and_a_user_loop_are_the_block_composition(kind, ident):
    """Every effect on, every compensation on: run_control (which runs a ForceStep) gives the commands, estimates and
    fed-back forces of the block composition; a ForceStep from the public constructor fed that composition's
    readings tick by tick (counts, the torque read at the tick, the force, the reference) returns its commands."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.finger_loop import ControlScenario

    comp = Compensation(tilt=(0.0, -math.radians(3.0)))
    sc = dataclasses.replace(ControlScenario(), controller=kind, params=ident, effects=_effects(), compensation=comp,
                             **RUN)
    res, log = run_control(kind, sc), _composition(sc)
    assert np.allclose(res.tau_cmd, log["tau"], rtol=0, atol=1e-12)
    assert np.allclose(res.q_hat, log["z"][:, :3], rtol=0, atol=1e-12)
    assert np.allclose(res.F_hat, log["F_fb" if kind == "sensorless" else "F_meas"], rtol=0, atol=1e-12)
    assert res.tau_cmd.max() > 0.02 and np.ptp(res.q_hat[:, 0]) > 0.05  # the loop pressed and the joints moved

    step = ForceStep("finger3", ident, kind, compensation=comp, compiled=False)
    counts = np.round(log["y"] / (2 * np.pi / step.counts_per_rev))
    torque = np.concatenate([[0.0], log["tau_meas"][:-1]])  # the reading at tick k: the period before it
    u = np.array([step.step(counts[k], torque[k], log["F_meas"][k], log["F_ref"][k])[0] for k in range(len(counts))])
    assert np.max(np.abs(u - log["tau"])) < 1e-9
    assert np.allclose(step.estimate[0], log["z"][-1, :3], rtol=0, atol=1e-9)
    step.reset()
    assert step.k == 0 and step.step(counts[0], torque[0], log["F_meas"][0], log["F_ref"][0])[0] == pytest.approx(u[0])


def test_the_filter_is_built_once_not_in_the_loop(monkeypatch):
    """The EKF's compiled step is made at construction (one build: the friction EKF's from its C export, else
    step_caller's), never by step() or reset()."""
    import alpes_dyn.control.step as mod

    made = []
    real, real_c = mod.step_caller, mod.ForceStep._compiled_c
    monkeypatch.setattr(mod, "step_caller", lambda *a, **k: made.append(a[1]) or real(*a, **k))
    monkeypatch.setattr(mod.ForceStep, "_compiled_c",
                        staticmethod(lambda e, label: made.append(label) or real_c(e, label)))
    s = ForceStep("finger2", controller="sensorless")
    fn = s.filter_step
    assert made == ["ekf_force_finger2"] and callable(fn)
    for k in range(30):
        u = s.step([float(k)], [0.01], None, 0.3)
    s.reset()
    s.step([0.0], [0.0], math.nan, 0.3)
    assert made == ["ekf_force_finger2"] and s.filter_step is fn
    assert u.shape == (1,) and 0.0 <= u[0] <= s.tau_max
    q, qd = s.estimate
    sq, sqd = s.std
    assert q.shape == (2,) and qd.shape == (2,) and s.covariance.shape == (4, 4) and (sq > 0).all() and (sqd > 0).all()


def test_force_controller_tuned_gains():
    from alpes_dyn.control.step import alpes_design
    from alpes_dyn.model.mjcf import palm_down_params

    d = alpes_design("finger3", palm_down_params(P), "sensor", None, NO_COMPENSATION, {})
    c = ForceController.tuned("sensor", d.model, d.normal, 1e-3, d.tau_max, ki=1.0)
    assert (c.kp, c.ki, c.prefilter_s, c.prefilter_order) == (DEFAULT_GAINS["sensor"]["kp"], 1.0, 0.025, 1)
    assert ForceController(kind="sensor", model=d.model, normal=d.normal, dt=1e-3, tau_max=0.05).kp != c.kp
    s = ForceStep("finger3", controller="pi", gains={"kp": 0.005})
    assert (s.controller.kp, s.controller.ki) == (0.005, DEFAULT_GAINS["pi"]["ki"]) and s.filter_step is None
    assert np.isnan(s.estimate[0]).all()
    with pytest.raises(InputError, match="^controller: unknown controller 'pid'"):
        ForceController.tuned("pid", d.model, d.normal, 1e-3, 0.05)


BAD_STEP = [
    (dict(controller="pid"), "controller: unknown controller 'pid'"),
    (dict(model="finger4"), "model: the force step is defined for one finger"),
    (dict(dt=0.0), "dt: expected a positive number of seconds"),
    (dict(compensation="all"), "compensation: expected a Compensation, got str"),
    (dict(gains={"kq": 1.0}), "kq"),
    (dict(gains=[1.0]), "gains: expected a dict"),
    (dict(frame="tip"), "frame: applies to a URDF + spec model"),
    (dict(torque_noise=-1.0), "torque_noise: expected a non-negative number"),
    (dict(normal=(0.0, 0.0, 0.0)), "normal: expected a non-zero 3-vector"),
    (dict(contact_q=(0.5, math.nan, 0.4)), "contact_q: expected 3 finite joint angles in rad"),
    (dict(model="finger2", contact_q=(0.5,)), "contact_q: expected 2 finite joint angles in rad"),
]


@pytest.mark.parametrize("kw, needle", BAD_STEP, ids=[b[1].split(":")[0] + str(i) for i, b in enumerate(BAD_STEP)])
def test_bad_construction_one_line(kw, needle):
    with pytest.raises(InputError) as e:
        ForceStep(**{"compiled": False, **kw})
    assert needle in str(e.value) and "\n" not in str(e.value)


BAD_SAMPLE = [
    (([1.0, 2.0], [0.0], 0.1, 0.2), "counts: expected 1 encoder counts, got shape (2,)"),
    (([math.nan], [0.0], 0.1, 0.2), "counts: expected finite encoder counts"),
    ((["a"], [0.0], 0.1, 0.2), "counts: expected 1 encoder counts"),
    (([0.0], [[0.0]], 0.1, 0.2), "torque: expected 1 motor torques in N m, got shape (1, 1)"),
    (([0.0], [math.inf], 0.1, 0.2), "torque: expected finite motor torques"),
    (([0.0], [0.0], None, 0.2), "force: the sensor controller needs the fingertip force"),
    (([0.0], [0.0], math.nan, 0.2), "force: the sensor controller needs the fingertip force"),
    (([0.0], [0.0], 0.1, math.nan), "reference: expected a finite force reference"),
]


@pytest.fixture(scope="module")
def finger3_step():
    """One finger3 step for the bad readings (built once: each case checks that its refused sample advanced
    nothing, so the next case starts from the same state)."""
    return ForceStep("finger3", compiled=False)


@pytest.mark.parametrize("args, needle", BAD_SAMPLE, ids=[f"{b[1].split(':')[0]}{i}" for i, b in enumerate(BAD_SAMPLE)])
def test_bad_readings_one_line(finger3_step, args, needle):
    s = finger3_step
    with pytest.raises(InputError) as e:
        s.step(*args)
    assert needle in str(e.value) and "\n" not in str(e.value) and s.k == 0  # nothing advanced


def _proportional(gain: float):
    """A loopback plant: the fingertip force is ``gain`` N per N m of the last command, the torque read is that
    command, the encoder still."""
    def respond(k, U):
        u = U[-1, 0] if len(U) else 0.0
        return np.zeros(1), np.array([u]), gain * u
    return respond


def test_run_on_bench_through_a_loopback():
    """The pi loop on a plant F = 20 N/(N m) x command: one read, step and write per tick, the time stamps the
    hardware's, the reference followed (the PI's integral settles it), the hand closed at the end."""
    hw = Loopback(respond=_proportional(20.0), t0=5.0)
    step = ForceStep("finger3", controller="pi", compiled=False)
    run = run_on_bench(hw, step, lambda t: 0.3 if t < 0.5 else 0.6, 1.0)
    assert run.command.shape == (1000, 1) and run.counts.shape == (1000, 1) and run.q_hat.shape == (1000, 3)
    assert np.allclose(run.t, 5.0 + 1e-3 * np.arange(1000)) and run.missed == 0 and hw.closed
    assert np.array_equal(hw.commands, run.command)  # every command written, in order
    assert np.allclose(run.force[1:], 20.0 * run.command[:-1, 0])  # each reading answers the command before it
    assert abs(run.force[490:500].mean() - 0.3) < 0.01 and abs(run.force[-10:].mean() - 0.6) < 0.01
    assert np.isnan(run.q_hat).all()

    hw2 = Loopback(respond=_proportional(20.0))
    ref = np.full(300, 0.4)
    run2 = run_on_bench(hw2, ForceStep("finger3", compiled=False), ref, 0.3, close=False)  # the sensor loop
    assert not hw2.closed and run2.command.shape == (300, 1) and np.isfinite(run2.q_hat).all()
    assert np.all((run2.command >= 0) & (run2.command <= 0.05))


class _Late(Loopback):
    """A loopback whose clock skips one tick at k = 10 (a missed period)."""

    def read(self):
        r = super().read()
        return Reading(r.t + (self.period if len(self._commands) >= 10 else 0.0), r.counts, r.torque, r.force)


def test_run_on_bench_counts_missed_periods_and_refuses_mismatches():
    run = run_on_bench(_Late(respond=_proportional(20.0)), ForceStep("finger3", None, "pi", compiled=False),
                       0.3, 0.05)
    assert run.missed == 1
    step = ForceStep("finger3", controller="pi", compiled=False)
    for hw, kw, needle in [
            (Loopback(period=2e-3), {}, "period: the hardware's period 0.002 s is not the step's dt 0.001 s"),
            (Loopback(motor_names=("a", "b")), {}, "motor_names: the hardware has 2 motor(s)"),
            (Loopback(tau_max=0.01), {}, "tau_max: the step commands up to 0.05 N m"),
            (Loopback(counts_per_rev=1000), {}, "counts_per_rev: the hardware's encoder has 1000"),
            (Loopback(), {"duration": -1.0}, "duration: expected a positive number of seconds"),
            (Loopback(), {"reference": [0.1, 0.2]}, "reference: expected one force per tick (10 values"),
            (object(), {}, "hw: expected a HardwareInterface")]:
        with pytest.raises(InputError) as e:
            run_on_bench(hw, step, kw.get("reference", 0.3), kw.get("duration", 0.01))
        assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_closed_loop_on_the_mujoco_stand_in():
    """run_on_bench on the MuJoCo stand-in (finger3 pressing its block, every effect of a real hand, its truth
    hidden): the sensor loop from an identified-like file (the cable's compliance) with the palm's tilt as the fit
    names it holds the step 0.2 -> 0.6 N: the RMSE of the sensor's reading after the rise (from 0.5 s, the 150 ms
    after the step left out) under 3 % of the step, overshoot under 12 %; the joint estimates in contact within 2
    degrees of the plant's joints (read from MuJoCo's data by the test only, measured 1.3 / 0.7 / 1.0)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.bench import MujocoHand
    from alpes_dyn.bench.effects import CABLE_STIFFNESS, TILT_DEG
    from alpes_dyn.model.mjcf import joint_permutation

    ident = with_values(P, {"transmission.tendon_compliance": Param(1.0 / (CABLE_STIFFNESS * P.r_m**2), "rad/(N m)",
                                                                   "identified", "test", "")})
    step = ForceStep("finger3", ident, "sensor", compensation=Compensation(tilt=(0.0, -math.radians(TILT_DEG))))
    hw = MujocoHand("finger3", scene="block", seed=3)
    perm, data, q_true = joint_permutation(hw._plant.mj, step.model.joint_names), hw._data, []
    write = hw.write
    hw.write = lambda u: q_true.append(data.qpos[perm].copy()) or write(u)  # the truth, for the test's reference
    run = run_on_bench(hw, step, lambda t: 0.2 if t < 1.0 else 0.6, 1.45)
    t = run.t - run.t[0]
    after = (t >= 0.5) & ~((t >= 1.0) & (t < 1.15))
    assert np.sqrt(np.mean((run.force[after] - run.F_ref[after]) ** 2)) < 0.03 * 0.4  # measured 2.8 %
    assert run.force[t >= 1.0].max() < 0.6 + 0.12 * 0.4 and run.missed == 0 and hw.closed
    contact = run.force > 0.05
    err = np.degrees(np.sqrt(np.mean((run.q_hat[contact] - np.array(q_true)[contact]) ** 2, axis=0)))
    assert contact.mean() > 0.6 and (err < 2.0).all(), err


def test_a_urdf_robot_step_is_run_controls(tmp_path):
    """A URDF + spec robot (test_anyrobot's tendon finger): the step's motor limit, gains and normal are
    run_control's (robot_control_settings), its command (m,) has the pulling motor's entry; params refused."""
    from test_anyrobot import FINGER_URDF, finger_spec

    import alpes_dyn as ad
    from alpes_dyn.control.finger_loop import ControlScenario, robot_control_settings

    (tmp_path / "f.urdf").write_text(FINGER_URDF)
    (tmp_path / "f.toml").write_text(finger_spec(Fs=(0.0, 0.0)) + "\n[rest_angle]\nmcp = 0.5\npip = 0.5\n")
    robot = ad.Model.from_urdf_file(tmp_path / "f.urdf", tmp_path / "f.toml")
    model, block, tau_max, gains = robot_control_settings(ControlScenario(model=robot, controller="sensor"))
    s = ForceStep(robot, controller="sensor", compiled=False, compensation=NO_COMPENSATION)
    assert s.tau_max == pytest.approx(tau_max, rel=1e-12) and s.controller.kp == pytest.approx(gains["kp"])
    assert np.allclose(s.controller.normal, block.normal / np.linalg.norm(block.normal)) and s.design.frame == "fingertip"
    u = s.step(np.zeros(s.m), np.zeros(s.m), 0.0, 0.3)
    assert u.shape == (s.m,) and u[s.motor] > 0 and np.count_nonzero(u) == 1
    with pytest.raises(InputError, match="^params: applies to the Alpes fingers"):
        ForceStep(robot, "x.toml", compiled=False)


def test_a_diverging_filter_is_named_and_leaves_the_state():
    """A current in mA read as N m (2306 against a 0.05 N m limit): the EKF leaves any joint range within a few
    samples; the step says so in one line naming the readings and keeps its last sane state."""
    s = ForceStep("finger3", compiled=False)
    with pytest.raises(InputError) as e:
        for _ in range(50):
            s.step([1e6], [2306.0], 0.1, 0.3)
    msg = str(e.value)
    assert msg.startswith("readings: the EKF diverged at sample") and "units" in msg and "\n" not in msg
    assert np.isfinite(s.state).all() and (np.abs(s.state) < 1e6).all() and s.k < 50


def test_the_observers_force_input_is_in_the_files_torque_units():
    """A torque constant off by s = 1 + e scales every torque an identification finds (springs, masses, friction,
    the rotor) and the torque reading by s, not the fingertip sensor's newtons: the EKF of that file, its torque
    noise scaled too, fed the readings s tau and F with ``force_scale`` s, estimates the joints of the true file's
    EKF fed tau and F (the same equations times s); with ``force_scale`` 1 the force is s times short against the
    file's torques, and the joints' split moves (0.45 degree here)."""
    s = 1.05
    p = load_params()
    f = p.finger
    scaled = dataclasses.replace(p, finger=dataclasses.replace(f, K=f.K * s, m=f.m * s, I=f.I * s,
                                                               F_s=None if f.F_s is None else f.F_s * s,
                                                               F_v=None if f.F_v is None else f.F_v * s),
                                 F_s=p.F_s * s, F_v=p.F_v * s, J_m=p.J_m * s)
    comp = dict(observer_compliance=False, command_input=False)  # the EKF on the reading (no command, no stretch)
    true = ForceStep("finger2", p, "sensor", compiled=False, compensation=Compensation(**comp))
    found = {fs: ForceStep("finger2", scaled, "sensor", compiled=False, torque_noise=5e-4 * s,
                           compensation=Compensation(force_scale=fs, **comp)) for fs in (s, 1.0)}
    counts0 = 1700.0  # the finger pulled to a fixed reading
    q = {}
    for name, step, tau in (("true", true, 0.03), ("scaled", found[s], 0.03 * s), ("unscaled", found[1.0], 0.03 * s)):
        for _ in range(600):  # 0.6 s pressing 0.4 N
            step.step(counts0, tau, 0.4, 0.4)
        q[name] = step.estimate[0]
    # the force input's own variance and the process noise are not scaled: 0.05 degree apart, against 0.45
    np.testing.assert_allclose(q["scaled"], q["true"], rtol=0, atol=math.radians(0.1))
    assert np.abs(q["unscaled"] - q["true"]).max() > math.radians(0.3)
