"""The EKF's step on a large state as loops over dense matrices, not one unrolled expression (issue 51, item 4).

The default step of :class:`~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter` is one CasADi ``SX``
expression: the model's RK4 substeps written out, their Jacobian A = dF/dz by automatic differentiation of that
expression, and the covariance arithmetic (:mod:`~alpes_dyn.estimation.observers.covariance`) one scalar operation
per entry. Its size grows with the state's cube and the substeps: on the Shadow hand with its wrist free (24 joints,
48 states) the Jacobian alone is too large for a build to finish in the memory of a workstation.

From :data:`LOOP_STATES` states on (or with ``looped=True``) the step is an ``MX`` graph of a few calls instead:

* the right-hand side f(z, w) and its dense Jacobians df/dz, df/dw, one ``SX`` function
  (:func:`stage_jacobians`; the stick and LuGre laws: one substep and its Jacobians);
* the RK4 stages, the substeps and the chain rule over them (:func:`linearization`): A = A_S ... A_1,
  G = sum over s of A_S ... A_s+1 G_s, with dk_s/dz = J_s (I + c_s dk_s-1/dz) -- the loops of the exported C
  (:mod:`~alpes_dyn.estimation.cexport.cexport_substeps`), each a dense matrix product that CasADi evaluates and
  generates as a loop;
* the prediction A P A^T + G Sigma_w G^T + Q and the Joseph-form update as dense matrix products and one linear
  solve (:func:`predicted`, :func:`updated`).

The numbers are the unrolled step's to rounding (the sums run in another order), not bit for bit.
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

__all__ = ["LOOP_STATES", "stage_jacobians", "linearization", "predicted", "updated", "looped_functions", "step_jacobians",
           "kept_size"]

LOOP_STATES = 40
"""States from which the EKF's step is built as loops (:mod:`this module <alpes_dyn.estimation.observers.looped>`):
the Alpes hand's 30 and a finger's 4-8 stay unrolled (bit for bit with their exported C); the Shadow hand, 44
states with its wrist held, 48 free, is looped."""


def stage_jacobians(dm: Any, name: str = "stage", dense: bool = True) -> cs.Function:
    """``SX`` function (z, w, p) -> (k (nz,), dk/dz (nz, nz), dk/dw (nz, nw)): the right-hand side of ``dm``
    and its Jacobians for RK4, or one substep and its Jacobians for the stick and LuGre laws (``dm.rhs_p`` None).

    Parameters
    ----------
    dm : DiscreteModel
        The observer's model (:class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel`): its ``rhs_p``
        (z, w, p) -> z' for RK4, or its ``substep_p`` when ``rhs_p`` is None.
    name : str, optional
        The function's name (default ``"stage"``).
    dense : bool, optional
        True (default): the Jacobians stored dense (the exported C's arrays); False: sparse (dq'/dz = [0 I]: the
        products by them skip the structural zeros).

    Returns
    -------
    casadi.Function
        ``SX`` (z, w, p) -> (k, dk_dz, dk_dw).
    """
    f = dm.rhs_p if dm.rhs_p is not None else dm.substep_p
    z, w, p = f.sx_in()
    k = f(z, w, p)
    store = cs.densify if dense else (lambda x: x)
    return cs.Function(name, [z, w, p], cs.cse([k, store(cs.jacobian(k, z)), store(cs.jacobian(k, w))]),
                       ["z", "w", "p"], ["k", "dk_dz", "dk_dw"])


def _rk4(f: cs.Function, z: cs.MX, w: cs.MX, p: cs.MX, h: float) -> tuple[cs.MX, cs.MX, cs.MX]:
    """One RK4 step of h s and its Jacobians by the chain rule through its four stages: (z_next, dz_next/dz,
    dz_next/dw); the stages' states as :func:`~alpes_dyn.simulation.integrate.rk4_expression` writes them."""
    nz = z.numel()
    eye = cs.MX(cs.DM.eye(nz))
    ks, dks, dws = [], [], []
    x, dx, dxw = z, None, None
    for c in (0.5 * h, 0.5 * h, h, None):
        k, J, W = f(x, w, p)
        dk = J if dx is None else cs.mtimes(J, dx)
        dkw = W if dxw is None else cs.mtimes(J, dxw) + W
        ks.append(k)
        dks.append(dk)
        dws.append(dkw)
        if c is not None:
            x, dx, dxw = z + c * k, eye + c * dk, c * dkw
    zn = z + (h / 6.0) * (ks[0] + 2.0 * ks[1] + 2.0 * ks[2] + ks[3])
    A = eye + (h / 6.0) * (dks[0] + 2.0 * dks[1] + 2.0 * dks[2] + dks[3])
    G = (h / 6.0) * (dws[0] + 2.0 * dws[1] + 2.0 * dws[2] + dws[3])
    return zn, A, G


