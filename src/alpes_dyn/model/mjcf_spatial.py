"""An MJCF spatial tendon (routed over sites, wrapping cylinders and spheres) as the spec's q-dependent ratios.

A motor of gear g on a spatial tendon of length L(q) turns by g L(q) (the actuator's length); its ratio on joint i is
rho_i(q) = g dL/dq_i, MuJoCo's ``gear * ten_J`` (``ten_moment`` before MuJoCo 3.3; stored sparse since, read densely
by :func:`tendon_jacobian`). The spec's polynomial form (:mod:`alpes_dyn.model.ratio_curve`) makes each rho_i a polynomial of
q_i alone, which holds where the tendon's path between two consecutive points fixed on bodies crosses one joint (sites
on every link, a wrapping geom on the parent of the joint it wraps): then L is a sum of one function per joint.
:func:`fit_spatial_tendon` sweeps each joint the tendon crosses over its range (the others at their reference angle),
MuJoCo computing the tendon's Jacobian, fits the polynomial of the lowest degree that meets the tolerance (at most
:data:`~alpes_dyn.model.ratio_curve.MAX_CURVE_DEGREE`), and measures the fit's error on the sweeps and at random
configurations over the joints' box (where a path that spans several joints shows up). A tendon wrapped on an arc about
the joint's own axis has a constant moment arm, represented exactly (degree 0); straight segments and geoms off the
axis give a smooth curve, represented to the error said (an :class:`MjcfCurveWarning` where it is over
:data:`TOLERANCE`).

Where the fit is not exact it also says why the form cannot follow the tendon (``SpatialFit.reason``), and the import
then carries the tendon's geometry instead (the spec's ``path``, :mod:`alpes_dyn.model.mjcf_path`): its path changes
over a joint's sweep (a
wrapping geom touched or left, a kink of the moment arm, or wrapped on its other side, a jump: MuJoCo's
``tendon_arm/arm26`` over 0-120 degrees, best polynomial 0.005 to 0.7 off), or a segment spans two joints (the ratio
on one changes with the other's angle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AlpesDynWarning
from .ratio_curve import MAX_CURVE_DEGREE

__all__ = ["MjcfCurveWarning", "SpatialFit", "fit_spatial_tendon", "tendon_jacobian"]

SAMPLES = 41
"""Chebyshev points per joint's sweep."""
CHECKS = 32
"""Random configurations (a fixed seed) on which the fit's error is measured besides the sweeps."""
TOLERANCE = 1e-10
"""The relative error (of the largest |ratio|) below which a degree is enough: a curve represented exactly (MuJoCo's
forward dynamics then agree to 1e-9 relative)."""


NEGLIGIBLE = 1e-12
"""A moment arm below this fraction of the tendon's largest is MuJoCo's rounding: the joint is not crossed."""


class MjcfCurveWarning(AlpesDynWarning):
    """A spatial tendon's moment arms are imported as a fitted curve whose error exceeds :data:`TOLERANCE` (relative):
    the message gives it, in rad/rad of the ratio and relative."""


@dataclass(frozen=True)
class SpatialFit:
    """A spatial tendon's ratios as the spec's form: ``joints`` {joint: rho_i(0)}, ``curve`` {joint: (c_1 ..
    c_P)} (joints with a constant ratio not in it), ``error`` the largest |ratio error| (rad/rad) over the sweeps and
    the random configurations, ``scale`` the largest |ratio| (error / scale: the relative error), ``length_error``
    the largest |error| of the motor angle g (L(q) - L(0)), rad; ``reason``: why the form cannot follow the tendon
    where the fit is not exact ("" if none was found): its path changes on a joint's sweep (a wrapping geom touched,
    left or wrapped on its other side: a kink or a jump of the moment arm, :func:`_break`), or a segment spans
    several joints (the ratio on one joint changes with another's angle)."""

    joints: dict
    curve: dict
    error: float
    scale: float
    length_error: float
    reason: str = ""


