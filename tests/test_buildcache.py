"""The compiled-library cache heals itself: broken libraries are never loaded but rebuilt, killed builds
are cleaned up, concurrent processes compile once (alpes_dyn.simulation.buildcache)."""

from __future__ import annotations

import ctypes
import fcntl
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import casadi as cs
import numpy as np
import pytest

from alpes_dyn.simulation.buildcache import CompilerError, build_library, verify_library
from alpes_dyn.simulation.codegen import CompiledStepLoop, _CFLAGS, _compiler

SOURCE = "int alpes_answer(void) { return 42; }\n"


def build(d: Path, source: str = SOURCE, cc: str | None = None):
    return build_library(source, "answer", cc or _compiler(), _CFLAGS, d)


def answer(lib: ctypes.CDLL) -> int:
    return int(lib.alpes_answer())


def entries(d: Path) -> set[str]:
    return {p.name for p in d.iterdir()}


def test_built_once_then_loaded_verified(tmp_path):
    path, compiled, seconds, lib = build(tmp_path)
    assert compiled and seconds > 0 and answer(lib) == 42
    assert verify_library(path)
    assert entries(tmp_path) == {path.name, path.name + ".sha256", path.stem + ".lock"}
    path2, compiled2, seconds2, lib2 = build(tmp_path)
    assert (path2, compiled2, seconds2) == (path, False, 0.0) and answer(lib2) == 42


def test_the_same_source_under_another_stem_is_loaded_not_compiled(tmp_path):
    """The hand's four fingers generate one source under four stems: the first compiles it, the others load it
    (the key is the source's, compiler's and flags' hash); another source under that stem is compiled."""
    path, compiled, _, _ = build(tmp_path)
    other, compiled2, seconds2, lib2 = build_library(SOURCE, "other", _compiler(), _CFLAGS, tmp_path)
    assert compiled and (other, compiled2, seconds2) == (path, False, 0.0) and answer(lib2) == 42
    source = SOURCE.replace("42", "43")
    new, compiled3, _, lib3 = build_library(source, "other", _compiler(), _CFLAGS, tmp_path)
    assert compiled3 and new != path and new.name.startswith("other_") and int(lib3.alpes_answer()) == 43


def built_elsewhere(tmp_path: Path, source: str = SOURCE) -> tuple[Path, Path]:
    """A library built (and loaded) in cache ``a``, then the cache copied to ``b``: this process has never
    loaded ``b``'s files (the dynamic loader would hand back a library it already has by path or inode)."""
    a, b = tmp_path / "a", tmp_path / "b"
    path = build(a, source)[0]
    shutil.copytree(a, b)
    return b, b / path.name


@pytest.mark.parametrize("damage", ["truncate", "flip", "no_record", "empty"])
def test_broken_library_is_rebuilt_not_loaded(tmp_path, damage):
    d, path = built_elsewhere(tmp_path, SOURCE + f"/* {damage} */\n")
    data = bytearray(path.read_bytes())
    if damage == "truncate":  # a full disk or a killed copy: loading it would be a bus error
        os.truncate(path, 1000)
    elif damage == "flip":  # loading it could be a segmentation fault
        data[len(data) // 2] ^= 0xFF
        path.write_bytes(bytes(data))
    elif damage == "no_record":
        (d / (path.name + ".sha256")).unlink()
    else:
        os.truncate(path, 0)
    assert not verify_library(path)
    path2, compiled, _, lib = build(d, SOURCE + f"/* {damage} */\n")
    assert path2 == path and compiled and verify_library(path) and answer(lib) == 42


def test_foreign_library_under_this_name_is_rebuilt(tmp_path):
    """Another model's library copied with its record under this one's name (the issue's ``malloc(): invalid
    size``): sound files, but built for another source. The record's model key tells; rebuilt, not loaded."""
    other = SOURCE.replace("42", "7")
    d, path = built_elsewhere(tmp_path)
    theirs = build(tmp_path / "c", other)[0]
    shutil.copyfile(theirs, path)
    shutil.copyfile(theirs.with_name(theirs.name + ".sha256"), path.with_name(path.name + ".sha256"))
    assert not verify_library(path)  # size and SHA-256 match their record, the model key does not
    path2, compiled, _, lib = build(d)
    assert path2 == path and compiled and verify_library(path) and answer(lib) == 42
    assert f"model {path.stem.rsplit('_', 1)[1]}" in path.with_name(path.name + ".sha256").read_text()


def test_stale_record_without_model_key_is_rebuilt(tmp_path):
    """A record of an older alpes_dyn (size and SHA-256 only, no model key): the library's identity is not
    known, so it is compiled again rather than loaded."""
    d, path = built_elsewhere(tmp_path, SOURCE + "/* stale */\n")
    record = path.with_name(path.name + ".sha256")
    record.write_text("".join(line for line in record.read_text().splitlines(keepends=True)
                              if not line.startswith("model ")))
    assert not verify_library(path)
    assert verify_library(path, key=None) is False
    path2, compiled, _, lib = build(d, SOURCE + "/* stale */\n")
    assert compiled and verify_library(path2) and answer(lib) == 42


def test_truncated_rollout_library_is_rebuilt(tmp_path, monkeypatch):
    """The issue's case: a cached step library truncated on disk, then a construction needing it."""
    x, w = cs.SX.sym("x", 2), cs.SX.sym("w", 1)
    step = cs.Function("f", [x, w], [cs.vertcat(x[0] + 0.5 * x[1], x[1] + w[0])])
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path / "a"))
    first = CompiledStepLoop(step, "trunc", threads=1)
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path / "b"))
    os.truncate(tmp_path / "b" / first.library.name, 1000)
    again = CompiledStepLoop(step, "trunc", threads=1)
    assert again.compiled and again.library == tmp_path / "b" / first.library.name
    X = again.run(np.array([[1.0, 2.0]]), np.ones((1, 3, 1)))
    assert X[0].tolist() == [[1.0, 2.0], [2.0, 3.0], [3.5, 4.0], [5.5, 5.0]]


