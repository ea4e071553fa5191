"""The planar finger against an independent closed-form Lagrangian (report eq. 2.1-2.5, 2.10-2.14).

The reference is derived here with sympy from the kinetic and potential energies only (E, U), the
report's own method, with the table's parameters read straight from the TOML file; nothing of
Pinocchio, ADAM or alpes_dyn's dynamics code is used.
"""

from __future__ import annotations

import functools
import tomllib

import numpy as np
import pytest
import sympy as sp

import alpes_dyn as ad
from alpes_dyn.model.params import default_params_path

RAW = tomllib.loads(default_params_path().read_text())
FINGER = {k: v["value"] for k, v in RAW["finger"].items()}
FRICTION = {k: v["value"] for k, v in RAW["friction"].items()}
TRANS = {k: v["value"] for k, v in RAW["transmission"].items()}
G0 = 9.81


@functools.lru_cache(maxsize=None)
def closed_form(n: int):
    """Lambdified A(q), C(q, qd) qd, dU/dq (gravity only) of an n-phalanx planar finger, from E and U."""
    q = sp.symbols(f"q1:{n + 1}")
    qd = sp.symbols(f"qd1:{n + 1}")
    L, s, m, I = (FINGER[k][:n] for k in ("L", "s", "m", "I"))
    E = 0
    U = 0
    th = 0
    base = sp.Matrix([0, 0])  # (x, z) of joint i
    for i in range(n):
        th = th + q[i]
        d = L[i] - s[i]  # COM distance from joint i
        c = base + d * sp.Matrix([sp.cos(th), sp.sin(th)])
        cd = sp.Matrix([sum(sp.diff(ci, qj) * qdj for qj, qdj in zip(q, qd)) for ci in c])
        thd = sum(qd[: i + 1])
        E += sp.Rational(1, 2) * m[i] * (cd.T * cd)[0] + sp.Rational(1, 2) * (I[i] - m[i] * d**2) * thd**2
        U += m[i] * G0 * c[1]
        base = base + L[i] * sp.Matrix([sp.cos(th), sp.sin(th)])
    A = sp.hessian(E, qd)  # eq. 2.3
    # eq. 2.5: C qd = A_dot qd - dE/dq
    Adot = sp.Matrix(n, n, lambda i, j: sum(sp.diff(A[i, j], qk) * qdk for qk, qdk in zip(q, qd)))
    Cqd = Adot * sp.Matrix(qd) - sp.Matrix([sp.diff(E, qi) for qi in q])
    Gg = sp.Matrix([sp.diff(U, qi) for qi in q])
    tip = base
    J = tip.jacobian(q)
    f = sp.lambdify([q, qd], [A, Cqd, Gg, J], "numpy")
    return lambda qq, vv: [np.array(x, dtype=float) for x in f(qq, vv)]


def spring_k(n: int, model: str) -> np.ndarray:
    K = np.array(FINGER["K"][:n])
    return {"torsional": K, "report": K * (FINGER["b"] / 2 + FINGER["r"]) ** 2, "none": 0 * K}[model]


def rel(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / max(np.max(np.abs(b)), 1e-300)


CASES = [(name, spring, extra) for name in ("finger2", "finger3") for spring in ad.SPRING_MODELS
         for extra in (False, True)]


@pytest.mark.parametrize("name,spring,extra", CASES)
def test_against_closed_form_lagrangian(name, spring, extra, rng):
    n = 2 if name == "finger2" else 3
    m = ad.Model.alpes(name, spring=spring, friction=extra, rotor_inertia=extra)
    ref = closed_form(n)
    k = spring_k(n, spring)
    # the rotor J_m on the tendon q_m = (r/r_m)(q_1 + ... + q_n): (r/r_m)^2 J_m on every entry (eq. 2.8)
    Ia = (FINGER["r"] / TRANS["r_m"]) ** 2 * TRANS["J_m"] * np.ones((n, n)) if extra else np.zeros((n, n))
    Fs, Fv = (FRICTION["F_s"], FRICTION["F_v"]) if extra else (0.0, 0.0)
    for _ in range(10):
        q = rng.uniform(-1.5, 1.5, n)
        v = rng.uniform(-3, 3, n)
        tau = rng.normal(scale=0.05, size=n)
        Fz = rng.normal()
        A, Cqd, Gg, J = ref(q, v)
        Afull = A + Ia
        G = Gg.ravel() + k * q
        fric = Fs * np.sign(v) + Fv * v
        assert rel(m.inertia_matrix(q), Afull) < 1e-10
        assert rel(m.coriolis_matrix(q, v) @ v, Cqd.ravel()) < 1e-10
        assert rel(m.gravity_torque(q), G) < 1e-10
        assert np.max(np.abs(m.spring_torque(q) - k * q)) <= 1e-15 * max(np.max(np.abs(k * q)), 1.0)
        assert np.max(np.abs(m.friction_torque(v) - fric)) <= 1e-15 * max(np.max(np.abs(fric)), 1.0)
        # J rows are (x, z); F = [0, 0, F_z] (eq. 2.13) gives J^T F = F_z * (z row)
        qdd_ref = np.linalg.solve(Afull, tau + J[1] * Fz - Cqd.ravel() - G - fric)
        assert rel(m.forward_dynamics(q, v, tau, F=[0.0, 0.0, Fz]), qdd_ref) < 1e-10
        assert rel(m.forward_dynamics(q, v, tau, F=Fz), qdd_ref) < 1e-10  # scalar = F_z
        assert rel(m.inverse_dynamics(q, v, qdd_ref, F=[0.0, 0.0, Fz]), tau) < 1e-9
        assert rel(m.contact_torque(q, Fz), J[1] * Fz) < 1e-12


@pytest.mark.parametrize("name", ["finger2", "finger3"])
def test_jacobian_is_the_reports(name, rng):
    """Report Section 2.2: rows x and z non-zero, row y zero."""
    m = ad.Model.alpes(name)
    n = m.n
    L = np.array(FINGER["L"][:n])
    for _ in range(10):
        q = rng.uniform(-2, 2, n)
        th = np.cumsum(q)
        J = np.zeros((3, n))
        for i in range(n):
            J[0, i] = -sum(L[j] * np.sin(th[j]) for j in range(i, n))
            J[2, i] = sum(L[j] * np.cos(th[j]) for j in range(i, n))
        assert np.max(np.abs(m.fingertip_jacobian(q) - J)) < 1e-15
        # and the sympy closed form agrees on x and z rows
        Jc = closed_form(n)(q, np.zeros(n))[3]
        assert np.max(np.abs(J[[0, 2]] - Jc)) < 1e-15


def test_spring_models_scale(rng):
    """eq. 2.14 read literally ('report') is (b/2 + r)^2 = 3.025e-5 times the torsional law."""
    q = rng.uniform(0.1, 1.0, 3)
    t = ad.Model.alpes("finger3", spring="torsional").spring_torque(q)
    r = ad.Model.alpes("finger3", spring="report").spring_torque(q)
    assert np.allclose(r / t, (0.003 / 2 + 0.004) ** 2, rtol=1e-14)
    assert np.allclose(t, np.array([0.04, 0.05, 0.06]) * q, rtol=1e-14)
    assert np.all(ad.Model.alpes("finger3", spring="none").spring_torque(q) == 0)
    # gravity torque at rest against the 'report' springs' torque per radian: about 10^4
    g = ad.Model.alpes("finger3", spring="none").gravity_torque(np.zeros(3))
    k_report = ad.Model.alpes("finger3", spring="report").extras.stiffness
    assert 1e3 < np.max(np.abs(g)) / np.max(k_report) < 1e5
