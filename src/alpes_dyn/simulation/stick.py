"""Dry friction that sticks: the time-stepping (implicit) Coulomb law, as MuJoCo resolves ``frictionloss``.

The smooth law F_s tanh(v / v_s) + F_v v (eq. 2.6-2.7 with a smooth sign, :mod:`alpes_dyn.model.extras`) cannot
hold a joint at rest: under a net torque below F_s it needs a velocity v_s atanh(tau / F_s), so a modelled joint
creeps where the real one stays. On a tendon finger the encoder sees only the sum of the joints (y = S q), and the
creep moves the split between them.

Here the friction is resolved over a step of h seconds instead (Stewart-Trinkle / Moreau time stepping, the law of
MuJoCo's ``frictionloss`` constraint): with M = M(q) the mass matrix and the net torque
N = tau + J^T F - C(q, v) v - G(q) - k (q - q_rest) (:meth:`~alpes_dyn.symbolic.dynamics.SymbolicDynamics.net_torque`)
evaluated at the step's start,

    (M + h diag(F_v)) v+ = M v + h N - h f,    |f_i| <= F_s,i,   f_i = F_s,i sign(v+_i) where v+_i != 0,

then q+ = q + h v+ (semi-implicit Euler). The new velocity v+ is the minimiser of the strictly convex
1/2 v^T A v - b^T v + h sum_i F_s,i |v_i| (A = M + h diag(F_v), b = M v + h N), found exactly by enumerating the
joints' modes (stuck, sliding forwards, backwards: :func:`coulomb_velocity`), unrolled into one CasADi expression
(``if_else``: its Jacobian is piecewise; on a stuck joint it says, correctly, that its velocity does not answer the
torque). Iterative solvers converge too slowly or not at all here: finger3's mass matrix has a condition number of
about 300; projected Gauss-Seidel (MuJoCo's PGS) still leaves rad/s errors after 10 sweeps, and a primal-dual
active-set method cycles on a quarter of random steps.
From rest (v = 0), the joints all stay at rest exactly when the static condition |N_i| <= F_s,i holds on each.
"""

from __future__ import annotations

import itertools
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..checks import one_of
from ..errors import InputError, ModelError
from ..model.friction import OBSERVER_LAWS
from ..model.robot import Model
from ..symbolic.dynamics import block_solve
from ..symbolic.statespace import StateSpace

__all__ = ["FRICTION_LAWS", "LIBRARY_LAWS", "observer_friction_law", "library_law", "law_model", "MAX_DRY_JOINTS",
           "check_friction_law", "coulomb_velocity", "mass_blocks",
           "stick_step_expression"]

FRICTION_LAWS: tuple[str, ...] = OBSERVER_LAWS
"""The observers' dry-friction laws (:data:`~alpes_dyn.model.friction.OBSERVER_LAWS`, which a parameter file's
``friction.observer_law`` names): ``smooth`` F_s tanh(v / v_s) through RK4, ``stick`` the time-stepping
Coulomb law of this module, ``lugre`` the LuGre law with a bristle state per joint through RK4
(:mod:`alpes_dyn.model.friction`, :mod:`alpes_dyn.simulation.lugre`)."""

LIBRARY_LAWS: dict[str, tuple[str, str]] = {"smooth": ("smooth", "tanh"), "stick": ("stick", "tanh"),
                                             "lugre": ("lugre", "lugre"), "creep": ("smooth", "creep")}
"""The library's friction laws, each as the observer runs it: name -> (the observer's law of :data:`FRICTION_LAWS`,
the parameter file's ``friction.law`` of :data:`~alpes_dyn.model.friction.FRICTION_MODELS`). ``smooth`` the tanh
sign, ``stick`` the time-stepping Coulomb law (on a tanh file: the file's smooth sign unused), ``lugre`` the
bristles (the file's sigma0/sigma1 where it is a LuGre file, else the defaults), ``creep`` MuJoCo's soft dry
friction (:class:`~alpes_dyn.model.friction.Creep`, solved inside the smooth law's dynamics; the file's band
constants where it is a creep file, else MuJoCo's defaults). The laws ``estimate --law-spread`` compares
(:mod:`alpes_dyn.estimation.observers.law_sigma`): a law is its file's law, not the observer's alone (a creep file
run with the smooth law is the creep law; the smooth law on it is the same file with ``friction.law = "tanh"``)."""

