"""Command line ``alpes-dyn``: URDF generation, dynamics, the report reproduced, observability, estimation.

Every bad input ends with one line on stderr naming the problem and exit code 2, never a traceback.
Exit code 3 (:data:`EXIT_UNTRUSTED`): ``identify`` ran, but its fit did not converge or its model is not
adequate to the recording; nothing was written (``--force`` writes the file, marked not trustworthy).
Vectors are comma-separated numbers; negative values work as ``--q=-0.1,0.2`` and ``--q -0.1,0.2``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import re
import sys
import time
import warnings
from typing import Any, Callable, Sequence

import numpy as np

from . import __version__
from .errors import AlpesDynError, InputError
from .analysis.observability import MAX_INSTRUCTIONS
from .fileio import atomic_write, check_outputs, native_stderr_to
from .limits import MAX_ARGS, MAX_ORDER, MAX_POINTS

VECTOR_OPTIONS = ("--q", "--v", "--u", "--tau", "--tau-m", "--force")
_NUMLIST = re.compile(r"^-[0-9.]")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        raise _UsageError(f"{self.prog}: {message}")


class _UsageError(Exception):
    pass


EXIT_UNTRUSTED = 3
"""Exit code of ``identify`` when the fit did not converge or the model is not adequate (and no --force)."""


class _Untrusted(Exception):
    """The fit ran but is not to be trusted: exit :data:`EXIT_UNTRUSTED` with one line."""


class UntrustedFitWarning(UserWarning):
    """``identify --force`` wrote a file from a fit that did not converge or whose model is not adequate."""


def _int_at_least(low: int, high: int | None = None) -> Callable[[str], int]:
    want = f"an integer >= {low}" if high is None else f"an integer from {low} to {high}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {want}, got {text!r}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {want}, got {value}")
        return value

    parse.__name__ = want
    return parse


_SEED = _int_at_least(0)
_POINTS = _int_at_least(1, MAX_POINTS)


def _one_of(value: str, choices: Sequence[str], option: str, kind: str) -> None:
    """InputError ``<option>: unknown <kind> 'x' (expected one of ...)`` unless ``value`` is a choice."""
    if value not in choices:
        raise InputError(f"{option}: unknown {kind} {value!r} (expected one of {', '.join(choices)})")


THUMB_PARAMETERS = "K,m_thumb_j1,m_thumb_j2,F_s_thumb_j1,F_s_thumb_j2,F_v_thumb_j1,F_v_thumb_j2"
"""What ``alpes-dyn identify --model thumb`` fits by default: the flexion joints' springs, masses and friction.
Not the ab/adduction joint's own parameters: its base's mass sits on the axis (nothing the encoders see depends on
it: standard error 100 %), and its friction is weak (F_v 21 % standard error: the joint only creeps) and, fitted
from 20 % off, spoils the rest on some thumbs (seed 2: 0.66 counts after 50 iterations, a mass 2.8 % off; without
it 0.58 counts, 0.32 %). Ask for them by name (``F_s_thumb_abd``...)."""


def _one_chain(model: str, models: Sequence[str], what: str) -> None:
    """InputError unless ``model`` is one of the one-chain ``models`` ``what`` is defined for."""
    if model not in models:
        raise InputError(f"--model: {what} is defined for one chain ({', '.join(models)}; a finger of the hand "
                         f"with --chain), got {model!r}")


def _one_finger(model: str, models: Sequence[str], what: str) -> None:
    """InputError unless ``model`` is one of the one-finger ``models`` ``what`` is defined for."""
    if model not in models:
        raise InputError(f"--model: {what} is defined for one finger ({', '.join(models)}), got {model!r}")


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


_INPUT_OPTIONS = (("params", "--params"), ("spec", "--spec"), ("data", "--data"), ("validate", "--validate"),
                  ("true_params", "--true-params"), ("observer_params", "--observer-params"),
                  ("plant_params", "--plant-params"))
_OUTPUT_OPTIONS = (("output", "-o"), ("true_params_out", "--true-params-out"), ("log", "--log"), ("plot", "--plot"))


def _check_run_files(args: argparse.Namespace, extensions: dict[str, Sequence[str]] | None = None) -> None:
    """The output policy (:func:`alpes_dyn.fileio.check_outputs`) of the command in ``args``, before any work:
    every output it writes (-o, --true-params-out, --log, --plot) checked against every file it reads
    (--params, --spec, --data, --true-params, --observer-params, --plant-params, a URDF --model) and the others."""
    inputs = [(flag, getattr(args, dest)) for dest, flag in _INPUT_OPTIONS if isinstance(getattr(args, dest, None), str)]
    model = getattr(args, "model", None)
    if isinstance(model, str) and _is_urdf_path(model):
        inputs.append(("--model", model))
    outputs = [(flag, getattr(args, dest, None)) for dest, flag in _OUTPUT_OPTIONS]
    outputs = [(f, v) for f, v in outputs if isinstance(v, str)]  # (--output of linearize is a list of names)
    check_outputs(outputs, inputs, extensions)


def _is_urdf_path(model: str) -> bool:
    return model.endswith(".urdf") or "/" in model


_ALPES_ONLY = (("spring", "--spring"), ("params", "--params"), ("friction", "--friction"),
               ("rotor_inertia", "--rotor-inertia"))


def _check_model_options(args: argparse.Namespace) -> None:
    """Refuse, with one line, the options that do not apply to the kind of --model given (never ignore them)."""
    if _is_urdf_path(args.model):
        for dest, flag in _ALPES_ONLY:
            if getattr(args, dest, None) not in (None, False):
                raise InputError(f"{flag}: applies to the Alpes models (finger2, finger3, hand); for a URDF --model "
                                 "put springs, friction and rotor inertia in a --spec file")
    elif getattr(args, "spec", None) is not None:
        raise InputError(f"--spec: applies to a URDF --model; the Alpes model {args.model!r} takes its transmission "
                         "from --params")


def _model_from_args(args: argparse.Namespace):
    from .model.robot import Model

    _check_model_options(args)
    if _is_urdf_path(args.model):
        return Model.from_urdf_file(args.model, getattr(args, "spec", None))
    return Model.alpes(args.model, spring=getattr(args, "spring", None) or "torsional",
                       friction=getattr(args, "friction", False), rotor_inertia=getattr(args, "rotor_inertia", False),
                       params=getattr(args, "params", None))


OUTPUT_HELP = ("y: sum (of each motor's joint angles, default), encoder (q_m = S q), joints, joints:<a>,<b>, "
               "tip_position:<frame>; several joined by '+', e.g. encoder+tip_position:tip")


def _outputs(text: str) -> list[str]:
    parts = [p.strip() for p in text.split("+")]
    if not all(parts):
        raise argparse.ArgumentTypeError(f"expected output names joined by '+', got {text!r}")
    return parts


def _one_or_list(outputs: list[str]) -> str | list[str]:
    return outputs[0] if len(outputs) == 1 else outputs


def cmd_linearize(args: argparse.Namespace) -> int:
    """(A, B, C, D) at a state and input (default: the rest state under the input), every row and column named."""
    from .symbolic.statespace import StateSpace

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


def _json_safe(x: Any) -> Any:
    """``x`` with every non-finite float (NaN, inf: not JSON) written as null."""
    if isinstance(x, float):
        return x if np.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def _emit(obj: dict[str, Any], text: str, as_json: bool) -> None:
    """Print the result: one JSON object (strict JSON: a non-finite number is null) or the text."""
    _write_stdout((json.dumps(_json_safe(obj), allow_nan=False) if as_json else text) + "\n")


class _StdoutError(AlpesDynError):
    """Standard output cannot take the result (a closed pipe, a full device)."""


def _write_stdout(text: str) -> None:
    """Write ``text`` to stdout and flush it; a closed pipe or a full device is :class:`_StdoutError` (one line,
    exit 2), and stdout is then pointed at /dev/null so that the interpreter's last flush cannot fail again."""
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:
        _drop_stdout()
        raise _StdoutError("stdout: broken pipe (the reader closed it before the end of the output)") from None
    except OSError as exc:
        _drop_stdout()
        raise _StdoutError(f"stdout: cannot write the output ({exc.strerror or exc})") from None


