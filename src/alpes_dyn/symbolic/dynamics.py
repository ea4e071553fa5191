"""Symbolic (CasADi) dynamics of a :class:`~alpes_dyn.Model`, from the same URDF and extras.

One small interface, two backends:

* ``pinocchio.casadi`` (Pinocchio's CRBA/RNEA templated on ``casadi.SX``) whenever it imports --
  it is not in the ``pin`` wheels on PyPI (pinocchio issues #2578, #2759);
* otherwise ``adam-robotics``' CasADi backend on the model's URDF string, fixed base: the joint
  block of its floating-base mass matrix and bias force at identity base pose and zero base
  velocity, with the model's gravity (ADAM's default is 9.80665 m/s^2; Pinocchio's 9.81).

Both give A(q) (without rotor or joint-side inertia), the bias b(q, qd) = C(q, qd) qd + gravity torque, and
tip positions/Jacobians. The extras (springs, friction, rotor inertia) are applied here once,
through :class:`~alpes_dyn.model.extras.JointExtras` with ``xp=casadi``, exactly as the numeric model
applies them with ``xp=numpy``. Forward dynamics solves eq. 3.3 block by block: the mass matrix
of a fixed-base tree is block diagonal over the branches from the root (one per finger), and each
block is solved on its own by an unrolled LDL^T (:func:`block_solve`), which keeps the expressions
of the 15-DoF hand small.
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..errors import ModelError
from ..model.friction import creep_of
from ..model.contact import REFERENCE_FRAMES, as_contacts
from ..model.mimic import MimicCoupling, urdf_mimics
from ..model.robot import Model
from .creep import band_inertia, creep_friction
from .tree_sparsity import block_solve, sparse_dm, tree_pattern  # noqa: F401 (block_solve, sparse_dm re-exported)

__all__ = ["SymbolicDynamics", "available_backends", "block_solve", "sparse_dm"]


def available_backends() -> tuple[str, ...]:
    """Symbolic backends importable here, preferred first."""
    out = []
    try:
        import pinocchio.casadi  # noqa: F401

        out.append("pinocchio.casadi")
    except ImportError:
        pass
    try:
        import adam.casadi  # noqa: F401

        out.append("adam")
    except ImportError:
        pass
    return tuple(out)


def _adam_parents(tree: Any, names: Sequence[str]) -> list[int]:
    """Each of ``names``' parent joint among ``names`` (-1 on the base) in ADAM's model ``tree`` (its joints'
    parent and child links; fixed joints passed through)."""
    by_child = {j.child: j for j in tree.joints.values()}
    index = {name: k for k, name in enumerate(names)}
    out = []
    for name in names:  # (a loop over the joints, once per model)
        j = by_child.get(tree.joints[name].parent)
        while j is not None and j.name not in index:
            j = by_child.get(j.parent)
        out.append(-1 if j is None else index[j.name])
    return out


class _Adam:
    """ADAM's KinDynComputations on the URDF. With ``<mimic>`` joints (which ADAM reads as independent joints) it is
    given the whole tree, the model's joints then the mimic ones, and every term is restricted to q_full = G q + o
    (:mod:`alpes_dyn.model.mimic`): G^T A G, G^T b(q_full, G qd), G^T g, the frames at q_full."""

    name = "adam"

    def __init__(self, model: Model) -> None:
        from adam.casadi import KinDynComputations

        g6 = np.concatenate([model.gravity, np.zeros(3)])
        names = list(model.joint_names)
        mimics = urdf_mimics(model.urdf)
        self.G: cs.DM | None = None
        if mimics:
            coupling = MimicCoupling(mimics, names, names + [m.name for m in mimics])
            names = list(coupling.full_names)
            self.G, self.o = sparse_dm(coupling.G), cs.DM(coupling.offset)
        try:
            self.kd = KinDynComputations(model.urdf, names, gravity=g6)
        except Exception as exc:  # adam raises assorted errors on bad URDFs
            raise ModelError(f"URDF could not be loaded by ADAM: {str(exc).splitlines()[0] if str(exc) else exc}") from None
        self.pattern = tree_pattern(_adam_parents(self.kd.rbdalgos.model, names))
        self.H = cs.SX.eye(4)
        self.vb = cs.SX.zeros(6)
        self.model_name = getattr(model, "name", "")  # a shim of the parametric model has none

    def _full(self, q: cs.SX) -> cs.SX:
        return q if self.G is None else cs.mtimes(self.G, q) + self.o

    def _down(self, x: cs.SX) -> cs.SX:
        return x if self.G is None else cs.mtimes(self.G.T, x)

    def _adam(self, what: str, fn: Any, *args: Any) -> cs.SX:
        """ADAM's ``fn(*args)``; its failure on a tree it cannot take (ADAM 0.x's recursive Newton-Euler on
        Panda's URDF: a shape mismatch in its sum of velocities) a :class:`ModelError` naming the term, one line."""
        try:
            return fn(*args)
        except (ValueError, IndexError, TypeError) as exc:
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ModelError(f"backend 'adam': adam-robotics cannot compute the {what} of model {self.model_name!r} "
                             f"({msg}); no symbolic model of it here") from None

    def mass_matrix(self, q: cs.SX) -> cs.SX:
        M = cs.project(self._adam("mass matrix", self.kd.mass_matrix, self.H, self._full(q))[6:, 6:], self.pattern)
        return M if self.G is None else cs.mtimes(self.G.T, cs.mtimes(M, self.G))

    def bias(self, q: cs.SX, v: cs.SX) -> cs.SX:
        vf = v if self.G is None else cs.mtimes(self.G, v)
        return self._down(self._adam("bias forces", self.kd.bias_force, self.H, self._full(q), self.vb, vf)[6:])

    def gravity(self, q: cs.SX) -> cs.SX:
        return self._down(self._adam("gravity torques", self.kd.gravity_term, self.H, self._full(q))[6:])

    def com_position(self, q: cs.SX) -> cs.SX:
        """The centre of mass (3,), m, at q (n,): at q_full on a model with mimic joints."""
        return self.kd.CoM_position(self.H, self._full(q))

    def tip_position(self, q: cs.SX, frame: str) -> cs.SX:
        return self.kd.forward_kinematics(frame, self.H, self._full(q))[:3, 3]

    def frame_pose(self, q: cs.SX, frame: str) -> tuple[cs.SX, cs.SX]:
        T = self.kd.forward_kinematics(frame, self.H, self._full(q))
        return T[:3, :3], T[:3, 3]


