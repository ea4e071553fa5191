"""The commands on one model: ``urdf`` and ``mjcf`` (its descriptions), ``import`` (an MJCF's URDF and spec),
``dynamics`` (A, C, G, J and the forward dynamics at one state), ``linearize`` (its state space at a point) and
``report`` (the report reproduced: the dynamics cross-checked, the observability of its models)."""

from __future__ import annotations

import argparse
import math
import time
import warnings
from typing import Any

import numpy as np

from ..errors import InputError
from ..fileio import atomic_write
from .analysis_cmds import _observability_summary
from .common import (_check_run_files, _emit, _fmt_table, _is_mjcf_path, _is_urdf_path, _model_from_args, _one_or_list, _write_stdout,
                     parse_vector)


def cmd_urdf(args: argparse.Namespace) -> int:
    from ..model.description import urdf_string
    from ..model.params import load_params

    if _is_mjcf_path(args.model):
        if args.params is not None:
            raise InputError("--params: applies to the Alpes models (finger2, finger3, thumb, hand); an MJCF --model's "
                             "values are its own")
        _check_run_files(args)
        text = _mjcf_urdf(args.model)
    elif _is_urdf_path(args.model):
        raise InputError(f"--model: {args.model!r} is a URDF already; this command writes the Alpes models' (finger2, "
                         "finger3, thumb, hand) or an MJCF file's; 'alpes-dyn mjcf --model FILE.urdf --spec FILE.toml' "
                         "exports a URDF with its spec")
    else:
        _check_run_files(args)
        text = urdf_string(args.model, load_params(args.params))
    _text_out(args, text, "urdf")
    return 0


def _text_out(args: argparse.Namespace, text: str, key: str) -> None:
    """A description's text to ``-o`` (atomically: never a partial file) or to stdout; with --json one object
    instead, ``{"model", "output", key: the text (null when written to -o)}``."""
    if args.output is not None:
        atomic_write(args.output, text, "-o")  # never a partial file (full disk, killed process)
    if args.json:
        _emit({"model": args.model, "output": args.output, key: None if args.output is not None else text}, "", True)
    elif args.output is None:
        _write_stdout(text)


def _mjcf_urdf(path: str) -> str:
    """The URDF of an MJCF file's tree (:func:`alpes_dyn.model.mjcf_import.mjcf_to_urdf`), checked to load as a
    Model with its spec; the importer's ``mjcf: ...`` errors named by the option, ``--model: ...``."""
    return _mjcf_import(path)[0]


def _mjcf_import(path: str, hold: tuple[str, ...] = ()):
    """(URDF text, spec, Model) of an MJCF file: what ``import`` writes and ``urdf --model FILE.xml`` prints, the
    pair loaded once as a Model (a URDF the library cannot load is refused before anything is written)."""
    from ..errors import ModelError
    from ..model.mjcf_import import mjcf_to_urdf, tree_error
    from ..model.robot import Model

    try:
        urdf, spec = mjcf_to_urdf(path, hold)
        model = Model(urdf, spec)
    except ModelError as exc:
        head, sep, tail = str(tree_error(exc)).partition(": ")
        raise InputError(f"--model: {tail}" if sep and head == "mjcf" else f"--hold: {tail}" if sep and head == "hold"
                         else str(exc)) from None
    return urdf, spec, model


