"""Checks and solvers of :class:`~alpes_dyn.Model` (:mod:`alpes_dyn.model.robot`): the URDF parsed by Pinocchio
(what it refuses, in one line), the mass matrix's definiteness at a generic configuration, Newton's method of the
static equilibrium, the arguments of ``random_state``, the tip frames of a URDF."""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pinocchio as pin

from ..errors import InputError, ModelError
from ..fileio import native_stderr_to
from .mimic import MimicCoupling, urdf_mimics
from .urdf_checks import check_urdf_structure

__all__ = ["newton_equilibrium"]


def _build_pinocchio(urdf: str) -> tuple[pin.Model, MimicCoupling | None]:
    """The URDF's Pinocchio model, and with ``<mimic>`` joints their :class:`MimicCoupling` (Pinocchio's mimic
    model, whose coordinates are the independent joints', and the whole tree's model beside it)."""
    check_urdf_structure(urdf)
    mimics = urdf_mimics(urdf)
    printed: list[str] = []  # urdfdom prints its parse errors on the process's stderr: into the message
    try:
        with native_stderr_to(printed):
            model = pin.buildModelFromXML(urdf, mimic=True) if mimics else pin.buildModelFromXML(urdf)
            full = pin.buildModelFromXML(urdf) if mimics else None
    except Exception as exc:  # pinocchio raises ValueError/RuntimeError with multi-line text
        errors = [line.removeprefix("Error:").strip() for line in printed if line.startswith("Error:")]
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        why = errors[0] if errors else first
        if mimics and "mimic" in why:  # name them: Pinocchio's text does not
            why += (" (" + ", ".join(f"{m.name!r} follows {m.primary!r}" for m in mimics) + "; Pinocchio needs the "
                    "joint followed before its mimic in its depth-first order, siblings by child link name)")
        raise ModelError(f"URDF could not be parsed by Pinocchio: {why}") from None
    if model.nv == 0:
        raise ModelError("URDF has no movable joint")
    if model.nq != model.nv:
        raise ModelError(
            f"URDF has joints with nq != nv (nq={model.nq}, nv={model.nv}); only fixed-base trees of "
            "revolute/prismatic joints are supported"
        )
    if full is None:
        return model, None
    names = [model.names[i] for i in range(1, model.njoints) if model.joints[i].nv > 0]
    coupling = MimicCoupling(mimics, names, list(full.names[1:]), full)
    _check_mimic_model(model, coupling)
    return model, coupling


def _check_mimic_model(model: pin.Model, coupling: MimicCoupling) -> None:
    """Pinocchio's mimic model against the whole tree at a generic q: every frame's placement and G^T A G
    (Pinocchio's mimic support is recent; its issues #2710 and #2761 were wrong CRBA and axes). ModelError if not."""
    q = _generic_configuration(model)
    data, fdata = model.createData(), coupling.full_data
    pin.framesForwardKinematics(model, data, q)
    pin.framesForwardKinematics(coupling.full_model, fdata, coupling.full_q(q))
    worst = max(float(np.max(np.abs(a.homogeneous - b.homogeneous))) for a, b in zip(data.oMf, fdata.oMf))
    A = pin.crba(model, data, q)
    A_full = pin.crba(coupling.full_model, fdata, coupling.full_q(q))
    A_red = coupling.project(np.triu(A_full) + np.triu(A_full, 1).T)
    scale = max(1.0, float(np.max(np.abs(A_red))))
    err = float(np.max(np.abs(np.triu(A) + np.triu(A, 1).T - A_red))) / scale
    if not (worst < 1e-9 and err < 1e-9):
        raise ModelError(f"URDF mimic joints ({', '.join(coupling.mimic_names)}): Pinocchio's mimic model disagrees "
                         f"with the whole tree at a generic configuration (frames by {worst:.3g} m, A by {err:.3g} "
                         "relative); remove the <mimic> elements for independent joints")


def _tips(pm: pin.Model, spec: Any, layout: Any) -> tuple[str, ...]:
    """The tip frames: the spec's, else the layout's, else the URDF's leaf frames (Pinocchio's frame order)."""
    if spec is not None and spec.tips is not None:
        return spec.tips
    if layout is not None:
        return layout.tips
    parents = {pm.frames[i].parentFrame for i in range(len(pm.frames))}
    return tuple(f.name for i, f in enumerate(pm.frames) if i not in parents and f.type == pin.FrameType.BODY)


