"""State-space form of the dynamics (report eq. 3.1-3.3, 3.11, 3.16).

x = [q; qd] (2n), xdot = f(x, u[, F]) = [qd; qdd(q, qd, B u, F)], y = h(x).

Inputs (``input=``):

* ``"joint"`` -- u = Gamma, the joint torques (n), the report's choice;
* ``"motor"`` -- u = tau_m, the motor torques (m), acting through the tendon transmission
  Gamma = S^T tau_m (:class:`~alpes_dyn.Transmission`), rho(q)^T tau_m where the ratios change with q
  (:meth:`StateSpace.input_torque`).

Measured contact forces are optional known inputs F: ``force=True`` is the report's one force
(eq. 2.9, 2.13: a 3-vector at the model's first tip, or ``tip``, base axes); ``contacts=`` any number
of forces or wrenches at any frames in any of Pinocchio's reference frames
(:class:`~alpes_dyn.model.contact.Contact`, or frame names for 3-D forces in base axes), stacked in F in the
order given.

Outputs (``output=``; one of them, or a list of them stacked in order):

* ``"sum"`` -- y = q_1 + ... + q_k per motor (the report's, one row per motor: the joints it drives);
* ``"encoder"`` -- q_m = S q per motor (Section 3: (r/r_m) sum q on the Alpes hand); s(q) = L(q) / r_m where the
  ratios change with q (the transmission's ``ratio_curve``, :mod:`alpes_dyn.model.ratio_curve`);
* ``"joints"`` -- y = q, every joint; ``"joints:<a>,<b>"`` -- the named joints;
* ``"tip_position:<frame>"`` -- the frame's position in the base frame (3 rows, m);
* a (p, n) array -- y = H q; a (p, 2n) array -- y = H x = H [q; qd];
* a callable ``g(q, xp)`` or ``g(q, v, xp)`` returning y for q (and qd) as numpy arrays
  (``xp=numpy``) and as CasADi SX columns (``xp=casadi``).

f and h exist both numerically (Pinocchio ABA, :meth:`StateSpace.f`) and symbolically (CasADi SX,
:attr:`StateSpace.f_expr`), from the same URDF and the same extras.
"""

from __future__ import annotations

import inspect
from typing import Any, Callable, NamedTuple

import casadi as cs
import numpy as np

from ..errors import InputError, ModelError
from ..limits import check_time_step
from ..rebuild import Rebuilt
from ..model.contact import Contact, as_contacts
from ..model.robot import Model
from .dynamics import SymbolicDynamics

__all__ = ["StateSpace", "INPUTS", "OUTPUTS"]

INPUTS = ("joint", "motor")
OUTPUTS = ("sum", "encoder", "joints", "joints:<names>", "tip_position:<frame>")


class _Output(NamedTuple):
    """One block of rows of h: symbolic and numeric forms, row names, (rows, 2n) matrix if linear."""

    sym: Callable[[Any, Any], Any]
    num: Callable[[np.ndarray, np.ndarray], np.ndarray]
    names: tuple[str, ...]
    matrix: np.ndarray | None


def _output_matrix(output: Any, n: int) -> np.ndarray:
    """An output matrix H (p, n) of finite numbers, else a ModelError saying what is wrong."""
    try:
        H = np.atleast_2d(np.asarray(output, dtype=float))
    except (TypeError, ValueError):
        raise ModelError(f"output matrix: expected a (p, {n}) array of numbers, got {output!r}") from None
    if H.ndim != 2 or H.shape[1] != n or H.shape[0] < 1:
        raise ModelError(f"output matrix: expected a finite (p, {n}) array, got shape {H.shape}")
    if not np.isfinite(H).all():
        raise ModelError("output matrix: contains NaN or inf")
    return H


def _output_expression(y: Any) -> cs.SX:
    """The column of what an output callable returned for a CasADi symbol (SX, numbers or a list of them)."""
    items = list(y) if isinstance(y, (list, tuple)) else [y]
    try:
        if not items or any(v is None or isinstance(v, (str, bytes)) for v in items):
            raise TypeError
        return cs.vec(cs.vertcat(*[cs.vec(cs.SX(v)) for v in items]))
    except (TypeError, NotImplementedError, RuntimeError, ValueError):
        raise ModelError(f"output function: returned {type(y).__name__} {y!r:.60}, expected CasADi expressions "
                         "or numbers") from None