def cmd_import(args: argparse.Namespace) -> int:
    """An MJCF's URDF and transmission spec written into a new (or empty) directory, whole or not at all: the pair
    ``--model DIR/<name>.urdf --spec DIR/<name>.toml`` reads (:meth:`alpes_dyn.model.robot.Model.from_mjcf`'s)."""
    from pathlib import Path

    from ..fileio import check_output_directory, write_directory
    from ..model.spec import TransmissionSpec

    if not _is_urdf_path(args.model) and not _is_mjcf_path(args.model) and not Path(args.model).suffix:
        raise InputError(f"--model: import reads an MJCF file (FILE.xml), got {args.model!r}; an Alpes model's MJCF: "
                         f"'alpes-dyn mjcf --model {args.model} -o FILE.xml'")
    if args.model.endswith(".urdf"):
        raise InputError(f"--model: {args.model!r} is a URDF already; give it with its spec: --model "
                         f"{args.model} --spec FILE.toml")
    name = Path(args.model).stem
    if not name or name.startswith("."):
        raise InputError(f"--model: the files written are named after the MJCF file; {Path(args.model).name!r} gives "
                         "no plain name (rename the file)")
    check_output_directory(args.out_dir, args.out_flag)  # before MuJoCo compiles: a new or empty directory
    hold = tuple(j.strip() for j in args.hold.split(",")) if args.hold is not None else ()
    if any(not j for j in hold):
        raise InputError(f"--hold: expected comma-separated joint names, got {args.hold!r}")
    urdf, spec, model = _mjcf_import(args.model, hold)
    from ..model.mjcf_import import _compile_held, not_imported

    lost = not_imported(_compile_held(args.model, hold))  # the JSON's and the text's "not imported" lines
    toml = (f"# the transmission spec of {Path(args.model).name} (alpes-dyn import): give it as --spec with "
            f"--model {name}.urdf\n" + spec.to_toml())
    if TransmissionSpec.from_toml(toml) != spec:  # never written as if it were the model's (to_toml's promise)
        raise RuntimeError(f"the spec of {args.model!r} does not read back equal to itself from its TOML")
    written = write_directory({f"{name}.urdf": urdf, f"{name}.toml": toml}, args.out_dir, args.out_flag)
    paths = {k: str(v) for k, v in written.items()}
    obj = {"model": args.model, "name": model.name, "directory": args.out_dir, "urdf": paths[f"{name}.urdf"],
           "spec": paths[f"{name}.toml"], "joints": list(model.joint_names), "motors": list(model.motor_names),
           "tips": list(model.tip_names), "not_imported": lost, "held": list(hold)}
    text = (f"{model.name}: {model.n} joints, {len(model.motor_names)} motor"
            f"{'s' if len(model.motor_names) != 1 else ''} ({', '.join(model.motor_names) or 'none'}), tips "
            f"{', '.join(model.tip_names) or 'none'}; written to {args.out_dir}/ ({name}.urdf, {name}.toml)\n"
            f"  use: --model {obj['urdf']} --spec {obj['spec']}" + "".join(f"\n  not imported: {x}" for x in lost))
    _emit(obj, text, args.json)
    return 0


def cmd_mjcf(args: argparse.Namespace) -> int:
    from ..model.mjcf import mjcf_string
    from ..model.params import load_params

    if not (math.isfinite(args.tilt) and abs(args.tilt) <= 180):
        raise InputError(f"--tilt: expected a finite angle in degrees within [-180, 180], got {args.tilt!r}")
    _check_run_files(args)
    if _is_urdf_path(args.model):
        text = _urdf_mjcf(args)
    else:
        if args.spec is not None:
            raise InputError(f"--spec: applies to a URDF model; the Alpes model {args.model!r} takes its transmission "
                             "from --params")
        text = _alpes_mjcf(args, mjcf_string, load_params)
    _text_out(args, text, "mjcf")
    return 0


_MJCF_ALPES_ONLY = (("params", "--params", None), ("spring", "--spring", None), ("friction", "--friction", False),
                    ("rotor_inertia", "--rotor-inertia", False), ("no_contact", "--no-contact", False),
                    ("scene", "--scene", "none"), ("palm_down", "--palm-down", False),
                    ("tendon_stiffness", "--tendon-stiffness", None), ("tendon_damping", "--tendon-damping", 0.0),
                    ("tendon_dead_band", "--tendon-dead-band", 0.0), ("tendon_rotor", "--tendon-rotor", False), ("tilt", "--tilt", 0.0))


_MJCF_URDF_WHY = {
    "scene": "a URDF model's block scene (placed from its kinematics) is alpes-dyn control's (--frame, --motor)",
    "no_contact": "a URDF model's collisions are its URDF's",
    "palm_down": "a URDF model's gravity is its spec's (gravity = [...])",
    "tilt": "a URDF model's gravity is its spec's (gravity = [...])",
}
"""Why an Alpes plant option does not apply to a URDF model, where the default reason (its spec) does not say it."""


def _urdf_mjcf(args: argparse.Namespace) -> str:
    """The MJCF of a URDF + spec model (:func:`alpes_dyn.model.mjcf_export.model_mjcf`); the Alpes plant's options
    refused by name (the spec holds springs, friction and rotor inertia)."""
    from ..model.mjcf_export import model_mjcf
    from ..model.robot import Model

    for dest, flag, default in _MJCF_ALPES_ONLY:
        if getattr(args, dest) != default:
            raise InputError(f"{flag}: applies to the Alpes models (finger2, finger3, hand, thumb); "
                             + _MJCF_URDF_WHY.get(dest, "a URDF model's springs, friction and rotor inertia come from "
                                                        "its --spec"))
    return model_mjcf(Model.from_urdf_file(args.model, args.spec), limits=not args.no_limits, stiction=args.stiction)