def newton_equilibrium(residual, jacobian, q0: np.ndarray, tol: float = 1e-12, iterations: int = 50) -> np.ndarray:
    """Newton's method for residual(q) = 0 (N m) from q0, steps capped at 0.5 rad.

    Parameters
    ----------
    residual : callable
        q (n,) -> the torque residual (n,), N m.
    jacobian : callable
        q (n,) -> d residual/dq (n, n), N m/rad.
    q0 : numpy.ndarray, shape (n,)
        The start, rad.
    tol : float, optional
        Converged when max |residual| < tol, N m (default 1e-12).
    iterations : int, optional
        The most Newton steps (default 50).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The equilibrium q, rad.

    Raises
    ------
    InputError
        A singular Jacobian, or no convergence within ``iterations``.
    """
    q = np.array(q0, dtype=float)
    for _ in range(iterations):
        r = residual(q)
        if np.max(np.abs(r)) < tol:
            return q
        try:
            dq = np.linalg.solve(jacobian(q), -r)
        except np.linalg.LinAlgError:
            raise InputError("static equilibrium: singular stiffness (a joint without spring?)") from None
        q = q + dq * min(1.0, 0.5 / max(float(np.max(np.abs(dq))), 1e-300))  # at most 0.5 rad per step
    raise InputError("static equilibrium: Newton's method did not converge (torque beyond the springs' range?)")


def _generic_configuration(model: pin.Model) -> np.ndarray:
    """A fixed, generic q inside the joint limits (golden-ratio fractions of each range)."""
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    lo = np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.pi)
    hi = np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.pi)
    frac = np.mod(0.5 + 0.6180339887498949 * np.arange(1, model.nv + 1), 1.0)
    return lo + frac * (hi - lo)


def _check_mass_matrix(model: pin.Model, data: pin.Data, names: Sequence[str]) -> None:
    """ModelError if A(q) + I_a is singular at a generic q: a joint that moves only massless links."""
    A = pin.crba(model, data, _generic_configuration(model))
    A = np.triu(A) + np.triu(A, 1).T
    d = np.diag(A)
    scale = float(np.max(np.abs(d))) if d.size else 0.0
    for i, name in enumerate(names):
        if not d[i] > 1e-14 * scale:
            raise ModelError(f"joint {name!r} moves no mass: the links it carries are massless, so A(q) is singular "
                             "(give them a mass and inertia, or make the joint fixed)")
    try:
        np.linalg.cholesky(A)
    except np.linalg.LinAlgError:
        raise ModelError("A(q) is singular at a generic configuration (massless links?)") from None


def _check_positive(model: pin.Model, data: pin.Data, R: np.ndarray) -> None:
    """A(q) + R stays positive definite at a generic q (R >= 0 by construction; a guard on the sum)."""
    A = pin.crba(model, data, _generic_configuration(model))
    A = np.triu(A) + np.triu(A, 1).T + R
    try:
        np.linalg.cholesky(A)
    except np.linalg.LinAlgError:  # pragma: no cover - R = S^T J S >= 0 cannot make it indefinite
        raise ModelError("A(q) + S^T diag(J_m) S is not positive definite at a generic configuration") from None


def _check_random_args(rng: object, speed: object, size: object) -> tuple[np.random.Generator, float, int | None]:
    if not isinstance(rng, np.random.Generator):
        if rng is not None and (isinstance(rng, (bool, np.bool_)) or not isinstance(rng, (int, np.integer))
                                or rng < 0):
            raise InputError(f"rng: expected a numpy Generator, an integer seed >= 0 or None, got {rng!r}")
        rng = np.random.default_rng(rng)
    try:
        s = float(speed)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        s = float("nan")
    if not (math.isfinite(s) and s >= 0):
        raise InputError(f"speed: expected a finite number >= 0 rad/s, got {speed!r}")
    if size is not None and (isinstance(size, (bool, np.bool_)) or not isinstance(size, (int, np.integer))
                             or size < 0):
        raise InputError(f"size: expected an integer >= 0 or None, got {size!r}")
    return rng, s, None if size is None else int(size)