def tendon_jacobian(m, d) -> np.ndarray:
    """MuJoCo's tendon Jacobian dL/dqvel as a dense (ntendon, nv) array. MuJoCo 3.3 and later store ``d.ten_J``
    sparse, row t's non-zeros at ``m.ten_J_rowadr[t]`` over the columns ``m.ten_J_colind`` (``m.ten_J_rownnz[t]``
    of them: the dofs the tendon can move); older versions store it dense (``ten_moment``/``ten_J`` of size
    ntendon * nv).

    Parameters
    ----------
    m : mujoco.MjModel
        The model.
    d : mujoco.MjData
        Its data, after the position stage.

    Returns
    -------
    numpy.ndarray, shape (ntendon, nv)
        dL/dqvel, m/rad for hinges (a new array).
    """
    J = np.asarray(d.ten_J, dtype=float).ravel()
    if not hasattr(m, "ten_J_rownnz"):  # dense storage
        return J.reshape(m.ntendon, m.nv).copy()
    out = np.zeros((m.ntendon, m.nv))
    for t in range(m.ntendon):  # an import's check, not a hot path
        a, n = int(m.ten_J_rowadr[t]), int(m.ten_J_rownnz[t])
        out[t, np.asarray(m.ten_J_colind[a:a + n], dtype=int)] = J[a:a + n]
    return out


def _state(mujoco, m, d, q: np.ndarray, t: int) -> tuple[float, np.ndarray]:
    """The tendon ``t``'s length (m) and Jacobian (nv,) at joint angles q (qpos of hinges)."""
    d.qpos[:] = q
    mujoco.mj_fwdPosition(m, d)
    return float(d.ten_length[t]), tendon_jacobian(m, d)[t]


def _path(mujoco, m, d, t: int) -> tuple:
    """The tendon ``t``'s path at the current state, as what its smoothness depends on: the objects its points lie
    on (-1 a site, a geom's id twice where it wraps that geom) and, for each wrapped geom, the side it wraps (the sign
    of the arc's turn about the geom's z axis)."""
    a, n = int(d.ten_wrapadr[t]), int(d.ten_wrapnum[t])
    obj = np.asarray(d.wrap_obj).ravel()[a:a + n]
    pts = np.asarray(d.wrap_xpos).reshape(-1, 3)[a:a + n]
    sides = []
    for k in range(n - 1):
        g = int(obj[k])
        if g >= 0 and obj[k + 1] == g:
            c, z = d.geom_xpos[g], d.geom_xmat[g].reshape(3, 3)[:, 2]
            sides.append((g, int(np.sign(np.cross(pts[k] - c, pts[k + 1] - c) @ z))))
    return tuple(int(o) for o in obj), tuple(sides)


def _break(mujoco, m, before: tuple, after: tuple, where: str) -> str:
    """The reason a tendon's path differs between two configurations (``where``: "between j = a and b rad"): a
    wrapping geom touched or left (a kink of the moment arm), or wrapped on its other side (a jump)."""
    gname = lambda g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"  # noqa: E731
    sb, sa = dict(before[1]), dict(after[1])
    for g in sorted(set(sb) | set(sa)):
        if g in sb and g in sa and sb[g] != sa[g]:
            return f"it changes side of its wrapping geom {gname(g)!r} {where} (its moment arm jumps there)"
        if (g in sb) != (g in sa):
            return (f"it {'leaves' if g in sb else 'touches'} its wrapping geom {gname(g)!r} {where} (its moment arm "
                    "is not smooth there)")
    return f"its path changes {where} (its moment arm is not smooth there)"