def _alpes_mjcf(args: argparse.Namespace, mjcf_string, load_params) -> str:
    return mjcf_string(args.model, load_params(args.params), spring=args.spring or "torsional", friction=args.friction,
                       rotor_inertia=args.rotor_inertia, limits=not args.no_limits, contact=not args.no_contact,
                       scene=args.scene, palm_down=args.palm_down, stiction=args.stiction,
                       tendon_stiffness=args.tendon_stiffness, tendon_damping=args.tendon_damping,
                       tendon_rotor=args.tendon_rotor, tilt=math.radians(args.tilt),
                       tendon_dead_band=args.tendon_dead_band)


def cmd_dynamics(args: argparse.Namespace) -> int:
    m = _model_from_args(args)
    n = m.n
    q = parse_vector(args.q, "q") if args.q is not None else np.zeros(n)
    v = parse_vector(args.v, "v") if args.v is not None else np.zeros(n)
    tau = parse_vector(args.tau, "tau") if args.tau is not None else np.zeros(n)
    for x, name in ((q, "q"), (v, "v"), (tau, "tau")):
        if x.shape != (n,):
            raise InputError(f"--{name}: model {m.name!r} has {n} joints, got {x.size} values")
    tau_m = None
    if args.tau_m is not None:
        if m.transmission is None:
            raise InputError(f"--tau-m: model {m.name!r} has no motors (give a URDF --model a --spec with [[motor]])")
        if args.tau is not None:
            raise InputError("--tau-m: give joint torques --tau or motor torques --tau-m, not both")
        tau_m = parse_vector(args.tau_m, "tau-m")
        if tau_m.shape != (m.transmission.n_motors,):
            raise InputError(f"--tau-m: model {m.name!r} has {m.transmission.n_motors} motors "
                             f"({', '.join(m.motor_names)}), got {tau_m.size} values")
        tau = m.transmission.joint_torque(tau_m, q)  # Gamma = S^T tau_m (eq. 3.13; rho(q)^T tau_m on a ratio_curve)
    F = None
    if args.force is not None:
        F = parse_vector(args.force, "force")
        if F.shape != (3,):
            raise InputError(f"--force: expected 3 values Fx,Fy,Fz, got {F.size}")
    tip = args.tip if args.tip is not None else (m.default_tip if m.tips else None)
    A = m.inertia_matrix(q)
    C = m.coriolis_matrix(q, v)
    G = m.gravity_torque(q)
    J = m.fingertip_jacobian(q, tip)
    qdd = m.forward_dynamics(q, v, tau, F, tip)
    obj = {"model": m.name, "q": q.tolist(), "v": v.tolist(), "tau": tau.tolist(), "A": A.tolist(),
           "C": C.tolist(), "G": G.tolist(), "J": J.tolist(), "qdd": qdd.tolist(), "tip": tip,
           "joints": list(m.joint_names), "spring": m.spring, "F": None if F is None else F.tolist(),
           "motors": list(m.motor_names), "tips": list(m.tip_names)}
    outside = [j for j, x, lo, hi in zip(m.joint_names, q, m.lower, m.upper) if x < lo or x > hi]
    obj["outside_limits"] = outside  # joints whose q is outside the URDF limits (no stop in eq. 2.10)
    joints = m.joint_names
    motor_lines: list[str] = []
    if m.transmission is not None:
        q_m = m.transmission.motor_positions(q)
        obj["q_m"] = q_m.tolist()
        obj["tau_m"] = None if tau_m is None else tau_m.tolist()
        cols = ("q_m", "tau_m") if tau_m is not None else ("q_m",)
        vals = np.column_stack([q_m, tau_m]) if tau_m is not None else q_m[:, None]
        S, St = ("s(q) = L(q)/r_m", "rho(q)^T") if m.transmission.curved else ("S q", "S^T")
        motor_lines = [f"per motor: encoder angle q_m = {S} [rad]" + (f", motor torque tau_m [N m] (tau = {St} tau_m)"
                                                                      if tau_m is not None else "") + ":",
                       _fmt_table(vals, m.motor_names, cols)]
    text = "\n".join([
        f"model {m.name} ({n} joints in Pinocchio's order), spring model {m.spring}" + "".join(
            f"; {mj.name} mimics {mj.primary} (q = {mj.multiplier:g} q_{mj.primary} + {mj.offset:g})"
            for mj in (m.mimic.mimics if m.mimic is not None else ())),
        f"F [N] at {tip}: {'none' if F is None else np.array2string(F, precision=6)}",
        "per joint: q [rad], v [rad/s], tau [N m], G(q) = gravity + springs [N m], qdd [rad/s^2]:",
        _fmt_table(np.column_stack([q, v, tau, G, qdd]), joints, ("q", "v", "tau", "G", "qdd")),
        "A(q) [kg m^2]:", _fmt_table(A, joints, joints),
        "C(q, v) [N m s]:", _fmt_table(C, joints, joints),
        f"J(q) fingertip {tip}, linear, base axes [m]:", _fmt_table(J, ("x", "y", "z"), joints),
        *motor_lines, *_stop_lines(m, obj),
    ] + ([f"WARNING: q outside the joint limits at {', '.join(outside)} (the model has no joint stop: "
          "these terms hold as if the joints could go there)"] if outside else []))
    _emit(obj, text, args.json)
    return 0