MAX_DRY_JOINTS = 5
"""The most joints with dry friction in one coupled chain (a block of the mass matrix) that :func:`coulomb_velocity`
resolves: it enumerates 3^k modes (243 at 5; an Alpes finger has 3 joints, the thumb 2 on its tendon)."""


def check_friction_law(law: Any) -> str:
    """``law`` if it is one of :data:`FRICTION_LAWS`.

    Parameters
    ----------
    law : object
        The friction law's name.

    Returns
    -------
    str
        ``law``.

    Raises
    ------
    InputError
        Not one of :data:`FRICTION_LAWS`, naming ``friction_law``.
    """
    return one_of(law, FRICTION_LAWS, "friction_law")


def observer_friction_law(model: Model) -> str:
    """The observer's friction law for ``model``'s parameter file (``estimate`` without ``--friction-law``, the
    force loop's step, ``codegen --step``): the file's ``friction.observer_law`` where it holds one (``identify``
    writes the law its observer check chose by measurement, :mod:`~alpes_dyn.estimation.identification.law_choice`);
    else ``"lugre"`` where the file says ``friction.law = "lugre"``, else ``"smooth"``.

    Without the field, the switched stick-slip law (``"stick"``) is asked for by name (``--friction-law stick``,
    ``friction_law=``): measured with the plants' true files on MuJoCo's dry friction (``benchmarks/observer_law.py``,
    ``benchmarks/results/observer_law.json``), it holds the joints where they stick (the stiff constraint) closer
    than the smooth law, and the smooth law is closer where they creep (the soft constraint) or slide (the
    identification record's dither); as a rule for the files ``identify --effects stiction`` writes its predictions
    failed identify's observer check on every draw of ``benchmarks/bench_loop.py``'s stand-in (the CHANGELOG's
    entry), hence the choice by measurement, per file.

    Parameters
    ----------
    model : Model
        The observer's model.

    Returns
    -------
    str
        One of :data:`FRICTION_LAWS`.
    """
    from ..model.friction import lugre_of

    law = getattr(model.params, "observer_law", None)
    if law is not None:
        return law
    return "lugre" if lugre_of(model) is not None else "smooth"


def library_law(model: Model, friction_law: str) -> str:
    """The name in :data:`LIBRARY_LAWS` of the law the observer runs on ``model`` with ``friction_law``: ``creep``
    where ``friction_law`` is ``smooth`` and the file's ``friction.law`` is ``creep`` (the creep law solved in the
    smooth law's dynamics), else ``friction_law``.

    Parameters
    ----------
    model : Model
        The observer's model (its parameter file's ``friction.law``; a model without a file: none).
    friction_law : str
        The observer's law, one of :data:`FRICTION_LAWS`.

    Returns
    -------
    str
        A key of :data:`LIBRARY_LAWS`.

    Raises
    ------
    InputError
        ``friction_law`` not of :data:`FRICTION_LAWS`.
    """
    from ..model.friction import creep_of

    law = check_friction_law(friction_law)
    return "creep" if law == "smooth" and creep_of(model) is not None else law


