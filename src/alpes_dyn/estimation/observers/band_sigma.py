"""An observer's uncertainty from the dry-friction band: where the joints a motor's encoder does not tell apart can
rest, sized from the parameter file, added to the filter's own covariance.

A filter whose friction law is smooth (or any of the library's, on a plant whose friction is none of them) reports
in P the noise's uncertainty; its error on a plant that sticks is elsewhere. A joint held by dry friction rests
anywhere its friction's torque f_i, |f_i| <= F_s,i, balances the rest: about an equilibrium q_e (the springs,
gravity and the motors' torque in balance), a friction torque f moves the joints by K^-1 f, with

    K(q, u) = -d/dq [Gamma(q, u) - G(q) - k (q - q_rest)]            (the static stiffness, N m/rad, n x n)

the derivative of the net torque at rest (eq. 3.3 at qd = 0: the motors' torque Gamma through the tendons, gravity,
the springs). The encoders see H K^-1 f (H = dh/dq, the encoders' Jacobian, m x n): a filter that takes the
encoders as exact corrects that part and keeps the rest, the split between the joints, which no innovation shows.
With f of covariance C_f = diag((c F_s)^2), the joints' position set has the covariance

    C_q = X C_f X^T,    X = K^-1,
    C_split = C_q - C_q H^T (H C_q H^T)^-1 H C_q,                                                      (B1)

the Gaussian conditional of C_q given the encoders (the static limit of
:mod:`~alpes_dyn.analysis.joint_observability`'s torque b of prior F_s on each joint with dry friction), and each
joint's reported variance is

    sigma_i,k^2 = P_ii,k + (C_split(q_hat_k, u_k))_ii.                                                 (B2)

c, the friction torque's standard deviation as a fraction of F_s, is the observer's law's
(:data:`BAND_FRACTIONS`, :func:`band_fraction`): a uniform torque over the band would be 1/sqrt(3) = 0.58; a joint
that stops from sliding holds less than the band, and an observer whose law creeps follows part of it. The smooth
law's (:data:`BAND_FRACTION`, 0.25) was chosen by measurement on MuJoCo's stick-slip finger3 (the friction study's
``stiff`` case, :mod:`~alpes_dyn.studies.realism_friction`, four development draws, the identified and the true
file): the joints' NEES against their band (0.74-1.29 at the validation run's 100 samples) went from 2.7-17 with P
alone (no joint in band) to 0.36-2.75 at c = 0.25, 15 of 24 joints in band (5-11 at c = 0.2, 0.22, 0.28, 0.3; 4 at
0.35; on finger2 1.4-1.9 at 0.25, in band at 0.3). The stick-slip law holds a stuck joint where the plant holds
it, and what it leaves is a smaller share of the band, spread over the joints about as (B1) spreads it; LuGre's
bristles hold part of it: each law's c was measured the same way (the CHANGELOG's entry): with P alone (the torque
noise's, about 0.02 degree) the stick-slip law's NEES was 9-380, with its c 0.6-1.9. The creep law (MuJoCo's
soft dry friction, a creep file's smooth-law run) holds a joint within its creep band as the plant does, and where
every joint with dry friction is within it (|qd_hat_j| <= F_s,j / (a_j b), :class:`~alpes_dyn.model.friction.Creep`)
its filter's P is already of its error's size; the band is added only where a joint slides past that edge:

    sigma_i,k^2 = P_ii,k + s_k (C_split(q_hat_k, u_k))_ii,   s_k = 1 where a joint slides, else 0     (B3)

(:func:`sliding`; ``band_sigma(..., law="creep")``). Measured with the true file on MuJoCo's soft plants (the
friction study's ``soft`` and ``soft_3x``, three development draws each): P alone 1.7-2.9 at 1x F_s (every joint
over its band) and 0.12-10.9 at 3x; (B1) at every sample with c = 0.15 put 1x in its band (0.69-1.40) but 3x ten
to a hundred times too cautious (0.00-0.05: its band grows with F_s, the error does not); (B3) with c = 0.2: 1x
0.54-1.20 (8 of 9 joints in band), 3x 0.06-2.9 (what P alone leaves where the joints creep). What (B1) does not get
right is the smooth law's share between the joints: on finger3 its error is largest on the distal joint, which
(B1), stiffest there, gives the smallest share, and smallest on the middle one (NEES about 2 and 0.6-1 at c = 0.25,
with the true and the identified file alike); nor the size of a draw's error, up to twice another's where the file
predicts the same. The joints' errors were the same while the plant's joints
stuck as while they slid (the split a stick leaves stays through the next slide), so (B2) holds at every sample, not
only where the observer thinks a joint stuck. Everything in (B1) is the file's (F_s, the springs, the masses'
gravity, the ratios) and the estimate's (q_hat, the recorded torque): nothing reads the true joints. It does not
change the estimate: the filter runs as it did (feeding a stuck joint's variance back made the errors worse), only
the reported covariance is widened. ``estimate --data`` adds it by default where the observer's model has dry
friction (``--no-band-sigma``: the filter's P alone): a recording's plant is never the observer's own law, and the
filter's P alone claimed a tenth to a third of its error on every stick-slip draw measured. On a plant whose
friction is the observer's own law (the library's simulator: the simulated ``estimate`` scenario, which does not add
it) the filter's P is already consistent, and the band would make it cautious.

(B1) is computed in its information form (a basis of the split, no K^-1): so a joint without a spring that its own
encoder sees (the hand's thumb abduction) is simply seen. Where the band does not bound a direction of the split
(K not positive definite on it: two springless joints on one tendon, which gravity does not hold), that direction's
variance is the observers' prior (:data:`UNBOUNDED_STD`, the 0.5 rad of
:data:`~alpes_dyn.analysis.joint_observability.PRIOR_STD`) and :attr:`BandSigma.unbounded` names its joints;
whether the motion observes them is :func:`~alpes_dyn.analysis.joint_observability.joint_observability`'s flag.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as cs
import numpy as np

from ...checks import one_of
from ...errors import InputError
from ...model.friction import Creep, creep_of
from ...model.robot import Model
from ...symbolic.statespace import StateSpace
from .observers import Estimate

__all__ = ["BAND_FRACTION", "BAND_FRACTIONS", "UNBOUNDED_STD", "band_fraction", "BandSigma", "band_sigma",
           "sliding", "with_joint_variance"]

BAND_FRACTIONS: dict[str, float] = {"smooth": 0.25, "stick": 0.18, "lugre": 0.2, "creep": 0.2}
"""c of (B1) by the observer's law (a key of :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`, the file's law as
:func:`~alpes_dyn.simulation.stick.library_law` names it): the standard deviation of the friction torque a joint
holds at rest that the law leaves unexplained, as a fraction of its F_s (module docstring: chosen by measurement; a
uniform torque over the band would be 0.58)."""
BAND_FRACTION = BAND_FRACTIONS["smooth"]
"""c of (B1) for the smooth law, the default of :func:`band_sigma` (module docstring)."""
UNBOUNDED_STD = 0.5
"""rad: the added standard deviation of a joint the friction band does not bound (K not positive definite), the
observers' prior on a joint angle (:data:`~alpes_dyn.analysis.joint_observability.PRIOR_STD`)."""


