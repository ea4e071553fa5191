"""A compiled loop's library is built at -O1 first and rebuilt at -O3 once the loop has run enough steps to pay for
it (:class:`~alpes_dyn.simulation.codegen.CompiledStepLoop`, :func:`~alpes_dyn.simulation.buildcache.
cached_library`): the flags seen by the compiler, the cached -O3 build loaded without a build, and the same numbers
before and after the promotion (a finger's RK4 step against its -O3 build and against Pinocchio's RK4 step)."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

from alpes_dyn.simulation import codegen
from alpes_dyn.simulation.buildcache import CompilerError, build_library, cached_library
from alpes_dyn.simulation.codegen import CompiledStepLoop, _CFLAGS, _compiler


@pytest.fixture
def seen(tmp_path, monkeypatch):
    """The optimisation flag of every build, in order (the cache in ``tmp_path``)."""
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path))
    flags: list[str] = []
    monkeypatch.setattr(codegen, "build_library", lambda src, stem, cc, f, d: flags.append(f[0]) or
                        build_library(src, stem, cc, f, d))
    return flags


def _pendulum():
    x, w = cs.SX.sym("x", 2), cs.SX.sym("w", 1)
    step = cs.Function("f", [x, w], [cs.vertcat(x[0] + 0.01 * x[1], x[1] + 0.01 * (w[0] - cs.sin(x[0])))])
    X0, W = np.array([[0.3, -0.2], [1.0, 0.5]]), np.linspace(-1, 1, 2 * 50).reshape(2, 50, 1)
    return step, X0, W


def test_a_loop_is_built_quick_then_promoted_after_its_steps_with_the_same_numbers(seen, monkeypatch):
    """Not cached: built at -O1; runs of 2 x 50 steps under a threshold of 250 keep it; the third run crosses it and
    the loop is rebuilt at -O3 (another library, compiled now), whose run gives the -O1 run's numbers (to
    rounding); a later loop of the same step loads the -O3 build from the cache and never builds again."""
    monkeypatch.setattr(codegen, "_PROMOTE_STEPS", 250)
    step, X0, W = _pendulum()
    loop = CompiledStepLoop(step, "quick", threads=1, vectorize=False)
    assert seen == ["-O1"] and loop.compiled and loop.compile_seconds > 0
    quick = loop.library
    first = loop.run(X0, W)
    loop.run(X0, W)
    assert seen == ["-O1"] and loop.library == quick
    loop.run(X0, W)  # 300 steps run: promoted
    assert seen == ["-O1", "-O3"] and loop.library != quick and loop.compiled
    np.testing.assert_allclose(loop.run(X0, W), first, rtol=1e-14, atol=1e-15)
    again = CompiledStepLoop(step, "quick", threads=1, vectorize=False)
    assert seen == ["-O1", "-O3"] and not again.compiled and again.compile_seconds == 0.0
    assert again.library == loop.library
    for _ in range(4):
        again.run(X0, W)
    assert seen == ["-O1", "-O3"]  # the -O3 build in use: nothing more to build
    found = cached_library(_source_of(step), "quick", _compiler(),
                           _CFLAGS, loop.library.parent)
    assert found is not None and found[0] == loop.library and found[1:3] == (False, 0.0)


def _source_of(step):
    """The C source a scalar loop of ``step`` compiles (as CompiledStepLoop writes it)."""
    ins = step.sx_in()
    named = cs.Function("alpes_step", ins, step.call(ins))
    cg = cs.CodeGenerator("alpes_steploop.c", {"with_header": False})
    cg.add(named)
    fmt = dict(nx=2, nw=1, sz_arg=named.sz_arg(), sz_res=named.sz_res(), sz_iw=named.sz_iw(), sz_w=named.sz_w(),
               step="alpes_step", parg="")
    return "#define _GNU_SOURCE\n" + cg.dump() + codegen._DRIVER.format(lanes=1, vector_code="", **fmt)


def test_cached_library_builds_nothing(tmp_path):
    """An absent library: None, nothing written (the folder not even created); once built, the same path and
    library as build_library's, not compiled again."""
    src = "int alpes_answer(void) { return 42; }\n"
    assert cached_library(src, "answer", _compiler(), _CFLAGS, tmp_path / "c") is None
    assert not (tmp_path / "c").exists()
    path, compiled, _, _ = build_library(src, "answer", _compiler(), _CFLAGS, tmp_path / "c")
    found = cached_library(src, "answer", _compiler(), _CFLAGS, tmp_path / "c")
    assert compiled and found is not None and found[0] == path and found[1:3] == (False, 0.0)
    assert int(found[3].alpes_answer()) == 42
    assert cached_library(src, "answer", _compiler(), ("-O1",) + _CFLAGS[1:], tmp_path / "c") is None


def test_step_never_builds_and_a_failed_promotion_keeps_the_quick_library(seen, monkeypatch):
    """step() (a control loop's sample) counts no step toward the promotion; a promotion whose compiler fails
    leaves the -O1 library in use, its numbers unchanged, and is not tried again."""
    monkeypatch.setattr(codegen, "_PROMOTE_STEPS", 150)
    step, X0, W = _pendulum()
    loop = CompiledStepLoop(step, "failing", threads=1, vectorize=False)
    x = X0[0]
    for k in range(150):
        x = loop.step(x, W[0, k % 50])
    assert seen == ["-O1"]
    quick, first = loop.library, loop.run(X0, W)

    def refuse(src, stem, cc, f, d):
        seen.append(f[0])
        raise CompilerError("compiling failed: refused")

    monkeypatch.setattr(codegen, "build_library", refuse)
    loop.run(X0, W)  # 200 steps: the promotion tried, refused
    assert seen == ["-O1", "-O3"] and loop.library == quick
    np.testing.assert_allclose(loop.run(X0, W), first, rtol=1e-14, atol=1e-15)
    assert seen == ["-O1", "-O3"]


def test_a_fingers_rk4_step_promoted_steps_the_numbers_of_its_o3_build_and_of_pinocchio(seen, monkeypatch):
    """finger3's compiled RK4 roll-out (the motors' torques): its quick build and the build it is promoted to give
    the same states over 2 x 400 steps (to rounding), and one step equals Pinocchio's RK4 step (ABA)."""
    import alpes_dyn as ad
    from alpes_dyn.simulation.integrate import compile_rollout
    from test_simulation import _pinocchio_rk4

    monkeypatch.setattr(codegen, "_PROMOTE_STEPS", 800)
    m = ad.Model.alpes("finger3")
    ro = compile_rollout(m, 1e-3, input="motor", threads=1)
    rng = np.random.default_rng(3)
    X0 = np.array([np.concatenate(m.random_state(rng, speed=0.5)) for _ in range(2)])
    U = 0.02 + 0.005 * rng.standard_normal((2, 400, ro.system.n_inputs))
    quick = ro.rollout(X0, U)
    assert seen == ["-O1", "-O3"]  # 800 steps run: promoted after this run
    np.testing.assert_allclose(ro.rollout(X0, U), quick, rtol=1e-13, atol=1e-15)
    x1 = _pinocchio_rk4(m, X0[0], U[0, :1], [None], 1e-3)[1]
    assert np.max(np.abs(quick[0, 1] - x1)) < 1e-9
