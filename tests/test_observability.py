"""Nonlinear observability rank test (report Chapter 3, eq. 3.4-3.8, 3.14).

References, all independent of alpes_dyn's code:
* the report's results: finger2 with y = q1 + q2 has rank 4 of 4, finger3 with y = q1 + q2 + q3 rank 6 of 6;
* a closed-form sympy model of the two-phalanx finger (Lagrangian from E and U, parameters read from the
  TOML file), whose output derivatives y, y', y'', y''' (by sympy.diff, time-varying input) are compared
  with CasADi's, and whose finite-difference Jacobian is compared with O;
* rank bounds from the structure: one output adds at most one rank per derivative order, p outputs at
  most p (so the index of a single-output observable system is n - 1);
* symmetries that make a state unobservable: without gravity and springs a planar finger is invariant
  under q1 -> q1 + c, so y = q2 cannot see q1; the thumb's ab/adduction axis is parallel to gravity and has
  no spring, so its angle cannot be seen by the thumb's flexion encoder alone.
"""

from __future__ import annotations

import functools
import json
import re
import tomllib

import casadi as cs
import numpy as np
import pytest
import sympy as sp

import alpes_dyn as ad
from alpes_dyn import cli
from alpes_dyn.analysis.observability import (ObservabilityMatrix, normalised_singular_values, numerical_rank,
                                     observability)
from alpes_dyn.model.params import default_params_path
from alpes_dyn.symbolic.statespace import StateSpace

RAW = tomllib.loads(default_params_path().read_text())
FINGER = {k: v["value"] for k, v in RAW["finger"].items()}
G0 = -RAW["environment"]["gravity"]["value"][2]


@functools.lru_cache(maxsize=None)
def report(name: str, **kw):
    return observability(name, **kw)


# ----------------------------------------------------------------------------- the report's results
@pytest.mark.parametrize("name,n", [("finger2", 4), ("finger3", 6)])
def test_report_ranks(name, n):
    """Eq. 3.8 with O = d(y, ..., y^(n-1))/dx exactly as the report: rank n, observable."""
    r = observability(name, order="report")
    assert (r.n_states, r.n_outputs, r.rank, r.observable) == (n, 1, n, True)
    assert r.order == n - 1 and r.ranks_by_order == tuple(range(1, n + 1))
    auto = report(name)
    assert (auto.rank, auto.order, auto.index) == (n, n - 1, n - 1)  # one output: at most +1 per order
    assert 0 < auto.min_singular_value <= 1 and auto.condition == pytest.approx(1 / auto.min_singular_value)


@pytest.mark.parametrize("name", ["finger2", "finger3"])
@pytest.mark.parametrize("inp", ["joint", "motor"])
@pytest.mark.parametrize("spring", ["report", "torsional", "none"])
def test_fingers_observable_with_every_input_and_spring(name, inp, spring):
    n = 4 if name == "finger2" else 6
    r = observability(name, input=inp, spring=spring, points=4)
    assert (r.rank, r.index, r.observable) == (n, n - 1, True)
    assert r.rank_drops == []
    # at rest the finger lies straight along the horizontal: without springs nothing but gravity, whose
    # gradient vanishes there to first order, stiffens it
    c = observability(name, input=inp, spring=spring, points=4, constant_input=True)
    assert c.rank == n


def test_hand_whole_and_parts():
    r = report("hand")
    assert (r.n_states, r.n_outputs, r.rank, r.observable) == (30, 6, 30, True)
    names = [p.model for p in r.parts]
    assert names == ["index", "middle", "ring", "little", "thumb"]
    for p in r.parts:
        assert (p.n_states, p.rank, p.observable, p.coupled) == (6, 6, True, False)
        assert p.n_outputs == (2 if p.model == "thumb" else 1)
        # p outputs add at most p ranks per order: index >= 6 / p - 1; the fingers need all of y..y^(5)
        assert p.index == (2 if p.model == "thumb" else 5)
    assert r.index == 5
    # block structure: the whole rank is the sum of the parts' at every order
    assert r.ranks_by_order == tuple(np.sum([p.ranks_by_order for p in r.parts], axis=0))
    d = r.to_dict()
    for key in ("model", "n_states", "n_outputs", "rank", "observable", "rank_at_rest", "min_singular_value",
                "condition", "index", "seconds", "parts"):
        assert key in d and all(key in p for p in d["parts"])
    json.dumps(d)


def test_hand_encoders_and_motor_input():
    r = observability("hand", input="motor", output="encoder", points=4)
    assert r.rank == 30 and [p.rank for p in r.parts] == [6] * 5