def _stop_lines(m: Any, obj: dict[str, Any]) -> list[str]:
    """The joint stops each joint gets in a simulation with stops (``JointStops.of(model)``, and with
    ``per_joint=True``) and where they come from (:func:`~alpes_dyn.model.stops.stop_table`): ``obj["stops"]`` and
    the text's lines."""
    from ..model.stops import stop_table

    robot, own = stop_table(m), stop_table(m, per_joint=True)
    obj["stops"] = {"robot": robot, "per_joint": own}
    lines = [f"joint stops (simulate(stops=JointStops.of(model)); per joint: JointStops.of(model, per_joint=True)), "
             f"sized to give {math.degrees(robot['penetration_rad']):g} deg under the torque into the stop tau*: "
             "k [N m/rad], d [N m s/rad], tau* [N m]:"]
    w = max(len(j) for j in m.joint_names)
    lines.append(f"  {'':{w}s} {'lower':>9s} {'upper':>9s} {'tau*':>10s} {'k':>10s} {'d':>10s}  {'source':22s}"
                 f" {'k per joint':>11s} {'d per joint':>11s}  source")

    def num(x: Any, width: int) -> str:
        return f"{'-':>{width}s}" if x is None else f"{x:>{width}.4g}"
    for i, j in enumerate(m.joint_names):
        lines.append(f"  {j:{w}s} {m.lower[i]:>9.4g} {m.upper[i]:>9.4g} {num(robot['torque_into_stop'][i], 10)} "
                     f"{num(robot['stiffness'][i], 10)} {num(robot['damping'][i], 10)}  {robot['source'][i]:22s} "
                     f"{num(own['stiffness'][i], 11)} {num(own['damping'][i], 11)}  {own['source'][i]}")
    if robot["error"] is not None:
        lines.append(f"  not sized: {robot['error']}")
    return lines


def cmd_linearize(args: argparse.Namespace) -> int:
    """(A, B, C, D) at a state and input (default: the rest state under the input), every row and column named."""
    from ..symbolic.statespace import StateSpace

    m = _model_from_args(args)
    ss = StateSpace(m, input=args.input, output=_one_or_list(args.output))
    u = parse_vector(args.u, "u") if args.u is not None else np.zeros(ss.n_inputs)
    if u.shape != (ss.n_inputs,):
        raise InputError(f"--u: input {args.input!r} of model {m.name!r} has {ss.n_inputs} entries "
                         f"({', '.join(ss.input_names)}), got {u.size} values")
    if args.q is None and args.v is not None:
        raise InputError("--v: give --q with it (without --q the point is the rest state under --u)")
    if args.q is None:
        x0 = ss.equilibrium(u)
        where = "the rest state under u (f(x0, u) = 0)"
    else:
        q = parse_vector(args.q, "q")
        v = parse_vector(args.v, "v") if args.v is not None else np.zeros(m.n)
        for x, name in ((q, "q"), (v, "v")):
            if x.shape != (m.n,):
                raise InputError(f"--{name}: model {m.name!r} has {m.n} joints, got {x.size} values")
        x0 = np.concatenate([q, v])
        where = "the given state"
    if args.dt is not None and not (np.isfinite(args.dt) and args.dt > 0):
        raise InputError(f"--dt: expected a positive number of seconds, got {args.dt!r}")
    with warnings.catch_warnings():  # an overflow is reported below as the non-finite result it gives
        warnings.simplefilter("ignore", RuntimeWarning)
        A, B, C, D = ss.linearize(x0, u, dt=args.dt)
    bad = next((k for k, M in zip("ABCD", (A, B, C, D)) if not np.isfinite(M).all()), None)
    if bad is not None:
        raise InputError(f"{'--dt' if args.dt is not None else '--q'}: the linearisation's {bad} matrix is not finite "
                         f"at {'dt = %g s' % args.dt if args.dt is not None else 'this point'} (a smaller --dt, or "
                         "another point)")
    kind = "continuous" if args.dt is None else f"discrete, zero-order hold, dt = {args.dt:g} s"
    obj = {"model": m.name, "input": args.input, "output": args.output, "dt": args.dt, "x0": x0.tolist(),
           "u0": u.tolist(), "A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "D": D.tolist(),
           "states": list(ss.state_names), "inputs": list(ss.input_names), "outputs": list(ss.output_names)}
    xs, us, ys = ss.state_names, ss.input_names, ss.output_names
    text = "\n".join([
        f"Linearisation of {m.name} ({kind}) at {where}: input {args.input} ({ss.n_inputs}), "
        f"output {'+'.join(args.output)} ({ss.n_outputs})",
        "x0:", _fmt_table(x0[None], ("x0",), xs), "A:", _fmt_table(A, xs, xs), "B:", _fmt_table(B, xs, us),
        "C:", _fmt_table(C, ys, xs), "D:", _fmt_table(D, ys, us),
    ])
    _emit(obj, text, args.json)
    return 0