class StateSpace(Rebuilt):
    """x' = f(x, u[, F]), y = h(x) for a :class:`~alpes_dyn.Model`.

    Parameters
    ----------
    model : Model
        The dynamics.
    input : {"joint", "motor"}, optional
        Joint torques Gamma or motor torques tau_m.
    output : str or array_like or callable or list, optional
        A preset (``"sum"``, ``"encoder"``, ``"joints"``, ``"joints:<a>,<b>"``, ``"tip_position:<frame>"``), a
        (p, n) or (p, 2n) matrix, a callable ``g(q, xp)`` or ``g(q, v, xp)``, or a list of these (rows stacked in
        order); see the module doc.
    force : bool, optional
        Add the contact force F (3,) at ``tip`` (base axes) as a known input.
    tip : str or None, optional
        The tip frame of F (default: the model's first tip).
    smooth : bool, optional
        tanh for the Coulomb sign (default True: f is differentiable).
    backend : str, optional
        The symbolic backend, see :class:`~alpes_dyn.symbolic.dynamics.SymbolicDynamics`.
    contacts : list or None, optional
        Several contact forces/wrenches as known inputs, a list of :class:`~alpes_dyn.model.contact.Contact` or
        frame names (instead of ``force``/``tip``).

    Attributes
    ----------
    n_states, n_inputs, n_outputs, n_force: 2n, m, p, length of F (0 without contacts).
    B: (n, m) input matrix, Gamma = B u.
    H: (p, n) output matrix when y = H q, else None; output_matrix: (p, 2n) when y = H x, else None.
    contacts: the contacts of F, in order; tip: the first contact's frame (or the default tip).
    state_names, input_names, force_names, output_names: labels of x, u, F and y.
    x, u, F: CasADi SX symbols; f_expr (2n,), h_expr (p,): SX expressions of them.
    f_function, h_function: ``casadi.Function`` f(x, u[, F]) and h(x).
    """

    def __init__(self, model: Model, input: str = "joint", output: Any = "sum",
                 force: bool = False, tip: str | None = None, smooth: bool = True, backend: str = "auto",
                 contacts: Any = None) -> None:
        if not isinstance(model, Model):
            raise ModelError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
        self._remember(model, input=input, output=output, force=force, tip=tip, smooth=smooth, backend=backend,
                       contacts=contacts)
        self.model = model
        n = model.n
        self.n = n
        if input not in INPUTS:
            raise ModelError(f"unknown input {input!r} (expected one of {', '.join(INPUTS)})")
        tr = model.transmission
        if input == "motor":
            if tr is None:
                raise ModelError(f"input 'motor' needs a tendon transmission; model {model.name!r} has none")
            self.B = tr.actuation_matrix.copy()
            self.input_names = tuple(f"tau_m_{m}" for m in tr.motor_names)
        else:
            self.B = np.eye(n)
            self.input_names = tuple(f"tau_{j}" for j in model.joint_names)
        self.input = input
        self.smooth = smooth
        self.state_names = tuple(f"q_{j}" for j in model.joint_names) + tuple(f"qd_{j}" for j in model.joint_names)

        # contact forces
        if contacts is not None:
            self.contacts: tuple[Contact, ...] = as_contacts(contacts)
            if tip is not None:
                raise ModelError("tip: give the contact frames in contacts=, not tip=")
            for c in self.contacts:
                model.frame_id(c.frame)
            self._legacy_force = False
        elif force:
            t = tip if tip is not None else model.default_tip
            model.frame_id(t)
            self.contacts = (Contact(t),)
            self._legacy_force = True
        else:
            self.contacts = ()
            self._legacy_force = False
        self.force = bool(self.contacts)
        self.tip = self.contacts[0].frame if self.contacts else (tip if tip is not None else (
            model.tips[0] if model.tips and model.tips_named else None))
        self.force_names: tuple[str, ...] = (("F_x", "F_y", "F_z") if self._legacy_force
                                             else tuple(nm for c in self.contacts for nm in c.names))

        # symbolic f (eq. 3.3)
        self.sym = SymbolicDynamics(model, backend)
        self.x = cs.SX.sym("x", 2 * n)
        self.u = cs.SX.sym("u", self.B.shape[1])
        self.F = cs.SX.sym("F", len(self.force_names)) if self.force else None
        q, v = self.x[:n], self.x[n:]
        self._curve = tr.curve if input == "motor" and tr.curved else None
        tau = self.input_torque(q, self.u, v)
        qdd = self.sym.forward_dynamics(q, v, tau, self.F, self.tip, smooth,
                                        None if (self._legacy_force or not self.force) else self.contacts)
        self.f_expr: cs.SX = cs.vertcat(v, qdd)

        # output map
        pieces = self._outputs(output)
        self._pieces = pieces
        self.output_name: str = _output_label(output)
        self.h_expr: cs.SX = cs.vertcat(*(_output_expression(pc.sym(q, v)) for pc in pieces)) if pieces else cs.SX(0, 1)
        self.output_names = tuple(nm for pc in pieces for nm in pc.names)
        if len(self.output_names) != self.h_expr.shape[0]:  # callables: row names once the size is known
            self.output_names = tuple(f"y{i}" for i in range(self.h_expr.shape[0]))
        twice = next((nm for nm in self.output_names if self.output_names.count(nm) > 1), None)
        if twice is not None:  # y would hold the same row twice under one name (its Jacobian, rank-deficient)
            raise InputError(f"output: {twice!r} is asked for twice in {self.output_name!r}; name each output once")
        mats = [pc.matrix for pc in pieces]
        self.output_matrix: np.ndarray | None = np.vstack(mats) if mats and all(M is not None for M in mats) else None
        self.H: np.ndarray | None = (self.output_matrix[:, :n].copy() if self.output_matrix is not None
                                     and not self.output_matrix[:, n:].any() else None)
        ins = [self.x, self.u] + ([self.F] if self.force else [])
        names = ["x", "u"] + (["F"] if self.force else [])
        self.f_function = cs.Function("f", ins, [self.f_expr], names, ["xdot"])
        self.h_function = cs.Function("h", [self.x], [self.h_expr], ["x"], ["y"])

    # ---------------------------------------------------------------- output map
    def _outputs(self, output: Any) -> list[_Output]:
        if isinstance(output, (list, tuple)):
            if not output:
                raise ModelError("output: an empty list")
            return [pc for o in output for pc in self._outputs(o)]
        model, n = self.model, self.n
        tr = model.transmission
        if isinstance(output, str):
            kind, _, arg = output.partition(":")
            if kind in ("sum", "encoder") and not arg:
                if tr is None:
                    raise ModelError(f"output {output!r} needs a tendon transmission; model {model.name!r} has none")
                prefix = "sum" if kind == "sum" else "q_m"
                if kind == "encoder" and tr.curved:  # s(q) = L(q) / r_m: nonlinear, its Jacobian rho(q)
                    c = tr.curve
                    return [_Output(lambda q, v: c.angle(q, cs), lambda q, v: c.angle(q),
                                    tuple(f"{prefix}_{m}" for m in tr.motor_names), None)]
                H = (tr.sum_matrix if kind == "sum" else tr.S).copy()
                return [self._linear(np.hstack([H, np.zeros_like(H)]), tuple(f"{prefix}_{m}" for m in tr.motor_names))]
            if kind == "joints":
                names = model.joint_names if not arg else tuple(j.strip() for j in arg.split(","))
                idx = [model.joint_index(j) for j in names]
                H = np.zeros((len(idx), 2 * n))
                H[np.arange(len(idx)), idx] = 1.0
                return [self._linear(H, tuple(f"q_{j}" for j in names))]
            if kind == "tip_position" and arg:
                model.frame_id(arg)
                return [_Output(lambda q, v, f=arg: self.sym.fingertip_position(q, f),
                                lambda q, v, f=arg: model.fingertip_position(q, f),
                                tuple(f"{c}_{arg}" for c in ("x", "y", "z")), None)]
            raise ModelError(f"unknown output {output!r} (expected one of {', '.join(OUTPUTS)}, a matrix or a callable)")
        if callable(output):
            try:
                nargs = len(inspect.signature(output).parameters)
            except (TypeError, ValueError):
                nargs = 2
            if nargs not in (2, 3):
                raise ModelError(f"output function: expected g(q, xp) or g(q, v, xp), got {nargs} parameters")
            g = output
            sym = (lambda q, v: _call_sym(g, q, v, nargs))
            num = (lambda q, v: np.asarray(g(q, np) if nargs == 2 else g(q, v, np), dtype=float).reshape(-1))
            return [_Output(sym, num, (), None)]
        try:
            H = np.atleast_2d(np.asarray(output, dtype=float))
        except (TypeError, ValueError):
            raise ModelError(f"output: expected a preset name, a matrix or a callable, got {output!r}") from None
        if H.ndim != 2 or H.shape[1] not in (n, 2 * n) or H.shape[0] < 1:
            raise ModelError(f"output matrix: expected a finite (p, {n}) or (p, {2 * n}) array, got shape {H.shape}")
        if not np.isfinite(H).all():
            raise ModelError("output matrix: contains NaN or inf")
        if H.shape[1] == n:
            H = np.hstack([H, np.zeros_like(H)])
        return [self._linear(H, tuple(f"y{i}" for i in range(H.shape[0])))]

    def _linear(self, H: np.ndarray, names: tuple[str, ...]) -> _Output:
        n = self.n
        Hq, Hv = H[:, :n], H[:, n:]
        if Hv.any():
            return _Output(lambda q, v: cs.mtimes(cs.DM(H), cs.vertcat(q, v)),
                           lambda q, v: Hq @ q + Hv @ v, names, H)
        return _Output(lambda q, v: cs.mtimes(cs.DM(Hq), q), lambda q, v: Hq @ q, names, H)

    def input_torque(self, q: Any, u: Any, v: Any = None) -> Any:
        """The joint torques Gamma (n,) of the input u: B u, or rho(q)^T u for motor torques on ratios that change
        with q (the transmission's ``ratio_curve``; :attr:`B` is then rho(0)^T). Motor torques through tendons with
        sheath friction (the transmission's ``capstan``) lose :func:`~alpes_dyn.model.transmission.capstan_torque`'s
        share at the motor velocities rho(q) v.

        Parameters
        ----------
        q : ndarray or casadi.SX
            (n,) joint angles, rad.
        u : ndarray or casadi.SX
            (m,) the input (joint or motor torques, N m).
        v : ndarray or casadi.SX or None, optional
            (n,) joint velocities, rad/s (required with sheath friction).

        Returns
        -------
        ndarray or casadi.SX
            (n,) N m (SX for CasADi q, u).
        """
        numeric = isinstance(u, np.ndarray) and isinstance(q, np.ndarray)
        tr = self.model.transmission
        if self.input == "motor" and tr.has_capstan:
            if v is None:
                raise InputError("v: motor torques through tendons with sheath friction (capstan) need the joint "
                                 "velocities")
            if numeric:
                vm = v @ self.B if self._curve is None else self._curve.ratio(q) @ v
                u = tr.transmitted(u, vm, self.model.extras.smooth_velocity)
            else:
                vm = (cs.mtimes(cs.DM(self.B.T), v) if self._curve is None
                      else cs.mtimes(self._curve.ratio(q, cs), v))
                u = tr.transmitted(u, vm, self.model.extras.smooth_velocity, cs)
        if self._curve is None:
            return self.B @ u if numeric else cs.mtimes(cs.DM(self.B), u)
        return self._curve.ratio(q).T @ u if numeric else cs.mtimes(self._curve.ratio(q, cs).T, u)

    # ---------------------------------------------------------------- sizes
    @property
    def n_states(self) -> int:
        return 2 * self.n

    @property
    def n_inputs(self) -> int:
        return int(self.B.shape[1])

    @property
    def n_force(self) -> int:
        """Length of the contact-force input F (0 without contacts)."""
        return 0 if self.F is None else int(self.F.shape[0])

    @property
    def n_outputs(self) -> int:
        return int(self.h_expr.shape[0])

    def __repr__(self) -> str:
        return (f"StateSpace({self.model.name!r}, states={self.n_states}, input={self.input!r} ({self.n_inputs}), "
                f"output={self.output_name!r} ({self.n_outputs}), force={self.force})")

    # ---------------------------------------------------------------- numeric f, h
    def _check_x(self, x: Any) -> np.ndarray:
        return self.model.vector(x, "x", 2 * self.n)

    def f(self, x: np.ndarray, u: np.ndarray, F: np.ndarray | None = None) -> np.ndarray:
        """xdot = f(x, u[, F]), numerically with Pinocchio's ABA (eq. 3.3).

        Parameters
        ----------
        x : array_like
            (2n,) the state [q; v].
        u : array_like
            (m,) the input.
        F : array_like or None, optional
            The contact forces (with ``force`` or ``contacts``).

        Returns
        -------
        ndarray
            (2n,).
        """
        x = self._check_x(x)
        u = self.model.vector(u, "u", self.n_inputs)
        if self.force and F is None:
            raise InputError(f"F: this state space has contact forces as an input; pass F ({self.n_force},)")
        n = self.n
        if self.force and not self._legacy_force:
            qdd = self.model.forward_dynamics(x[:n], x[n:], self.input_torque(x[:n], u, x[n:]), F, None, self.smooth,
                                              self.contacts)
        else:
            qdd = self.model.forward_dynamics(x[:n], x[n:], self.input_torque(x[:n], u, x[n:]), F if self.force else None, self.tip,
                                              self.smooth)
        return np.concatenate([x[n:], qdd])

    # ---------------------------------------------------------------- equilibrium and linearisation
    def equilibrium(self, u: Any, F: Any = None, q0: Any = None, tol: float = 1e-12) -> np.ndarray:
        """The rest state x_eq = [q_eq; 0] (2n,) where f(x_eq, u[, F]) = 0: gravity, springs (and the contact
        forces) balance the input torques B u. Newton's method from ``q0`` (default 0) on
        G(q) - B u - sum J_c^T F_c = 0 (N m, eq. 2.10 at rest) to ``tol``, with the analytic Jacobian
        (:meth:`Model.static_equilibrium <alpes_dyn.Model.static_equilibrium>` without contacts; the
        contact term's by automatic differentiation).

        Parameters
        ----------
        u : array_like
            (m,) the input.
        F : array_like or None, optional
            The contact forces.
        q0 : array_like or None, optional
            (n,) Newton's start, rad (default 0).
        tol : float, optional
            The residual's tolerance, N m.

        Returns
        -------
        ndarray
            (2n,) the rest state.

        Raises
        ------
        InputError
            Newton's method does not converge.
        """
        u = self.model.vector(u, "u", self.n_inputs)
        tau = self.B @ u
        F = self._force_value(F)
        q0 = np.zeros(self.n) if q0 is None else self.model.vector(q0, "q0", self.n)
        if self._curve is not None:  # G(q) = rho(q)^T u: its Jacobian diag(sum_k u_k drho_ki/dq_i) off dG/dq
            from ..model.robot import newton_equilibrium

            if F is not None:
                raise InputError("F: the equilibrium under contact forces is not built for ratios that change with q")
            c = self._curve
            q = newton_equilibrium(lambda q: self.model.gravity_torque(q) - c.ratio(q).T @ u,
                                   lambda q: self.model.gravity_jacobian(q) - c.torque_jacobian(q, u), q0, tol)
        elif F is None:
            q = self.model.static_equilibrium(tau, q0, tol)
        else:
            from ..model.robot import newton_equilibrium

            ct = self._contact_torque_function()
            q = newton_equilibrium(
                lambda q: self.model.gravity_torque(q) - tau - np.asarray(ct(q, F)[0]).ravel(),
                lambda q: self.model.gravity_jacobian(q) - np.asarray(ct(q, F)[1]), q0, tol)
        return np.concatenate([q, np.zeros(self.n)])

    def _force_value(self, F: Any) -> np.ndarray | None:
        if self.force and F is None:
            raise InputError(f"F: this state space has contact forces as an input; pass F ({self.n_force},)")
        if not self.force and F is not None:
            raise InputError("F: this state space has no contact-force input (build it with force=True or contacts=)")
        return None if F is None else self.model.vector(F, "F", self.n_force)

    def _contact_torque_function(self) -> cs.Function:
        if getattr(self, "_ct_fun", None) is None:
            q = cs.SX.sym("q", self.n)
            tc = self.sym.contact_torque(q, self.F, self.contacts)
            self._ct_fun = cs.Function("contact", [q, self.F], [tc, cs.jacobian(tc, q)])
        return self._ct_fun

    def _jacobian_function(self) -> cs.Function:
        if getattr(self, "_lin_fun", None) is None:
            w = cs.vertcat(self.u, self.F) if self.force else self.u
            ins = [self.x, self.u] + ([self.F] if self.force else [])
            self._lin_fun = cs.Function("linearization", ins, [cs.jacobian(self.f_expr, self.x),
                                                               cs.jacobian(self.f_expr, w),
                                                               cs.jacobian(self.h_expr, self.x),
                                                               cs.jacobian(self.h_expr, w)])
        return self._lin_fun

    def linearize(self, x0: Any, u0: Any, F0: Any = None, dt: float | None = None,
                  method: str = "zoh") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) of the linearisation at (x0, u0[, F0]), as python-control's ``linearize``.

        Continuous (``dt`` None): dx' = A dx + B dw, dy = C dx + D dw with w = [u; F] (the contact
        forces, with ``force=True`` or ``contacts=``, are extra input columns after u): A = df/dx
        (2n, 2n), B = df/dw (2n, m [+ n_force]), C = dh/dx (p, 2n), D = dh/dw (p, m [+ n_force]; zero,
        h depends on x only), by automatic differentiation of the symbolic f and h (CasADi).
        Discrete (``dt`` > 0, s): x[k+1] = A_d x[k] + B_d w[k] with ``method`` ``"zoh"`` (the input held
        over the step: exp([[A, B], [0, 0]] dt), as ``control.sample_system(..., 'zoh')``) or
        ``"euler"`` (A_d = I + A dt, B_d = B dt); C and D are unchanged.

        Parameters
        ----------
        x0 : array_like
            (2n,) the operating state.
        u0 : array_like
            (m,) the operating input.
        F0 : array_like or None, optional
            The operating contact forces.
        dt : float or None, optional
            The sample period, s (None: continuous).
        method : {"zoh", "euler"}, optional
            The discretisation.

        Returns
        -------
        tuple of ndarray
            (A, B, C, D).
        """
        x0 = self._check_x(x0)
        u0 = self.model.vector(u0, "u", self.n_inputs)
        F0 = self._force_value(F0)
        if method not in ("zoh", "euler"):
            raise InputError(f"method: expected 'zoh' or 'euler', got {method!r}")
        if dt is not None and (isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating))
                               or not np.isfinite(dt) or dt <= 0):
            raise InputError(f"dt: expected a positive number of seconds or None, got {dt!r}")
        if dt is not None:
            check_time_step(float(dt))
        args = [x0, u0] + ([F0] if F0 is not None else [])
        A, B, C, D = (np.asarray(M, dtype=float) for M in self._jacobian_function()(*args))
        if not all(np.isfinite(M).all() for M in (A, B, C, D)):
            raise InputError("linearize: the Jacobians are not finite at this point (state or inputs too large?)")
        if dt is None:
            return A, B, C, D
        import warnings

        with warnings.catch_warnings():  # an overflow is refused below, as the non-finite result it gives
            warnings.simplefilter("ignore", RuntimeWarning)
            if method == "euler":
                Ad, Bd = np.eye(A.shape[0]) + A * dt, B * dt
            else:
                from scipy.linalg import expm

                N, m = A.shape[0], B.shape[1]
                E = np.zeros((N + m, N + m))
                E[:N, :N], E[:N, N:] = A, B
                Phi = expm(E * float(dt))
                Ad, Bd = Phi[:N, :N], Phi[:N, N:]
        if not (np.isfinite(Ad).all() and np.isfinite(Bd).all()):
            raise InputError(f"dt: the discrete A, B are not finite at dt = {float(dt):g} s (too long a step for "
                             "these dynamics)")
        return Ad, Bd, C, D

    def to_control(self, x0: Any, u0: Any, F0: Any = None, dt: float | None = None, method: str = "zoh") -> Any:
        """The linearisation (:meth:`linearize`) as a ``control.StateSpace`` (python-control, optional extra
        ``alpes_dyn[control]``) named after the model, with its state, input and output names; discrete
        with ``dt``.

        Parameters
        ----------
        x0, u0, F0, dt, method : see :meth:`linearize`
            The operating point and the discretisation.

        Returns
        -------
        control.StateSpace
            The linear system.
        """
        try:
            import control
        except ImportError:
            raise ModelError("to_control: python-control is not installed (pip install 'alpes_dyn[control]')") from None
        A, B, C, D = self.linearize(x0, u0, F0, dt, method)
        return control.ss(A, B, C, D, 0 if dt is None else float(dt), states=list(self.state_names),
                          inputs=list(self.input_names) + list(self.force_names), outputs=list(self.output_names),
                          name=self.model.name)

    def h(self, x: np.ndarray) -> np.ndarray:
        """y = h(x), numerically (Pinocchio for frame positions).

        Parameters
        ----------
        x : array_like
            (2n,) the state.

        Returns
        -------
        ndarray
            (p,).
        """
        x = self._check_x(x)
        q, v = x[: self.n], x[self.n:]
        return np.concatenate([np.asarray(pc.num(q, v), dtype=float).reshape(-1) for pc in self._pieces])


def _call_sym(g: Callable[..., Any], q: cs.SX, v: cs.SX, nargs: int) -> cs.SX:
    try:
        return g(q, cs) if nargs == 2 else g(q, v, cs)
    except Exception as exc:
        raise ModelError(f"output function failed on a CasADi symbol: {exc}") from None


def _output_label(output: Any) -> str:
    if isinstance(output, str):
        return output
    if isinstance(output, (list, tuple)):
        return "+".join(_output_label(o) for o in output)
    if callable(output):
        return getattr(output, "__name__", "custom")
    return "matrix"