# ----------------------------------------------------------------------------- against a closed form
@functools.lru_cache(maxsize=None)
def closed_form_outputs(spring: str = "torsional"):
    """y, y', y'', y''' of the two-phalanx finger, y = q1 + q2, u = joint torques, as numpy functions of
    (x (4,), w = [u, u', u''] (6,)), from the Lagrangian (report eq. 2.1-2.5, 2.11, 2.14, 3.11-3.13)."""
    n = 2
    q, qd = sp.symbols("q1:3"), sp.symbols("qd1:3")
    L, s, m, I = (FINGER[k][:n] for k in ("L", "s", "m", "I"))
    k = {"torsional": FINGER["K"][:n], "none": [0, 0]}[spring]
    E = U = sp.Integer(0)
    th, base = sp.Integer(0), sp.Matrix([0, 0])
    for i in range(n):
        th = th + q[i]
        d = L[i] - s[i]
        c = base + d * sp.Matrix([sp.cos(th), sp.sin(th)])
        cd = c.jacobian(q) * sp.Matrix(qd)
        E += sp.Rational(1, 2) * m[i] * (cd.T * cd)[0] + sp.Rational(1, 2) * (I[i] - m[i] * d**2) * sum(qd[: i + 1]) ** 2
        U += m[i] * G0 * c[1] + sp.Rational(1, 2) * k[i] * q[i] ** 2
        base = base + L[i] * sp.Matrix([sp.cos(th), sp.sin(th)])
    A = sp.hessian(E, qd)
    Adot = sp.Matrix(n, n, lambda i, j: sum(sp.diff(A[i, j], a) * b for a, b in zip(q, qd)))
    rhs_bias = Adot * sp.Matrix(qd) - sp.Matrix([sp.diff(E, a) for a in q]) + sp.Matrix([sp.diff(U, a) for a in q])
    us = [sp.Matrix(sp.symbols(f"u{j}_1:3")) for j in range(3)]
    Ainv = sp.Matrix([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]]) / (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0])
    qdd = Ainv * (us[0] - rhs_bias)  # eq. 3.12
    x = list(q) + list(qd)
    f = list(qd) + list(qdd)
    phis = [q[0] + q[1]]
    for order in range(1, 4):
        phi = phis[-1]
        dphi = sum(sp.diff(phi, a) * b for a, b in zip(x, f))
        for j in range(order - 1):
            dphi += sum(sp.diff(phi, a) * b for a, b in zip(us[j], us[j + 1]))
        phis.append(dphi)
    fn = sp.lambdify([x, [a for u in us for a in u]], phis, "numpy", cse=True)
    return lambda xx, ww: np.array(fn(list(xx), list(ww)), dtype=float)


def finite_difference_O(fn, x, w, h=1e-6):
    cols = [(fn(x + h * e, w) - fn(x - h * e, w)) / (2 * h) for e in np.eye(x.size)]
    return np.column_stack(cols)


def test_output_derivatives_and_O_match_closed_form(rng):
    ref = closed_form_outputs()
    om = ObservabilityMatrix(StateSpace(ad.Model.alpes("finger2")))
    F = cs.Function("Y", [om.x, om._w(3)], [cs.vertcat(*(om.lie_derivative(k) for k in range(4)))])
    for _ in range(5):
        x = np.concatenate([rng.uniform(0, 1.5, 2), rng.uniform(-2, 2, 2)])
        w = rng.uniform(-0.05, 0.05, 6)
        y_ref = ref(x, w)
        y = np.asarray(F(x, w)).reshape(-1)
        assert np.allclose(y, y_ref, rtol=1e-9, atol=1e-9 * np.abs(y_ref).max())
        O = om.evaluate(3, x, w)
        Ofd = finite_difference_O(ref, x, w)
        scale = np.abs(Ofd).max(axis=1, keepdims=True)
        assert np.all(np.abs(O - Ofd) <= 1e-5 * scale)
        # constant input: the same as time-varying with u' = u'' = 0
        oc = ObservabilityMatrix(StateSpace(ad.Model.alpes("finger2")), constant_input=True)
        w0 = np.concatenate([w[:2], np.zeros(4)])
        assert np.allclose(oc.evaluate(3, x, w[:2]), finite_difference_O(ref, x, w0), rtol=0,
                           atol=1e-5 * np.abs(oc.evaluate(3, x, w[:2])).max())