def dynamics_crosscheck(seed: int = 0, points: int = 20) -> dict[str, Any]:
    """Pinocchio vs the symbolic backend (A, G, qdd) and vs the report's Jacobian formula (Section 2.2)."""
    from ..model.robot import Model
    from ..model.reference import report_jacobian
    from ..symbolic.dynamics import SymbolicDynamics
    import casadi as cs

    rng = np.random.default_rng(seed)
    out: dict[str, Any] = {}
    for name in ("finger2", "finger3", "hand"):
        m = Model.alpes(name)
        S = SymbolicDynamics(m)
        qs, vs, ts = (cs.SX.sym(s, m.n) for s in ("q", "v", "t"))
        f = cs.Function("f", [qs, vs, ts], [S.inertia_matrix(qs), S.gravity_torque(qs),
                                            S.forward_dynamics(qs, vs, ts, smooth=False)])
        errs = {"A": 0.0, "G": 0.0, "qdd": 0.0, "J_report": 0.0}
        for _ in range(points):
            q, v = m.random_state(rng)
            tau = rng.normal(scale=0.05, size=m.n)
            A, G, a = (np.array(x).reshape(-1) for x in f(q, v, tau))
            rel = lambda x, y: float(np.max(np.abs(x - y)) / max(np.max(np.abs(y)), 1e-300))  # noqa: E731
            errs["A"] = max(errs["A"], rel(A.reshape(m.n, m.n), m.inertia_matrix(q)))
            errs["G"] = max(errs["G"], rel(G, m.gravity_torque(q)))
            errs["qdd"] = max(errs["qdd"], rel(a, m.forward_dynamics(q, v, tau)))
            if name != "hand":
                L = m.params.finger.L[: m.n]
                errs["J_report"] = max(errs["J_report"], rel(m.fingertip_jacobian(q), report_jacobian(L, q)))
        if name == "hand":
            del errs["J_report"]
        out[name] = {"backend": S.backend, "points": points, "max_rel_error": errs}
    return out


def cmd_report(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    dyn = dynamics_crosscheck(args.seed, args.points)
    obs = _observability_summary(args)
    obj = {"dynamics": dyn, "observability": {k: v for k, v in obs.items() if k != "lines"},
           "seconds": time.perf_counter() - t0}
    lines = ["Alpes hand: the report reproduced", "", "Dynamics cross-check (max relative error over random states)"]
    for name, d in dyn.items():
        e = d["max_rel_error"]
        lines.append(f"  {name:8s} Pinocchio vs {d['backend']}: A {e['A']:.1e}  G {e['G']:.1e}  qdd {e['qdd']:.1e}"
                     + (f"  J vs report Sec. 2.2 {e['J_report']:.1e}" if "J_report" in e else ""))
    lines += ["", "Observability (rank of d(y, y', ..., y^(n-1))/dx, eq. 3.8)"]
    lines += obs["lines"]
    lines.append(f"\n{obj['seconds']:.2f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0
