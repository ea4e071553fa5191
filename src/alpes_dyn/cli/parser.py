"""The command line's grammar: the ``argparse`` parser of every command, its options, help texts and
examples (one function per command, in the order ``alpes-dyn --help`` lists them)."""

from __future__ import annotations

import argparse
from .. import __version__
from ..analysis.observability_matrix import MAX_INSTRUCTIONS
from .arguments import (OUTPUT_HELP, _POINTS, _SEED, _common, _int_at_least, _json_option,  # noqa: F401
                        _model_option, _out_dir_option, _outputs, _positive_number, _positive_seconds, _strict_float)
from .analysis_cmds import cmd_identifiability, cmd_observability
from .common import FORCE_USE_HELP, _UsageError, _drift_choice
from .control_cmds import cmd_control
from .codegen_cmds import cmd_codegen
from .estimation_cmds import FRICTION_LAW_HELP, THUMB_PARAMETERS, cmd_estimate, cmd_identify
from .experiment_cmds import cmd_experiment
from .on_hand_cmds import add_options as add_on_hand_options
from .model_cmds import cmd_dynamics, cmd_import, cmd_linearize, cmd_mjcf, cmd_report, cmd_urdf
from .study_cmds import cmd_sweep

DESCRIPTION = "Command line ``alpes-dyn``: URDF generation, dynamics, the report reproduced, observability, estimation."
"""``alpes-dyn --help``'s first line: the first line of the package's docstring (:mod:`alpes_dyn.cli`)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2
        raise _UsageError(f"{self.prog}: {message}")


def _add_urdf(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("urdf", help="print or write the URDF of a model",
                       epilog="Example: alpes-dyn urdf --model finger3 -o finger3.urdf")
    _model_option(s, "finger2, finger3, thumb, hand, or an MJCF path (FILE.xml: the URDF of its tree; "
                     "'alpes-dyn import' writes its spec too)")
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    s.add_argument("--params", default=None, metavar="FILE", help="parameter file (default: the shipped one)")
    _json_option(s)
    s.set_defaults(func=cmd_urdf)


def _add_import(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("import", help="write the URDF and the transmission spec of a MuJoCo model (MJCF) with fixed "
                       "tendons, for --model FILE.urdf --spec FILE.toml",
                       epilog="Example: alpes-dyn import --model hand.xml --out-dir hand; then alpes-dyn dynamics "
                              "--model hand/hand.urdf --spec hand/hand.toml")
    s.add_argument("--model", required=True, metavar="FILE.xml",
                   help="the MJCF file (MuJoCo compiles it: its includes, defaults and classes resolved)")
    _out_dir_option(s, "the directory to create (new, or empty): <name>.urdf and <name>.toml, <name> the MJCF "
                       "file's name without its extension; written whole or not at all")
    s.add_argument("--hold", metavar="J1,J2,...", help="hinges to weld at their reference angle, the actuators on "
                   "them dropped (e.g. a hand's wrist: each finger then a branch of its own for --chain)")
    _json_option(s)
    s.set_defaults(func=cmd_import)


def _add_mjcf(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("mjcf", help="print or write the MuJoCo model (MJCF) of a model: springs, stops, tendons, "
                       "motors, sensors", epilog="Example: alpes-dyn mjcf --model finger3 --scene block -o finger3.xml")
    _model_option(s, "finger2, finger3, hand, thumb, or a URDF path (with --spec)")
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    s.add_argument("--spec", default=None, metavar="FILE.toml",
                   help="a URDF model's transmission spec: motors, tendons, springs, friction, rotor inertia")
    s.add_argument("--params", default=None, metavar="FILE", help="Alpes models: parameter file (default: the shipped one)")
    s.add_argument("--scene", default="none", choices=("none", "block", "cylinder"),
                   help="Alpes models: add a fixed block on a finger's pad (finger2, finger3) or a cylinder in the hand "
                        "(a URDF --model's block scene: alpes-dyn control)")
    s.add_argument("--spring", default=None, choices=("report", "torsional", "none"),
                   help="Alpes models: spring model (default torsional)")
    s.add_argument("--friction", action="store_true", help="Alpes models: joint damping F_v and frictionloss F_s (eq. 2.6; a URDF --model has "
                   "its spec's, always)")
    s.add_argument("--rotor-inertia", action="store_true", help="Alpes models: the rotor J_m on each tendon: tendon "
                   "armature J_m/r_m^2 (eq. 2.8; a URDF --model has its spec's rotor_inertia, always)")
    s.add_argument("--no-limits", action="store_true", help="no joint stops")
    s.add_argument("--no-contact", action="store_true", help="Alpes models: collisions disabled")
    s.add_argument("--palm-down", action="store_true", help="Alpes models: gravity reversed: the hand turned over "
                   "(control scene)")
    s.add_argument("--stiction", type=_strict_float, nargs="?", const=5e-4, default=None, metavar="SECONDS",
                   help="stick-slip dry friction on every joint with Coulomb friction: solreffriction of this time "
                        "constant (default %(const)g s; MuJoCo's 0.02 s is soft on a light finger), solimpfriction 0.999")
    s.add_argument("--tendon-stiffness", type=_strict_float, default=None, metavar="N_PER_M",
                   help="Alpes models: series-elastic, pull-only tendon of stiffness k_t with a rotor joint per motor")
    s.add_argument("--tendon-damping", type=_strict_float, default=0.0, metavar="N_S_PER_M",
                   help="Alpes models: damping c_t of the series-elastic tendon (default 0)")
    s.add_argument("--tendon-dead-band", type=_strict_float, default=0.0, metavar="M",
                   help="Alpes models: the series-elastic cable's play: slack up to this stretch, m (default 0)")
    s.add_argument("--tendon-rotor", action="store_true", help="Alpes models: rotor inertia J_m / r_m^2 on each rigid tendon")
    s.add_argument("--tilt", type=_strict_float, default=0.0, metavar="DEG",
                   help="Alpes models: palm tilted in the finger's plane by DEG degrees (gravity rotated about y; a "
                        "URDF --model's gravity is its spec's)")
    _json_option(s)
    s.set_defaults(func=cmd_mjcf)


def _add_dynamics(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("dynamics", help="A, C, G, J and forward dynamics at one state",
                       epilog="Example: alpes-dyn dynamics --model finger3 --q=-0.1,0.2,0.3 --v=0,0,0 --tau=0.01,0,0")
    _common(s)
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


def _add_report(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("report", help="the report reproduced: dynamics cross-check and observability")
    s.add_argument("--points", type=_POINTS, default=20, help="random states per check (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_report)


def _add_observability(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("observability", help="nonlinear observability rank test (eq. 3.4-3.8)")
    _common(s)
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


def _add_linearize(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("linearize", help="A, B, C, D of the state space at a point (continuous, or discrete with --dt)",
                       epilog="Example: alpes-dyn linearize --model finger3 --input motor --output encoder --u 0.02")
    _common(s)
    s.add_argument("--input", default="joint", choices=("joint", "motor"), help="u = joint torques or motor torques")
    s.add_argument("--output", default="sum", type=_outputs, help=OUTPUT_HELP)
    s.add_argument("--u", help="input u0 (joint or motor torques, N m; default zeros)")
    s.add_argument("--q", help="joint angles of x0, rad (default: the rest state under --u)")
    s.add_argument("--v", help="joint velocities of x0, rad/s (default zeros; needs --q)")
    s.add_argument("--dt", type=_strict_float, default=None, help="time step, s: discretise with a zero-order hold")
    s.set_defaults(func=cmd_linearize)


def _add_estimate(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("estimate", help="simulate a finger and estimate its joints from the motor encoder, or run "
                       "the observer on a recording (--data)",
                       epilog="Examples: alpes-dyn estimate --model finger3 --observer ekf-params --mismatch 0.1 "
                              "--plot estimate.png; alpes-dyn estimate --data rec.csv --params ident.toml --friction")
    _common(s)
    s.set_defaults(model="finger3")
    for a in s._actions:
        if a.dest == "model":
            a.help = ("finger2, finger3 or thumb (with --friction), or with --data a URDF path (with --spec) "
                      "(default %(default)s)")
    s.add_argument("--chain", default=None, metavar="FINGER|MOTOR",
                   help="a finger model as that finger of the hand (its own [finger.<name>] values in the files); "
                        "on a URDF --model with --data a motor's name: the observer on the sub-model of its "
                        "branches from the base, with every motor driving them (the recording's columns of the "
                        "other motors and joints are ignored)")
    s.add_argument("--observer", default="ekf",
                   help="ekf, ukf, or ekf-params, ukf-params (which also estimate the input and spring gains: use "
                        "them with --mismatch) (default %(default)s)")
    s.add_argument("--mismatch", type=_strict_float, default=0.0,
                   help="relative error of the observer's springs and masses, e.g. 0.1 (default %(default)s)")
    s.add_argument("--duration", type=_strict_float, default=5.0, help="simulated time, s (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed of the simulated scenario (default %(default)s)")
    s.add_argument("--plot", metavar="FILE.png", help="the simulated scenario (not with --data): write a figure "
                   "of true and estimated joints (format by extension: .png, .pdf, .svg...)")
    s.add_argument("--true-params", default=None, metavar="FILE",
                   help="parameter file of the simulated (true) finger, e.g. from a perturbed draw")
    s.add_argument("--observer-params", default=None, metavar="FILE",
                   help="parameter file of the observer's model, e.g. written by 'alpes-dyn identify' (default: the "
                        "simulated finger's, --true-params, or the shipped one, mis-scaled by --mismatch)")
    s.add_argument("--friction", action="store_true",
                   help="the finger has friction (eq. 2.6-2.7), the true one and the observer's model (default: as "
                        "the observer's parameter file says: friction where 'identify' fitted it with friction)")
    s.add_argument("--no-friction", action="store_true",
                   help="no friction, whatever the parameter file says (--friction and --no-friction override the "
                        "file, with one warning line where it says otherwise)")
    s.add_argument("--data", default=None, metavar="REC.csv",
                   help="run the observer on this recording (encoder and torque; RMSE where it has true_q_* columns) "
                        "instead of the simulated scenario; the observer's model is --params (e.g. the file "
                        "'alpes-dyn identify -o' wrote; its friction as the file's fit had)")
    s.add_argument("--friction-free", action="store_true",
                   help="with --data on a URDF --model: the observer's model without its spec's friction")
    s.add_argument("--torque-noise", type=_strict_float, default=None, metavar="NM",
                   help="with --data: white noise of the recorded torque, N m (default: estimated from the recording)")
    s.add_argument("--torque-constant", type=_strict_float, default=None, metavar="NM_PER_A",
                   help="with --data: the motors' torque constant, N m/A, to read a recording's current_<motor> "
                        "columns (A) as motor torques (a recording with current columns needs it)")
    s.add_argument("--disturbance", action="store_true", help="with --data: also estimate a slowly varying torque per motor")
    s.add_argument("--log", default=None, metavar="FILE.csv",
                   help="with --data: write the estimated joints, velocities and standard deviations as CSV (q_std_*: "
                        "the filter's, widened by the dry-friction band unless --no-band-sigma)")
    s.add_argument("--rotor-inertia", action="store_true",
                   help="with --data: the observer's model with the file's rotor inertia J_m on each tendon (what "
                        "'identify' fitted with when its JSON's effects hold rotor)")
    s.add_argument("--encoder-offset", default=None, metavar="RAD[,RAD...]",
                   help="with --data: each encoder's zero on this rig, rad (identify's encoder_offset_<motor>), "
                        "taken off the reading (with --chain MOTOR on a URDF: one per motor of its branches)")
    s.add_argument("--tilt", default=None, metavar="TILT_X,TILT_Y",
                   help="with --data: the palm's orientation, rad (identify's tilt_x, tilt_y): the observer's "
                        "gravity turned by it")
    s.add_argument("--torque-delay", type=int, default=None, metavar="SAMPLES", help="with --data: the recorded "
                   "torque lags the motor's by this many whole samples (identify's torque_delay): read that much earlier")
    s.add_argument("--sigma-limit", type=_strict_float, default=None, metavar="DEG", help="a joint that no 0.5 s "
                   "window of the motion pins within DEG degrees (1 sigma, dry friction unknown) is flagged (default 1)")
    s.add_argument("--friction-law", default=None, metavar="LAW", help=FRICTION_LAW_HELP)
    s.add_argument("--stops", action="store_true", help="with --data: the joints' end stops in the observer's model "
                   "(for a finger whose joints reach their stops)")
    s.add_argument("--law-spread", action="store_true", help="with --data: each joint's sigma widened by the "
                   "spread of its estimate between the library's friction laws (smooth, stick, lugre, creep: the "
                   "observer run again with each other law on the same file, four runs in all)")
    s.add_argument("--band-sigma", action="store_true", help="with --data and friction (the default there): each "
                   "joint's sigma widened by where the dry-friction band lets the joints the encoder does not tell "
                   "apart rest (from the file's F_s, springs and gravity, a share of F_s by the observer's friction "
                   "law; the estimate unchanged); given, an error where it cannot apply")
    s.add_argument("--no-band-sigma", action="store_true", help="with --data: each joint's sigma the filter's own "
                   "covariance alone (without the dry-friction band of --band-sigma)")
    s.add_argument("--force", action="store_true", help=FORCE_USE_HELP)
    s.set_defaults(func=cmd_estimate)


def _add_codegen(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("codegen", help="write the observer's step as standalone C (source, header, test program): "
                       "no Python, no heap",
                       epilog="Example: alpes-dyn codegen --model finger3 --observer ekf --out-dir ekf_c; then "
                              "cc -O2 -o ekf_c/alpes_ekf_main ekf_c/main.c ekf_c/alpes_ekf.c -lm")
    s.add_argument("--model", default="finger3", help="finger2, finger3, or thumb (with --friction), or a URDF path "
                   "(with --spec: the observer of 'estimate --data' on it) (default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml",
                   help="a URDF --model's transmission spec (motors, encoder, springs, friction); required with one")
    s.add_argument("--chain", default=None, metavar="FINGER",
                   help="Alpes models: a finger model as that finger of the hand (its own [finger.<name>] values "
                        "in --params)")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="Alpes models: the observer's parameter file, e.g. written by 'alpes-dyn identify' "
                        "(default: the shipped one)")
    s.add_argument("--friction", action="store_true", help="Alpes models: the observer's model has friction "
                   "(eq. 2.6-2.7; default: as --params says: friction where 'identify' fitted it with friction; a "
                   "URDF --model's has its spec's)")
    s.add_argument("--no-friction", action="store_true", help="Alpes models: no friction, whatever --params says "
                   "(--friction and --no-friction override the file, with one warning line where it says otherwise)")
    s.add_argument("--observer", default="ekf",
                   help="ekf, ukf, ekf-params or ukf-params (the estimation scenario's filters and noise settings) "
                        "(default %(default)s)")
    s.add_argument("--controller", default=None,
                   help="also the fingertip force controller of 'alpes-dyn control' (finger2, finger3 on the block, "
                        "or a URDF --model's tip frame on its block): sensor, sensorless or pi, as alpes_force.h, "
                        "alpes_force.c and force_main.c")
    s.add_argument("--step", action="store_true",
                   help="write the whole force step instead (ForceStep.step in C: the EKF with the file's friction, "
                        "the compensation of its identified effects, the --controller with its tuned gains; the "
                        "contact normal an input of each call) for finger2 or finger3 and --params: alpes_step.h, "
                        "alpes_step.c, alpes_step_ekf.*, alpes_step_force.*, main.c; for --model hand the whole "
                        "hand's (HandForceStep: a step per flexion chain, each fingertip's force and normal an input, "
                        "the thumb's ab/adduction PD): alpes_hand.h, alpes_hand.c, alpes_hand_<chain>*, main.c; for a URDF "
                        "--model with --spec, the robot's ForceStep (--frame, --motor)")
    s.add_argument("--frame", default=None, metavar="NAME",
                   help="a URDF --model with --controller: the tip frame that presses the block (default: the only "
                        "tip the motor moves)")
    s.add_argument("--motor", default=None, metavar="NAME",
                   help="a URDF --model with --controller: the spec's motor that pulls (default: the only motor, or "
                        "the only one moving --frame)")
    _out_dir_option(s, "the directory to create (new, or empty): <prefix>.h, <prefix>.c, main.c")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.add_argument("--force", action="store_true", help=FORCE_USE_HELP)
    s.set_defaults(func=cmd_codegen)


def _add_experiment(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("experiment", help="simulate the identification experiment on a finger or the thumb, write a "
                       "recording CSV",
                       epilog="Example: alpes-dyn experiment --model finger3 --chain index --params true.toml --seed 1 "
                              "-o rec.csv")
    s.add_argument("--model", default="finger3", help="finger2, finger3, thumb, hand (the six motors at once, one "
                   "recording), or a URDF path (with --spec) (default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml",
                   help="a URDF --model's transmission spec: the robot the excitation is designed on (and the true "
                        "one, unless --true-spec)")
    s.add_argument("--true-spec", default=None, metavar="TRUE.toml",
                   help="a URDF --model: the spec of the simulated (true) robot, e.g. with other springs")
    s.add_argument("--true-model", default=None, metavar="TRUE.urdf", help="a URDF --model: the simulated (true) "
                   "robot's URDF, e.g. other masses (spec: --true-spec, else --spec); the bias is trimmed on it")
    s.add_argument("--chain", default=None, metavar="FINGER",
                   help="Alpes models: a finger model as that finger of the hand (index, middle, ...: its own [finger.<name>] "
                        "values in --params)")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="Alpes models: the true parameter file (default: the shipped one)")
    s.add_argument("--perturb", type=_strict_float, default=None, metavar="SPREAD",
                   help="Alpes models: draw the true chain from --params with K, m, friction each times U(1-SPREAD, 1+SPREAD) "
                        "per link (seeded by --seed): the --chain finger's own values, the thumb's, or the shared "
                        "finger's; write it with --true-params-out")
    s.add_argument("--true-params-out", default=None, metavar="FILE", help="Alpes models, with --perturb: write the drawn true parameters "
                   "there")
    s.add_argument("--duration", type=_strict_float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--amplitude", type=_strict_float, default=0.5, metavar="FRACTION",
                   help="the multisine's amplitude, a fraction in (0, 1] of the largest keeping the nominal robot "
                        "in range (default %(default)s); 1 where friction hides the masses")
    s.add_argument("--stick-seconds", type=_strict_float, default=0.0, metavar="S",
                   help="a slow, undithered torque ramp through stiction recorded after the excitation, S s "
                        "(default %(default)s: none; 6 where the joints' dry friction sticks), marked held_out: "
                        "identify leaves it out of the fit and judges its observer check and the observer's friction "
                        "law on it")
    s.add_argument("--rig", choices=("auto", "level", "hanging", "both"), default="auto",
                   help="an Alpes hand's orientation: auto (default): palm up unless the finger leaves its range "
                        "there, then hung fingers down, scaled down where even that leaves it; level: palm up; "
                        "hanging: fingers down; both (one finger): half palm up, half hung, each its own run (the "
                        "masses' split pinned). Each checks the whole record first and says what it chose. With --bench: auto and "
                        "level palm up, hanging hung, both palm up then hung (two runs joined in -o); with "
                        "--design-only --rig both: -o's name with _level and _hanging, one profile per rig")
    s.add_argument("--seed", type=_SEED, default=0, help="seed of the sensor noise (default %(default)s)")
    add_on_hand_options(s)  # --design-only, --bench, -o, --json (cli.on_hand_cmds)
    s.set_defaults(func=cmd_experiment)


def _add_identify(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("identify", help="fit a finger's or the thumb's springs, masses and friction to a recording",
                       epilog="Example: alpes-dyn identify --model finger3 --chain index --data rec.csv -o ident.toml. "
                              "Exit codes: 0 written (or --force), 2 bad input, 3 the fit did not converge or the "
                              "model is not adequate to the recording (residual coloured, correlated with the "
                              "torque, above the sensor floor, or a poor --validate fit): nothing written")
    s.add_argument("--model", default="finger3", help="finger2, finger3, thumb, hand (every chain from one "
                   "recording of the six motors, one file; --chain NAME: that chain only), or a URDF path (with "
                   "--spec) (default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml", help="a URDF --model's spec: the values to start "
                   "from and the base of -o's spec (the identified values, their standard errors in [identified])")
    s.add_argument("--chain", default=None, metavar="FINGER|MOTOR",
                   help="a finger model as that finger of the hand (its own values, the fit into [finger.<name>]; "
                        "the thumb's [thumb]); a URDF --model: a motor, fit only its joints' parameters (and its "
                        "own) on its branches' sub-model (-o: the whole spec with the chain's values replaced)")
    s.add_argument("--data", required=True, nargs="+", metavar="FILE.csv",
                   help="the recording (documented CSV format); with a 'run' column, or several files (each a run "
                        "of its own), several runs fitted together, each from its own initial state, the parameters "
                        "shared")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="Alpes models: parameter file to start from, and the base of the written file (default: the "
                        "shipped one)")
    s.add_argument("--torque-constant", type=_strict_float, default=None, metavar="NM_PER_A",
                   help="the motors' torque constant, N m/A, to read the recordings' current_<motor> columns (A) as "
                        "motor torques (a recording with current columns needs it)")
    s.add_argument("--parameters", default=None,
                   help="what to fit: kinds K, m, F_s, F_v, friction, input_gain, J_m (with --rotor-inertia), "
                        "encoder_offset (each encoder's zero, rad), tilt (tilt_x, tilt_y: the palm's orientation, "
                        "rad; a planar finger sees tilt_y only) and/or names K_1, m_2, encoder_offset_finger, "
                        f"tilt_y... (default K,m,friction; on the thumb {THUMB_PARAMETERS}: the ab/adduction's own "
                        "mass and friction are barely seen by the encoders; name them to fit them; on a URDF --model "
                        "the masses of links that only motorless joints move are held, seen only with those joints' "
                        "springs), each with the "
                        "parameters of --effects added; given, the selection as named (no effect added unless "
                        "--effects stiction)")
    s.add_argument("--law-spread", action="store_true",
                   help="widen each standard error by the friction law's model error: the fit made again with the "
                        "other friction law (smooth or stick-slip) from the kept one, each std widened by the "
                        "difference and by the memoryless laws' model-form share of each spring, mass and friction "
                        "(one fit more; with --effects auto on the Alpes models)")
    s.add_argument("--effects", default=None, metavar="LIST",
                   help="the real hand's effects to fit, comma-separated: stiction (the stick-slip friction law, "
                        "v_s = 0.02 rad/s, kept in the file), rotor (the file's rotor inertia J_m on each tendon, "
                        "held), compliance (the tendon's stretch, tendon_compliance), "
                        "tilt (the palm's tilt, on top of the recording's gravity columns where it has them: the rig's "
                        "orientation as set up), offset (the "
                        "encoders' zero), delay, capstan (the tendons' sheath friction), lugre (the LuGre friction law: "
                        "sigma0, sigma1 fitted, friction.law written), creep (a dry friction that creeps before it "
                        "slides, MuJoCo's default frictionloss: creep_kappa, creep_rate fitted, friction.law written); "
                        "'auto' (the default): "
                        "compliance,tilt, then the fit again with what the first one's adequacy check names, the "
                        "lower residual kept; 'none' for the rigid, smooth-friction fit (with --parameters: none)")
    s.add_argument("--rotor-inertia", action="store_true",
                   help="Alpes models: the model with the file's rotor inertia J_m on each tendon (eq. 2.8); fit it "
                        "with J_m (a URDF --model's rotors are its spec's, always on)")
    s.add_argument("--excitation", default="documented",
                   help="'documented' (the torque is the documented multisine and its dither: fit it on their lines, default), "
                        "'none' (use the measured torque as it is) or comma-separated frequencies in Hz")
    s.add_argument("--torque-noise", type=_strict_float, default=None,
                   help="white noise of the recorded torque, N m (errors in variables). Default: estimated from "
                        "the torque off the excitation's lines; with --excitation none, 0 (the torque taken as exact)")
    s.add_argument("--validate", default=None, metavar="REC2.csv",
                   help="a held-out recording of the same finger: the fitted model simulated on its torque, fit %% "
                        "and NRMSE per encoder (MATLAB's compare), part of the adequacy verdict")
    s.add_argument("--drift", type=_drift_choice, default=None, metavar="offset|gain|offset,gain",
                   help="'offset': each encoder's offset drifts, piecewise linear in time (knots every 15 s), 0 at the "
                        "first sample, fitted (the JSON's 'drift'); 'gain': each motor's torque constant likewise, "
                        "relative to the first sample's (the encoder sees no absolute scale); 'offset,gain': both")
    s.add_argument("--encoder-noise", type=_strict_float, default=None, metavar="COUNTS",
                   help="the encoder's white noise beyond its quantisation, counts, for the sensor floor of the "
                        "adequacy check (default: estimated from the recording)")
    s.add_argument("--force", action="store_true", help="write -o even when the fit did not converge or the model is "
                   "not adequate (marked not trustworthy); without it such a fit writes nothing and exits with code 3")
    s.add_argument("-o", "--output", default=None, metavar="FILE.toml", help="write the identified parameter file "
                   "(a URDF --model: its identified spec, and where the fit has masses the URDF with them, FILE.urdf)")
    s.add_argument("--mjcf", default=None, metavar="ROBOT.xml", help="a URDF --model imported from this MJCF "
                   "(alpes-dyn import): with -o FILE.toml also write FILE.xml, the MJCF with the identified masses "
                   "(inertias scaled), joint stiffness, damping, frictionloss and rotors, everything else as written")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_identify)


def _add_identifiability(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("identifiability", help="which physical parameters a finger's encoder can identify: "
                       "structural rank and Cramér-Rao bounds of an experiment",
                       epilog="Example: alpes-dyn identifiability --model finger3 --parameters K,m --design documented")
    s.add_argument("--model", default="finger3", help="finger2, finger3, or a URDF path (with --spec) "
                   "(default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml", help="a URDF --model's transmission spec")
    s.add_argument("--params", default=None, metavar="FILE", help="Alpes models: parameter file (default: the shipped one)")
    s.add_argument("--parameters", default=None,
                   help="kinds K, m, F_s, F_v, friction, input_gain, encoder_offset, tilt and/or names K_1, m_2, "
                        "tilt_y... (default K,m,friction; the finger has friction when friction parameters are chosen)")
    s.add_argument("--output", default="encoder", type=_outputs, help="the measured output (default encoder: S q)")
    s.add_argument("--design", default="documented",
                   help="experiment of the Cramér-Rao bounds: documented (the identification multisine, default), "
                        "scenario (the Alpes fingers' estimation scenario's small torque wiggle) or none (structural only)")
    s.add_argument("--duration", type=_strict_float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--camera-times", default=None, metavar="T1,T2,...",
                   help="times (s) where a camera or a jig measures every joint angle once (noise 0.1 degree)")
    s.add_argument("--points", type=_POINTS, default=8, help="random points for the generic rank (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--max-operations", type=_int_at_least(1), default=MAX_INSTRUCTIONS,
                   help="size cap of one derivative order's function, CasADi operations (default %(default)s); "
                        "above it the rank is a lower bound")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_identifiability)


def _add_sweep(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("sweep", help="a study over seeded draws of a finger within its tolerances, on Dask workers "
                       "(experiment, identification, EKF per draw)",
                       epilog="Example: alpes-dyn sweep --model finger3 --draws 8 --seed 1 --workers 2 -o sweep.csv")
    s.add_argument("--study", default="robustness",
                   help="robustness: per draw a finger drawn +-spread per link, its experiment, the fit and the EKF "
                        "before/after (default %(default)s)")
    s.add_argument("--model", default="finger3", help="finger2 or finger3 (K, m, friction drawn), or a URDF path "
                   "(with --spec: its spec's stiffness and friction drawn and fitted on every joint, motorless ones "
                   "too; the URDF's masses held) (default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml",
                   help="a URDF --model's transmission spec: the nominal robot; required with one")
    s.add_argument("--draws", type=_int_at_least(1), default=4, help="number of draws (default %(default)s)")
    s.add_argument("--seed", type=_SEED, default=0, help="seed of the first draw; draw k has seed + k "
                   "(default %(default)s)")
    s.add_argument("--spread", type=_strict_float, default=0.2, help="relative spread per link (a URDF --model: per "
                   "value of its spec) (default %(default)s)")
    s.add_argument("--duration", type=_strict_float, default=4.0, help="experiment length, s (default %(default)s)")
    s.add_argument("--no-fit", action="store_true", help="no identification: the EKF on the nominal file only")
    s.add_argument("--workers", type=_int_at_least(1), default=2,
                   help="processes of the local Dask cluster (default %(default)s)")
    s.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a running Dask scheduler, e.g. tcp://host:8786, instead of a local cluster")
    s.add_argument("--serial", action="store_true", help="one draw after another in this process (no Dask)")
    s.add_argument("-o", "--output", default=None, metavar="FILE.csv", help="write the table as CSV")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_sweep)


def _add_control(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("control", help="closed-loop fingertip force control on a MuJoCo plant (needs mujoco)",
                       epilog="Examples: alpes-dyn control --model finger3 --controller sensor --reference step "
                              "--plot control.png; alpes-dyn control --model robot.urdf --spec robot.toml "
                              "--frame fingertip --motor flexor")
    s.add_argument("--model", default="finger3",
                   help="finger2 or finger3 on the block, hand grasping the cylinder (a loop per motor, the "
                        "references of control.HAND_LEVELS), or a URDF path (with --spec): one motor's tip frame "
                        "on a block placed from the robot's kinematics (default %(default)s)")
    s.add_argument("--spec", default=None, metavar="FILE.toml",
                   help="a URDF --model's transmission spec (motors, encoder, springs, friction); required with one")
    s.add_argument("--frame", default=None, metavar="NAME",
                   help="a URDF --model only: the tip frame that presses the block (default: the only tip the "
                        "motor moves)")
    s.add_argument("--motor", default=None, metavar="NAME",
                   help="a URDF --model only: the spec's motor that pulls (default: the only motor, or the only "
                        "one moving --frame)")
    s.add_argument("--contact-q", default=None, metavar="Q1,Q2,...",
                   help="a URDF --model only: the joint angles (rad, every joint) at which the frame meets the "
                        "block (default: where the motor's free pull covers 25 %% of its joints' ranges)")
    s.add_argument("--tau-max", type=_positive_number("N m"), default=None, metavar="NM",
                   help="a URDF --model only: the motor torque limit, N m (default: twice the static torque of "
                        "the largest reference force, at least 1 N, at the contact)")
    s.add_argument("--controller", default="sensor",
                   help="sensor (feedforward + PI on the FlexiForce), sensorless (force estimated from the motor "
                        "torque and the observer), pi (PI on the FlexiForce alone) (default %(default)s)")
    s.add_argument("--reference", default="step",
                   help="step (0.2, 0.6, 0.2 N), ramp (0.2 to 0.6 N in 1 s), sine (0.3-0.8 N at 1 Hz) "
                        "(default %(default)s)")
    s.add_argument("--params", default=None, metavar="FILE",
                   help="the Alpes models only: the controller's parameter file (default: shipped)")
    s.add_argument("--plant-params", default=None, metavar="FILE",
                   help="the Alpes models only: the plant's parameter file (default: the controller's)")
    s.add_argument("--plant-effects", default=None, choices=("none", "all"),
                   help="the Alpes models only: a real hand's effects on the MuJoCo plant; all: the realism "
                        "benchmark's (stick-slip, a 3.95e4 N/m cable with its rotor and 0.5 deg of slack at the motor "
                        "shaft, palm 3 deg off, torque constant 5 %% off, encoder 4 counts off, torque read 1 sample "
                        "late); the flags below change one effect of it (or, without it, add that effect alone)")
    s.add_argument("--stiction", type=_strict_float, nargs="?", const=5e-4, default=None, metavar="SECONDS",
                   help="plant: stick-slip dry friction, the constraint's time constant (default %(const)g s)")
    s.add_argument("--tendon-stiffness", type=_strict_float, default=None, metavar="N_PER_M",
                   help="plant: series-elastic, pull-only tendon of stiffness k_t with its rotor")
    s.add_argument("--tendon-damping", type=_strict_float, default=None, metavar="N_S_PER_M",
                   help="plant: damping c_t of the series-elastic tendon")
    s.add_argument("--tendon-dead-band", type=_strict_float, default=None, metavar="M",
                   help="plant: the series-elastic cable's slack, m")
    s.add_argument("--tendon-rotor", action="store_true", help="plant: the rotor inertia on the rigid tendon")
    s.add_argument("--tilt", type=_strict_float, default=None, metavar="DEG",
                   help="plant: the palm tilted in the finger's plane, deg")
    s.add_argument("--torque-constant-error", type=_strict_float, default=None, metavar="FRACTION",
                   help="plant: the motor gives tau / (1 + e) for the command tau, the current sensor reads (1 + e) "
                        "times it")
    s.add_argument("--encoder-offset", type=_strict_float, default=None, metavar="COUNTS",
                   help="plant: the encoder's zero off by this many counts")
    s.add_argument("--torque-delay", type=int, default=None, metavar="SAMPLES",
                   help="plant: the torque read this many whole samples late")
    s.add_argument("--no-compensation", action="store_true",
                   help="with plant effects: the rigid design (the observer and the controllers blind to them); "
                        "default: the tendon's stretch off the encoder, the command as the observer's torque, the "
                        "identified friction's feedforward")
    s.add_argument("--force-scale", type=_strict_float, default=None, metavar="SCALE",
                   help="sensorless controller on a finger with plant effects: the force estimate divided by SCALE "
                        "(0.5-2; a one-point calibration against the fingertip sensor, control.force_scale_of: 1.05 "
                        "undoes a torque constant 5 %% high, which the encoder cannot see)")
    s.add_argument("--calibrate", action="store_true",
                   help="sensorless controller on a finger with plant effects: first a calibration run (another noise "
                        "draw, seed + 1000) reads the scale, the estimate over the fingertip sensor at the first level; "
                        "the loop then runs with it (--force-scale given by the data)")
    s.add_argument("--duration", type=_positive_seconds, default=None,
                   help="simulated time, s (default 3 for a finger or a URDF, 3.5 for the hand)")
    s.add_argument("--seed", type=_SEED, default=0, help="random seed (default %(default)s)")
    s.add_argument("--log", metavar="FILE.csv", help="write the traces (t, F_ref, F_z, q, q_hat, tau_m) as CSV")
    s.add_argument("--plot", metavar="FILE.png", help="write a figure of force, torque and joints")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.add_argument("--force", action="store_true", help=FORCE_USE_HELP)
    s.set_defaults(func=cmd_control)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``alpes-dyn`` and of each of its commands (which set ``func``, the command to run)."""
    p = _Parser(prog="alpes-dyn", description=DESCRIPTION,
                epilog="Vectors: comma-separated numbers; negative values as --q=-0.1,0.2 (or --q -0.1,0.2).")
    p.add_argument("--version", action="version", version=f"alpes-dyn {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in (_add_urdf, _add_mjcf, _add_import, _add_dynamics, _add_report, _add_observability, _add_linearize,
                _add_estimate, _add_codegen, _add_experiment, _add_identify, _add_identifiability, _add_sweep,
                _add_control):
        add(sub)
    return p