def test_rank_at_rest_matches_closed_form():
    """Without springs the straight finger at rest (x = 0, u = 0) loses rank; with springs it does not."""
    for spring, expect in (("none", 2), ("torsional", 4)):
        ref = closed_form_outputs(spring)
        Ofd = finite_difference_O(ref, np.zeros(4), np.zeros(6))
        # each row in the units of its size at a generic state (finite-difference noise stays small)
        typical = np.abs(finite_difference_O(ref, np.array([0.4, 0.7, 1.0, -0.5]), np.full(6, 0.02))).max(axis=1)
        s = np.linalg.svd(Ofd / typical[:, None], compute_uv=False)
        assert int(np.sum(s > 1e-6 * s[0])) == expect  # the reference's own tolerance
        r = observability("finger2", spring=spring, points=4)
        assert r.rank_at_rest == expect and r.rank == 4


# ----------------------------------------------------------------------------- unobservable systems
def free_finger2() -> ad.Model:
    m0 = ad.Model.alpes("finger2", spring="none")
    return ad.Model(m0.urdf, gravity=[0.0, 0.0, 0.0], name="free_finger2")


@pytest.mark.parametrize("order", ["auto", "report"])
def test_output_blind_to_a_joint_is_unobservable(order):
    """No gravity, no spring, y = q2: q1 is a symmetry, rank 3 of 4 with null direction dq1."""
    r = observability(StateSpace(free_finger2(), output=np.array([[0.0, 1.0]])), order=order)
    assert (r.rank, r.observable) == (3, False)
    assert r.ranks_by_order == (1, 2, 3, 3) and r.index == 2
    v = r.unobservable_directions
    assert v.shape == (4, 1) and abs(abs(v[0, 0]) - 1) < 1e-9
    assert not np.isfinite(r.condition) and r.to_dict()["condition"] is None
    json.dumps(r.to_dict(), allow_nan=False)
    # the same output with gravity sees q1 again
    assert observability(ad.Model.alpes("finger2", spring="none"), output=np.array([[0.0, 1.0]])).rank == 4


def test_hand_without_abduction_encoder():
    hand = ad.Model.alpes("hand")
    H = hand.transmission.sum_matrix[:5]  # every encoder but the thumb's ab/adduction
    r = observability(StateSpace(hand, output=H), points=4)
    assert (r.rank, r.observable) == (29, False)
    thumb = r.parts[-1]
    assert (thumb.model, thumb.n_outputs, thumb.rank) == ("thumb", 1, 5)
    v = r.unobservable_directions[:, 0]
    assert abs(abs(v[hand.joint_names.index("thumb_abd")]) - 1) < 1e-9
    assert all(p.rank == 6 for p in r.parts[:4])
    # parts chosen by the user: the thumb's flexion joints alone; their output derivatives also depend on the
    # ab/adduction velocity (centrifugal and Coriolis terms), so the part is reported as coupled
    r2 = observability(StateSpace(hand, output=H), points=4, parts={"thumb_flexion": ["thumb_j1", "thumb_j2"]})
    (p,) = r2.parts
    assert (p.n_states, p.n_outputs, p.coupled) == (4, 1, True)


# ----------------------------------------------------------------------------- the rank rule
def test_rank_is_scale_aware(rng):
    """Row scaling (outputs in other units, derivatives of higher order) changes neither rank nor s_n/s_1."""
    A = rng.normal(size=(6, 6))
    D = np.diag(10.0 ** np.arange(0, 18, 3))  # rows from 1 to 1e15
    assert numerical_rank(D @ A) == 6 and np.linalg.matrix_rank(D @ A) < 6  # numpy's raw rule fails here
    assert np.allclose(normalised_singular_values(D @ A), normalised_singular_values(A), rtol=1e-9)
    B = A.copy()
    B[5] = 2 * B[0] - 1e-3 * B[3]  # exactly dependent
    assert numerical_rank(D @ B) == 5
    assert numerical_rank(np.zeros((3, 4))) == 0
    s = normalised_singular_values(np.ones((2, 4)))  # two equal rows, fewer rows than columns
    assert s.shape == (4,) and s[0] == 1.0 and np.all(np.abs(s[1:]) < 1e-15) and numerical_rank(np.ones((2, 4))) == 1