def law_model(model: Model, law: str) -> tuple[Model, str]:
    """``model`` with the library's law ``law`` (:data:`LIBRARY_LAWS`): the same model whose parameter file says
    ``friction.law`` as the law needs (a copy, :meth:`~alpes_dyn.model.robot.Model.copy`: no refit, the file's
    other values kept; ``model`` itself where its file already says it or where the law reads no file), and the
    observer's law to run it with.

    Parameters
    ----------
    model : Model
        The observer's model.
    law : str
        A key of :data:`LIBRARY_LAWS`.

    Returns
    -------
    tuple of (Model, str)
        The model, and the observer's law of :data:`FRICTION_LAWS`.

    Raises
    ------
    InputError
        ``law`` not of :data:`LIBRARY_LAWS` (named ``law``), or ``creep`` on a model without a parameter file (the
        law's band is read from it).
    """
    from ..model.params import Param, with_values

    if not isinstance(law, str) or law not in LIBRARY_LAWS:
        raise InputError(f"law: expected one of {', '.join(LIBRARY_LAWS)}, got {law!r:.40}")
    observer, file_law = LIBRARY_LAWS[law]
    p = model.params
    if p is None:
        if file_law == "creep":
            raise InputError("law: creep needs a parameter file (friction.law, its band), the model has none")
        return model, observer
    if p.friction_law == file_law:
        return model, observer
    p = with_values(p, {"friction.law": Param(file_law, "-", "assumed", f"the {law} law of a law spread",
                                              "the joints' friction law")})
    return model.copy(params=p), observer


def coulomb_velocity(A: cs.SX, b: cs.SX, limit: Any, blocks: Sequence[Sequence[int]] | None = None) -> cs.SX:
    """argmin_v 1/2 v^T A v - b^T v + sum_i limit_i |v_i|, exactly, by enumerating the joints' modes.

    Block by block over the structural strongly connected components of A (one per finger of the hand, as
    :func:`~alpes_dyn.symbolic.dynamics.block_solve`), each joint with dry friction is stuck (v_i = 0), sliding
    forwards or backwards (friction impulse limit_i sign(v_i)); a joint without is always sliding. For each of the
    3^k modes of a block's k joints with dry friction, the sliding joints' velocities solve their rows exactly
    (:func:`~alpes_dyn.symbolic.dynamics.block_solve` on their sub-block), and the mode is kept if it is
    consistent: |lambda_i| <= limit_i on its stuck joints (lambda = b - A v, the friction impulse that holds them)
    and s_i v_i >= 0 on its sliding ones. The problem is strictly convex: exactly one v is consistent (at a
    boundary two modes give that same v; the first, the more stuck, is taken).

    Parameters
    ----------
    A : casadi.SX
        (n, n) symmetric positive definite (M + h diag(F_v), kg m^2).
    b : casadi.SX
        (n,) kg m^2 rad/s, M v + h N.
    limit : array_like
        (n,) numbers >= 0, h F_s (N m s).
    blocks : sequence of sequences of int, optional
        The joints of each block, where A's entries between blocks are zero in value but not in structure (a hand's
        mass matrix from a backend that does not keep its zeros, :func:`mass_blocks`); default A's structural
        blocks.

    Returns
    -------
    casadi.SX
        (n,) rad/s, v+ (the module's equation); exactly 0 on the stuck joints.

    Raises
    ------
    ModelError
        A block has more than :data:`MAX_DRY_JOINTS` joints with dry friction.
    """
    n = b.shape[0]
    lim = np.asarray(limit, dtype=float).reshape(-1)
    if blocks is None:
        nb, perm, offsets = A.sparsity().scc()
        blocks = [list(perm[offsets[k]:offsets[k + 1]]) for k in range(nb)]
    v: list[Any] = [None] * n
    for rows in blocks:  # a loop over the hand's fingers, when the expression is built
        rows = list(rows)
        vb = _block_velocity(A[rows, rows], b[rows], lim[rows])
        for i, row in enumerate(rows):
            v[row] = vb[i]
    return cs.vertcat(*v)


