"""Practical identifiability: the Fisher information and Cramér-Rao bounds of one experiment.

For an experiment (motor torques U (N, m) held per sample period dt, gravity per period, encoder noise, optional
joint angles measured a few times by a camera or a jig), :func:`fisher_information` computes the output-error
Fisher information matrix from the exact forward sensitivities of the RK4-discretised model
(:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`):

    FIM = sum_k (dy_k/dphi)^T R^-1 (dy_k/dphi),     phi = (theta, x0),

with y_k the encoder angles S q_k (rad) at the N + 1 samples (plus the tendon's stretch C u_k-1 where its compliance
is among the parameters), R = sigma_e^2 I, sigma_e^2 = (noise_counts * step)^2 + step^2 / 12 (Gaussian noise plus
the quantisation of a step of 2 pi / counts_per_rev), and the camera's joint angles q_k at ``camera_times`` with
noise ``camera_noise`` (rad). The unknown initial state is a nuisance: its block is marginalised (the Schur
complement F_tt - F_tx F_xx^-1 F_xt). The Cramér-Rao bound of an unbiased estimate is cov >= FIM^-1: each
parameter's standard deviation (absolute, and relative to its value) and the correlation matrix. The measured
torque is taken as exact (its noise is not in this FIM; see the identification guide). The structural test is
:mod:`alpes_dyn.analysis.identifiability` (which re-exports these names).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..checks import as_float_array
from ..errors import InputError, ModelError
from ..model.robot import Model
from ..model.transmission import torque_before

__all__ = ["FisherReport", "fisher_information", "INITIAL_STATES"]

_EPS = float(np.finfo(float).eps)
INITIAL_STATES = ("unknown", "known")
"""The initial state of :func:`fisher_information`'s experiment: ``"unknown"`` (marginalised) or ``"known"``."""


def _theta(theta: Any, pd_nominal: np.ndarray, names: Sequence[str], additive: np.ndarray | None = None) -> np.ndarray:
    """The parameter values: positive (log coordinates), any finite value for the additive ones."""
    additive = np.zeros(len(names), dtype=bool) if additive is None else additive
    if theta is None:
        th = pd_nominal.copy()
    else:
        try:
            th = np.asarray(theta, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"theta: expected {len(names)} numbers, got {theta!r}") from None
        if th.shape != pd_nominal.shape:
            raise InputError(f"theta: expected {len(names)} values ({', '.join(names)}), got {th.size}")
    if not np.isfinite(th).all() or np.any((th <= 0) & ~additive):
        bad = next(n for n, v, a in zip(names, th, additive) if not (np.isfinite(v) and (v > 0 or a)))
        raise InputError(f"theta: {bad} must be a finite positive value (log coordinates), got "
                         f"{th[list(names).index(bad)]!r}")
    return th