def test_killed_builds_are_cleaned(tmp_path):
    path, _, _, _ = build(tmp_path)
    name = path.stem
    own = tmp_path / f".build@{name}@killed1"  # a build of this library killed by kill -9
    other = tmp_path / ".build@other_0123@killed2"  # another library's, its lock free: also dead
    busy = tmp_path / ".build@busy_4567@running"  # another library being built right now: kept
    legacy_old, legacy_new = tmp_path / "tmpold", tmp_path / "tmpnew"  # folders of versions before the lock
    for d in (own, other, busy, legacy_old, legacy_new):
        d.mkdir()
        (d / "x.c").write_text("int x;\n")
    old = time.time() - 2 * 3600
    os.utime(legacy_old, (old, old))
    (tmp_path / (path.name + ".sha256")).unlink()  # force a build (the cleaning runs under the build lock)
    fd = os.open(tmp_path / "busy_4567.lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        assert build(tmp_path)[1]
    finally:
        os.close(fd)
    left = entries(tmp_path)
    assert not {own.name, other.name, legacy_old.name} & left
    assert {busy.name, legacy_new.name} <= left


def test_compile_error_is_one_line_and_leaves_nothing(tmp_path):
    with pytest.raises(CompilerError) as e:
        build(tmp_path, "int broken( {\n")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("compiling answer.c failed:")
    assert not any(n.endswith(".so") or n.startswith(".build@") for n in entries(tmp_path))


def test_unwritable_cache_is_a_compiler_error(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(CompilerError, match="cache directory .* cannot be created"):
        build(tmp_path / "file" / "cache")


def test_concurrent_processes_compile_once(tmp_path):
    """Three processes need the same library at once: one compiles (slowly), the others wait and load it."""
    cc = tmp_path / "slow-cc"
    cc.write_text(f"#!/bin/sh\nsleep 1\nexec {shutil.which(_compiler())} \"$@\"\n")
    cc.chmod(0o755)
    cache = tmp_path / "cache"
    code = ("import sys; from pathlib import Path; from alpes_dyn.simulation.buildcache import build_library; "
            "from alpes_dyn.simulation.codegen import _CFLAGS; "
            f"p, c, s, lib = build_library({SOURCE!r}, 'answer', {str(cc)!r}, _CFLAGS, Path({str(cache)!r})); "
            "print(int(c), lib.alpes_answer())")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    procs = [subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=env) for _ in range(3)]
    outs = [p.communicate(timeout=120) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    results = sorted(o.split() for o, _ in outs)
    assert results == [["0", "42"], ["0", "42"], ["1", "42"]]
    assert not any(n.startswith(".build@") for n in entries(cache))


def test_large_generated_sources_compile_at_O1():
    """A source over 2 MB (the hand's EKF step) is built at -O1: 150 s -> 16 s to compile, the same speed."""
    from alpes_dyn.simulation.codegen import _LARGE_SOURCE, _cflags

    assert _cflags("x" * 1000) == _CFLAGS and _cflags("x" * _LARGE_SOURCE) == _CFLAGS
    big = _cflags("x" * (_LARGE_SOURCE + 1))
    assert big[0] == "-O1" and big[1:] == _CFLAGS[1:]
    assert _cflags("x" * (_LARGE_SOURCE + 1), "-O0") == ("-O0",) + _CFLAGS[1:]
    assert _cflags("x" * _LARGE_SOURCE, "-O0") == _CFLAGS  # a small source stays at -O3 whatever is asked


def test_a_large_source_at_O0_runs_the_steps_of_O3(tmp_path, monkeypatch):
    """``large_level="-O0"`` (the prediction loops of the observer's check): a source over the size is built at
    -O0 and steps the same numbers as the -O3 build of a small one (to rounding); any other level is refused."""
    from alpes_dyn.errors import InputError
    from alpes_dyn.simulation import codegen

    x, w = cs.SX.sym("x", 2), cs.SX.sym("w", 1)
    step = cs.Function("f", [x, w], [cs.vertcat(x[0] + 0.01 * x[1], x[1] + 0.01 * (w[0] - cs.sin(x[0])))])
    X0, W = np.array([[0.3, -0.2], [1.0, 0.5]]), np.linspace(-1, 1, 2 * 50).reshape(2, 50, 1)
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path))
    ref = CompiledStepLoop(step, "small", threads=1, vectorize=False).run(X0, W)
    seen = []
    monkeypatch.setattr(codegen, "_LARGE_SOURCE", 100)
    monkeypatch.setattr(codegen, "build_library", lambda src, stem, cc, flags, d: seen.append(flags[0]) or
                        build_library(src, stem, cc, flags, d))
    loop = CompiledStepLoop(step, "large", threads=1, vectorize=False, large_level="-O0")
    assert seen == ["-O0"] and loop.compiled
    np.testing.assert_allclose(loop.run(X0, W), ref, rtol=1e-12, atol=1e-14)
    with pytest.raises(InputError, match=r"^large_level: '-O3' is not one of -O1, -O0$"):
        CompiledStepLoop(step, "large", large_level="-O3")