# ----------------------------------------------------------------------------- errors and CLI
def test_bad_input():
    with pytest.raises(ad.ModelError, match=r"unknown output 'tip'"):
        observability("finger2", output="tip")
    with pytest.raises(ad.ModelError, match=r"unknown input 'current'"):
        observability("finger2", input="current")
    with pytest.raises(ad.ModelError, match=r"output matrix: expected a finite \(p, 2\) or \(p, 4\) array, got shape \(1, 3\)"):
        observability("finger2", output=np.ones((1, 3)))
    with pytest.raises(ad.ModelError, match=r"unknown model 'finger4'"):
        observability("finger4")
    with pytest.raises(ad.InputError, match=r"points: expected a positive integer, got 0"):
        observability("finger2", points=0)
    with pytest.raises(ad.InputError, match=r"order: expected 'auto', 'report' or a non-negative integer"):
        observability("finger2", order="all")
    with pytest.raises(ad.ModelError, match=r"parts: unknown joint 'thumb_j3' in part 'thumb'"):
        observability("hand", parts={"thumb": ["thumb_j1", "thumb_j3"]})
    ss = StateSpace(ad.Model.alpes("finger2"))
    with pytest.raises(ad.ModelError, match=r"input/output: a StateSpace has its own"):
        observability(ss, output="sum")
    om = ObservabilityMatrix(ss)
    with pytest.raises(ad.InputError, match=r"x: expected shape \(4,\) or \(N, 4\), got \(3,\)"):
        om.evaluate(2, np.zeros(3), np.zeros(4))
    with pytest.raises(ad.InputError, match=r"w: expected shape \(4,\) or \(N, 4\)"):
        om.evaluate(2, np.zeros(4), np.zeros(2))
    with pytest.raises(ad.InputError, match=r"x: contains NaN"):
        om.evaluate(1, np.array([0, np.nan, 0, 0]), np.zeros(2))
    with pytest.raises(ad.InputError, match=r"order: expected a non-negative integer, got -1"):
        om.evaluate(-1, np.zeros(4), np.zeros(2))


def test_cli_json_and_text(capsys):
    assert cli.main(["observability", "--model", "finger2", "--json", "--points", "4"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert (d["model"], d["n_states"], d["n_outputs"], d["rank"], d["observable"], d["index"]) == (
        "finger2", 4, 1, 4, True, 3)
    assert d["parts"] == [] and d["seconds"] > 0 and d["rank_at_rest"] == 4
    assert cli.main(["observability", "--model", "finger3", "--input", "motor", "--spring", "none",
                     "--constant-input", "--order", "report"]) == 0
    out = capsys.readouterr().out
    assert "input motor (1)" in out and "spring none" in out and "constant input" in out
    assert "finger3" in out and "6/6" in out and "4/6" in out  # rank 6 of 6, 4 at rest (no spring)


@pytest.mark.parametrize("argv,pattern", [
    (["--points", "0"], r"--points: expected an integer from 1 to 10000, got 0"),
    (["--order", "x"], r"--order: expected auto, report or a non-negative integer, got 'x'"),
    (["--output", "tip"], r"unknown output 'tip'"),
    (["--input", "current"], r"argument --input: invalid choice: 'current'"),
])
def test_cli_errors(argv, pattern, capsys):
    assert cli.main(["observability", "--model", "finger2", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert re.search(pattern, err)


def test_cli_urdf_without_transmission(capsys):
    path = str(ad.example_robot_urdf("double_pendulum"))
    assert cli.main(["observability", "--model", path]) == 2
    assert "output 'sum' needs a tendon transmission" in capsys.readouterr().err


# ----------------------------------------------------------------------------- names and the size cap
def test_module_is_reachable_and_function_renamed():
    import importlib

    mod = importlib.import_module("alpes_dyn.analysis.observability")
    assert ad.observability is mod and mod.__name__ == "alpes_dyn.analysis.observability"
    assert ad.check_observability is mod.check_observability is mod.observability is observability
    r = ad.observability("finger2", points=2)  # the former spelling still works (the module is callable)
    assert (r.rank, r.n_states) == (4, 4)


def test_operation_cap_is_a_parameter_with_a_true_message():
    """finger3 needs orders past y^(3); a tiny cap stops it with a message naming the parameter, not order."""
    ss = StateSpace(ad.Model.alpes("finger3"))
    small = ObservabilityMatrix(ss, max_operations=10)
    for k in range(3):
        small.block(k)  # the first orders are never refused (the estimate needs three of them)
    need = 3 * small.block(2).n_instructions()
    with pytest.raises(ad.InputError, match=rf"max_operations: d y\^\(3\)/dx would need about {need} operations, "
                                            r"more than max_operations=10 \(raise it"):
        small.block(3)
    with pytest.raises(ad.InputError, match=r"max_operations: d y\^\(3\)/dx would need"):
        observability("finger3", max_operations=10)  # order='auto' is in use: the message does not suggest it
    assert ObservabilityMatrix(ss, max_operations=need).block(3).n_instructions() > 0
    with pytest.raises(ad.InputError, match=r"max_operations: expected a positive integer, got 0"):
        observability("finger3", max_operations=0)
    assert cli.main(["observability", "--model", "finger3", "--max-operations", "10"]) == 2
    assert cli.main(["observability", "--model", "finger3", "--max-operations", "x"]) == 2
