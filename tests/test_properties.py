"""Property-based tests (hypothesis) of the invariants of eq. 2.10 over random valid models and states.

Models: random serial chains of 1-4 revolute joints written as URDF text here (random lengths,
masses, COM offsets, box-shaped inertias -- so physical --, joint axes and frames) with random
springs, friction and rotor inertia; and random finger parameters written into a parameter file
(the Alpes path: parameter file -> URDF -> model). Invariants:

* A(q) (+ I_a) symmetric positive definite;
* A_dot - 2 C skew-symmetric (A_dot by a central difference along v);
* inverse_dynamics(forward_dynamics(tau)) = tau (with springs, friction, a contact force);
* power: d/dt (kinetic + potential energy) = v . (tau - friction) (central difference along the
  flow), and the friction's power -v . f(v) <= 0;
* work-energy over one RK4 step with friction off: E(x_1) - E(x_0) = tau . (q_1 - q_0) (tau held);
* a compiled rollout equals simulate(method="rk4").

Sizes are small (max_examples 3-25, deadline None, derandomized) so that the module runs in seconds.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import alpes_dyn as ad
from alpes_dyn.model.params import default_params_path
from alpes_dyn.simulation import CompiledRollout, simulate

# derandomize: CI sees the same examples every run (a failure is reproducible); database=None: no .hypothesis/
SETTINGS = dict(deadline=None, database=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
pos = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False, allow_subnormal=False)  # noqa: E731
# (a subnormal number, e.g. 1e-320, is refused in a parameter file: alpes_dyn.limits.check_physical)


@st.composite
def chains(draw, max_joints: int = 4) -> ad.Model:
    """A random physical serial chain of revolute joints with random extras."""
    n = draw(st.integers(1, max_joints))
    parts = ['<robot name="chain">', '<link name="base"/>']
    parent, prev_L = "base", 0.0
    for i in range(n):
        L = draw(pos(0.01, 0.1))
        m = draw(pos(0.005, 0.2))
        d = draw(pos(0.0, 1.0)) * L
        a, b, c = (draw(pos(0.005, 0.05)) for _ in range(3))  # a box a x b x c: its inertia is physical
        ixx, iyy, izz = m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12
        axis = np.array([draw(pos(-1, 1)) for _ in range(3)])
        axis = axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 0.1 else np.array([0.0, -1.0, 0.0])
        rpy = [draw(pos(-3.1, 3.1)) for _ in range(3)]
        parts += [
            f'<link name="l{i}"><inertial><origin xyz="{d!r} 0 0" rpy="0 0 0"/><mass value="{m!r}"/>'
            f'<inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" izz="{izz!r}"/></inertial></link>',
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="{prev_L!r} 0 0" rpy="{rpy[0]!r} {rpy[1]!r} {rpy[2]!r}"/>'
            f'<axis xyz="{" ".join(repr(float(x)) for x in axis)}"/>'
            f'<limit lower="-2.5" upper="2.5" effort="1" velocity="20"/></joint>',
        ]
        parent, prev_L = f"l{i}", L
    parts += ['<link name="tip"/>', f'<joint name="tip_joint" type="fixed"><parent link="{parent}"/>'
              f'<child link="tip"/><origin xyz="{prev_L!r} 0 0" rpy="0 0 0"/></joint>', "</robot>"]
    extras = ad.JointExtras(
        stiffness=np.array([draw(pos(0.0, 0.1)) for _ in range(n)]),
        armature=np.array([draw(pos(0.0, 1e-5)) for _ in range(n)]),
        coulomb=np.array([draw(pos(0.0, 0.005)) for _ in range(n)]),
        viscous=np.array([draw(pos(0.0, 0.01)) for _ in range(n)]),
        smooth_velocity=draw(pos(0.005, 0.05)),
    )
    return ad.Model("\n".join(parts), extras=extras)


BASE_TOML = default_params_path().read_text(encoding="utf-8")


@st.composite
def alpes_fingers(draw) -> ad.Model:
    """finger3 from a parameter file with random phalanges and springs (physically consistent:
    I about the joint = m d^2 + I_com with I_com >= m rho^2 / 4, the URDF's triangle inequality)."""
    L = [draw(pos(0.02, 0.08)) for _ in range(3)]
    s = [draw(pos(0.2, 0.8)) * x for x in L]
    m = [draw(pos(0.005, 0.05)) for _ in range(3)]
    I = [mi * (Li - si) ** 2 + mi * Li**2 * draw(pos(0.05, 0.5)) for mi, Li, si in zip(m, L, s)]
    K = [draw(pos(0.0, 0.1)) for _ in range(3)]
    text = BASE_TOML
    for key, vals in (("L", L), ("s", s), ("m", m), ("I", I), ("K", K)):
        text, k = re.subn(rf"^{key} = \{{ value = \[[^\]]*\]", f"{key} = {{ value = [{', '.join(map(repr, vals))}]",
                          text, count=1, flags=re.M)
        assert k == 1
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "finger.toml"
        path.write_text(text, encoding="utf-8")
        return ad.Model.alpes("finger3", friction=True, rotor_inertia=True, params=path)


models = st.one_of(chains(), alpes_fingers())


def state(model: ad.Model, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q, v = model.random_state(rng)
    return q, v, rng.uniform(-0.05, 0.05, model.n)


seeds = st.integers(0, 2**32 - 1)


@settings(max_examples=25, **SETTINGS)
@given(models, seeds)
def test_inertia_symmetric_positive_definite(model, seed):
    q, _, _ = state(model, seed)
    A = model.inertia_matrix(q)
    assert np.array_equal(A, A.T)
    assert np.linalg.eigvalsh(A).min() > 1e-9 * np.abs(A).max()
    np.linalg.cholesky(A)


@settings(max_examples=25, **SETTINGS)
@given(models, seeds)
def test_adot_minus_2c_skew(model, seed):
    q, v, _ = state(model, seed)
    h = 1e-6
    Adot = (model.inertia_matrix(q + h * v) - model.inertia_matrix(q - h * v)) / (2 * h)
    C = model.coriolis_matrix(q, v)
    N = Adot - 2 * C
    rounding = np.finfo(float).eps / h * np.abs(model.inertia_matrix(q)).max() * (1 + np.abs(v).max())
    assert np.abs(N + N.T).max() <= 1e-6 * (np.abs(Adot).max() + np.abs(C).max()) + 100 * rounding


@settings(max_examples=25, **SETTINGS)
@given(models, seeds, st.booleans())
def test_inverse_of_forward_is_identity(model, seed, smooth):
    q, v, tau = state(model, seed)
    F = np.random.default_rng(seed + 1).uniform(-0.5, 0.5, 3)
    a = model.forward_dynamics(q, v, tau, F, smooth=smooth)
    back = model.inverse_dynamics(q, v, a, F, smooth=smooth)
    assert np.allclose(back, tau, rtol=1e-9, atol=1e-12 * (1 + np.abs(tau).max()))


def energy(model: ad.Model, q: np.ndarray, v: np.ndarray) -> float:
    return model.kinetic_energy(q, v) + model.potential_energy(q)


@settings(max_examples=25, **SETTINGS)
@given(models, seeds)
def test_power_balance_with_springs_and_friction(model, seed):
    """dE/dt = v . (tau - f(v)) along the flow, and friction never supplies power."""
    q, v, tau = state(model, seed)
    for smooth in (False, True):
        f = model.friction_torque(v, smooth)
        assert -v @ f <= 0.0
        a = model.forward_dynamics(q, v, tau, smooth=smooth)
        h = 1e-7
        dE = (energy(model, q + h * v, v + h * a) - energy(model, q - h * v, v - h * a)) / (2 * h)
        power = v @ (tau - f)
        scale = abs(v @ tau) + abs(v @ f) + abs(v @ model.gravity_torque(q)) + abs(v @ model.inertia_matrix(q) @ a)
        assert abs(dE - power) <= 1e-5 * scale + 1e-12


def _natural_frequency(model: ad.Model, q: np.ndarray) -> float:
    """Largest sqrt(eig(A^-1 dG/dq)) (rad/s): the fastest oscillation of the linearised model."""
    ev = np.linalg.eigvals(np.linalg.solve(model.inertia_matrix(q), model.gravity_jacobian(q)))
    return float(np.sqrt(np.abs(ev).max()))


@settings(max_examples=15, **SETTINGS)
@given(models, seeds)
def test_work_energy_over_an_rk4_step(model, seed):
    """Friction off: E(x_1) - E(x_0) = tau . (q_1 - q_0) for tau held over the step (to RK4's O(dt^5))."""
    model = ad.Model(model.urdf, extras=ad.JointExtras(model.extras.stiffness, model.extras.armature,
                                                        np.zeros(model.n), np.zeros(model.n)),
                     gravity=model.gravity)
    q, v, tau = state(model, seed)
    omega = _natural_frequency(model, q) + np.abs(v).max() + 1.0
    dt = 1e-3 / omega
    res = simulate(model, np.concatenate([q, v]), tau, duration=dt, dt=dt, output=np.eye(model.n)[:1])
    q1, v1 = res.q[-1], res.v[-1]
    dE = energy(model, q1, v1) - energy(model, q, v)
    work = tau @ (q1 - q)
    scale = model.kinetic_energy(q, v) + abs(model.potential_energy(q)) + abs(work)
    assert abs(dE - work) <= 1e-9 * scale


@pytest.fixture(scope="module")
def rollout_cache(tmp_path_factory):
    """Random models compile libraries of their own: keep them out of the shared cache."""
    mp = pytest.MonkeyPatch()
    mp.setenv("ALPES_DYN_CACHE", str(tmp_path_factory.mktemp("rollouts")))
    yield
    mp.undo()


@settings(max_examples=3, **SETTINGS)
@given(chains(max_joints=3), seeds)
def test_rollout_equals_simulate(rollout_cache, model, seed):
    q, v, _ = state(model, seed)
    rng = np.random.default_rng(seed)
    N, dt = 20, 1e-3
    U = rng.uniform(-0.02, 0.02, (N, model.n))
    X = CompiledRollout(model, dt, threads=1).rollout(np.concatenate([q, v]), U)[0]
    ref = simulate(model, np.concatenate([q, v]), U, duration=N * dt, dt=dt, output=np.eye(model.n)[:1]).x
    assert np.allclose(X, ref, rtol=1e-12, atol=1e-12 * (1 + np.abs(ref).max()))