def linearization(dm: Any) -> cs.Function:
    """``MX`` function (z, w, p) -> (z_next (nz,), A = dz_next/dz (nz, nz), G = dz_next/dw (nz, nw)), dense, of
    ``dm``'s ``substeps`` steps over one period, by the chain rule over :func:`stage_jacobians` (RK4's four stages
    per substep, or the stick / LuGre law's substep): the code of one right-hand side, called 4 x substeps times.

    Parameters
    ----------
    dm : DiscreteModel
        The observer's model (:class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel`): its ``nz``,
        ``nw``, ``values`` (the parameters p), period ``dt`` (s) and ``substeps`` per period.

    Returns
    -------
    casadi.Function
        ``MX`` (z, w, p) -> (z_next, A, G), A and G dense.
    """
    f = stage_jacobians(dm, "stage_jacobians", dense=False)
    z, w, p = cs.MX.sym("z", dm.nz), cs.MX.sym("w", dm.nw), cs.MX.sym("p", dm.values.size)
    h = dm.dt / dm.substeps
    x, A, G = z, None, None
    for _ in range(dm.substeps):
        x, As, Gs = _rk4(f, x, w, p, h) if dm.rhs_p is not None else f(x, w, p)
        A, G = (As, Gs) if A is None else (cs.mtimes(As, A), cs.mtimes(As, G) + Gs)
    return cs.Function("linearization", [z, w, p], [x, cs.densify(A), cs.densify(G)], ["z", "w", "p"],
                       ["z_next", "A", "G"])


def _symmetric(M: cs.MX) -> cs.MX:
    """(M + M^T) / 2: exactly symmetric."""
    return 0.5 * (M + M.T)


def predicted(A: cs.MX, G: cs.MX, P: cs.MX, Sw: np.ndarray, Q: np.ndarray) -> tuple[cs.MX, cs.MX]:
    """The covariance's prediction A P A^T + G Sigma_w G^T + Q, dense, exactly symmetric.

    Parameters
    ----------
    A : casadi.MX
        (nz, nz) dz_next/dz over one period.
    G : casadi.MX
        (nz, nw) dz_next/dw over one period.
    P : casadi.MX
        (nz, nz) the state's covariance before the step.
    Sw : numpy.ndarray, shape (nw, nw)
        Sigma_w, the input noise's covariance (numbers).
    Q : numpy.ndarray, shape (nz, nz)
        The process noise's covariance (numbers).

    Returns
    -------
    P_pred : casadi.MX
        (nz, nz) A P A^T + G Sigma_w G^T + Q, exactly symmetric.
    N : casadi.MX
        (nz, nz) G Sigma_w G^T + Q.
    """
    N = cs.mtimes([G, cs.MX(cs.DM(Sw)), G.T]) + cs.MX(cs.DM(Q))
    return _symmetric(cs.mtimes([A, P, A.T]) + N), N


