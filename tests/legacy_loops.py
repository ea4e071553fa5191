"""The closed loops as they were written by hand before the engine (alpes_dyn.simulation.loop), kept as the tests'
oracle: each block composition must give these numbers to the last bit on the same seeds (tests/test_loop.py).

Copied from the library at commit d8e2e74 (run_estimation, run_control, run_hand_control, mujoco_recording,
estimate_recording), their input checks left out; the helpers they call (the torque profile, the rest states, the
noise settings, the EKF's step callers) are the library's, unchanged by the engine.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from alpes_dyn.model.transmission import torque_before
from alpes_dyn.estimation.observers.blocks import batch_step_caller, step_caller
from alpes_dyn.estimation.observers.observers import make_observer, true_gains
from alpes_dyn.estimation.observers.scenario import (EstimationScenario, _held_joints, _torque, default_noise,
                                           mismatched_params, rest_with_held_joints, static_equilibrium)
from alpes_dyn.model.params import HandParams, load_params
from alpes_dyn.model.robot import Model
from alpes_dyn.simulation.integrate import simulate, stable_substeps
from alpes_dyn.symbolic.statespace import StateSpace


def legacy_estimation(observer: str = "ekf", **kw) -> dict[str, np.ndarray]:
    """The old run_estimation: x_true, y, u_meas, z, P, rmse."""
    sc = dataclasses.replace(EstimationScenario(), **kw)
    p = sc.params if isinstance(sc.params, HandParams) else load_params(sc.params)
    truth = Model.alpes(sc.model, spring=sc.spring, friction=sc.friction, params=p, chain=sc.chain)
    rng = np.random.default_rng(sc.seed)
    n, m = truth.n, truth.transmission.n_motors
    _, held_motors = _held_joints(truth)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N + 1)
    u_true = _torque(sc, t[:-1], m, held_motors)
    q0 = rest_with_held_joints(truth, u_true[0]) + rng.uniform(-sc.q0_offset, sc.q0_offset, size=n)
    x0 = np.concatenate([q0, np.zeros(n)])
    sub = max(sc.substeps, stable_substeps(truth, sc.dt))
    sim = simulate(truth, x0, np.repeat(u_true, sub, axis=0), sc.duration, sc.dt / sub,
                   "rk4", input="motor", output="encoder", joint_range="ignore")
    x_true = sim.x[::sub]
    step = 2 * np.pi / truth.transmission.counts_per_rev
    # the stretch under the torque held before each sample (torque_before: the convention since 2026-12-02)
    y_cont = truth.transmission.encoder_angles(x_true[:, :n], torque_before(np.concatenate([u_true, u_true[-1:]])))
    y = truth.transmission.quantize(y_cont + sc.encoder_noise_counts * step * rng.standard_normal(y_cont.shape))
    u_meas = u_true + sc.torque_noise * rng.standard_normal(u_true.shape)
    meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
    d = sc.mismatch
    mass_scale, spring_scale = 1.0 + sc.mismatch_signs[0] * d, 1.0 + sc.mismatch_signs[1] * d
    p_obs = mismatched_params(p, mass_scale, spring_scale) if d != 0 else p
    obs_model = Model.alpes(sc.model, spring=sc.spring, friction=sc.friction, params=p_obs, chain=sc.chain)
    ss = StateSpace(obs_model, input="motor", output="encoder")
    pars = tuple(sc.parameters) if observer.endswith("-params") else ()
    noise = default_noise(sc, n, m, len(pars), meas_var)
    # the smooth law's model error (issue 50, added since) is make_observer's own: with_friction_noise
    filt = make_observer(observer, ss, sc.dt, parameters=pars,
                         substeps=max(sc.substeps, stable_substeps(obs_model, sc.dt)) if sc.friction else 1, **noise)
    z0 = np.concatenate([np.zeros(2 * n), np.ones(len(pars))])
    P0 = np.array([0.5**2] * n + [1.0**2] * n + [0.2**2] * len(pars))
    est = filt.run(z0, P0, u_meas, y)
    k0 = int(round(sc.transient_s / sc.dt))
    err = est.z[:, :n] - x_true[:, :n]
    gains = true_gains(mass_scale, spring_scale)
    return dict(x_true=x_true, y=y, u_meas=u_meas, z=est.z, P=est.P, rmse=np.sqrt(np.mean(err[k0:] ** 2, axis=0)),
                gains=np.array([[est.z[-1, 2 * n + i], gains.get(nm, np.nan)]
                                for i, nm in enumerate(filt.model.parameters)]).reshape(-1, 2))


def legacy_control(controller: str = "sensor", **kw) -> dict[str, np.ndarray]:
    """The old run_control's loop: F_true, F_meas, F_hat, q_true, q_hat, tau_cmd, tau_meas."""
    import mujoco

    from alpes_dyn.control.controller import DEFAULT_GAINS, ForceController, reference_profile, static_contact_force
    from alpes_dyn.control.finger_loop import ControlScenario, _plant_and_params
    from alpes_dyn.model.mjcf import BLOCK_CONTACT_Q, block_normal, joint_permutation, load_mujoco, mjcf_string

    sc = dataclasses.replace(ControlScenario(), controller=controller, **kw)
    _, p, pp = _plant_and_params(sc)
    n = 2 if sc.model == "finger2" else 3
    cq = tuple((sc.contact_q or BLOCK_CONTACT_Q)[:n])
    model = Model.alpes(sc.model, params=p)
    plant_model = Model.alpes(sc.model, params=pp)
    mj = load_mujoco(mjcf_string(sc.model, pp, friction=True, scene="block", contact_q=cq,
                                 timestep=sc.dt / sc.substeps))
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, model.joint_names)
    normal = block_normal(cq)
    tr = model.transmission
    rng = np.random.default_rng(sc.seed)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    F_ref = reference_profile(sc.reference, t, sc.levels, sc.sine, sc.step_times)
    d.qpos[perm] = static_equilibrium(plant_model, np.zeros(plant_model.n))
    mujoco.mj_forward(mj, d)
    s_enc = mj.sensor("encoder_finger").adr[0]
    s_frc = mj.sensor("torque_finger").adr[0]
    s_touch = mj.sensor("flexiforce_finger").adr[0]
    use_obs = sc.controller != "pi"
    step = 2 * np.pi / tr.counts_per_rev
    if use_obs:
        ss = StateSpace(model, input="motor", output="encoder", force=True)
        est_sc = EstimationScenario(torque_noise=sc.torque_noise, encoder_noise_counts=sc.encoder_noise_counts)
        meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
        noise = default_noise(est_sc, n, 1, 0, meas_var)
        f_var = (sc.force_noise**2 + sc.force_resolution**2 / 12) if sc.controller == "sensor" else 0.05**2
        noise["input_noise"] = [sc.torque_noise**2] + [f_var] * 3
        ekf = make_observer("ekf", ss, sc.dt, **noise)
        z0 = np.concatenate([static_equilibrium(model, np.zeros(n)), np.zeros(n)])
        P0 = np.array([0.05**2] * n + [0.1**2] * n)
        s = np.concatenate([z0, np.diag(P0).reshape(-1, order="F")])
        fstep = step_caller(ekf.filter_step_p, f"ekf_force_{sc.model}", sc.compiled, ekf.model.values)
    ctl = ForceController(sc.controller, model, normal, sc.dt, p.tau_max, **{**DEFAULT_GAINS[sc.controller], **sc.gains})
    out = {k: np.empty(N) for k in ("F_true", "F_meas", "F_hat", "tau_cmd", "tau_meas")}
    out["q_true"], out["q_hat"] = np.empty((N, n)), np.full((N, n), np.nan)
    enc_noise = sc.encoder_noise_counts * step * rng.standard_normal(N + 1)
    trq_noise = sc.torque_noise * rng.standard_normal(N)
    frc_noise = sc.force_noise * rng.standard_normal(N)
    alpha = sc.dt / (sc.force_filter_s + sc.dt)
    F_filt, tau_meas_prev, sd = 0.0, 0.0, d.sensordata
    for k in range(N):
        out["q_true"][k] = d.qpos[perm]
        F_true = float(sd[s_touch])
        F_meas = max(0.0, round((F_true + frc_noise[k]) / sc.force_resolution) * sc.force_resolution)
        y = round((float(sd[s_enc]) + enc_noise[k]) / step) * step
        if use_obs:
            F_in = F_meas if sc.controller == "sensor" else F_filt
            if k > 0:
                s = fstep(s, np.concatenate([[tau_meas_prev], -F_in * normal, [y]]))
            q_hat = s[:n]
            if sc.controller == "sensorless":
                F_est = static_contact_force(model, q_hat, np.array([tau_meas_prev]), normal)
                F_filt += alpha * (max(F_est, 0.0) - F_filt)
                F_fb = F_filt
            else:
                F_fb = F_meas
            out["q_hat"][k] = q_hat
        else:
            q_hat, F_fb = None, F_meas
        tau = ctl.update(float(F_ref[k]), F_fb, q_hat)
        d.ctrl[0] = tau
        for _ in range(sc.substeps):
            mujoco.mj_step(mj, d)
        tau_meas_prev = float(sd[s_frc]) + trq_noise[k]
        out["F_true"][k], out["F_meas"][k], out["F_hat"][k] = F_true, F_meas, F_fb
        out["tau_cmd"][k], out["tau_meas"][k] = tau, tau_meas_prev
    return out


