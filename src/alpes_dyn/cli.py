"""Command line ``alpes-dyn``: URDF generation, dynamics, the report reproduced, observability, estimation.

Every bad input ends with one line on stderr naming the problem and exit code 2, never a traceback.
Vectors are comma-separated numbers; negative values work as ``--q=-0.1,0.2`` and ``--q -0.1,0.2``.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .errors import AlpesDynError, InputError, ModelError

VECTOR_OPTIONS = ("--q", "--v", "--tau", "--force")
_NUMLIST = re.compile(r"^-[0-9.]")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        raise _UsageError(f"{self.prog}: {message}")


class _UsageError(Exception):
    pass


def _int_at_least(low: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {value}")
        return value

    parse.__name__ = f"integer >= {low}"
    return parse


_SEED = _int_at_least(0)
_POINTS = _int_at_least(1)


def parse_vector(text: str, name: str) -> np.ndarray:
    """``"-0.1,0.2"`` -> array([-0.1, 0.2]); a clear :class:`InputError` otherwise."""
    parts = [p.strip() for p in text.split(",")]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"--{name}: expected comma-separated numbers, got {text!r}") from None
    a = np.array(vals)
    if not np.isfinite(a).all():
        raise InputError(f"--{name}: contains NaN or inf ({text!r})")
    return a


def _join_negative_vectors(argv: Sequence[str]) -> list[str]:
    """Turn ``--q -0.1,0.2`` into ``--q=-0.1,0.2`` (argparse would read -0.1,0.2 as an option)."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in VECTOR_OPTIONS and i + 1 < len(argv) and _NUMLIST.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def _model_from_args(args: argparse.Namespace):
    from .model import Model

    spring = getattr(args, "spring", "torsional")
    if args.model.endswith(".urdf") or "/" in args.model:
        return Model.from_urdf_file(args.model)
    return Model.alpes(args.model, spring=spring, friction=getattr(args, "friction", False),
                       rotor_inertia=getattr(args, "rotor_inertia", False), params=getattr(args, "params", None))


def _emit(obj: dict[str, Any], text: str, as_json: bool) -> None:
    print(json.dumps(obj) if as_json else text)


def _fmt_matrix(M: np.ndarray) -> str:
    return "\n".join("  " + " ".join(f"{x: .6e}" for x in row) for row in np.atleast_2d(M))


# ----------------------------------------------------------------------------- urdf
def cmd_urdf(args: argparse.Namespace) -> int:
    from .description import urdf_string
    from .params import load_params

    text = urdf_string(args.model, load_params(args.params))
    if args.output:
        try:
            Path(args.output).write_text(text)
        except OSError as exc:
            raise InputError(f"-o: cannot write {args.output!r} ({exc.strerror or exc})") from None
    else:
        sys.stdout.write(text)
    return 0


# ----------------------------------------------------------------------------- mjcf (issue 9)
def cmd_mjcf(args: argparse.Namespace) -> int:
    from .mjcf import mjcf_string
    from .params import load_params

    text = mjcf_string(args.model, load_params(args.params), spring=args.spring, friction=args.friction,
                       rotor_inertia=args.rotor_inertia, limits=not args.no_limits, contact=not args.no_contact,
                       scene=args.scene, palm_down=args.palm_down)
    if args.output:
        try:
            Path(args.output).write_text(text)
        except OSError as exc:
            raise InputError(f"-o: cannot write {args.output!r} ({exc.strerror or exc})") from None
    else:
        sys.stdout.write(text)
    return 0