def _drop_stdout() -> None:
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError, AttributeError):
        pass


def _fmt_matrix(M: np.ndarray) -> str:
    return "\n".join("  " + " ".join(f"{x: .6e}" for x in row) for row in np.atleast_2d(M))


def _fmt_table(M: np.ndarray, rows: Sequence[str], cols: Sequence[str]) -> str:
    """A matrix with a header of column names and each row led by its name."""
    M = np.atleast_2d(M)
    w = max([len(r) for r in rows] + [1])
    cw = max([len(c) for c in cols] + [13])
    head = "  " + " " * w + " " + " ".join(f"{c:>{cw}s}" for c in cols)
    return "\n".join([head] + ["  " + f"{r:<{w}s} " + " ".join(f"{x:>{cw}.6e}" for x in row)
                               for r, row in zip(rows, M)])


# ----------------------------------------------------------------------------- urdf
def cmd_urdf(args: argparse.Namespace) -> int:
    from .model.description import urdf_string
    from .model.params import load_params

    _check_run_files(args)
    text = urdf_string(args.model, load_params(args.params))
    if args.output is not None:
        atomic_write(args.output, text, "-o")  # never a partial file (full disk, killed process)
    else:
        _write_stdout(text)
    return 0


# ----------------------------------------------------------------------------- mjcf (issue 9)
def cmd_mjcf(args: argparse.Namespace) -> int:
    from .model.mjcf import mjcf_string
    from .model.params import load_params

    if not math.isfinite(args.tilt):
        raise InputError(f"--tilt: expected a finite angle in degrees, got {args.tilt!r}")
    _check_run_files(args)
    text = mjcf_string(args.model, load_params(args.params), spring=args.spring, friction=args.friction,
                       rotor_inertia=args.rotor_inertia, limits=not args.no_limits, contact=not args.no_contact,
                       scene=args.scene, palm_down=args.palm_down, stiction=args.stiction,
                       tendon_stiffness=args.tendon_stiffness, tendon_damping=args.tendon_damping,
                       tendon_rotor=args.tendon_rotor, tilt=math.radians(args.tilt))
    if args.output is not None:
        atomic_write(args.output, text, "-o")
    else:
        _write_stdout(text)
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
        tau = m.transmission.joint_torque(tau_m)  # Gamma = S^T tau_m (eq. 3.13)
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
        motor_lines = ["per motor: encoder angle q_m = S q [rad]" + (", motor torque tau_m [N m] (tau = S^T tau_m)"
                                                                     if tau_m is not None else "") + ":",
                       _fmt_table(vals, m.motor_names, cols)]
    text = "\n".join([
        f"model {m.name} ({n} joints in Pinocchio's order), spring model {m.spring}",
        f"F [N] at {tip}: {'none' if F is None else np.array2string(F, precision=6)}",
        "per joint: q [rad], v [rad/s], tau [N m], G(q) = gravity + springs [N m], qdd [rad/s^2]:",
        _fmt_table(np.column_stack([q, v, tau, G, qdd]), joints, ("q", "v", "tau", "G", "qdd")),
        "A(q) [kg m^2]:", _fmt_table(A, joints, joints),
        "C(q, v) [N m s]:", _fmt_table(C, joints, joints),
        f"J(q) fingertip {tip}, linear, base axes [m]:", _fmt_table(J, ("x", "y", "z"), joints),
        *motor_lines,
    ] + ([f"WARNING: q outside the joint limits at {', '.join(outside)} (the model has no joint stop: "
          "these terms hold as if the joints could go there)"] if outside else []))
    _emit(obj, text, args.json)
    return 0


# ----------------------------------------------------------------------------- report (main job)
def dynamics_crosscheck(seed: int = 0, points: int = 20) -> dict[str, Any]:
    """Pinocchio vs the symbolic backend (A, G, qdd) and vs the report's Jacobian formula (Section 2.2)."""
    from .model.robot import Model
    from .model.reference import report_jacobian
    from .symbolic.dynamics import SymbolicDynamics
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
    from .analysis.observability import observability

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
    from .analysis.observability import observability

    order: str | int = getattr(args, "order", "auto")
    if order not in ("auto", "report"):
        try:
            order = int(order)
        except ValueError:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order!r}") from None
        if order < 0:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order}")
        if order > MAX_ORDER:
            raise InputError(f"--order: {order if order < 10**30 else 'an integer of %d digits' % len(str(order))} "
                             f"is over the limit of {MAX_ORDER}")
    model = _model_from_args(args)
    rep = observability(model, input=args.input, output=_one_or_list(args.output), points=args.points, seed=args.seed,
                        constant_input=getattr(args, "constant_input", False), order=order,
                        max_operations=args.max_operations)
    _emit(rep.to_dict(), rep.to_text(), args.json)
    return 0