class _PinCasadi:  # pragma: no cover - pinocchio.casadi is not in the PyPI wheels used in CI
    name = "pinocchio.casadi"

    def __init__(self, model: Model) -> None:
        import pinocchio as pin
        import pinocchio.casadi as cpin

        self.pin, self.cpin = pin, cpin
        if model.mimic is not None:
            raise ModelError(f"backend 'pinocchio.casadi': model {model.name!r} has mimic joints "
                             f"({', '.join(model.mimic.mimic_names)}), which it is not tested on; use backend='adam'")
        m = model.pin_model.copy()
        m.armature[:] = 0.0
        self.cmodel = cpin.Model(m)
        self.cdata = self.cmodel.createData()
        self.frames = {f.name: i for i, f in enumerate(m.frames)}

    def mass_matrix(self, q: cs.SX) -> cs.SX:
        M = self.cpin.crba(self.cmodel, self.cdata, q)
        return cs.triu(M) + cs.triu(M, False).T

    def bias(self, q: cs.SX, v: cs.SX) -> cs.SX:
        return self.cpin.nonLinearEffects(self.cmodel, self.cdata, q, v)

    def gravity(self, q: cs.SX) -> cs.SX:
        return self.cpin.computeGeneralizedGravity(self.cmodel, self.cdata, q)

    def tip_position(self, q: cs.SX, frame: str) -> cs.SX:
        self.cpin.framesForwardKinematics(self.cmodel, self.cdata, q)
        return self.cdata.oMf[self.frames[frame]].translation

    def frame_pose(self, q: cs.SX, frame: str) -> tuple[cs.SX, cs.SX]:
        self.cpin.framesForwardKinematics(self.cmodel, self.cdata, q)
        M = self.cdata.oMf[self.frames[frame]]
        return M.rotation, M.translation