# ----------------------------------------------------------------------------- dynamics
def cmd_dynamics(args: argparse.Namespace) -> int:
    m = _model_from_args(args)
    n = m.n
    q = parse_vector(args.q, "q") if args.q is not None else np.zeros(n)
    v = parse_vector(args.v, "v") if args.v is not None else np.zeros(n)
    tau = parse_vector(args.tau, "tau") if args.tau is not None else np.zeros(n)
    for x, name in ((q, "q"), (v, "v"), (tau, "tau")):
        if x.shape != (n,):
            raise InputError(f"--{name}: model {m.name!r} has {n} joints, got {x.size} values")
    F = None
    if args.force is not None:
        F = parse_vector(args.force, "force")
        if F.shape != (3,):
            raise InputError(f"--force: expected 3 values Fx,Fy,Fz, got {F.size}")
    tip = args.tip if args.tip is not None else (m.tips[0] if m.tips else None)
    A = m.inertia_matrix(q)
    C = m.coriolis_matrix(q, v)
    G = m.gravity_torque(q)
    J = m.fingertip_jacobian(q, tip)
    qdd = m.forward_dynamics(q, v, tau, F, tip)
    obj = {"model": m.name, "q": q.tolist(), "v": v.tolist(), "tau": tau.tolist(), "A": A.tolist(),
           "C": C.tolist(), "G": G.tolist(), "J": J.tolist(), "qdd": qdd.tolist(), "tip": tip,
           "joints": list(m.joint_names), "spring": m.spring, "F": None if F is None else F.tolist()}
    outside = [j for j, x, lo, hi in zip(m.joint_names, q, m.lower, m.upper) if x < lo or x > hi]
    obj["outside_limits"] = outside  # joints whose q is outside the URDF limits (no stop in eq. 2.10)
    text = "\n".join([
        f"model {m.name} ({n} joints: {', '.join(m.joint_names)}), spring model {m.spring}",
        f"q   [rad]      {np.array2string(q, precision=6)}",
        f"v   [rad/s]    {np.array2string(v, precision=6)}",
        f"tau [N m]      {np.array2string(tau, precision=6)}",
        f"F   [N] at {tip}: {'none' if F is None else np.array2string(F, precision=6)}",
        "A(q) [kg m^2]:", _fmt_matrix(A),
        "C(q, v) [N m s]:", _fmt_matrix(C),
        "G(q) = gravity + springs [N m]:", _fmt_matrix(G),
        f"J(q) fingertip {tip} [m]:", _fmt_matrix(J),
        "qdd [rad/s^2]:", _fmt_matrix(qdd),
    ] + ([f"WARNING: q outside the joint limits at {', '.join(outside)} (the model has no joint stop: "
          "these terms hold as if the joints could go there)"] if outside else []))
    _emit(obj, text, args.json)
    return 0


# ----------------------------------------------------------------------------- report (main job)
def dynamics_crosscheck(seed: int = 0, points: int = 20) -> dict[str, Any]:
    """Pinocchio vs the symbolic backend (A, G, qdd) and vs the report's Jacobian formula (Section 2.2)."""
    from .model import Model
    from .reference import report_jacobian
    from .symbolic import SymbolicDynamics
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


# ---- owned by the observability work (issue 3): replace the body, keep the signature
def _observability_summary(args: argparse.Namespace) -> dict[str, Any]:
    """Observability of finger2, finger3 and the hand in the report's setting (u = joint torques,
    y = sum of joint angles), with the report's spring law (eq. 2.14) and the torsional one."""
    from .observability import observability

    lines = ["  model    spring     states outputs  rank  observable  index  min sv    condition  at rest  parts"]
    results: dict[str, Any] = {}
    for spring in ("report", "torsional"):
        for name in ("finger2", "finger3", "hand"):
            r = observability(name, input="joint", output="sum", spring=spring, points=args.points, seed=args.seed)
            d = r.to_dict()
            d.pop("rank_drops", None)
            results[f"{name}/{spring}"] = d
            cond = f"{r.condition:9.2e}" if np.isfinite(r.condition) else "      inf"
            parts = ", ".join(f"{p.model} {p.rank}/{p.n_states}" for p in r.parts)
            lines.append(f"  {name:8s} {spring:10s} {r.n_states:6d} {r.n_outputs:7d} {f'{r.rank}/{r.n_states}':>5s}  "
                         f"{'yes' if r.observable else 'NO':10s} {r.index:6d}  {r.min_singular_value:9.2e} {cond} "
                         f"{f'{r.rank_at_rest}/{r.n_states}':>7s}  {parts}")
    lines.append("  (report: finger2 rank 4 of 4, finger3 rank 6 of 6, both observable. Fingers: O up to y^(n-1) as in "
                 "the report; hand: up to y^(5), where its rank is already full. min sv = median over "
                 f"{args.points} random points of s_n/s_1 of the row-normalised O)")
    return {"lines": lines, "input": "joint", "output": "sum", "points": args.points, "seed": args.seed,
            "results": results}