# ---- owned by the observers work (issue 4)
def cmd_estimate(args: argparse.Namespace) -> int:
    """Simulate the default scenario (alpes_dyn.estimation.scenario) and estimate the joints from the motor encoder."""
    from .estimation.observers import OBSERVERS
    from .estimation.scenario import ESTIMATION_MODELS, check_plot_path, plot_estimation, run_estimation

    if args.data is not None:
        return _estimate_data(args)
    for flag, dest in (("--disturbance", "disturbance"), ("--torque-noise", "torque_noise"), ("--log", "log")):
        if getattr(args, dest) not in (None, False):
            raise InputError(f"{flag}: applies to an observer on a recording (--data REC.csv)")
    _check_model_options(args)
    _one_chain(args.model, ESTIMATION_MODELS, "the estimation scenario")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    if args.plot is not None:
        check_plot_path(args.plot)  # before the run: matplotlib, a writable file name, a known format
    _check_run_files(args)
    t0 = time.perf_counter()
    if args.true_params is not None and args.params is not None:
        raise InputError("--true-params: give either --params or --true-params (the simulated finger's file)")
    if args.observer_params is not None and args.mismatch != 0:
        raise InputError("--observer-params: give either --mismatch or --observer-params, not both")
    res = run_estimation(args.observer, model=args.model, spring=args.spring or "torsional",
                         params=args.true_params if args.true_params is not None else args.params,
                         observer_params=args.observer_params, friction=args.friction,
                         mismatch=args.mismatch, duration=args.duration, seed=args.seed, chain=args.chain)
    if args.plot is not None:
        plot_estimation(res, args.plot)
    obj = res.to_dict()
    obj["seconds"] = time.perf_counter() - t0
    if args.plot is not None:
        obj["plot"] = args.plot
    deg = np.degrees
    lines = [
        f"{res.scenario.model}{f' ({args.chain})' if args.chain else ''}: joints estimated from the motor encoder "
        f"by {args.observer} "
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
    if args.plot is not None:
        lines.append(f"  figure: {args.plot}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0


_SCENARIO_ONLY = (("--mismatch", "mismatch", 0.0), ("--duration", "duration", 5.0), ("--seed", "seed", 0),
                  ("--true-params", "true_params", None), ("--observer-params", "observer_params", None),
                  ("--plot", "plot", None))


def _estimate_data(args: argparse.Namespace) -> int:
    """``estimate --data REC.csv``: the observer on a recorded encoder and torque (estimation.replay)."""
    from .estimation.observers import OBSERVERS
    from .estimation.recording import read_recording
    from .estimation.replay import estimate_recording
    from .model.robot import Model

    for flag, dest, default in _SCENARIO_ONLY:
        if getattr(args, dest) != default:
            hint = "; the observer's model is --params" if dest in ("true_params", "observer_params") else ""
            raise InputError(f"{flag}: applies to the simulated scenario, not to a recording (--data){hint}")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    _check_run_files(args)  # the output policy: --log is not --data (nor --params...), not a link, a device...
    t0 = time.perf_counter()
    if _is_urdf_path(args.model):
        model = _model_from_args(args)
    else:
        _check_model_options(args)
        model = Model.alpes(args.model, spring=args.spring or "torsional", friction=args.friction,
                            params=args.params, chain=args.chain)
    rec = read_recording(args.data, model)
    res = estimate_recording(rec, model, args.observer, torque_noise=args.torque_noise,
                             disturbance=args.disturbance)
    if args.log is not None:
        res.to_csv(args.log)
    obj = res.to_dict()
    obj.update({"data": args.data, "model": args.model, "chain": args.chain, "params": args.params,
                "seconds": time.perf_counter() - t0})
    if args.log is not None:
        obj["log"] = args.log
    deg = np.degrees
    lines = [f"{args.model}{f' ({args.chain})' if args.chain else ''}: joints estimated by {args.observer} from "
             f"{args.data} ({rec.n_samples} samples, {rec.duration:g} s)",
             f"  torque noise {res.settings['torque_noise_Nm']:.3g} N m"
             + (" (estimated from the recording)" if args.torque_noise is None else "")
             + ("; a disturbance torque per motor" if args.disturbance else "")]
    if res.rmse is not None:
        head = f"RMSE after {res.settings['transient_s']:g} s [deg]:"
        lines.append(f"  {head:30s}"
                     + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.rmse)))
    else:
        lines.append("  no true_q_* columns: no error to report")
    lines.append(f"  {'final estimate [deg]:':30s}"
                 + "  ".join(f"{j} {deg(q):.2f}" for j, q in zip(res.joint_names, res.q_hat[-1])))
    if res.disturbance is not None:
        lines.append(f"  {'final disturbance [N m]:':30s}"
                     + "  ".join(f"{mn} {d:.3g}" for mn, d in zip(res.motor_names, res.disturbance[-1])))
    if args.log is not None:
        lines.append(f"  log: {args.log}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0


def cmd_sweep(args: argparse.Namespace) -> int:
    """A study over seeded draws, on Dask workers or serially (studies.sweep)."""
    from .estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign
    from .studies.sweep import STUDIES, sweep

    _one_of(args.study, tuple(STUDIES), "--study", "study")
    if args.model not in EXPERIMENT_MODELS or args.model == "thumb":
        raise InputError(f"--model: the robustness study is defined for one finger (finger2, finger3), got "
                         f"{args.model!r}")
    if not (np.isfinite(args.spread) and 0 <= args.spread < 1):
        raise InputError(f"--spread: expected a fraction in [0, 1), got {args.spread!r}")
    if args.serial and (args.scheduler is not None or args.workers != 2):
        raise InputError("--serial: runs in this process; give no --workers or --scheduler with it")
    if args.scheduler is not None and args.workers != 2:
        raise InputError("--workers: sizes a local cluster; a --scheduler has its own workers")
    _check_run_files(args)
    opts = {"model": args.model, "spread": args.spread, "duration": args.duration, "fit": not args.no_fit}
    ExperimentDesign(duration=args.duration).check()  # before any worker starts
    res = sweep(STUDIES[args.study], args.draws, seed=args.seed, options=opts, workers=args.workers,
                scheduler=args.scheduler, serial=args.serial)
    res.meta.update({"study": args.study, **opts})
    if args.output is not None:
        res.to_csv(args.output)
    obj = res.to_dict()
    if args.output is not None:
        obj["output"] = args.output
    head = (f"{args.study} study on {args.model}: {args.draws} draws (seeds {args.seed}..{args.seed + args.draws - 1}), "
            f"+-{100 * args.spread:g} % per link, {args.duration:g} s experiments; {res.backend} on {res.workers} "
            f"worker{'s' if res.workers != 1 else ''}, {res.seconds:.1f} s")
    lines = [head, res.table()] + ([f"  table: {args.output}"] if args.output else [])
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


def _check_control_outputs(args: argparse.Namespace) -> None:
    """Before a closed-loop run: matplotlib for ``--plot`` and writable ``--log``/``--plot`` paths."""
    if args.plot:
        try:
            importlib.import_module("matplotlib")
        except ImportError:
            raise InputError("--plot: matplotlib is not installed (pip install 'alpes_dyn[plot]')") from None
    _check_run_files(args, {"--plot": ("png",)})


def _write_control_outputs(res: Any, args: argparse.Namespace, plot: Any) -> dict[str, Any]:
    """The run's ``--log`` CSV and ``--plot`` figure; its JSON object with their paths."""
    if args.log:
        res.to_csv(args.log)
    if args.plot:
        plot(res, args.plot)
    obj = res.to_dict()
    for k, v in (("log", args.log), ("plot", args.plot)):
        if v:
            obj[k] = v
    return obj


def _output_lines(args: argparse.Namespace) -> list[str]:
    return ([f"  log: {args.log}"] if args.log else []) + ([f"  figure: {args.plot}"] if args.plot else [])


def _na(x: Any, fmt: str) -> str:
    return "n/a" if x is None else format(x, fmt)


def cmd_control(args: argparse.Namespace) -> int:
    """Closed loop on MuJoCo: a finger presses a block with the force asked for, or the hand grasps a cylinder."""
    from .control.force import CONTROL_MODELS, CONTROLLERS, REFERENCES, plot_control, run_control

    if args.model != "hand" and args.model not in CONTROL_MODELS:
        raise InputError(f"--model: the control scenario is defined for one finger ({', '.join(CONTROL_MODELS)}) "
                         f"or the hand on the cylinder (hand), got {args.model!r}")
    _one_of(args.controller, CONTROLLERS, "--controller", "controller")
    _one_of(args.reference, REFERENCES, "--reference", "reference")
    if args.model == "hand":
        return _control_hand(args)
    if args.duration is None:
        args.duration = 3.0
    _check_control_outputs(args)
    res = run_control(args.controller, model=args.model, reference=args.reference, duration=args.duration,
                      seed=args.seed, params=args.params, plant_params=args.plant_params)
    obj = _write_control_outputs(res, args, plot_control)
    f = _na

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
    _emit(obj, "\n".join(lines + _output_lines(args)), args.json)
    return 0


def _control_hand(args: argparse.Namespace) -> int:
    """``alpes-dyn control --model hand``: run_hand_control, one loop per motor, per-chain metrics."""
    from .control.force import HandControlScenario, plot_hand_control, run_hand_control

    if args.reference != "step":
        raise InputError(f"--reference: the hand's loops follow step references (control.HAND_LEVELS), "
                         f"got {args.reference!r}")
    sc = HandControlScenario()
    duration = sc.duration if args.duration is None else args.duration
    if duration < sc.step_time + 0.25:
        raise InputError(f"--duration: the hand's run needs at least {sc.step_time + 0.25:g} s (its references "
                         f"step up at {sc.step_time:g} s), got {duration:g}")
    _check_control_outputs(args)
    res = run_hand_control(args.controller, duration=duration, seed=args.seed, params=args.params,
                           plant_params=args.plant_params)
    obj = _write_control_outputs(res, args, plot_hand_control)
    f = _na

    lines = [f"the hand grasping the cylinder, {args.controller} loops, MuJoCo plant ({duration:g} s, seed {args.seed}, "
             f"references step up at {sc.step_time:g} s)",
             f"  {'chain':7s} {'asked':>6s} {'held':>7s} {'SSE':>7s} {'overshoot':>9s} {'rise':>7s} {'RMSE':>8s} "
             f"{'q RMSE':>7s}"]
    for row in res.table():
        rise = "n/a" if row["rise_time_s"] is None else f"{1e3 * row['rise_time_s']:.0f} ms"
        lines.append(f"  {row['chain']:7s} {row['F_ref']:4.2f} N {row['F_held']:5.3f} N "
                     f"{f(row['steady_state_error'], '7.2%')} {f(row['overshoot'], '9.1%')} {rise:>7s} "
                     f"{row['force_rmse']:6.4f} N {f(row['q_rmse_deg'], '5.2f')}{'' if row['q_rmse_deg'] is None else ' deg'}")
    lines.append(f"  thumb ab/adduction held at {np.degrees(res.q_abduction[-1]):.1f} deg; "
                 f"loop {res.realtime_ratio:.1f}x faster than real time")
    _emit(obj, "\n".join(lines + _output_lines(args)), args.json)
    return 0


# ----------------------------------------------------------------------------- identification (issue 8)
def cmd_experiment(args: argparse.Namespace) -> int:
    """Simulate the documented identification experiment and write its recording."""
    from .model.description import model_params
    from .estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign, experiment, perturbed_params
    from .model.params import load_params, write_params

    _one_chain(args.model, EXPERIMENT_MODELS, "the identification experiment")
    _check_run_files(args)
    if args.perturb is None and args.true_params_out is not None:
        raise InputError("--true-params-out: goes with --perturb (otherwise the true file is --params)")
    truth = load_params(args.params)
    model_params(args.model, truth, args.chain)  # a bad --chain: one line, before any work
    if args.perturb is not None:  # the chain's own values drawn (the thumb's, a finger's, or the shared finger's)
        chains = ("thumb",) if args.model == "thumb" else ((args.chain,) if args.chain else None)
        truth = perturbed_params(truth, args.perturb, args.seed, chains=chains)
    rec = experiment(args.model, truth, ExperimentDesign(duration=args.duration), seed=args.seed,
                     nominal_params=args.params, path=args.output, chain=args.chain)
    if args.true_params_out is not None:
        write_params(truth, args.true_params_out, header=f"true parameters drawn by alpes-dyn experiment "
                                                        f"(spread {args.perturb:g}, seed {args.seed})")
    obj = {"model": args.model, "output": args.output, "samples": rec.n_samples, "duration_s": rec.duration,
           "dt_s": rec.dt, "columns": list(rec.columns()), "true_params": args.true_params_out}
    text = (f"{args.model}: identification experiment, {rec.n_samples} samples over {rec.duration:g} s "
            f"written to {args.output}" + (f"; true parameters in {args.true_params_out}"
                                            if args.true_params_out else ""))
    _emit(obj, text, args.json)
    return 0


def cmd_identify(args: argparse.Namespace) -> int:
    """Fit the parameters of a finger to a recording; write the identified parameter file."""
    from .estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign
    from .estimation.adequacy import AdequacyWarning
    from .estimation.identification import check_selection, identify
    from .model.robot import Model

    _one_chain(args.model, EXPERIMENT_MODELS, "identification")
    _check_run_files(args)  # the output policy: -o is none of --data, --validate, --params, nor a link...
    exc = args.excitation
    if exc == "documented":
        freqs = ExperimentDesign().frequencies
    elif exc == "none":
        freqs = None
    else:
        freqs = tuple(parse_vector(exc, "excitation"))
    model = Model.alpes(args.model, friction=True, rotor_inertia=args.rotor_inertia, params=args.params,
                        chain=args.chain)
    parameters = args.parameters
    if parameters is None and args.model == "thumb":
        parameters = THUMB_PARAMETERS
    check_selection(model, parameters)  # a bad selection named before the recording is read
    with warnings.catch_warnings():  # the command reports the verdict itself, in its one line
        warnings.simplefilter("ignore", AdequacyWarning)
        res = identify(model, args.data, parameters, excitation=freqs, torque_noise=args.torque_noise,
                       validation=args.validate, encoder_noise=args.encoder_noise)
    written = args.output is not None and (res.trustworthy or args.force)
    if written:
        res.write(args.output)
    obj = res.to_dict()
    obj["output"] = args.output if written else None
    obj["chain"] = model.chain
    lines = [f"{args.model}{f' ({args.chain})' if args.chain else ''}: parameters identified from {args.data} "
             f"({res.iterations} Gauss-Newton iterations, "
             f"{'converged' if res.converged else 'NOT converged'}, {res.seconds:.1f} s)",
             f"  {'parameter':{max(10, *(len(n) for n in res.names))}s} {'value':>12s} {'std':>10s} {'start':>12s}  unit"]
    w = max(10, *(len(n) for n in res.names))
    for n, v, sd, i, u in zip(res.names, res.values, res.std, res.initial, res.units):
        lines.append(f"  {n:{w}s} {v:12.6g} {sd:10.3g} {i:12.6g}  {u}")
    lines.append(f"  encoder residual {res.residual_rms:.3g} counts RMS")
    a = res.adequacy
    if a is not None:
        lines.append(f"  sensor floor {a.floor.total:.3g} counts (quantisation {a.floor.quantisation:.3g}, noise "
                     f"{a.floor.noise:.3g}, torque {a.floor.torque:.3g}); {a.summary()}")
        if a.validation is not None:
            v = a.validation
            lines.append(f"  validation on {args.validate}: fit {', '.join(f'{x:.1f}' for x in v.fit_percent)} %, "
                         f"NRMSE {', '.join(f'{x:.3g}' for x in v.nrmse)}")
    if written:
        lines.append(f"  written to {args.output}" + ("" if res.trustworthy else " (marked NOT trustworthy)"))
    _emit(obj, "\n".join(lines), args.json)
    if not res.trustworthy:
        why = res.status()
        if not args.force:
            raise _Untrusted(f"alpes-dyn: identify: not trustworthy, {'nothing written' if args.output else 'no file'}"
                             f" (--force writes it anyway): {why}")
        warnings.warn(UntrustedFitWarning(f"identify --force: {args.output or 'the fit'} is NOT trustworthy: {why}"))
    return 0


DESIGNS = ("documented", "scenario", "none")


def cmd_identifiability(args: argparse.Namespace) -> int:
    """Structural identifiability of physical parameters, and the Cramér-Rao bounds of an experiment."""
    from .estimation.experiment import ExperimentDesign, _profile, _schedule, excitation
    from .analysis.identifiability import fisher_information, identifiability
    from .model.robot import Model
    from .estimation.scenario import SCENARIO_MODELS, EstimationScenario, _torque
    from .model.stops import JointRangeWarning

    _one_finger(args.model, SCENARIO_MODELS, "identifiability")
    _one_of(args.design, DESIGNS, "--design", "design")
    spec = args.parameters if args.parameters is not None else "K,m,friction"
    cams = tuple(float(c) for c in parse_vector(args.camera_times, "camera-times")) if args.camera_times else ()
    design = ExperimentDesign(duration=args.duration, camera_times=cams).check() if args.design != "none" else None
    friction = any(k in spec for k in ("F_s", "F_v", "friction"))
    model = Model.alpes(args.model, friction=friction, params=args.params)
    rep = identifiability(model, spec, output=args.output, points=args.points, seed=args.seed,
                          max_operations=args.max_operations)
    obj: dict[str, Any] = {"structural": rep.to_dict(), "design": args.design, "practical": None}
    lines = [rep.to_text()]
    if design is not None:
        t, _, G = _schedule(design)
        if args.design == "documented":
            nominal = model if friction else Model.alpes(args.model, friction=True, params=args.params)
            with warnings.catch_warnings():  # the amplitude search tries runs that leave the joint range
                warnings.simplefilter("ignore", JointRangeWarning)
                bias, amp = excitation(nominal, design)
            U = _profile(design, t, bias, amp)[:-1, None]
        else:
            U = _torque(EstimationScenario(model=args.model), t[:-1], model.transmission.n_motors)
        fim = fisher_information(model, spec, U=U, G=G[:-1], design=design)
        obj["practical"] = fim.to_dict()
        lines += [f"Practical identifiability, design {args.design!r} ({args.duration:g} s)"
                  + (" with the camera" if cams else "") + ":", fim.to_text()]
    _emit(obj, "\n".join(lines), args.json)
    return 0


# ----------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="alpes-dyn", description=__doc__.splitlines()[0],
                epilog="Vectors: comma-separated numbers; negative values as --q=-0.1,0.2 (or --q -0.1,0.2).")
    p.add_argument("--version", action="version", version=f"alpes-dyn {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def common(sp: argparse.ArgumentParser, model_default: str | None = "finger3") -> None:
        sp.add_argument("--model", default=model_default, required=model_default is None,
                        help="finger2, finger3, hand, or a path to a fixed-base URDF file (default %(default)s)")
        sp.add_argument("--spec", default=None, metavar="FILE.toml",
                        help="transmission spec of a URDF --model: motors, ratios, encoder, springs, friction, "
                             "rotor inertia (see the user guide, 'Your own robot')")
        sp.add_argument("--spring", default=None, choices=("report", "torsional", "none"),
                        help="Alpes models: spring model torsional 1/2 K q^2 (default), report (eq. 2.14 literally), "
                             "none")
        sp.add_argument("--params", default=None, metavar="FILE",
                        help="Alpes models: parameter file (default: the shipped one)")
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
    s.add_argument("--rotor-inertia", action="store_true", help="the rotor J_m on each tendon: tendon armature J_m/r_m^2 "
                   "(eq. 2.8)")
    s.add_argument("--no-limits", action="store_true", help="no joint stops")
    s.add_argument("--no-contact", action="store_true", help="collisions disabled")
    s.add_argument("--palm-down", action="store_true", help="gravity reversed: the hand turned over (control scene)")
    s.add_argument("--stiction", type=float, nargs="?", const=5e-4, default=None, metavar="SECONDS",
                   help="stick-slip dry friction: frictionloss F_s with solreffriction of this time constant "
                        "(default %(const)g s when given without a value)")
    s.add_argument("--tendon-stiffness", type=float, default=None, metavar="N_PER_M",
                   help="series-elastic, pull-only tendon of stiffness k_t with a rotor joint per motor")
    s.add_argument("--tendon-damping", type=float, default=0.0, metavar="N_S_PER_M",
                   help="damping c_t of the series-elastic tendon (default 0)")
    s.add_argument("--tendon-rotor", action="store_true", help="rotor inertia J_m / r_m^2 on each rigid tendon")
    s.add_argument("--tilt", type=float, default=0.0, metavar="DEG",
                   help="palm tilted in the finger's plane by DEG degrees (gravity rotated about y)")
    s.set_defaults(func=cmd_mjcf)

    s = sub.add_parser("dynamics", help="A, C, G, J and forward dynamics at one state",
                       epilog="Example: alpes-dyn dynamics --model finger3 --q=-0.1,0.2,0.3 --v=0,0,0 --tau=0.01,0,0")
    common(s)
    s.add_argument("--q", help="joint angles, rad, e.g. --q=-0.1,0.2,0.3 (default zeros)")
    s.add_argument("--v", help="joint velocities, rad/s (default zeros)")
    s.add_argument("--tau", help="joint torques Gamma, N m (default zeros)")
    s.add_argument("--tau-m", help="motor torques tau_m, N m, in motor order: Gamma = S^T tau_m (instead of --tau)")
    s.add_argument("--force", help="contact force Fx,Fy,Fz at the tip, N, base frame (eq. 2.9, 2.13)")
    s.add_argument("--tip", help="tip frame name (default: the first tip)")
    s.add_argument("--friction", action="store_true", help="Alpes models: switch on friction (eq. 2.6-2.7)")
    s.add_argument("--rotor-inertia", action="store_true", help="Alpes models: switch on the rotor inertia J_m "
                                                                "on each tendon, S^T J_m S (eq. 2.8)")
    s.set_defaults(func=cmd_dynamics)

    s = sub.add_parser("report", help="the report reproduced: dynamics cross-check and observability")
    s.add_argument("--points", type=_POINTS, default=20, help="random states per check (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_report)

    s = sub.add_parser("observability", help="nonlinear observability rank test (eq. 3.4-3.8)")
    common(s)
    s.add_argument("--input", default="joint", choices=("joint", "motor"), help="u = joint torques or motor torques")
    s.add_argument("--output", default="sum", type=_outputs, help=OUTPUT_HELP)
    s.add_argument("--points", type=_POINTS, default=8, help="random points for the generic rank (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--order", default="auto", help="highest derivative order: auto (until the rank stops growing, "
                   "default), report (y..y^(n-1), eq. 3.8) or an integer")
    s.add_argument("--constant-input", action="store_true", help="inputs constant (u' = u'' = ... = 0)")
    s.add_argument("--max-operations", type=_int_at_least(1), default=MAX_INSTRUCTIONS,
                   help="size cap of one derivative order's function, CasADi operations (default %(default)s)")
    s.set_defaults(func=cmd_observability)

    s = sub.add_parser("linearize", help="A, B, C, D of the state space at a point (continuous, or discrete with --dt)",
                       epilog="Example: alpes-dyn linearize --model finger3 --input motor --output encoder --u 0.02")
    common(s)
    s.add_argument("--input", default="joint", choices=("joint", "motor"), help="u = joint torques or motor torques")
    s.add_argument("--output", default="sum", type=_outputs, help=OUTPUT_HELP)
    s.add_argument("--u", help="input u0 (joint or motor torques, N m; default zeros)")
    s.add_argument("--q", help="joint angles of x0, rad (default: the rest state under --u)")
    s.add_argument("--v", help="joint velocities of x0, rad/s (default zeros; needs --q)")
    s.add_argument("--dt", type=float, default=None, help="time step, s: discretise with a zero-order hold")
    s.set_defaults(func=cmd_linearize)

    s = sub.add_parser("estimate", help="simulate a finger and estimate its joints from the motor encoder, or run "
                       "the observer on a recording (--data)",
                       epilog="Examples: alpes-dyn estimate --model finger3 --observer ekf-params --mismatch 0.1 "
                              "--plot estimate.png; alpes-dyn estimate --data rec.csv --params ident.toml --friction")
    common(s)
    s.set_defaults(model="finger3")
    for a in s._actions:
        if a.dest == "model":
            a.help = "finger2, finger3 or thumb (with --friction) (default %(default)s)"
    s.add_argument("--chain", default=None, metavar="FINGER",
                   help="a finger model as that finger of the hand (its own [finger.<name>] values in the files)")
    s.add_argument("--observer", default="ekf",
                   help="ekf, ukf, or ekf-params, ukf-params (which also estimate the input and spring gains: use "
                        "them with --mismatch) (default %(default)s)")
    s.add_argument("--mismatch", type=float, default=0.0,
                   help="relative error of the observer's springs and masses, e.g. 0.1 (default %(default)s)")
    s.add_argument("--duration", type=float, default=5.0, help="simulated time, s (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--plot", metavar="FILE.png", help="write a figure of true and estimated joints (format by "
                   "extension: .png, .pdf, .svg...)")
    s.add_argument("--true-params", default=None, metavar="FILE",
                   help="parameter file of the simulated (true) finger, e.g. from a perturbed draw")
    s.add_argument("--observer-params", default=None, metavar="FILE",
                   help="parameter file of the observer's model, e.g. written by 'alpes-dyn identify' (default: the "
                        "simulated finger's, --true-params, or the shipped one, mis-scaled by --mismatch)")
    s.add_argument("--friction", action="store_true",
                   help="the finger has friction (eq. 2.6-2.7), the true one and the observer's model")
    s.add_argument("--data", default=None, metavar="REC.csv",
                   help="run the observer on this recording (encoder and torque; RMSE where it has true_q_* columns) "
                        "instead of the simulated scenario; the observer's model is --params (e.g. the file "
                        "'alpes-dyn identify -o' wrote), with --friction if it has friction")
    s.add_argument("--torque-noise", type=float, default=None, metavar="NM",
                   help="with --data: white noise of the recorded torque, N m (default: estimated from the recording)")
    s.add_argument("--disturbance", action="store_true",
                   help="with --data: also estimate a slowly varying torque per motor (what the model leaves)")
    s.add_argument("--log", default=None, metavar="FILE.csv",
                   help="with --data: write the estimated joints, velocities and standard deviations as CSV")
    s.set_defaults(func=cmd_estimate)

    s = sub.add_parser("experiment", help="simulate the identification experiment on a finger or the thumb, write a "
                       "recording CSV",
                       epilog="Example: alpes-dyn experiment --model finger3 --chain index --params true.toml --seed 1 "
                              "-o rec.csv")
    s.add_argument("--model", default="finger3", help="finger2, finger3 or thumb (default %(default)s)")
    s.add_argument("--chain", default=None, metavar="FINGER",
                   help="a finger model as that finger of the hand (index, middle, ...: its own [finger.<name>] "
                        "values in --params)")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="the true parameter file (default: the shipped one)")
    s.add_argument("--perturb", type=float, default=None, metavar="SPREAD",
                   help="draw the true chain from --params with K, m, friction each times U(1-SPREAD, 1+SPREAD) "
                        "per link (seeded by --seed): the --chain finger's own values, the thumb's, or the shared "
                        "finger's; write it with --true-params-out")
    s.add_argument("--true-params-out", default=None, metavar="FILE", help="write the (drawn) true parameters there")
    s.add_argument("--duration", type=float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="seed of the sensor noise (default %(default)s)")
    s.add_argument("-o", "--output", required=True, metavar="FILE.csv", help="the recording to write")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_experiment)

    s = sub.add_parser("identify", help="fit a finger's or the thumb's springs, masses and friction to a recording",
                       epilog="Example: alpes-dyn identify --model finger3 --chain index --data rec.csv -o ident.toml. "
                              "Exit codes: 0 written (or --force), 2 bad input, 3 the fit did not converge or the "
                              "model is not adequate to the recording (residual coloured, correlated with the "
                              "torque, above the sensor floor, or a poor --validate fit): nothing written")
    s.add_argument("--model", default="finger3", help="finger2, finger3 or thumb (default %(default)s)")
    s.add_argument("--chain", default=None, metavar="FINGER",
                   help="a finger model as that finger of the hand: starts from its own values and writes the fit "
                        "into its [finger.<name>] table (the thumb's go to [thumb])")
    s.add_argument("--data", required=True, metavar="FILE.csv", help="the recording (documented CSV format)")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="parameter file to start from, and the base of the written file (default: the shipped one)")
    s.add_argument("--parameters", default=None,
                   help="what to fit: kinds K, m, F_s, F_v, friction, input_gain, J_m (with --rotor-inertia), "
                        "encoder_offset (each encoder's zero, rad), tilt (tilt_x, tilt_y: the palm's orientation, "
                        "rad; a planar finger sees tilt_y only) and/or names K_1, m_2, encoder_offset_finger, "
                        f"tilt_y... (default K,m,friction; on the thumb {THUMB_PARAMETERS}: the ab/adduction's own "
                        "mass and friction are barely seen by the encoders; name them to fit them)")
    s.add_argument("--rotor-inertia", action="store_true",
                   help="the model with the file's rotor inertia J_m on each tendon (eq. 2.8); fit it with J_m")
    s.add_argument("--excitation", default="documented",
                   help="'documented' (the torque is the documented multisine: fit it on its lines, default), "
                        "'none' (use the measured torque as it is) or comma-separated frequencies in Hz")
    s.add_argument("--torque-noise", type=float, default=None,
                   help="white noise of the recorded torque, N m (errors in variables). Default: estimated from "
                        "the torque off the excitation's lines; with --excitation none, 0 (the torque taken as exact)")
    s.add_argument("--validate", default=None, metavar="REC2.csv",
                   help="a held-out recording of the same finger: the fitted model simulated on its torque, fit %% "
                        "and NRMSE per encoder (MATLAB's compare), part of the adequacy verdict")
    s.add_argument("--encoder-noise", type=float, default=None, metavar="COUNTS",
                   help="the encoder's white noise beyond its quantisation, counts, for the sensor floor of the "
                        "adequacy check (default: estimated from the recording)")
    s.add_argument("--force", action="store_true",
                   help="write -o even when the fit did not converge or the model is not adequate (the file is "
                        "marked not trustworthy); without it such a fit writes nothing and exits with code 3")
    s.add_argument("-o", "--output", default=None, metavar="FILE.toml", help="write the identified parameter file")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_identify)

    s = sub.add_parser("identifiability", help="which physical parameters a finger's encoder can identify: "
                       "structural rank and Cramér-Rao bounds of an experiment",
                       epilog="Example: alpes-dyn identifiability --model finger3 --parameters K,m --design documented")
    s.add_argument("--model", default="finger3", help="finger2 or finger3 (default %(default)s)")
    s.add_argument("--params", default=None, metavar="FILE", help="parameter file (default: the shipped one)")
    s.add_argument("--parameters", default=None,
                   help="kinds K, m, F_s, F_v, friction, input_gain, encoder_offset, tilt and/or names K_1, m_2, "
                        "tilt_y... (default K,m,friction; the finger has friction when friction parameters are "
                        "chosen)")
    s.add_argument("--output", default="encoder", type=_outputs, help="the measured output (default encoder: S q)")
    s.add_argument("--design", default="documented",
                   help="experiment of the Cramér-Rao bounds: documented (the identification multisine, default), "
                        "scenario (the estimation scenario's small torque wiggle) or none (structural only)")
    s.add_argument("--duration", type=float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--camera-times", default=None, metavar="T1,T2,...",
                   help="times (s) where a camera or a jig measures every joint angle once (noise 0.1 degree)")
    s.add_argument("--points", type=_POINTS, default=8, help="random points for the generic rank (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--max-operations", type=_int_at_least(1), default=MAX_INSTRUCTIONS,
                   help="size cap of one derivative order's function, CasADi operations (default %(default)s); "
                        "above it the rank is a lower bound")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_identifiability)

    s = sub.add_parser("sweep", help="a study over seeded draws of a finger within its tolerances, on Dask workers "
                       "(experiment, identification, EKF per draw)",
                       epilog="Example: alpes-dyn sweep --model finger3 --draws 8 --seed 1 --workers 2 -o sweep.csv")
    s.add_argument("--study", default="robustness",
                   help="robustness: per draw a finger drawn +-spread per link, its experiment, the fit and the EKF "
                        "before/after (default %(default)s)")
    s.add_argument("--model", default="finger3", help="finger2 or finger3 (default %(default)s)")
    s.add_argument("--draws", type=_int_at_least(1), default=4, help="number of draws (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="seed of the first draw; draw k has seed + k "
                   "(default %(default)s)")
    s.add_argument("--spread", type=float, default=0.2, help="relative spread per link (default %(default)s)")
    s.add_argument("--duration", type=float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--no-fit", action="store_true", help="no identification: the EKF on the nominal file only")
    s.add_argument("--workers", type=_int_at_least(1), default=2,
                   help="processes of the local Dask cluster (default %(default)s)")
    s.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a running Dask scheduler, e.g. tcp://host:8786, instead of a local cluster")
    s.add_argument("--serial", action="store_true", help="one draw after another in this process (no Dask)")
    s.add_argument("-o", "--output", default=None, metavar="FILE.csv", help="write the table as CSV")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_sweep)

    s = sub.add_parser("control", help="closed-loop fingertip force control on a MuJoCo plant (needs mujoco)",
                       epilog="Example: alpes-dyn control --model finger3 --controller sensor --reference step "
                              "--plot control.png")
    s.add_argument("--model", default="finger3",
                   help="finger2 or finger3 on the block, or hand grasping the cylinder (a loop per motor, the "
                        "references of control.HAND_LEVELS) (default %(default)s)")
    s.add_argument("--controller", default="sensor",
                   help="sensor (feedforward + PI on the FlexiForce), sensorless (force estimated from the motor "
                        "torque and the observer), pi (PI on the FlexiForce alone) (default %(default)s)")
    s.add_argument("--reference", default="step",
                   help="step (0.2, 1.0, 0.5 N), ramp (0.2 to 1.0 N in 1 s), sine (0.3-0.8 N at 1 Hz) "
                        "(default %(default)s)")
    s.add_argument("--params", default=None, metavar="FILE", help="the controller's parameter file (default: shipped)")
    s.add_argument("--plant-params", default=None, metavar="FILE",
                   help="the plant's parameter file (default: the controller's)")
    s.add_argument("--duration", type=_positive_seconds, default=None,
                   help="simulated time, s (default 3 for a finger, 3.5 for the hand)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--log", metavar="FILE.csv", help="write the traces (t, F_ref, F_z, q, q_hat, tau_m) as CSV")
    s.add_argument("--plot", metavar="FILE.png", help="write a figure of force, torque and joints")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_control)
    return p


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _run(argv: list[str]) -> tuple[int, str | None]:
    """(exit code, error line or None) of one command."""
    try:
        if len(argv) > MAX_ARGS:
            raise InputError(f"{len(argv)} command-line arguments, over the limit of {MAX_ARGS}")
        args = build_parser().parse_args(_join_negative_vectors(argv))
        func: Callable[[argparse.Namespace], int] = args.func
        return func(args), None
    except _UsageError as exc:
        return 2, _one_line(str(exc))
    except _Untrusted as exc:
        return EXIT_UNTRUSTED, _one_line(str(exc))
    except AlpesDynError as exc:
        return 2, f"alpes-dyn: error: {_one_line(str(exc))}"
    except KeyboardInterrupt:
        return 130, "alpes-dyn: interrupted"
    except MemoryError:  # a size no check foresaw: still the input's
        return 2, "alpes-dyn: error: out of memory: the input asks for arrays larger than this machine holds"
    except (OverflowError, RecursionError) as exc:
        return 2, f"alpes-dyn: error: an input too large ({type(exc).__name__}: {_one_line(str(exc))[:200]})"
    except Exception as exc:  # never a traceback for a user
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return 1, f"alpes-dyn: internal error: {type(exc).__name__}: {_one_line(msg)}"