def legacy_hand(controller: str = "sensor", **kw) -> dict[str, np.ndarray]:
    """The old run_hand_control's loop: per chain c, ``<field>_<c>``; and ``q_abduction``."""
    import mujoco

    from alpes_dyn.control.controller import ForceController, static_contact_force
    from alpes_dyn.control.finger_loop import _plant_and_params
    from alpes_dyn.control.hand_grasp import hand_gains
    from alpes_dyn.control.hand_loop import (HAND_LEVELS, HandControlScenario, chain_frame, chain_model,
                                             cylinder_normal, hand_chains)
    from alpes_dyn.model.mjcf import CYLINDER, joint_permutation, load_mujoco, mjcf_string

    sc = dataclasses.replace(HandControlScenario(), controller=controller, **kw)
    _, p, pp = _plant_and_params(sc)
    chains = hand_chains(p)
    levels = HAND_LEVELS if sc.levels is None else sc.levels
    mj = load_mujoco(mjcf_string("hand", pp, friction=True, scene="cylinder", timestep=sc.dt / sc.substeps))
    d = mujoco.MjData(mj)
    sd = d.sensordata
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    rng = np.random.default_rng(sc.seed)
    use_obs = sc.controller != "pi"
    center = np.asarray(CYLINDER["center"], dtype=float)
    C = []
    for c in chains:
        m = chain_model(p, c, sc.thumb_abduction)
        R, pos = chain_frame(p, c, sc.thumb_abduction)
        perm = joint_permutation(mj, [f"{c}_{j}" for j in m.joint_names])
        q0 = static_equilibrium(chain_model(pp, c, sc.thumb_abduction), np.zeros(m.n))
        d.qpos[perm] = q0
        a, b = (float(x) for x in levels[c])
        C.append(dict(name=c, model=m, n=m.n, perm=perm, center=R.T @ (center - pos),
                      axis=R.T @ np.array([0.0, 1.0, 0.0]), F_ref=np.where(t < sc.step_time, a, b),
                      enc=mj.sensor(f"encoder_{c}").adr[0], frc=mj.sensor(f"torque_{c}").adr[0],
                      touch=mj.sensor(f"flexiforce_{c}").adr[0], act=mj.actuator(c).id, z0=q0))
    abd_q = mj.joint("thumb_abd").qposadr[0]
    abd_act = mj.actuator("thumb_abduction").id
    abd_enc = mj.sensor("encoder_thumb_abduction").adr[0]
    d.qpos[abd_q] = 0.0
    mujoco.mj_forward(mj, d)
    step = 2 * np.pi / C[0]["model"].transmission.counts_per_rev
    groups: dict[str, list[int]] = {}
    callers = {}
    S: list[np.ndarray] = []
    if use_obs:
        est_sc = EstimationScenario(torque_noise=sc.torque_noise, encoder_noise_counts=sc.encoder_noise_counts)
        meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
        f_var = (sc.force_noise**2 + sc.force_resolution**2 / 12) if sc.controller == "sensor" else 0.05**2
        for i, ch in enumerate(C):
            n = ch["n"]
            ss = StateSpace(ch["model"], input="motor", output="encoder", force=True)
            noise = default_noise(est_sc, n, 1, 0, meas_var)
            noise["input_noise"] = [sc.torque_noise**2] + [f_var] * 3
            filt = make_observer("ekf", ss, sc.dt, **noise)
            fstep, values = filt.filter_step_p, filt.model.values  # the step of run(): the model's numbers an input
            key = fstep.serialize() + values.tobytes().hex()
            if key not in callers:
                callers[key] = batch_step_caller(fstep, f"ekf_force_hand_{ch['model'].name}", sc.compiled, values)
            groups.setdefault(key, []).append(i)
            z0 = np.concatenate([static_equilibrium(ch["model"], np.zeros(n)), np.zeros(n)])
            S.append(np.concatenate([z0, np.diag([0.05**2] * n + [0.1**2] * n).reshape(-1, order="F")]))
    ctls = [ForceController(sc.controller, ch["model"], cylinder_normal(ch["model"], ch["z0"], ch["center"], ch["axis"]),
                            sc.dt, p.tau_max, **hand_gains(sc.controller, sc.gains, ch["name"])) for ch in C]
    nc = len(C)
    out = {f"{k}_{ch['name']}": np.empty(N) for k in ("F_true", "F_meas", "F_hat", "tau_cmd", "tau_meas") for ch in C}
    for ch in C:
        out[f"q_true_{ch['name']}"] = np.empty((N, ch["n"]))
        out[f"q_hat_{ch['name']}"] = np.full((N, ch["n"]), np.nan)
    out["q_abduction"] = np.empty(N)
    enc_noise = sc.encoder_noise_counts * step * rng.standard_normal((nc + 1, N))
    trq_noise = sc.torque_noise * rng.standard_normal((nc, N))
    frc_noise = sc.force_noise * rng.standard_normal((nc, N))
    alpha = sc.dt / (sc.force_filter_s + sc.dt)
    a_v = sc.dt / (sc.abduction_filter_s + sc.dt)
    F_filt, tau_meas_prev, F_in_prev = np.zeros(nc), np.zeros(nc), np.zeros(nc)
    normals = [ctl.normal.copy() for ctl in ctls]
    y_abd_prev, v_abd = None, 0.0
    res = sc.force_resolution
    for k in range(N):
        y, F_meas = np.empty(nc), np.empty(nc)
        for i, ch in enumerate(C):
            out[f"q_true_{ch['name']}"][k] = d.qpos[ch["perm"]]
            F_true = float(sd[ch["touch"]])
            out[f"F_true_{ch['name']}"][k] = F_true
            F_meas[i] = max(0.0, round((F_true + frc_noise[i, k]) / res) * res)
            y[i] = round((float(sd[ch["enc"]]) + enc_noise[i, k]) / step) * step
        if use_obs and k > 0:
            for key, idx in groups.items():
                WY = np.stack([np.concatenate([[tau_meas_prev[i]], -F_in_prev[i] * normals[i], [y[i]]]) for i in idx])
                S_next = callers[key](np.stack([S[i] for i in idx]), WY)
                for j, i in enumerate(idx):
                    S[i] = S_next[j]
        for i, ch in enumerate(C):
            if use_obs:
                q_hat = S[i][: ch["n"]]
                out[f"q_hat_{ch['name']}"][k] = q_hat
                normals[i] = cylinder_normal(ch["model"], q_hat, ch["center"], ch["axis"])
                if sc.controller == "sensorless":
                    F_est = static_contact_force(ch["model"], q_hat, np.array([tau_meas_prev[i]]), normals[i])
                    F_filt[i] += alpha * (max(F_est, 0.0) - F_filt[i])
                    F_fb = F_filt[i]
                else:
                    F_fb = F_meas[i]
                F_in_prev[i] = F_fb
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, q_hat, normal=normals[i])
            else:
                F_fb = F_meas[i]
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, None)
            d.ctrl[ch["act"]] = tau
            out[f"F_meas_{ch['name']}"][k], out[f"F_hat_{ch['name']}"][k] = F_meas[i], F_fb
            out[f"tau_cmd_{ch['name']}"][k] = tau
        y_abd = round((float(sd[abd_enc]) + enc_noise[nc, k]) / step) * step / p.abduction_ratio
        if y_abd_prev is not None:
            v_abd += a_v * ((y_abd - y_abd_prev) / sc.dt - v_abd)
        y_abd_prev = y_abd
        out["q_abduction"][k] = d.qpos[abd_q]
        u = sc.abduction_kp * (sc.thumb_abduction - y_abd) - sc.abduction_kd * v_abd
        d.ctrl[abd_act] = min(max(u, -p.tau_max), p.tau_max)
        for _ in range(sc.substeps):
            mujoco.mj_step(mj, d)
        for i, ch in enumerate(C):
            tau_meas_prev[i] = float(sd[ch["frc"]]) + trq_noise[i, k]
            out[f"tau_meas_{ch['name']}"][k] = tau_meas_prev[i]
    return out