# ---- owned by the observability work (issue 3)
def cmd_observability(args: argparse.Namespace) -> int:
    from .observability import observability

    order: str | int = getattr(args, "order", "auto")
    if order not in ("auto", "report"):
        try:
            order = int(order)
        except ValueError:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order!r}") from None
        if order < 0:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order}")
    model = _model_from_args(args)
    rep = observability(model, input=args.input, output=args.output, points=args.points, seed=args.seed,
                        constant_input=getattr(args, "constant_input", False), order=order)
    _emit(rep.to_dict(), rep.to_text(), args.json)
    return 0


# ---- owned by the observers work (issue 4)
def cmd_estimate(args: argparse.Namespace) -> int:
    """Simulate the default scenario (alpes_dyn.scenario) and estimate the joints from the motor encoder."""
    from .observers import OBSERVERS
    from .scenario import SCENARIO_MODELS, plot_estimation, run_estimation

    if args.model not in SCENARIO_MODELS:
        raise InputError(f"--model: the estimation scenario is defined for one finger ({', '.join(SCENARIO_MODELS)}), "
                         f"got {args.model!r}")
    if args.observer not in OBSERVERS:
        raise InputError(f"--observer: unknown observer {args.observer!r} (expected one of {', '.join(OBSERVERS)})")
    if args.plot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise InputError("--plot: matplotlib is not installed (pip install 'alpes_dyn[plot]')") from None
    t0 = time.perf_counter()
    res = run_estimation(args.observer, model=args.model, spring=args.spring, params=args.params,
                         mismatch=args.mismatch, duration=args.duration, seed=args.seed)
    if args.plot:
        plot_estimation(res, args.plot)
    obj = res.to_dict()
    obj["seconds"] = time.perf_counter() - t0
    if args.plot:
        obj["plot"] = args.plot
    deg = np.degrees
    lines = [
        f"{res.scenario.model}: joints estimated from the motor encoder by {args.observer} "
        f"(mismatch {args.mismatch:g}, {args.duration:g} s, seed {args.seed})",
        f"  encoder {res.counts_per_rev:g} counts/rev + {res.scenario.encoder_noise_counts:g} count noise; "
        f"motor torque noise {res.scenario.torque_noise:g} N m",
        f"  {f'RMSE after {res.scenario.transient_s:g} s [deg]:':30s}"
        + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.rmse)),
        f"  {'final error [deg]:':30s}"
        + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.final_error)),
    ]
    for name, p in res.parameters.items():
        lines.append(f"  {name}: estimated {p['estimate']:.4f}, true {p['true']:.4f}")
    if args.plot:
        lines.append(f"  figure: {args.plot}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0


# ----------------------------------------------------------------------------- control (issue 9)
def _positive_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


_positive_seconds.__name__ = "seconds"


def cmd_control(args: argparse.Namespace) -> int:
    """Closed loop on MuJoCo: a finger presses a block with the force asked for."""
    from .control import CONTROL_MODELS, CONTROLLERS, REFERENCES, plot_control, run_control

    if args.model not in CONTROL_MODELS:
        raise InputError(f"--model: the control scenario is defined for one finger ({', '.join(CONTROL_MODELS)}), "
                         f"got {args.model!r}")
    if args.controller not in CONTROLLERS:
        raise InputError(f"--controller: unknown controller {args.controller!r} (expected one of {', '.join(CONTROLLERS)})")
    if args.reference not in REFERENCES:
        raise InputError(f"--reference: unknown reference {args.reference!r} (expected one of {', '.join(REFERENCES)})")
    if args.plot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise InputError("--plot: matplotlib is not installed (pip install 'alpes_dyn[plot]')") from None
    for opt, path in (("--log", args.log), ("--plot", args.plot)):
        if path and not Path(path).resolve().parent.is_dir():
            raise InputError(f"{opt}: cannot write {path!r} (no such directory)")
    res = run_control(args.controller, model=args.model, reference=args.reference, duration=args.duration,
                      seed=args.seed, params=args.params, plant_params=args.plant_params)
    if args.log:
        res.to_csv(args.log)
    if args.plot:
        plot_control(res, args.plot)
    obj = res.to_dict()
    for k, v in (("log", args.log), ("plot", args.plot)):
        if v:
            obj[k] = v

    def f(x: Any, fmt: str) -> str:
        return "n/a" if x is None else format(x, fmt)

    lines = [
        f"{args.model} pressing a block, {args.controller} controller, {args.reference} reference, MuJoCo plant "
        f"({args.duration:g} s, seed {args.seed})",
        f"  force RMSE {res.force_rmse:.4f} N; steady-state error {f(res.steady_state_error, '.2%')}; "
        f"overshoot {f(res.overshoot, '.1%')}; 10-90 % rise "
        f"{'n/a' if res.rise_time_s is None else f'{res.rise_time_s:.3f} s'}",
        "  joints observed during contact, RMSE [deg]: "
        + ("n/a (no observer)" if res.q_rmse_deg is None else
           "  ".join(f"{j} {e:.2f}" for j, e in zip(res.joint_names, res.q_rmse_deg))),
        f"  motor torque limit {res.tau_max:g} N m, saturated {res.saturated:.1%} of the time; "
        f"loop {res.realtime_ratio:.1f}x faster than real time",
    ]
    if args.log:
        lines.append(f"  log: {args.log}")
    if args.plot:
        lines.append(f"  figure: {args.plot}")
    _emit(obj, "\n".join(lines), args.json)
    return 0


# ----------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="alpes-dyn", description=__doc__.splitlines()[0],
                epilog="Vectors: comma-separated numbers; negative values as --q=-0.1,0.2 (or --q -0.1,0.2).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def common(sp: argparse.ArgumentParser, model_default: str | None = "finger3") -> None:
        sp.add_argument("--model", default=model_default, required=model_default is None,
                        help="finger2, finger3, hand, or a path to a fixed-base URDF file (default %(default)s)")
        sp.add_argument("--spring", default="torsional", choices=("report", "torsional", "none"),
                        help="spring model: torsional 1/2 K q^2 (default), report (eq. 2.14 literally), none")
        sp.add_argument("--params", default=None, metavar="FILE", help="parameter file (default: the shipped one)")
        sp.add_argument("--json", action="store_true", help="print one JSON object")

    s = sub.add_parser("urdf", help="print or write the URDF of a model")
    s.add_argument("model", help="finger2, finger3 or hand")
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    s.add_argument("--params", default=None, metavar="FILE", help="parameter file (default: the shipped one)")
    s.set_defaults(func=cmd_urdf)

    s = sub.add_parser("mjcf", help="print or write the MuJoCo model (MJCF) of a model: springs, stops, tendons, "
                       "motors, sensors", epilog="Example: alpes-dyn mjcf finger3 --scene block -o finger3.xml")
    s.add_argument("model", help="finger2, finger3 or hand")
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    s.add_argument("--params", default=None, metavar="FILE", help="parameter file (default: the shipped one)")
    s.add_argument("--scene", default="none", choices=("none", "block", "cylinder"),
                   help="add a fixed block on a finger's pad (finger2, finger3) or a cylinder in the hand")
    s.add_argument("--spring", default="torsional", choices=("report", "torsional", "none"),
                   help="spring model (default %(default)s)")
    s.add_argument("--friction", action="store_true", help="joint damping F_v and frictionloss F_s (eq. 2.6)")
    s.add_argument("--rotor-inertia", action="store_true", help="joint armature N^2 J_m (eq. 2.8)")
    s.add_argument("--no-limits", action="store_true", help="no joint stops")
    s.add_argument("--no-contact", action="store_true", help="collisions disabled")
    s.add_argument("--palm-down", action="store_true", help="gravity reversed: the hand turned over (control scene)")
    s.set_defaults(func=cmd_mjcf)

    s = sub.add_parser("dynamics", help="A, C, G, J and forward dynamics at one state",
                       epilog="Example: alpes-dyn dynamics --model finger3 --q=-0.1,0.2,0.3 --v=0,0,0 --tau=0.01,0,0")
    common(s)
    s.add_argument("--q", help="joint angles, rad, e.g. --q=-0.1,0.2,0.3 (default zeros)")
    s.add_argument("--v", help="joint velocities, rad/s (default zeros)")
    s.add_argument("--tau", help="joint torques Gamma, N m (default zeros)")
    s.add_argument("--force", help="contact force Fx,Fy,Fz at the tip, N, base frame (eq. 2.9, 2.13)")
    s.add_argument("--tip", help="tip frame name (default: the first tip)")
    s.add_argument("--friction", action="store_true", help="switch on friction (eq. 2.6-2.7)")
    s.add_argument("--rotor-inertia", action="store_true", help="switch on rotor inertia N^2 J_m (eq. 2.8)")
    s.set_defaults(func=cmd_dynamics)

    s = sub.add_parser("report", help="the report reproduced: dynamics cross-check and observability")
    s.add_argument("--points", type=_POINTS, default=20, help="random states per check (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_report)

    s = sub.add_parser("observability", help="nonlinear observability rank test (eq. 3.4-3.8)")
    common(s)
    s.add_argument("--input", default="joint", choices=("joint", "motor"), help="u = joint torques or motor torques")
    s.add_argument("--output", default="sum", choices=("sum", "encoder"), help="y = sum of joint angles or encoders")
    s.add_argument("--points", type=_POINTS, default=8, help="random points for the generic rank (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--order", default="auto", help="highest derivative order: auto (until the rank stops growing, "
                   "default), report (y..y^(n-1), eq. 3.8) or an integer")
    s.add_argument("--constant-input", action="store_true", help="inputs constant (u' = u'' = ... = 0)")
    s.set_defaults(func=cmd_observability)

    s = sub.add_parser("estimate", help="simulate a finger and estimate its joints from the motor encoder",
                       epilog="Example: alpes-dyn estimate --model finger3 --observer ekf-params --mismatch 0.1 "
                              "--plot estimate.png")
    common(s)
    s.set_defaults(model="finger3")
    for a in s._actions:
        if a.dest == "model":
            a.help = "finger2 or finger3 (default %(default)s)"
    s.add_argument("--observer", default="ekf",
                   help="ekf, ukf, or ekf-params, ukf-params (which also estimate the input and spring gains: use "
                        "them with --mismatch) (default %(default)s)")
    s.add_argument("--mismatch", type=float, default=0.0,
                   help="relative error of the observer's springs and masses, e.g. 0.1 (default %(default)s)")
    s.add_argument("--duration", type=float, default=5.0, help="simulated time, s (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--plot", metavar="FILE.png", help="write a figure of true and estimated joints")
    s.set_defaults(func=cmd_estimate)

    s = sub.add_parser("control", help="closed-loop fingertip force control on a MuJoCo plant (needs mujoco)",
                       epilog="Example: alpes-dyn control --model finger3 --controller sensor --reference step "
                              "--plot control.png")
    s.add_argument("--model", default="finger3", help="finger2 or finger3 (default %(default)s)")
    s.add_argument("--controller", default="sensor",
                   help="sensor (feedforward + PI on the FlexiForce), sensorless (force estimated from the motor "
                        "torque and the observer), pi (PI on the FlexiForce alone) (default %(default)s)")
    s.add_argument("--reference", default="step",
                   help="step (0.2, 1.0, 0.5 N), ramp (0.2 to 1.0 N in 1 s), sine (0.3-0.8 N at 1 Hz) "
                        "(default %(default)s)")
    s.add_argument("--params", default=None, metavar="FILE", help="the controller's parameter file (default: shipped)")
    s.add_argument("--plant-params", default=None, metavar="FILE",
                   help="the plant's parameter file (default: the controller's)")
    s.add_argument("--duration", type=_positive_seconds, default=3.0, help="simulated time, s (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--log", metavar="FILE.csv", help="write the traces (t, F_ref, F_z, q, q_hat, tau_m) as CSV")
    s.add_argument("--plot", metavar="FILE.png", help="write a figure of force, torque and joints")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_control)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser().parse_args(_join_negative_vectors(argv))
        func: Callable[[argparse.Namespace], int] = args.func
        return func(args)
    except _UsageError as exc:
        print(str(exc), file=sys.stderr)
        return 2
    except AlpesDynError as exc:
        print(f"alpes-dyn: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("alpes-dyn: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # never a traceback for a user
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        print(f"alpes-dyn: internal error: {type(exc).__name__}: {msg}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