class SymbolicDynamics:
    """CasADi SX expressions of a model's dynamics (eq. 2.10, 3.3).

    Parameters
    ----------
    model : Model
        The numeric model; its URDF, gravity and extras are reused as they are.
    backend : str, optional
        ``"auto"`` (``pinocchio.casadi`` if it imports, else ``"adam"``), ``"adam"`` or
        ``"pinocchio.casadi"``.

    Every method takes ``casadi.SX`` columns (q, v, tau of length n) and returns SX.
    """

    def __init__(self, model: Model, backend: str = "auto") -> None:
        have = available_backends()
        if backend == "auto":
            if not have:
                raise ModelError("no symbolic backend: install adam-robotics (or a pinocchio with casadi)")
            backend = have[0]
        if backend not in ("adam", "pinocchio.casadi"):
            raise ModelError(f"unknown symbolic backend {backend!r} (expected auto, adam or pinocchio.casadi)")
        if backend not in have:
            raise ModelError(f"symbolic backend {backend!r} is not importable here (have: {', '.join(have) or 'none'})")
        self.model = model
        self.n = model.n
        self._be: Any = _PinCasadi(model) if backend == "pinocchio.casadi" else _Adam(model)
        self.backend: str = self._be.name
        self.extras = model.extras

    def _tip(self, tip: str | None) -> str:
        self.model.frame_id(tip)  # validates
        return tip if tip is not None else self.model.default_tip

    def inertia_matrix(self, q: cs.SX) -> cs.SX:
        """A(q) + I_a (n, n): the rigid-body mass matrix plus the joint-side ``armature`` on the
        diagonal and the rotors' S^T diag(J_m) S (eq. 2.8, :attr:`Model.rotor_matrix
        <alpes_dyn.Model.rotor_matrix>`; its structural zeros kept, so :func:`block_solve` still
        splits the hand by finger).

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.

        Returns
        -------
        casadi.SX
            (n, n) kg m^2.
        """
        M = self._be.mass_matrix(q)
        if np.any(self.extras.armature != 0):
            M = M + cs.diag(cs.DM(self.extras.armature))
        if self.model._rotor_curved:  # rho(q)^T diag(J_m) rho(q), rho's structure that of S
            tr = self.model.transmission
            rho = tr.curve.ratio(q, cs)
            M = M + cs.mtimes(rho.T, cs.mtimes(cs.diag(cs.DM(tr.rotor_inertia)), rho))
        elif self.model._rotor:
            M = M + sparse_dm(self.model.rotor_matrix)
        return M

    def rotor_bias(self, q: cs.SX, v: cs.SX) -> cs.SX:
        """rho(q)^T diag(J_m) (drho/dt) qd (n,), the rotors' velocity product on ratios that change with q (zeros
        otherwise; :meth:`Transmission.rotor_bias <alpes_dyn.model.transmission.Transmission.rotor_bias>`).

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        v : casadi.SX
            (n,) joint velocities, rad/s.

        Returns
        -------
        casadi.SX
            (n,) N m.
        """
        if not self.model._rotor_curved:
            return cs.SX.zeros(self.n)
        tr = self.model.transmission
        return cs.mtimes(tr.curve.ratio(q, cs).T, cs.DM(tr.rotor_inertia) * tr.curve.rate_product(q, v, cs))

    def bias_torque(self, q: cs.SX, v: cs.SX) -> cs.SX:
        """C(q, qd) qd + gravity torque (no springs).

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        v : casadi.SX
            (n,) joint velocities, rad/s.

        Returns
        -------
        casadi.SX
            (n,) N m.
        """
        return self._be.bias(q, v)

    def gravity_torque(self, q: cs.SX) -> cs.SX:
        """G(q) of eq. 2.11: gravity plus springs.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.

        Returns
        -------
        casadi.SX
            (n,) N m.
        """
        return self._be.gravity(q) + self.extras.spring_torque(q, cs)

    def fingertip_position(self, q: cs.SX, tip: str | None = None) -> cs.SX:
        """Tip position in the base frame.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        tip : str or None, optional
            The tip frame (default: the model's first tip).

        Returns
        -------
        casadi.SX
            (3,) m.
        """
        return self._be.tip_position(q, self._tip(tip))

    def fingertip_jacobian(self, q: cs.SX, tip: str | None = None) -> cs.SX:
        """Linear Jacobian of a tip in the base frame (Section 2.2), by AD of its position.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        tip : str or None, optional
            The tip frame (default: the model's first tip).

        Returns
        -------
        casadi.SX
            (3, n) m/rad.
        """
        if not isinstance(q, cs.SX) or not q.is_valid_input():
            qs = cs.SX.sym("q", self.n)
            J = cs.jacobian(self.fingertip_position(qs, tip), qs)
            return cs.substitute(J, qs, q)
        return cs.jacobian(self.fingertip_position(q, tip), q)

    def frame_pose(self, q: cs.SX, frame: str) -> tuple[cs.SX, cs.SX]:
        """The pose of ``frame`` in the base frame.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        frame : str
            The frame's name.

        Returns
        -------
        tuple of casadi.SX
            (R (3, 3), p (3,) m).
        """
        return self._be.frame_pose(q, self._tip(frame))

    def frame_jacobian(self, q: cs.SX, frame: str | None = None, reference: str = "local_world_aligned",
                       dim: int = 6) -> cs.SX:
        """Frame Jacobian (6, n) [linear; angular] or (3, n) linear rows, in Pinocchio's ``reference``
        (:data:`~alpes_dyn.model.contact.REFERENCE_FRAMES`), by AD of the frame pose (R, p):
        J_v = dp/dq, column j of the angular part in base axes vee((dR/dq_j) R^T); ``local`` rotates
        both by R^T, ``world`` moves the linear part to the base origin, J_v + [p]x J_w.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        frame : str or None, optional
            The frame (default: the model's first tip).
        reference : str, optional
            One of :data:`~alpes_dyn.model.contact.REFERENCE_FRAMES`.
        dim : {3, 6}, optional
            The linear rows alone, or linear and angular.

        Returns
        -------
        casadi.SX
            (dim, n).
        """
        if reference not in REFERENCE_FRAMES:
            raise ModelError(f"reference: unknown {reference!r} (expected one of {', '.join(REFERENCE_FRAMES)})")
        if dim not in (3, 6) or isinstance(dim, bool):
            raise ModelError(f"dim: expected 3 (linear rows) or 6 (linear and angular), got {dim!r}")
        if not isinstance(q, cs.SX) or not q.is_valid_input():
            qs = cs.SX.sym("q", self.n)
            return cs.substitute(self.frame_jacobian(qs, frame, reference, dim), qs, q)
        R, p = self.frame_pose(q, frame)
        Jv = cs.jacobian(p, q)
        if reference == "local_world_aligned" and dim == 3:
            return Jv
        dR = cs.jacobian(cs.vec(R), q)  # (9, n), column-major vec
        cols = []
        for j in range(self.n):
            W = cs.mtimes(cs.reshape(dR[:, j], 3, 3), R.T)
            cols.append(cs.vertcat(W[2, 1], W[0, 2], W[1, 0]))
        Jw = cs.horzcat(*cols)
        if reference == "local":
            Jv, Jw = cs.mtimes(R.T, Jv), cs.mtimes(R.T, Jw)
        elif reference == "world":
            Jv = Jv + cs.mtimes(cs.skew(p), Jw)
        return cs.vertcat(Jv, Jw)[:dim, :]

    def contact_torque(self, q: cs.SX, F: Any, contacts: Any) -> cs.SX:
        """Sum of J_c^T F_c (eq. 2.9), (n,), for ``contacts`` (:class:`~alpes_dyn.model.contact.Contact` or frame
        names) and their stacked forces/wrenches.

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        F : casadi.SX or array_like
            (sum of the contacts' dims,) the stacked forces (N) and wrenches.
        contacts : sequence
            :class:`~alpes_dyn.model.contact.Contact` or frame names.

        Returns
        -------
        casadi.SX
            (n,) N m.
        """
        cts = as_contacts(contacts)
        out = cs.SX.zeros(self.n)
        k = 0
        for c in cts:
            J = self.frame_jacobian(q, c.frame, c.reference, c.dim)
            out = out + cs.mtimes(J.T, F[k: k + c.dim])
            k += c.dim
        return out

    def forward_dynamics(self, q: cs.SX, v: cs.SX, tau: cs.SX, F: Any = None, tip: str | None = None,
                         smooth: bool = True, contacts: Any = None) -> cs.SX:
        """qdd = (A + I_a)^-1 (tau + J^T F - C qd - G - friction) (eq. 3.3, 3.12), (n,).

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        v : casadi.SX
            (n,) joint velocities, rad/s.
        tau : casadi.SX
            (n,) joint torques, N m.
        F : casadi.SX or array_like or None, optional
            A 3-vector at ``tip`` in the base frame, or with ``contacts`` the stacked F of them all
            (:meth:`contact_torque`).
        tip : str or None, optional
            The tip frame (default: the model's first tip).
        contacts : sequence or None, optional
            Several frames, forces or wrenches (:meth:`contact_torque`).
        smooth : bool, optional
            tanh for the Coulomb sign (default True: the result is differentiable); on a model whose file's
            ``friction.law`` is ``creep``, the creep law instead (:class:`~alpes_dyn.model.friction.Creep`,
            solved with the dynamics: :func:`~alpes_dyn.symbolic.creep.creep_friction`).

        Returns
        -------
        casadi.SX
            (n,) rad/s^2.
        """
        law = creep_of(self.model) if self.extras.has_friction else None
        if law is None:
            rhs = self.net_torque(q, v, tau, self.extras.passive_torque(q, v, smooth, cs), F, tip, contacts)
            return block_solve(self.inertia_matrix(q), rhs)
        # the creep law (model.friction.Creep): the dry friction solved with the dynamics (symbolic.creep)
        passive = self.extras.spring_torque(q, cs) + cs.DM(self.extras.viscous) * v
        rhs, M = self.net_torque(q, v, tau, passive, F, tip, contacts), self.inertia_matrix(q)
        a = band_inertia(self._be.mass_matrix(cs.SX.zeros(self.n)), law.kappa)  # the links' at q = 0
        Fs = np.asarray(self.extras.coulomb, dtype=float)
        return block_solve(M, rhs - creep_friction(M, rhs, v, cs.DM(Fs), a, law.rate, Fs > 0))

    def net_torque(self, q: cs.SX, v: cs.SX, tau: cs.SX, passive: Any, F: Any = None, tip: str | None = None,
                   contacts: Any = None) -> cs.SX:
        """The right side of eq. 3.3, tau + J^T F - C qd - G - ``passive``, (n,) N m: what the mass matrix
        accelerates. ``passive`` (n,) N m: the extras' torque (springs and friction,
        :meth:`~alpes_dyn.model.extras.JointExtras.passive_torque`, in :meth:`forward_dynamics`; the springs alone
        in a step that resolves the dry friction itself, :mod:`alpes_dyn.simulation.stick`).

        Parameters
        ----------
        q : casadi.SX
            (n,) joint angles, rad.
        v : casadi.SX
            (n,) joint velocities, rad/s.
        tau : casadi.SX
            (n,) joint torques, N m.
        passive : casadi.SX
            (n,) the extras' torque, N m.
        F : casadi.SX or array_like or None, optional
            A 3-vector at ``tip`` in the base frame, or with ``contacts`` the stacked F of them all
            (:meth:`contact_torque`).
        tip : str or None, optional
            The tip frame (default: the model's first tip).
        contacts : sequence or None, optional
            Several frames, forces or wrenches (:meth:`contact_torque`).

        Returns
        -------
        casadi.SX
            (n,) N m.
        """
        rhs = tau - self.bias_torque(q, v) - passive
        if self.model._rotor_curved:
            rhs = rhs - self.rotor_bias(q, v)
        if F is not None and contacts is not None:
            rhs = rhs + self.contact_torque(q, F, contacts)
        elif F is not None:
            rhs = rhs + cs.mtimes(self.fingertip_jacobian(q, tip).T, F)
        return rhs

    def forward_dynamics_function(self, with_force: bool = False, tip: str | None = None,
                                  smooth: bool = True) -> cs.Function:
        """``casadi.Function`` ``fd(q, v, tau[, F]) -> qdd``.

        Parameters
        ----------
        with_force : bool, optional
            F (3,) at ``tip`` an input.
        tip : str or None, optional
            The tip frame (default: the model's first tip).
        smooth : bool, optional
            tanh for the Coulomb sign.

        Returns
        -------
        casadi.Function
            The forward dynamics.
        """
        q, v, tau = (cs.SX.sym(s, self.n) for s in ("q", "v", "tau"))
        if with_force:
            F = cs.SX.sym("F", 3)
            return cs.Function("forward_dynamics", [q, v, tau, F],
                               [self.forward_dynamics(q, v, tau, F, tip, smooth)], ["q", "v", "tau", "F"], ["qdd"])
        return cs.Function("forward_dynamics", [q, v, tau], [self.forward_dynamics(q, v, tau, None, tip, smooth)],
                           ["q", "v", "tau"], ["qdd"])