def fit_spatial_tendon(mujoco, m, t: int, gear: float, joint_names: list[str]) -> SpatialFit:
    """The ratios g dL/dq of spatial tendon ``t`` of MuJoCo model ``m`` (hinges only, qpos = q), fitted per joint
    (module doc).

    Parameters
    ----------
    mujoco : module
        The ``mujoco`` module.
    m : mujoco.MjModel
        The compiled model.
    t : int
        The tendon's id.
    gear : float
        The actuator's gear g (rad of motor per m of tendon).
    joint_names : list of str
        The names of m's joints, in order.

    Returns
    -------
    SpatialFit
        The per-joint ratios and curves, their errors, and the reason where a joint's ratio is not a curve of its own
        angle.
    """
    d = mujoco.MjData(m)
    lo, hi = m.jnt_range[:, 0].copy(), m.jnt_range[:, 1].copy()
    ref = np.clip(m.qpos0.copy(), lo, hi)
    rng = np.random.default_rng(0)
    boxes = lo + (hi - lo) * rng.random((CHECKS, m.njnt))
    dof = m.jnt_dofadr
    Js = np.abs([_state(mujoco, m, d, q, t)[1][dof] for q in np.vstack([ref, boxes])])
    crossed = np.any(Js > NEGLIGIBLE * np.max(Js), axis=0)  # (MuJoCo's rounding: 1e-18 m/rad on a joint not crossed)
    x = np.cos(np.pi * (np.arange(SAMPLES) + 0.5) / SAMPLES)  # Chebyshev points of [-1, 1]
    coefs: dict[int, np.ndarray] = {}
    scale, err, reason = 0.0, 0.0, ""
    for j in np.flatnonzero(crossed):
        qs = 0.5 * (lo[j] + hi[j]) + 0.5 * (hi[j] - lo[j]) * x
        r = np.empty(SAMPLES)
        order = np.argsort(qs)
        path = None
        for k in order:  # MuJoCo's kinematics, a sample at a time, in increasing angle (an import, not a hot path)
            q = ref.copy()
            q[j] = qs[k]
            r[k] = gear * _state(mujoco, m, d, q, t)[1][dof[j]]
            here = _path(mujoco, m, d, t)
            if path is not None and here != path and not reason:
                reason = _break(mujoco, m, path, here, f"between {joint_names[j]} = {q_prev:.4g} and {qs[k]:.4g} rad")
            path, q_prev = here, float(qs[k])
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
    _state(mujoco, m, d, ref, t)
    ref_path, moved = _path(mujoco, m, d, t), ""
    for q in boxes:  # the random configurations: a path over several joints, the fit between the sweep's points
        L, J = _state(mujoco, m, d, q, t)
        here = _path(mujoco, m, d, t)
        if here != ref_path and not moved:  # a change that the one-joint sweeps did not cross
            at = ", ".join(f"{joint_names[j]} = {q[j]:.4g}" for j in sorted(coefs))
            moved = _break(mujoco, m, ref_path, here, f"between the reference angles and {at} rad")
        rho = S + np.sum(C * q[None, :] ** p, axis=0)
        s_q = S @ q + np.sum(C * q[None, :] ** (p + 1) / (p + 1))
        err = max(err, float(np.max(np.abs(rho - gear * J[dof]))))
        len_err = max(len_err, abs(s_q - gear * (L - L0)))
    joints = {joint_names[j]: float(c[0]) for j, c in coefs.items()}
    curve = {joint_names[j]: tuple(float(v) for v in c[1:]) for j, c in coefs.items() if len(c) > 1}
    if err > TOLERANCE * scale and not reason:
        reason = moved
    if err > TOLERANCE * scale and not reason:
        reason = _coupled(mujoco, m, d, t, boxes[:4], ref, sorted(coefs), joint_names, TOLERANCE * scale / abs(gear))
    return SpatialFit(joints, curve, err, scale, len_err, reason)


def _coupled(mujoco, m, d, t: int, qs: np.ndarray, ref: np.ndarray, crossed: list, names: list, tol: float) -> str:
    """"" or the reason the tendon ``t`` is not a sum of one function per joint: at one of the configurations ``qs``
    the ratio on a crossed joint i differs from its value with the other joints at ``ref``, and moving one other
    joint k alone changes it."""
    dof = m.jnt_dofadr
    for q, i in ((q, i) for q in qs for i in crossed):
        qi = ref.copy()
        qi[i] = q[i]
        base = _state(mujoco, m, d, qi, t)[1][dof[i]]
        if abs(_state(mujoco, m, d, q, t)[1][dof[i]] - base) <= tol:
            continue
        for k in crossed:
            qk = qi.copy()
            qk[k] = q[k]
            if k != i and abs(_state(mujoco, m, d, qk, t)[1][dof[i]] - base) > tol:
                return (f"a segment of its path spans joints {names[k]} and {names[i]} (its moment arm on {names[i]} "
                        f"changes with {names[k]}'s angle: not one function per joint)")
    return ""