def _block_velocity(A: cs.SX, b: cs.SX, lim: np.ndarray) -> cs.SX:
    """:func:`coulomb_velocity` on one block: the consistent mode's velocity (if_else over the 3^k modes, the more
    stuck first; the frictionless A^-1 b where rounding leaves none consistent)."""
    n = lim.size
    dry = [i for i in range(n) if lim[i] > 0]
    if len(dry) > MAX_DRY_JOINTS:
        raise ModelError(f"friction_law: 'stick' resolves at most {MAX_DRY_JOINTS} coupled joints with dry friction "
                         f"(3^k modes), a chain here has {len(dry)}; use 'smooth'")
    out = block_solve(A, b)
    modes = list(itertools.product((0, 1, -1), repeat=len(dry)))
    for mode in reversed(modes):  # built from the last, so that the first consistent mode is the outermost choice
        sign = dict(zip(dry, mode))
        sliding = [i for i in range(n) if sign.get(i, 1) != 0]
        vm = cs.SX.zeros(n)
        if sliding:
            push = cs.DM([lim[i] * sign.get(i, 0) for i in sliding])
            vm[sliding] = block_solve(A[sliding, sliding], b[sliding] - push)
        lam = b - cs.mtimes(A, vm)
        ok = cs.SX(1)
        for i in dry:
            ok = cs.logic_and(ok, cs.fabs(lam[i]) <= lim[i] if sign[i] == 0 else sign[i] * vm[i] >= 0)
        out = cs.if_else(ok, vm, out)
    return out


def mass_blocks(model: Model) -> list[list[int]]:
    """The joints of each block of ``model``'s mass matrix (with its rotors), from its value at a generic
    configuration (the mid-point of each joint's range, or 0.3 rad where the range is open): two joints share a block
    where one drives the other through the tree or a tendon. A fixed-base tree's branches from the root never couple,
    whatever q, so the blocks found at one q are those at every q.

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.

    Returns
    -------
    list of list of int
        The joints' indices of each block, in order.
    """
    lo, hi = model.lower, model.upper
    q = np.where(np.isfinite(lo) & np.isfinite(hi) & (hi - lo < 10.0), 0.5 * (lo + hi), 0.3)
    coupled = model.inertia_matrix(q) != 0.0
    label = np.arange(model.n)
    for _ in range(model.n):  # propagate the smallest joint index along the couplings (n joints: n rounds at most)
        label = np.min(np.where(coupled, label[None, :], model.n), axis=1)
    return [np.flatnonzero(label == k).tolist() for k in np.unique(label)]


def stick_step_expression(ss: StateSpace, x: cs.SX, tau: cs.SX, F: Any, h: float) -> cs.SX:
    """One step of h seconds of the time-stepping Coulomb law (module docstring): x+ = [q + h v+; v+], (2n,).

    Parameters
    ----------
    ss : StateSpace
        The system (its model's springs, F_s and F_v; its tip or contacts for ``F``).
    x : casadi.SX
        (2n,) [q; v], rad and rad/s.
    tau : casadi.SX
        (n,) N m, the joint torques of the inputs (:meth:`~alpes_dyn.symbolic.statespace.StateSpace.input_torque`).
    F : casadi.SX or None
        The contact force(s) of a state space with ``force=True`` (N), else None.
    h : float
        The step, s (> 0).
    """
    n = ss.n
    q, v = x[:n], x[n: 2 * n]
    sym = ss.sym
    ex = sym.extras
    passive = ex.spring_torque(q, cs)
    if F is not None and not ss._legacy_force:
        net = sym.net_torque(q, v, tau, passive, F, None, ss.contacts)
    else:
        net = sym.net_torque(q, v, tau, passive, F, ss.tip)
    M = sym.inertia_matrix(q)
    A = M + cs.diag(cs.DM(h * ex.viscous)) if np.any(ex.viscous) else M
    b = cs.mtimes(M, v) + h * net
    vn = coulomb_velocity(A, b, h * np.asarray(ex.coulomb, dtype=float), mass_blocks(ss.model))
    return cs.vertcat(q + h * vn, vn)