def updated(z: cs.MX, P: cs.MX, y: cs.MX, h: cs.MX, H: cs.MX, R: np.ndarray) -> tuple[cs.MX, cs.MX]:
    """The measurement update in the Joseph form: S = H P H^T + R, K = P H^T S^-1 (one solve), z + K (y - h),
    (I - K H) P (I - K H)^T + K R K^T.

    Parameters
    ----------
    z : casadi.MX
        (nz,) the predicted state.
    P : casadi.MX
        (nz, nz) its covariance.
    y : casadi.MX
        (ny,) the measurement.
    h : casadi.MX
        (ny,) its prediction h(z).
    H : casadi.MX
        (ny, nz) dh/dz at z.
    R : numpy.ndarray, shape (ny, ny)
        The measurement noise's covariance (numbers).

    Returns
    -------
    z_upd : casadi.MX
        (nz,) the updated state.
    P_upd : casadi.MX
        (nz, nz) its covariance, exactly symmetric.
    """
    nz = P.shape[0]
    H = cs.densify(H)
    PHt = cs.mtimes(P, H.T)
    Rm = cs.MX(cs.DM(np.asarray(R, float)))
    S = _symmetric(cs.mtimes(H, PHt)) + Rm
    K = cs.solve(S, PHt.T, "qr").T
    IKH = cs.MX(cs.DM.eye(nz)) - cs.mtimes(K, H)
    Pu = cs.mtimes([IKH, P, IKH.T]) + cs.mtimes([K, Rm, K.T])
    return z + cs.mtimes(K, y - h), _symmetric(Pu)


def looped_functions(filt: Any) -> dict[str, cs.Function]:
    """The functions of an EKF ``filt`` (its model, ``Sw``, ``Q``, ``R`` set) built as loops, by the names of its
    attributes: ``measurement`` (``SX``, z -> (h, H)), ``_update`` (z, P, y) -> (z_upd, P_upd), ``linearized_p``
    (z, w, p) -> (z_next, A, the lower triangle of N = G Sigma_w G^T + Q), ``linearized`` the same at p = the model's
    numbers, ``_predict_fn`` (z, P, w) -> (z_pred, P_pred) there, ``filter_step_p`` (s = [z; vec P], [w; y], p)
    -> s_next, and ``_kept_step_p``, the same step keeping its prediction and Jacobians (:func:`~alpes_dyn.estimation.observers.ahead.kept_run`); all
    ``MX`` but the first.

    Parameters
    ----------
    filt : ExtendedKalmanFilter
        The filter (:class:`~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter`): its ``model``
        (a :class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel`), noises ``Sw`` (nw, nw), ``Q``
        (nz, nz), ``R`` (ny, ny) and ``kind`` (the step's name prefix).

    Returns
    -------
    dict of str to casadi.Function
        The functions above, by attribute name.
    """
    mdl = filt.model
    nz, nw, ny = mdl.nz, mdl.nw, mdl.ny
    zs = cs.SX.sym("zs", nz)
    hs = mdl.output(zs)
    meas = cs.Function("measurement", [zs], [hs, cs.jacobian(hs, zs)], ["z"], ["h", "H"])
    z, P, y = cs.MX.sym("z", nz), cs.MX.sym("P", nz, nz), cs.MX.sym("y", ny)
    w, p = cs.MX.sym("w", nw), cs.MX.sym("p", mdl.values.size)
    h, H = meas(z)
    update = cs.Function("update", [z, P, y], list(updated(z, P, y, h, H, filt.R)), ["z", "P", "y"],
                         ["z_upd", "P_upd"])
    lin = linearization(mdl)
    zn, A, G = lin(z, w, p)
    Pp, N = predicted(A, G, P, filt.Sw, filt.Q)
    linearized_p = cs.Function("linearized", [z, w, p], [zn, A, cs.tril(N)], ["z", "w", "p"], ["z_next", "A", "N"])
    predict_p = cs.Function("predict", [z, P, w, p], [zn, Pp], ["z", "P", "w", "p"], ["z_pred", "P_pred"])
    s, r = cs.MX.sym("s", nz + nz * nz), cs.MX.sym("wy", nw + ny)
    zp, Pp = predict_p(s[:nz], cs.reshape(s[nz:], nz, nz), r[:nw], p)
    zu, Pu = update(zp, Pp, r[nw:])
    step = cs.Function(f"{filt.kind}_step", [s, r, p], [cs.vertcat(zu, cs.vec(Pu))], ["s", "wy", "p"], ["s_next"])
    # the same step keeping its prediction and Jacobians (kept_run): s = [z; vec P; the last step's, unread]
    sk = cs.MX.sym("s", kept_size(mdl))
    zk, Ak, Gk = lin(sk[:nz], r[:nw], p)
    Pk = predicted(Ak, Gk, cs.reshape(sk[nz: nz + nz * nz], nz, nz), filt.Sw, filt.Q)[0]
    zku, Pku = update(zk, Pk, r[nw:])
    kept = cs.Function(f"{filt.kind}_kept", [sk, r, p], [cs.vertcat(zku, cs.vec(Pku), zk, cs.vec(Pk), cs.vec(Ak),
                                                                     cs.vec(Gk))], ["s", "wy", "p"], ["s_next"])
    zs, Ps, ws = cs.MX.sym("z", nz), cs.MX.sym("P", nz, nz), cs.MX.sym("w", nw)
    at = cs.DM(mdl.values)  # the model's numbers
    return {"measurement": meas, "_update": update, "linearized_p": linearized_p, "filter_step_p": step,
            "_kept_step_p": kept,
            "linearized": cs.Function("linearized", [zs, ws], linearized_p(zs, ws, at), ["z", "w"],
                                      ["z_next", "A", "N"]),
            "_predict_fn": cs.Function("predict", [zs, Ps, ws], predict_p(zs, Ps, ws, at), ["z", "P", "w"],
                                       ["z_pred", "P_pred"])}