@dataclass
class FisherReport:
    """Result of :func:`fisher_information`: the Fisher information of an experiment and its Cramér-Rao bounds.

    Attributes
    ----------
    model: model name. parameters: names (p); theta (p,): the values (their units); units (p,).
    fim: (p, p) Fisher information of theta (the initial state marginalised when unknown), 1/unit^2.
    fim_full: (p + 2n, p + 2n) information of (theta, x0) before marginalisation.
    covariance: (p, p) Cramér-Rao bound fim^-1; where the information is singular (``rank`` < p) the
        parameters along a zero-information direction get an infinite variance (NaN covariances).
    std: (p,) Cramér-Rao standard deviations (units, inf when not identifiable from this experiment);
        relative_std: std / |theta|.
    correlation: (p, p) correlation matrix of the bound.
    rank: numerical rank of ``fim`` (log scale); eigenvalues of the relative information, ascending.
    encoder_std: the encoder's noise standard deviation used (rad, noise and quantisation);
    samples: output samples; camera_samples: joint-angle samples; duration: s.
    initial_state: ``"unknown"`` (marginalised) or ``"known"``.
    """

    model: str
    parameters: tuple[str, ...]
    theta: np.ndarray
    units: tuple[str, ...]
    fim: np.ndarray
    fim_full: np.ndarray
    covariance: np.ndarray
    std: np.ndarray
    relative_std: np.ndarray
    correlation: np.ndarray
    rank: int
    encoder_std: float
    samples: int
    camera_samples: int
    duration: float
    initial_state: str
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: parameters {name: {value, unit, std, relative_std}}, correlation, fim, settings."""
        return {
            "model": self.model,
            "parameters": {n: {"value": float(v), "unit": u, "std": _num(s), "relative_std": _num(r)}
                           for n, v, u, s, r in zip(self.parameters, self.theta, self.units, self.std,
                                                    self.relative_std)},
            "correlation": [[_num(c) for c in row] for row in self.correlation], "fim": self.fim.tolist(), "rank": self.rank,
            "encoder_std_rad": self.encoder_std, "samples": self.samples, "camera_samples": self.camera_samples,
            "duration_s": self.duration, "initial_state": self.initial_state, "seconds": self.seconds,
        }

    def to_text(self) -> str:
        lines = [f"Cramér-Rao bounds on {self.model}: {self.samples} encoder samples over {self.duration:g} s "
                 f"(noise {self.encoder_std:.3g} rad incl. quantisation)"
                 + (f", {self.camera_samples} camera samples" if self.camera_samples else "")
                 + f", initial state {self.initial_state}"
                 + ("" if self.rank == len(self.parameters) else
                    f"; information rank {self.rank}/{len(self.parameters)}"),
                 f"  {'parameter':12s} {'value':>11s} {'std':>10s} {'rel. std':>9s}  unit"]
        for n, v, u, s, r in zip(self.parameters, self.theta, self.units, self.std, self.relative_std):
            rs = f"{r:9.2%}" if np.isfinite(r) else "unbounded"
            lines.append(f"  {n:12s} {v:11.5g} {s:10.3g} {rs:>9s}  {u}")
        p = len(self.parameters)
        C = self.correlation
        iu = np.triu_indices(p, 1)
        if p > 1 and np.isfinite(C[iu]).any():
            a = np.where(np.isfinite(C[iu]), np.abs(C[iu]), -1.0)
            k = int(np.argmax(a))
            i, j = iu[0][k], iu[1][k]
            lines.append(f"  largest correlation: {self.parameters[i]}, {self.parameters[j]} {C[i, j]:+.4f}")
        if self.rank < p:
            lines.append("  unbounded: along a direction this experiment gives no information on "
                         "(see identifiability() for its name)")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()


def _num(x: float) -> float | None:
    """JSON number, None for inf/NaN (not identifiable from the experiment)."""
    return float(x) if np.isfinite(x) else None


def _array(a: Any, name: str, ndim: int) -> np.ndarray:
    out = as_float_array(a, name, "an array of numbers")
    if out.ndim != ndim:
        raise InputError(f"{name}: expected a {ndim}-D array, got shape {out.shape}")
    if not np.isfinite(out).all():
        raise InputError(f"{name}: contains NaN or inf")
    return out


def _nonneg(v: Any, name: str) -> float:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(v) and v >= 0):
        raise InputError(f"{name}: expected a non-negative number, got {v!r}")
    return float(v)


def fisher_information(model: Model, parameters: str | Sequence[str] | None = None, U: Any = None, G: Any = None,
                       dt: float | None = None, *, design: Any = None, x0: Any = None, theta: Any = None,
                       encoder_noise_counts: float | None = None, quantisation: bool = True,
                       camera_times: Sequence[float] | None = None, camera_noise: float | None = None,
                       initial_state: str = "unknown", substeps: int | None = None,
                       sensitivity: Any = None, counts_per_rev: float | None = None) -> FisherReport:
    """Fisher information and Cramér-Rao bounds of ``parameters`` for one experiment (see the module doc).

    Parameters
    ----------
    model : Model
        The finger (:class:`~alpes_dyn.Model` with a transmission: the motor input, the encoder output y = S q; a
        model without one: joint torques in, joint encoders y = q out, ``counts_per_rev`` given).
    parameters : str, sequence of str or None, optional
        The selection for :func:`~alpes_dyn.symbolic.parametric.select_parameters`.
    U : array_like, shape (N,) or (N, motors)
        The motor torques, N m, held over each of the N sample periods.
    G : array_like, shape (3,) or (N, 3), optional
        Gravity, m/s^2 (base frame): for the whole experiment or per period (several hand orientations); default
        the model's.
    dt : float or None, optional
        The sample period, s (default 1e-3).
    design : object, optional
        Any object with any of the fields ``dt``, ``substeps``, ``encoder_noise_counts``, ``camera_times``,
        ``camera_noise`` (e.g. :class:`alpes_dyn.estimation.experiments.experiment.ExperimentDesign`): the
        defaults of the arguments of the same names.
    x0 : array_like, shape (2n,), optional
        The initial state; default the static equilibrium under U[0] and G[0] (where the balance alone does not
        place a joint without spring, the thumb's ab/adduction, that joint held mid-range).
    theta : array_like, shape (p,), optional
        The parameter values, default the model's (nominal).
    encoder_noise_counts : float or None, optional
        The Gaussian encoder noise, counts (default 0.5).
    quantisation : bool, optional
        With it (default) the quantisation's step / sqrt(12) is added in quadrature to the encoder noise.
    camera_times : sequence of float or None, optional
        Times (s, within the experiment, on the sample grid) where every joint angle is measured once, with noise
        ``camera_noise``.
    camera_noise : float or None, optional
        The camera's noise, rad (default 0.1 degree).
    initial_state : str, optional
        ``"unknown"`` (nuisance parameters, marginalised; default) or ``"known"``.
    substeps : int or None, optional
        RK4 steps per sample period (default the design's, 4, or more where the model's friction asks for them:
        :func:`~alpes_dyn.simulation.integrate.stable_substeps`, as the experiment's simulation; with 4 a dry
        friction of v_s = 3 mrad/s made the Shadow finger's sensitivities overflow into a FIM of 1e39 with
        negative diagonal entries).
    sensitivity : SensitivityModel, optional
        A :class:`~alpes_dyn.simulation.sensitivity.SensitivityModel` of the same model, parameters, dt and
        substeps to reuse (its compiled code), else one is built.
    counts_per_rev : float or None, optional
        The encoder resolution, counts per revolution (default the transmission's; required without a
        transmission).

    Returns
    -------
    FisherReport
        The information, its bounds and the experiment's settings.

    Raises
    ------
    ModelError
        ``model`` is not a Model.
    InputError
        An unknown ``initial_state`` or a malformed input.
    """
    t0 = time.perf_counter()
    if not isinstance(model, Model):
        raise ModelError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
    given = substeps is not None or sensitivity is not None
    dt, substeps, noise, cam_times, cam_noise = _settings(design, dt, substeps, encoder_noise_counts, camera_times,
                                                          camera_noise)
    if not given:  # as the experiment integrates it: more steps where the friction's sign is sharper
        from ..simulation.integrate import stable_substeps

        substeps = max(int(substeps), stable_substeps(model, dt))
    if initial_state not in INITIAL_STATES:
        raise InputError(f"initial_state: expected one of {', '.join(INITIAL_STATES)}, got {initial_state!r}")
    tr = model.transmission
    _check_counts_per_rev(model, counts_per_rev)
    Ua = _torques(U, tr.n_motors if tr is not None else model.n, tr is not None)
    N = Ua.shape[0]
    Ga = _gravity(G, model, N)
    cam_idx = _camera_samples(cam_times, dt, N)
    sm = _sensitivity_model(model, parameters, dt, substeps, sensitivity)
    p = sm.p
    additive = np.array([prm.additive for prm in sm.dynamics.parameters], dtype=bool)
    th = _theta(theta, sm.nominal, sm.names, additive)
    unit = np.where(additive, 1.0, th)  # log coordinates, the additive parameters (offsets, tilt) as they are
    x0a = _initial_state(model, x0, Ua, Ga)
    step = 2.0 * np.pi / float(counts_per_rev if counts_per_rev is not None else tr.counts_per_rev)
    sigma = math.sqrt((noise * step) ** 2 + (step ** 2 / 12.0 if quantisation else 0.0))
    if sigma <= 0 and not cam_idx:
        raise InputError("encoder_noise_counts: zero noise without quantisation gives infinite information")
    F = _information(model, sm, x0a, Ua, Ga, th, unit, sigma, cam_idx, cam_noise)
    Flog = _marginal_information(F, p, initial_state)
    rank, cov_log, sd, rel, corr = _cramer_rao(Flog, unit, additive, th)
    fim = Flog / np.outer(unit, unit)
    fim_full = F.copy()
    fim_full[:p] /= unit[:, None]
    fim_full[:, :p] /= unit[None, :]
    units = tuple(prm.unit for prm in sm.dynamics.parameters)
    return FisherReport(
        model=model.name, parameters=tuple(sm.names), theta=th, units=units, fim=fim, fim_full=fim_full,
        covariance=cov_log * np.outer(unit, unit), std=sd, relative_std=rel, correlation=corr, rank=rank,
        encoder_std=sigma, samples=N + 1, camera_samples=len(cam_idx), duration=N * float(dt),
        initial_state=initial_state, seconds=time.perf_counter() - t0)


# ----------------------------------------------------------------------------- reading the experiment
def _settings(design: Any, dt: float | None, substeps: int | None, encoder_noise_counts: float | None,
              camera_times: Sequence[float] | None, camera_noise: float | None
              ) -> tuple[float, Any, float, tuple, float]:
    """(dt s, substeps, encoder noise counts, camera times s, camera noise rad): each argument, else the field of
    the same name of ``design``, else its default; the noises checked non-negative."""
    from ..simulation.integrate import _check_dt

    def pick(value: Any, name: str, default: Any) -> Any:
        if value is not None:
            return value
        return getattr(design, name, default) if design is not None else default

    dt = _check_dt(pick(dt, "dt", 1e-3))
    substeps = pick(substeps, "substeps", 4)
    noise = _nonneg(pick(encoder_noise_counts, "encoder_noise_counts", 0.5), "encoder_noise_counts")
    cam_times = tuple(pick(camera_times, "camera_times", ()))
    cam_noise = _nonneg(pick(camera_noise, "camera_noise", math.radians(0.1)), "camera_noise")
    return dt, substeps, noise, cam_times, cam_noise


def _check_counts_per_rev(model: Model, counts_per_rev: Any) -> None:
    """The encoder's resolution: the transmission's, or ``counts_per_rev`` (required without one), positive."""
    if model.transmission is None and counts_per_rev is None:
        raise ModelError(f"model: {model.name!r} has no transmission: give counts_per_rev (its joint encoders)")
    if counts_per_rev is not None and (isinstance(counts_per_rev, (bool, np.bool_)) or not isinstance(
            counts_per_rev, (int, float, np.integer, np.floating)) or not (math.isfinite(counts_per_rev)
                                                                          and counts_per_rev > 0)):
        raise InputError(f"counts_per_rev: expected a positive number, got {counts_per_rev!r}")


def _torques(U: Any, n_in: int, motors: bool) -> np.ndarray:
    """The experiment's torques as (N, n_in), N m, N >= 2: motor torques (``motors``) or joint torques."""
    if U is None:
        raise InputError("U: the motor torques of the experiment are required, (N,) or (N, motors) N m")
    Ua = _array(U, "U", 1 if np.ndim(U) == 1 else 2)
    if Ua.ndim == 1:
        Ua = Ua[:, None]
    N, nu = Ua.shape
    if nu != n_in:
        raise InputError(f"U: expected {n_in} {'motor' if motors else 'joint'} torque column(s), got {nu}")
    if N < 2:
        raise InputError(f"U: expected at least 2 sample periods, got {N}")
    return Ua


def _gravity(G: Any, model: Model, N: int) -> np.ndarray:
    """Gravity per sample period, (N, 3) m/s^2: the model's, one vector (3,) repeated, or (N, 3) as given."""
    if G is None:
        return np.tile(np.asarray(model.gravity, dtype=float), (N, 1))
    Ga = _array(G, "G", np.ndim(G) if np.ndim(G) in (1, 2) else 2)
    Ga = np.tile(Ga, (N, 1)) if Ga.ndim == 1 else Ga
    if Ga.shape != (N, 3):
        raise InputError(f"G: expected (3,) or ({N}, 3) gravity vectors, got {np.shape(G)}")
    return Ga


def _camera_samples(cam_times: Sequence[Any], dt: float, N: int) -> list[int]:
    """The sample indices (0..N) of the camera's times (s), each on the sample grid."""
    cam_idx = []
    for tc in cam_times:
        try:
            k = round(float(tc) / dt) if math.isfinite(float(tc)) else -1
        except (TypeError, ValueError):
            raise InputError(f"camera_times: expected times in s, got {tc!r}") from None
        if not 0 <= k <= N or abs(k * dt - float(tc)) > 1e-6 * dt + 1e-12:
            raise InputError(f"camera_times: {tc!r} is not a sample time in [0, {N * dt:g}] s")
        cam_idx.append(int(k))
    return cam_idx


def _sensitivity_model(model: Model, parameters: Any, dt: float, substeps: Any, sensitivity: Any) -> Any:
    """``sensitivity`` checked to be of this model, dt, substeps and parameters; else a new
    :class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`."""
    from ..simulation.sensitivity import SensitivityModel

    if sensitivity is None:
        return SensitivityModel(model, parameters, dt, substeps)
    sm = sensitivity
    if not isinstance(sm, SensitivityModel) or sm.model is not model or sm.dt != float(dt) \
            or sm.substeps != int(substeps):
        raise InputError("sensitivity: expected a SensitivityModel of this model with the same dt and substeps")
    if parameters is not None:
        from ..symbolic.parametric import select_parameters

        names = tuple(p.name for p in select_parameters(model, parameters))
        if names != sm.names:
            raise InputError(f"sensitivity: its parameters {', '.join(sm.names)} are not {', '.join(names)}")
    return sm


def _initial_state(model: Model, x0: Any, Ua: np.ndarray, Ga: np.ndarray) -> np.ndarray:
    """x0 (2n,) as given (checked), else the rest under the first torque Ua[0] and gravity Ga[0] (the joints without
    spring held mid-range where the balance alone cannot place them)."""
    n, nx = model.n, 2 * model.n
    tr = model.transmission
    if x0 is not None:
        x0a = _array(x0, "x0", 1)
        if x0a.shape != (nx,):
            raise InputError(f"x0: expected {nx} values (q, qd), got {x0a.shape[0]}")
        return x0a
    m0 = model if np.array_equal(model.gravity, Ga[0]) else model.copy(gravity=Ga[0])
    try:
        q_rest = m0.static_equilibrium(None, tau_m=Ua[0]) if tr is not None else m0.static_equilibrium(Ua[0])
    except InputError:
        if tr is None or not model.springless_joints:
            raise
        from ..estimation.experiments.experiment import _mean_equilibrium  # the experiment's rest: joints without spring mid-range

        q_rest = _mean_equilibrium(model, Ua[0], Ga[0])
    return np.concatenate([q_rest, np.zeros(n)])


# ----------------------------------------------------------------------------- the information
def _information(model: Model, sm: Any, x0a: np.ndarray, Ua: np.ndarray, Ga: np.ndarray, th: np.ndarray,
                 unit: np.ndarray, sigma: float, cam_idx: list[int], cam_noise: float) -> np.ndarray:
    """F (p + 2n, p + 2n): the Fisher information of (log theta, x0) (the additive parameters as they are), from the
    exact sensitivities of the encoder outputs y_k = S q_k (+ offset, + C u_k-1) at the N + 1 samples (noise
    ``sigma`` rad) and of the camera's joint angles at ``cam_idx`` (noise ``cam_noise`` rad)."""
    n, nx, p = model.n, 2 * model.n, sm.p
    tr = model.transmission
    xs, X = sm.run(x0a[None], Ua[None], Ga[None], th)
    X = X[0]  # (N+1, nx, nx + p): d x_k / d(x0, theta)
    cols = np.concatenate([np.arange(nx, nx + p), np.arange(nx)])  # (theta, x0)
    S = np.asarray(tr.S, dtype=float) if tr is not None else np.eye(n)
    if tr is not None and tr.curved:  # y = s(q): its sensitivities rho(q) dq
        Jy = np.einsum("kmj,kjd->kmd", tr.ratio(xs[0, :, :n]), X[:, :n, :][:, :, cols])
    else:
        Jy = np.einsum("mj,kjd->kmd", S, X[:, :n, :][:, :, cols])
    for k, i in sm.dynamics._sel["encoder_offset"]:  # y = S q + offset
        Jy[:, i, k] += 1.0
    U_samples = torque_before(np.concatenate([Ua, Ua[-1:]]))  # the torque held before each sample
    for k, i in sm.dynamics._sel["tendon_compliance"]:  # y_k = S q_k + C u_k-1: the torque itself
        Jy[:, i, k] += U_samples[:, i]
    Jy = Jy.reshape(-1, p + nx)
    Jy[:, :p] *= unit  # log coordinates inside (well scaled), converted back below
    F = Jy.T @ Jy / sigma ** 2 if sigma > 0 else np.zeros((p + nx, p + nx))
    if cam_idx:
        Jc = X[cam_idx][:, :n, :][:, :, cols].reshape(-1, p + nx).copy()
        Jc[:, :p] *= unit
        F = F + (Jc.T @ Jc / cam_noise ** 2 if cam_noise > 0 else 0.0)
    if not np.isfinite(F).all():
        raise InputError("fisher_information: the sensitivities are not finite (experiment unstable?)")
    return F


def _marginal_information(F: np.ndarray, p: int, initial_state: str) -> np.ndarray:
    """The (p, p) information of the parameters: F's parameter block, the unknown initial state marginalised (the
    Schur complement F_tt - F_tx F_xx^-1 F_xt); symmetrised."""
    Ftt = F[:p, :p]
    if initial_state == "unknown":
        Fxx, Fxt = F[p:, p:], F[p:, :p]
        Flog = Ftt - Fxt.T @ np.linalg.pinv(Fxx, rcond=1e-13, hermitian=True) @ Fxt
    else:
        Flog = Ftt
    d = np.diag(Flog)
    if np.any(d < -1e-8 * max(float(np.max(np.abs(np.diag(Ftt)))), 1e-300)):  # information is never negative
        raise InputError("fisher_information: the information lost its sign marginalising the initial state (the "
                         "sensitivities grew past double precision: experiment unstable, or too few RK4 substeps)")
    return 0.5 * (Flog + Flog.T)


def _cramer_rao(Flog: np.ndarray, unit: np.ndarray, additive: np.ndarray, th: np.ndarray
                ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The bound cov >= Flog^-1 of the (p, p) log information: (rank, covariance in log coordinates, std in the
    parameters' units, relative std, correlation); a parameter along a zero-information direction unbounded."""
    p = Flog.shape[0]
    # rank and inverse on the relative (log) information, scaled to unit diagonal
    d = np.sqrt(np.clip(np.diag(Flog), 0, None))
    dn = np.where(d > 0, d, 1.0)
    Fs = Flog / np.outer(dn, dn)
    w, V = np.linalg.eigh(Fs)
    tol = max(p, 1) * 1e3 * _EPS * max(w.max(), 0)
    rank = int(np.sum(w > tol))
    cov_log = np.linalg.pinv(Fs, rcond=1e-12, hermitian=True) / np.outer(dn, dn)
    rel = np.sqrt(np.clip(np.diag(cov_log), 0, None))
    if rank < p:  # a parameter with a component along a zero-information direction: unbounded
        V0 = V[:, w <= tol]
        free = (np.linalg.norm(V0, axis=1) > 1e-6) | (d == 0)
        rel = np.where(free, np.inf, rel)
        cov_log[free, :] = np.nan
        cov_log[:, free] = np.nan
        np.fill_diagonal(cov_log, np.where(free, np.inf, np.diag(cov_log)))
    sd = rel * np.abs(unit)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_log / np.outer(rel, rel)
        rel = np.where(additive, sd / np.abs(th), rel)  # an additive parameter at 0: inf
    return rank, cov_log, sd, rel, corr