def band_fraction(law: str) -> float:
    """c of (B1) for the observer's friction law (:data:`BAND_FRACTIONS`).

    Parameters
    ----------
    law : str
        The law the observer ran, as :func:`~alpes_dyn.simulation.stick.library_law` names it (``smooth``,
        ``stick``, ``lugre``, ``creep``).

    Returns
    -------
    float
        c, in units of each joint's F_s.

    Raises
    ------
    InputError
        ``law`` not one of :data:`BAND_FRACTIONS`.
    """
    return BAND_FRACTIONS[one_of(law, tuple(BAND_FRACTIONS), "law")]


def with_joint_variance(estimate: Estimate, variance: np.ndarray) -> Estimate:
    """``estimate`` with ``variance`` added to its n joints' variances (the diagonal of P's first n rows and
    columns; the rest of P and the estimate itself as they were).

    Parameters
    ----------
    estimate : Estimate
        An observer's estimate: ``z`` (N, nz) with the n joints' angles first (rad), ``P`` (N, nz, nz).
    variance : numpy.ndarray
        (N, n) rad^2, finite and >= 0.

    Returns
    -------
    Estimate
        A new estimate (P copied).

    Raises
    ------
    InputError
        ``estimate`` not of N samples with at least n joints, or ``variance`` not finite and >= 0.
    """
    N, n = variance.shape
    if estimate.z.shape[0] != N or estimate.z.shape[1] < n:
        raise InputError(f"estimate: expected {N} samples of at least {n} joints, got {estimate.z.shape}")
    if not (np.isfinite(variance).all() and (variance >= 0).all()):
        raise InputError("variance: expected finite variances >= 0")
    P = estimate.P.copy()
    idx = np.arange(n)
    P[:, idx, idx] += variance
    return Estimate(t=estimate.t, z=estimate.z, P=P, names=estimate.names)