def step_jacobians(filt: Any) -> cs.Function:
    """(z, w) -> (z_next (nz,), A = dz_next/dz, G = dz_next/dw), dense, at the model's numbers: of a looped filter
    (``filt.looped``) by :func:`linearization` (``MX``), else by automatic differentiation of its unrolled step
    (``SX``); what the consistency checks (:mod:`~alpes_dyn.estimation.observers.consistency`,
    :mod:`~alpes_dyn.estimation.observers.innovation`) evaluate along a run.

    Parameters
    ----------
    filt : ExtendedKalmanFilter
        The filter (:class:`~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter`): its ``model`` and
        ``looped`` flag (absent: False).

    Returns
    -------
    casadi.Function
        (z, w) -> (z_next, A, G).
    """
    mdl = filt.model
    if getattr(filt, "looped", False):
        z, w = cs.MX.sym("z", mdl.nz), cs.MX.sym("w", mdl.nw)
        return cs.Function("jacobians", [z, w], linearization(mdl)(z, w, cs.DM(mdl.values)))
    z, w = cs.SX.sym("z", mdl.nz), cs.SX.sym("w", mdl.nw)
    zn = mdl.step(z, w)
    return cs.Function("jacobians", [z, w], [zn, cs.densify(cs.jacobian(zn, z)), cs.densify(cs.jacobian(zn, w))])


def kept_size(dm: Any) -> int:
    """The length of the kept step's state (:func:`~alpes_dyn.estimation.observers.ahead.kept_run`):
    [z; vec P; z_pred; vec P_pred; vec A; vec G].

    Parameters
    ----------
    dm : DiscreteModel
        The filter's discrete model (its ``nz`` states and ``nw`` known inputs).

    Returns
    -------
    int
        2 nz + 3 nz^2 + nz nw, doubles per sample.
    """
    nz, nw = dm.nz, dm.nw
    return 2 * nz + 3 * nz * nz + nz * nw
