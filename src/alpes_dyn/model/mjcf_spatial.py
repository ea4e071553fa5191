"""An MJCF spatial tendon (routed over sites, wrapping cylinders and spheres) as the spec's q-dependent ratios.

A motor of gear g on a spatial tendon of length L(q) turns by g L(q) (the actuator's length); its ratio on joint i is
rho_i(q) = g dL/dq_i, MuJoCo's ``gear * ten_J`` (``ten_moment`` before MuJoCo 3.3). The spec's form
(:mod:`alpes_dyn.model.ratio_curve`) makes each rho_i a polynomial of q_i alone, which holds where the tendon's path
between two consecutive points fixed on bodies crosses one joint (sites on every link, a wrapping geom on the parent
of the joint it wraps): then L is a sum of one function per joint. :func:`fit_spatial_tendon` sweeps each joint the
tendon crosses over its range (the others at their reference angle), MuJoCo computing the tendon's Jacobian, fits the
polynomial of the lowest degree that meets the tolerance (at most :data:`~alpes_dyn.model.ratio_curve.MAX_CURVE_DEGREE`),
and measures the fit's error on the sweeps and at random configurations over the joints' box (where a path that
spans several joints shows up). A tendon wrapped on an arc about the joint's own axis has a constant moment arm,
represented exactly (degree 0); straight segments and geoms off the axis give a curve, represented to the error said.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AlpesDynWarning
from .ratio_curve import MAX_CURVE_DEGREE

__all__ = ["MjcfCurveWarning", "SpatialFit", "fit_spatial_tendon"]

SAMPLES = 41
"""Chebyshev points per joint's sweep."""
CHECKS = 32
"""Random configurations (a fixed seed) on which the fit's error is measured besides the sweeps."""
TOLERANCE = 1e-10
"""The relative error (of the largest |ratio|) below which a degree is enough: a curve represented exactly (MuJoCo's
forward dynamics then agree to 1e-9 relative)."""


class MjcfCurveWarning(AlpesDynWarning):
    """A spatial tendon's moment arms are imported as a fitted curve whose error exceeds :data:`TOLERANCE` (relative):
    the message gives it, in rad/rad of the ratio and relative."""


@dataclass(frozen=True)
class SpatialFit:
    """A spatial tendon's ratios as the spec's form: ``joints`` {joint: rho_i(0)}, ``curve`` {joint: (c_1 ..
    c_P)} (joints with a constant ratio not in it), ``error`` the largest |ratio error| (rad/rad) over the sweeps and
    the random configurations, ``scale`` the largest |ratio| (error / scale: the relative error), ``length_error``
    the largest |error| of the motor angle g (L(q) - L(0)), rad."""

    joints: dict
    curve: dict
    error: float
    scale: float
    length_error: float


def _state(mujoco, m, d, q: np.ndarray, t: int) -> tuple[float, np.ndarray]:
    """The tendon ``t``'s length (m) and Jacobian (nv,) at joint angles q (qpos of hinges)."""
    d.qpos[:] = q
    mujoco.mj_fwdPosition(m, d)
    return float(d.ten_length[t]), np.asarray(d.ten_J).reshape(m.ntendon, m.nv)[t].copy()


def fit_spatial_tendon(mujoco, m, t: int, gear: float, joint_names: list[str]) -> SpatialFit:
    """The ratios g dL/dq of spatial tendon ``t`` of MuJoCo model ``m`` (hinges only, qpos = q), fitted per joint
    (module doc). ``joint_names``: the names of m's joints in order."""
    d = mujoco.MjData(m)
    lo, hi = m.jnt_range[:, 0].copy(), m.jnt_range[:, 1].copy()
    ref = np.clip(m.qpos0.copy(), lo, hi)
    rng = np.random.default_rng(0)
    boxes = lo + (hi - lo) * rng.random((CHECKS, m.njnt))
    dof = m.jnt_dofadr
    crossed = np.zeros(m.njnt, bool)
    for q in np.vstack([ref, boxes]):
        crossed |= _state(mujoco, m, d, q, t)[1][dof] != 0
    x = np.cos(np.pi * (np.arange(SAMPLES) + 0.5) / SAMPLES)  # Chebyshev points of [-1, 1]
    coefs: dict[int, np.ndarray] = {}
    scale, err = 0.0, 0.0
    for j in np.flatnonzero(crossed):
        qs = 0.5 * (lo[j] + hi[j]) + 0.5 * (hi[j] - lo[j]) * x
        r = np.empty(SAMPLES)
        for k, qj in enumerate(qs):  # MuJoCo's kinematics, a sample at a time (an import, not a hot path)
            q = ref.copy()
            q[j] = qj
            r[k] = gear * _state(mujoco, m, d, q, t)[1][dof[j]]
        s = float(np.max(np.abs(r)))
        scale = max(scale, s)
        for P in range(0, MAX_CURVE_DEGREE + 1):
            c = np.polynomial.polynomial.polyfit(qs, r, P) if P else np.array([np.mean(r)])
            e = float(np.max(np.abs(np.polynomial.polynomial.polyval(qs, c) - r)))
            if e <= TOLERANCE * s:
                break
        coefs[int(j)] = c
        err = max(err, e)
    S = np.zeros(m.njnt)
    C = np.zeros((MAX_CURVE_DEGREE, m.njnt))
    for j, c in coefs.items():
        S[j] = c[0]
        C[: len(c) - 1, j] = c[1:]
    L0 = _state(mujoco, m, d, np.zeros(m.njnt), t)[0]
    p = np.arange(1, MAX_CURVE_DEGREE + 1)[:, None]
    len_err = 0.0
    for q in boxes:  # the random configurations: a path over several joints, the fit between the sweep's points
        L, J = _state(mujoco, m, d, q, t)
        rho = S + np.sum(C * q[None, :] ** p, axis=0)
        s_q = S @ q + np.sum(C * q[None, :] ** (p + 1) / (p + 1))
        err = max(err, float(np.max(np.abs(rho - gear * J[dof]))))
        len_err = max(len_err, abs(s_q - gear * (L - L0)))
    joints = {joint_names[j]: float(c[0]) for j, c in coefs.items()}
    curve = {joint_names[j]: tuple(float(v) for v in c[1:]) for j, c in coefs.items() if len(c) > 1}
    return SpatialFit(joints, curve, err, scale, len_err)