def test_level_builds_any_source_at_it_with_the_steps_of_O3(tmp_path, monkeypatch):
    """``level="-O0"`` (the observer check's prediction loops of a finger, whose source is under the size): a small
    source is built at -O0 whatever its size, and steps the numbers of its -O3 build (to rounding; -ffp-contract=off
    both); a level other than -O1 and -O0 is refused, naming ``level``."""
    from alpes_dyn.errors import InputError
    from alpes_dyn.simulation import codegen

    assert codegen._cflags("x" * 1000, level="-O0") == ("-O0",) + _CFLAGS[1:]
    assert codegen._cflags("x" * (codegen._LARGE_SOURCE + 1), "-O1", "-O0")[0] == "-O0"
    x, w = cs.SX.sym("x", 2), cs.SX.sym("w", 1)
    step = cs.Function("f", [x, w], [cs.vertcat(x[0] + 0.01 * x[1], x[1] + 0.01 * (w[0] - cs.sin(x[0])))])
    X0, W = np.array([[0.3, -0.2], [1.0, 0.5]]), np.linspace(-1, 1, 2 * 50).reshape(2, 50, 1)
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path))
    seen = []
    monkeypatch.setattr(codegen, "build_library", lambda src, stem, cc, flags, d: seen.append(flags[0]) or
                        build_library(src, stem, cc, flags, d))
    ref = CompiledStepLoop(step, "levelled", threads=1, vectorize=False).run(X0, W)  # the quick -O1 build
    loop = CompiledStepLoop(step, "levelled", threads=1, vectorize=False, level="-O0")
    assert seen == ["-O1", "-O0"] and loop.compiled  # another key: built, not the default's library loaded
    np.testing.assert_allclose(loop.run(X0, W), ref, rtol=1e-12, atol=1e-14)
    for bad in ("-O3", "O0", 0):
        with pytest.raises(InputError, match=r"^level: .* is not one of -O1, -O0$"):
            CompiledStepLoop(step, "levelled", level=bad)


def test_default_threads_follow_omp_num_threads(monkeypatch):
    """The compiled loops' default thread count: the CPUs this process may use, capped by OMP_NUM_THREADS where it
    is a positive integer (Dask's workers set it to their thread count), ignored where it is not."""
    import os

    from alpes_dyn.simulation.codegen import _default_threads

    cpus = max(1, len(os.sched_getaffinity(0)))
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert _default_threads() == cpus
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    assert _default_threads() == 1
    monkeypatch.setenv("OMP_NUM_THREADS", str(cpus + 7))
    assert _default_threads() == cpus
    for bad in ("0", "two", "", "-3"):
        monkeypatch.setenv("OMP_NUM_THREADS", bad)
        assert _default_threads() == cpus


def test_expression_key_follows_the_expression_not_the_object():
    """One key for two functions built apart from one expression (the compiled loops and the C sources are shared
    by it); another for a changed expression; the numbers kept as an input do not enter it."""
    from alpes_dyn.simulation.buildcache import expression_key

    def made(power):
        x, p = cs.SX.sym("x", 2), cs.SX.sym("p", 2)
        return cs.Function("f", [x, p], [p * x ** power])

    key = expression_key(made(2))
    assert key == expression_key(made(2)) and len(key) == 40
    assert key != expression_key(made(3))