def legacy_mujoco_recording(model, true_params, torque, dt=1e-3, *, effects=None, seed=0, timestep=1e-4,
                            encoder_noise_counts=0.5, torque_noise=5e-4) -> dict[str, np.ndarray]:
    """The old mujoco_recording (q0 the plant's rest, RK4): encoder counts, torque, true_q."""
    import mujoco

    from alpes_dyn.bench.mujoco_plant import as_params as _params, initial_qpos as _initial_state
    from alpes_dyn.control.plants import PlantEffects, plant_mjcf, plant_model
    from alpes_dyn.model.mjcf import joint_permutation, load_mujoco

    e = (effects or PlantEffects()).check()
    p = _params(true_params)
    truth = plant_model(model, p, e, None)
    m = truth.transmission.n_motors
    u = np.asarray(torque, dtype=float)
    sub = int(round(dt / timestep))
    mj = load_mujoco(plant_mjcf(model, p, e, None, timestep))
    mj.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, truth.joint_names)
    q_init = truth.static_equilibrium(truth.transmission.joint_torque(u[0]), np.zeros(truth.n),
                                      fixed=truth.springless_joints)
    d.qpos[:] = _initial_state(mj, truth, perm, q_init, u[0], p, e)
    mujoco.mj_forward(mj, d)
    tr = truth.transmission
    enc_adr = [mj.sensor_adr[mj.sensor(f"encoder_{mn}").id] for mn in tr.motor_names]
    dofs = np.array([mj.jnt_dofadr[mj.joint(j).id] for j in truth.joint_names])
    ex = truth.extras

    def smooth_friction(_m, dd) -> None:
        v = dd.qvel[dofs]
        dd.qfrc_passive[dofs] -= ex.coulomb * np.tanh(v / ex.smooth_velocity) + ex.viscous * v

    N = u.shape[0] - 1
    qm, q = np.empty((N + 1, m)), np.empty((N + 1, truth.n))
    qm[0], q[0] = d.sensordata[enc_adr], d.qpos[perm]
    previous = mujoco.get_mjcb_passive()
    if e.stiction is None:
        mujoco.set_mjcb_passive(smooth_friction)
    try:
        for k in range(N):
            d.ctrl[:] = u[k]
            mujoco.mj_step(mj, d, nstep=sub)
            mujoco.mj_fwdPosition(mj, d)
            mujoco.mj_sensorPos(mj, d)
            qm[k + 1], q[k + 1] = d.sensordata[enc_adr], d.qpos[perm]
    finally:
        mujoco.set_mjcb_passive(previous)
    rng = np.random.default_rng(seed)
    step = 2 * np.pi / tr.counts_per_rev
    counts = np.round((qm + encoder_noise_counts * step * rng.standard_normal(qm.shape)) / step + e.encoder_offset)
    measured = (1.0 + e.torque_constant_error) * u + torque_noise * rng.standard_normal(u.shape)
    return dict(encoder=counts, torque=measured, true_q=q)


