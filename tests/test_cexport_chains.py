"""The model's C code by blocks (estimation.cexport.cexport_chains): the blocks of one structure share a function, side
by side in vector lanes (GCC, Clang) or one call each (-DALPES_NO_LANES); either gives CasADi's numbers to the last
bit, on a small function with three blocks -- two of one structure with different constants, one of another --,
with 2 lanes (SSE2), 4 (AVX: a spare lane) or none."""

from __future__ import annotations

import platform
import shutil
import subprocess

import casadi as cs
import numpy as np
import pytest

from alpes_dyn.estimation.cexport.cexport_chains import chain_model_source, model_blocks

CC = shutil.which("cc") or shutil.which("gcc")

_MAIN = r"""
#include <stdio.h>
int main(void) {
  double z[6], w[3], zn[6], A[%(annz)d], work[%(nwork)d];
  const double* arg[2];
  double* res[2];
  int i;
  for (i = 0; i < 6; ++i) if (scanf("%%lf", &z[i]) != 1) return 2;
  for (i = 0; i < 3; ++i) if (scanf("%%lf", &w[i]) != 1) return 2;
  arg[0] = z; arg[1] = w; res[0] = zn; res[1] = A;
  if (model(arg, res, 0, work, 0)) return 1;
  for (i = 0; i < 6; ++i) printf("%%.17g\n", zn[i]);
  for (i = 0; i < %(annz)d; ++i) printf("%%.17g\n", A[i]);
  return 0;
}
"""


def _function():
    """z = [q (3); v (3)], w (3): three one-joint "chains" (q_i, v_i, w_i), the first two the same computation
    with other constants, the third another; outputs z_next and A = dz_next/dz (block-sparse)."""
    z, w = cs.SX.sym("z", 6), cs.SX.sym("w", 3)
    q, v = z[:3], z[3:]
    k = [0.7, 1.3, 0.0]
    acc = [(w[i] - k[i] * cs.sin(q[i]) - 0.1 * v[i] * v[i]) / (2.0 + cs.cos(q[i])) for i in range(2)]
    acc.append(cs.sqrt(1.0 + q[2] ** 2) * cs.tanh(v[2]) - 1.0 / (3.0 + w[2] * w[2]))
    zn = cs.vertcat(q + 1e-3 * v, v + 1e-3 * cs.vertcat(*acc))
    return cs.Function("model", [z, w], [zn, cs.jacobian(zn, z)])


def test_blocks_of_the_function():
    f = _function()
    assert model_blocks(f, 6) == [0, 1, 2, 0, 1, 2]


@pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH")
@pytest.mark.parametrize("flags", [[], ["-DALPES_NO_LANES"], ["-mavx"]], ids=["lanes", "no-lanes", "avx"])
def test_model_by_blocks_equals_casadi_bit_for_bit(flags, tmp_path):
    f = _function()
    src = chain_model_source(f, model_blocks(f, 6), "model")
    assert src is not None
    code, nwork = src
    assert "2 structure(s), lanes 2, 1" in code  # the two alike blocks share a function
    prelude = "#include <math.h>\n#define casadi_real double\n#define casadi_int long long int\n"
    (tmp_path / "m.c").write_text(prelude + code + _MAIN % {"annz": f.nnz_out(1), "nwork": nwork})
    exe = tmp_path / "m"
    if flags == ["-mavx"] and platform.machine() not in ("x86_64", "AMD64"):
        pytest.skip("-mavx: x86-64 only")
    subprocess.run([CC, "-O2", "-std=c99", "-Wall", "-Werror", *flags, "-o", str(exe), str(tmp_path / "m.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=120)
    rng = np.random.default_rng(5)
    for _ in range(3):
        z, w = rng.standard_normal(6), rng.standard_normal(3)
        out = subprocess.run([str(exe)], input=" ".join(repr(float(x)) for x in np.r_[z, w]), check=True, capture_output=True,
                             text=True).stdout
        got = np.array([float(x) for x in out.split()])
        zn, A = f(z, w)
        want = np.r_[np.array(zn).ravel(), np.array(A.nonzeros())]
        assert got.shape == want.shape and np.array_equal(got, want)


def test_one_block_or_another_operation_keeps_casadis_code():
    z, w = cs.SX.sym("z", 2), cs.SX.sym("w", 1)
    coupled = cs.Function("m", [z, w], [cs.vertcat(z[0] + z[1], z[1] * w)])
    assert chain_model_source(coupled, model_blocks(coupled, 2), "m") is None  # one block
    fmin = cs.Function("m", [z, w], [cs.vertcat(cs.fmin(z[0], w), z[1])])
    assert model_blocks(fmin, 2) == [0, 1]
    assert chain_model_source(fmin, [0, 1], "m") is None  # fmin: not among the operations written out