@dataclasses.dataclass(frozen=True)
class BandSigma:
    """The joints' variance from the friction band along a run (:func:`band_sigma`, (B1) of the module docstring).

    Attributes
    ----------
    fraction : float
        c of (B1).
    variance : numpy.ndarray
        (N, n) rad^2, the diagonal of C_split per sample and joint.
    unbounded : tuple of str
        The joints of a direction the band does not bound at some sample (:data:`UNBOUNDED_STD` there).
    """

    fraction: float
    variance: np.ndarray
    unbounded: tuple[str, ...] = ()

    def widened(self, estimate: Estimate) -> Estimate:
        """``estimate`` with :attr:`variance` added to its joints' variances, (B2) (:func:`with_joint_variance`).

        Parameters
        ----------
        estimate : Estimate
            The observer's estimate the variance was computed along.

        Returns
        -------
        Estimate
            The same estimate, its joints' variances (rad^2) widened.

        Raises
        ------
        InputError
            ``estimate`` not of N samples with at least n joints.
        """
        return with_joint_variance(estimate, self.variance)

    def to_dict(self, start: int = 0) -> dict[str, Any]:
        """JSON: ``fraction``, ``band_rms_deg`` (per joint, the RMS of the added standard deviation from sample
        ``start`` on), ``unbounded``.

        Parameters
        ----------
        start : int, optional
            The first sample counted (e.g. past the observer's transient); default 0.

        Returns
        -------
        dict
            The JSON object.
        """
        rms = np.sqrt(np.mean(self.variance[start:], axis=0))
        return {"fraction": self.fraction, "band_rms_deg": np.degrees(rms).tolist(), "unbounded": list(self.unbounded)}


def _static_terms(model: Model) -> cs.Function:
    """(q, u) -> (K, H): the static stiffness of the module docstring (the net torque at rest differentiated in q,
    the springs alone as the passive torque: the friction is the unknown) and the encoders' Jacobian dh/dq."""
    ss = StateSpace(model, input="motor", output="encoder")
    n = model.n
    q, u = cs.SX.sym("q", n), cs.SX.sym("u", ss.n_inputs)
    v = cs.SX.zeros(n)
    sym = ss.sym
    r = sym.net_torque(q, v, ss.input_torque(q, u, v), sym.extras.spring_torque(q, cs), None, ss.tip)
    H = cs.jacobian(ss.h_function(cs.vertcat(q, v)), q)
    return cs.Function("band_static", [q, u], [cs.densify(-cs.jacobian(r, q)), cs.densify(H)])


def band_sigma(model: Model, states: Any, inputs: Any, fraction: float = BAND_FRACTION,
               law: str | None = None) -> BandSigma:
    """The joints' variance from the friction band, (B1) of the module docstring, at every sample (with the creep
    law, at the samples where a joint slides, (B3)).

    Parameters
    ----------
    model : Model
        The observer's :class:`~alpes_dyn.Model` (with motors and encoders; its F_s, springs, gravity, ratios).
    states : array_like
        (N, >= n) the observer's estimate, the n joints' angles first (rad; the rest ignored).
    inputs : array_like
        (N-1, m) the motor torques held from each sample to the next, N m (the last held at the last sample).
    fraction : float, optional
        c of (B1), finite and >= 0 (default :data:`BAND_FRACTION`).
    law : str or None, optional
        The observer's law as :func:`band_fraction` takes it; ``"creep"`` (where ``model``'s file holds the creep
        law) keeps (B1) at the samples where the estimate has a joint with dry friction beyond its creep band's edge
        (``states`` then [q; qd], (N, >= 2n)) and 0 elsewhere, (B3); default None: every sample.

    Returns
    -------
    BandSigma
        The diagonal of C_split per sample and joint, rad^2.

    Raises
    ------
    InputError
        Naming the argument: a model without motors and encoders, states or inputs of the wrong shape or not
        finite, ``fraction`` not a finite number >= 0.
    """
    if not isinstance(model, Model) or model.transmission is None:
        raise InputError("model: expected an alpes_dyn Model with motors and encoders")
    if isinstance(fraction, bool) or not isinstance(fraction, (int, float, np.floating)) or not (
            np.isfinite(fraction) and fraction >= 0):
        raise InputError(f"fraction: expected a finite number >= 0, got {fraction!r:.40}")
    n, m = model.n, model.transmission.n_motors
    X = np.asarray(states, dtype=float)
    if X.ndim != 2 or X.shape[0] < 2 or X.shape[1] < n or not np.isfinite(X[:, :n]).all():
        raise InputError(f"states: expected (N >= 2, >= {n}) finite states, got shape {X.shape}")
    N = X.shape[0]
    U = np.asarray(inputs, dtype=float)
    if U.shape != (N - 1, m) or not np.isfinite(U).all():
        raise InputError(f"inputs: expected ({N - 1}, {m}) finite motor torques, got shape {U.shape}")
    K, H = (np.asarray(a) for a in _static_terms(model).map(N)(X[:, :n].T, np.vstack([U, U[-1:]]).T))
    K = K.reshape(n, N, n).transpose(1, 0, 2)  # the map stacks the samples side by side
    H = H.reshape(m, N, n).transpose(1, 0, 2)
    out = _split(K, H, fraction * np.asarray(model.extras.coulomb, dtype=float), fraction, model.joint_names)
    creep = creep_of(model) if law is not None and one_of(law, tuple(BAND_FRACTIONS), "law") == "creep" else None
    if creep is None:
        return out
    if X.shape[1] < 2 * n or not np.isfinite(X[:, n:2 * n]).all():
        raise InputError(f"states: the creep law's band needs the joints' velocities, (N, >= {2 * n}) finite "
                         f"states, got shape {X.shape}")
    return dataclasses.replace(out, variance=out.variance * sliding(model, creep, X[:, n:2 * n])[:, None])