def legacy_estimate_recording(rec, model, observer="ekf", *, torque_noise=None, disturbance=False,
                              disturbance_walk=2e-4) -> dict[str, np.ndarray]:
    """The old estimate_recording (no gravity columns, no tilt, no encoder offset, no encoder noise): z, P."""
    from alpes_dyn.estimation.observers.replay import _initial_state

    dt = rec.dt
    if torque_noise is None:
        torque_noise = float(np.sqrt(np.mean(np.diff(rec.torque, n=2, axis=0) ** 2) / 6.0))  # as replay (second difference)
    substeps = stable_substeps(model, dt)
    n, m = model.n, model.transmission.n_motors
    pars = tuple(f"disturbance_{mn}" for mn in model.transmission.motor_names) if disturbance else ()
    gains = ("input_gain", "spring_gain") if observer.endswith("-params") else ()
    tr = model.transmission
    step = 2 * np.pi / tr.counts_per_rev
    y = tr.unstretched(rec.encoder * step - np.zeros(m), torque_before(rec.torque))
    meas_var = step**2 / 12 + (0.0 * step) ** 2 + (tr.tendon_compliance * torque_noise) ** 2
    Q = np.diag([1e-9**2] * n + [2e-4**2] * n + [2e-5**2] * len(gains) + [disturbance_walk**2 * dt] * len(pars))
    ss = StateSpace(model, input="motor", output="encoder")
    # (the friction's process noise, issue 50, added since: make_observer's own, with_friction_noise)
    filt = make_observer(observer, ss, dt, parameters=gains + pars,
                         substeps=substeps, process_noise=Q, measurement_noise=list(meas_var * np.ones(m)),
                         input_noise=[torque_noise**2] * m)
    z0 = np.concatenate([_initial_state(model, rec.torque[0]), np.ones(len(gains)), np.zeros(len(pars))])
    P0 = np.array([0.5**2] * n + [1.0**2] * n + [0.2**2] * len(gains) + [(10 * torque_noise + 1e-4) ** 2] * len(pars))
    est = filt.run(z0, P0, rec.torque[:-1], y)
    return dict(z=est.z, P=est.P)