def _tolerant_streams() -> None:
    """Text that the terminal's encoding cannot show (the é of Cramér under ``PYTHONIOENCODING=ascii``) is
    written as a backslash escape rather than raising UnicodeEncodeError."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="backslashreplace")  # type: ignore[union-attr]
        except (AttributeError, ValueError, OSError):
            pass


def _say(line: str) -> None:
    """One line on stderr; nothing if stderr is closed (``2>&-``) or cannot be written."""
    if sys.stderr is None:
        return
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; exit code 0, 2 for bad input (one line on stderr), 3 for an identification not to be
    trusted (:data:`EXIT_UNTRUSTED`), 1 for an internal error.

    Whatever Python warnings (e.g. numpy's RuntimeWarning) and native libraries (urdfdom, CasADi) would
    print on stderr is captured: it is appended to the error line, or, after a successful command,
    summarised in one ``alpes-dyn: warning:`` line. stderr never gets more than one line. A closed or full
    stdout (``| head``, ``> /dev/full``) is exit 2 with one line; a closed stderr (``2>&-``) is written to
    nowhere, the exit code unchanged.
    """
    _tolerant_streams()
    argv = list(sys.argv[1:] if argv is None else argv)
    printed: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with native_stderr_to(printed):
            try:
                code, error = _run(argv)
            except SystemExit as done:  # --help, --version: argparse printed them
                try:
                    _write_stdout("")
                except _StdoutError as exc:
                    code, error = 2, f"alpes-dyn: error: {exc}"
                else:
                    raise done
    notes = [_one_line(f"{w.category.__name__}: {w.message}") for w in caught] + [_one_line(p) for p in printed]
    more = f" (+{len(notes) - 1} more)" if len(notes) > 1 else ""
    if error is not None:
        _say(error + (f" [{notes[0]}{more}]" if notes else ""))
    elif notes:
        _say(f"alpes-dyn: warning: {notes[0]}{more}")
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