def sliding(model: Model, creep: Creep, velocities: np.ndarray) -> np.ndarray:
    """(N,) bool: the samples where a joint with dry friction moves faster than its creep band's edge
    v_c,j = F_s,j / (a_j b) (:class:`~alpes_dyn.model.friction.Creep`, a_j = kappa / (M(0)^-1)_jj): (B3).

    Parameters
    ----------
    model : Model
        The observer's model (its F_s and its inertia matrix at q = 0).
    creep : Creep
        The creep law (kappa, b).
    velocities : numpy.ndarray
        (N, n) the joints' estimated velocities, rad/s.

    Returns
    -------
    numpy.ndarray
        (N,) True where a joint slides.
    """
    Fs = np.asarray(model.extras.coulomb, dtype=float)
    _, edge = creep.band(np.linalg.inv(model.inertia_matrix(np.zeros(model.n))), Fs)
    return np.any((np.abs(velocities) > edge) & (Fs > 0), axis=1)


def _split(K: np.ndarray, H: np.ndarray, band: np.ndarray, fraction: float, joints: tuple[str, ...]) -> BandSigma:
    """(B1) at every sample from K (N, n, n), H (N, m, n) and the friction torques' standard deviations ``band``
    (n,), N m, in its information form (no K^-1: a springless joint that its own encoder sees is not unbounded):
    the joints' displacements dq = K^-1 f with f_i = 0 where ``band`` is 0 and H dq = 0 (what the encoders see)
    are the null space of A = [H; K_nf] (K's rows of the joints without friction), of information
    Lambda = K_f^T diag(band_f^-2) K_f there; C_split = N (N^T Lambda N)^-1 N^T, N an orthonormal basis of that
    null space (A's right singular vectors beyond its rank), the Gaussian conditional of (B1). Each of its
    directions' variance is capped at :data:`UNBOUNDED_STD`^2 (a direction the band does not bound: K not positive
    definite on it), whose joints are named unbounded."""
    N, n = K.shape[0], K.shape[1]
    fr = np.abs(band) > 0
    A = np.concatenate([H, K[:, ~fr, :]], axis=1)
    _, sv, Vt = np.linalg.svd(A, full_matrices=True)
    rank = np.sum(sv > 1e-9 * sv[:, :1], axis=1)
    Kf = K[:, fr, :] / band[fr][None, :, None]
    lam = Kf.transpose(0, 2, 1) @ Kf
    var, loose = np.zeros((N, n)), np.zeros(n, dtype=bool)
    cap = UNBOUNDED_STD ** 2
    for r in np.unique(rank):  # the samples by A's rank: one group unless the ratios' structure changes
        k = np.flatnonzero(rank == r)
        basis = Vt[k, r:, :].transpose(0, 2, 1)  # (k, n, d)
        w, W = np.linalg.eigh(basis.transpose(0, 2, 1) @ lam[k] @ basis)
        V = basis @ W  # the directions, orthonormal, in the joints
        var[k] = np.einsum("kij,kj->ki", V ** 2, np.minimum(1.0 / np.maximum(w, 1.0 / cap), cap))
        loose |= np.any((w <= 1.0 / cap)[:, None, :] & (V ** 2 > 0.01), axis=(0, 2))
    return BandSigma(float(fraction), var, tuple(j for j, h in zip(joints, loose) if h))
