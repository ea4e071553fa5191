"""The solver of the multiple-shooting fit: constrained Gauss-Newton with a homotopy and two starts.

It drives a :class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem` (residuals, defects, their Jacobians and the
KKT matrices) and knows nothing of the model. Three stages:

1. :meth:`GaussNewton.fit_nodes`: each interval's start state alone on its encoder samples (theta fixed, the
   intervals decoupled), Levenberg-Marquardt per interval;
2. :meth:`GaussNewton.homotopy`: continuity as a quadratic penalty tightened tenfold per phase (four phases of
   Levenberg-Marquardt), friction and the torque lines held on the first start; a step whose parameter part the
   trust region shortens has its nodes solved again for the shortened step;
3. :meth:`GaussNewton.constrained`: the constrained problem, Gauss-Newton on the KKT system (Levenberg-Marquardt
   damped), an l1-merit line search (:meth:`GaussNewton.line_search`) with a second-order correction (Nocedal &
   Wright, Section 18.3) and a filter's second chance against the Maratos effect.

:meth:`GaussNewton.solve` runs stages 2-3 from two starts (friction held during the homotopy, then free) where the
first ends above the basin limit (three times the quantisation floor: wrong basins leave several counts). Why each
stage exists is told in :mod:`alpes_dyn.estimation.identification.identification` and at each rule below. Compared on the same
problem with IPOPT (CasADi's ``nlpsol``): about as fast, and this one converges without tight bounds where IPOPT
did not (issue 18).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ...progress import _Progress
from .shooting import Evaluation, FitDiverged, ShootingProblem

__all__ = ["GaussNewton", "SolverResult", "MAX_LOG_STEP", "MAX_COEF_STEP", "COEF_STEP_RECORD", "MAX_COEF_GROWTH",
           "CRAWL_STEPS", "SOC_STEPS", "SOFT_PHASES", "BASIN_LIMIT", "JOIN_STEPS",
           "WINDOW_ITERATIONS"]

MAX_LOG_STEP = 0.3
"""The trust region on log theta per iteration (at most a 35 % change of any parameter)."""
MAX_COEF_STEP = 1.0
COEF_STEP_RECORD = 4000
"""The trust region on the torque's line corrections per iteration: a whitened coefficient by at most
MAX_COEF_STEP sqrt(max(N / COEF_STEP_RECORD, 1)) prior standard deviations over N samples: one standard deviation up
to a 4 s record at 1 kHz, growing as sqrt(N) beyond (a torque error of a given size is sqrt(N) times more standard
deviations of a coefficient in a longer record). One standard deviation whatever the record leaves long fits
crawling, the coefficients asking for tens of them per step; a much wider cap sends fits on MuJoCo's plants
(``benchmarks/realism.py``) to other basins."""
MAX_COEF_GROWTH = 16.0
"""The most the constrained stage (stage 3) widens the line corrections' trust region (:data:`COEF_STEP_RECORD`'s
rule), doubling it at each step they alone cut and that is taken whole, from the :data:`CRAWL_STEPS`-th such step
in a row (:meth:`GaussNewton.next_radius`). On MuJoCo's all-effects finger3 plants with the documented experiment
the coefficients ask for tens of standard deviations per step, and without the growth the fit crawls one per step
through many iterations of stage 3 (``benchmarks/realism.py``)."""
CRAWL_STEPS = 3
"""Steps in a row cut by the line corrections' trust region, each taken whole, before it grows (:meth:`GaussNewton.next_radius`)."""
SOC_STEPS = 4
"""Second-order corrections at most, one after another, of a stage-3 step whose whole length the merit refuses
(:meth:`GaussNewton.line_search`), each while the defects fall by half or more. A Gauss-Newton step along a curved
valley (on MuJoCo's finger3 plant with the palm tilted: the tilt against the masses) lowers the cost and raises the
defects quadratically; after one correction the merit may still refuse every length, and the fit crawls at damped
steps into the iteration cap with its masses off. Two to three corrections bring the defects down by orders of
magnitude with the cost's fall intact, and the fit converges."""
SOFT_PHASES = 4
"""Phases of the homotopy (stage 2): the continuity penalty's weight 1, 10, 100, 1000 times 1 / |initial defect|."""
JOIN_STEPS = 2
"""Gauss-Newton steps at most of :meth:`GaussNewton.join_nodes`: from the model's response at the window's
parameters two steps bring the defects down to a small fraction of the nodes' scale, and stage 3 converges in as
many iterations from there as after more steps or after the homotopy."""
WINDOW_ITERATIONS = 15
"""Stage 3's iterations at most from a long record's window start (:mod:`~alpes_dyn.estimation.identification.long_record`;
then the whole fit of the whole record): the fingers' converge well within it, while a start that crawls (the
hand's thumb on a long record) would otherwise spend a large share of the fit reaching the iteration cap before
the whole fit converges."""
BASIN_LIMIT = 3.0 / math.sqrt(12.0)
"""counts: an encoder residual above three times the quantisation floor (1/sqrt(12) count) asks for the second
start (the wrong basins leave several counts, the right one the encoder noise, about 0.58)."""


@dataclass
class SolverResult:
    """Where a start of stages 2-3 ended: the variables, the :class:`~alpes_dyn.estimation.identification.shooting.Evaluation`
    there (with its Jacobians), the Gauss-Newton iterations, whether the stopping rule was met and why it stopped."""

    nodes: np.ndarray
    offs: np.ndarray
    glob: np.ndarray
    at: Evaluation
    iterations: int
    converged: bool
    reason: str


class GaussNewton:
    """The solver of stages 1-3 (the module docstring).

    Parameters
    ----------
    max_iterations : int, optional
        The Gauss-Newton iterations at most per start of stage 3 (default 50).
    tol : float, optional
        The stopping rule's relative change of the cost (default 1e-6).
    show : bool, optional
        A progress line on stderr (default False).
    """

    def __init__(self, max_iterations: int = 50, tol: float = 1e-6, show: bool = False) -> None:
        self.max_iterations, self.tol, self.show = max_iterations, tol, show

    @staticmethod
    def trial(pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray) -> Evaluation | None:
        """The residuals and defects at a trial point (``evaluate(..., jac=False)``), or None where they are not
        finite or the point overflows (:class:`~alpes_dyn.estimation.identification.shooting.FitDiverged`: a step
        that sends a parameter or a state to NaN or inf is refused like a step that raises the cost).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        nodes : numpy.ndarray, shape (K, nx)
            The intervals' start states at the trial point (rad, rad/s).
        offs : numpy.ndarray
            The per-interval offsets at the trial point.
        glob : numpy.ndarray, shape (p,)
            The global parameters (log values) at the trial point.

        Returns
        -------
        Evaluation or None
            The evaluation without Jacobian, or None where the point is refused.
        """
        try:
            e = pb.evaluate(nodes, offs, glob, jac=False)
        except FitDiverged:
            return None
        return e if np.isfinite(e.r).all() and np.isfinite(e.c).all() else None

    # --- stage 1 ----------------------------------------------------------------------------------------------

    @staticmethod
    def fit_nodes(pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                  sweeps: int = 8) -> np.ndarray:
        """Stage 1: the nodes alone (theta fixed, intervals decoupled), ``sweeps`` Levenberg-Marquardt steps per
        interval, from :meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.initial_nodes`; the
        Jacobians with respect to the start states alone (``evaluate(..., jac="state")``: the same numbers as the
        first nx columns of the whole Jacobian, at a third to a fifth of its cost). After the first sweep only the
        intervals whose start moved are evaluated again (:meth:`~alpes_dyn.estimation.identification.shooting.
        ShootingProblem.state_rows`; the intervals are decoupled, so the others' rows are the ones they had).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (residuals, defects, their Jacobians and KKT matrices).
        nodes : numpy.ndarray, shape (S, nx)
            The intervals' start states to start from ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (log theta, p), the whitened line corrections (ncg), the drifts' knots (nd).
        sweeps : int, optional
            Levenberg-Marquardt steps per interval (default 8).

        Returns
        -------
        numpy.ndarray, shape (S, nx)
            The nodes fitted (a copy; ``nodes`` is not changed).
        """
        nx, n_int = pb.nx, pb.n_int
        nodes = nodes.copy()
        mu_n = 1e-2 * np.ones(n_int)
        e = pb.evaluate(nodes, offs, glob, jac="state")  # the start states' sensitivities alone
        r, A = e.r, e.J
        e = None
        for sweep in range(sweeps):
            if sweep and better.any():
                r[better], A[better] = pb.state_rows(nodes, offs, glob, np.flatnonzero(better))
            Hn = A.transpose(0, 2, 1) @ A  # (BLAS: einsum's loops took seconds on the whole Shadow hand)
            gn = (r[:, None, :] @ A)[:, 0]
            Dn = np.einsum("sii->si", Hn)
            dn = -np.linalg.solve(Hn + mu_n[:, None, None] * np.einsum("si,ij->sij", Dn + 1e-12, np.eye(nx)),
                                  gn[:, :, None])
            t2 = GaussNewton.trial(pb, nodes + dn[:, :, 0], offs, glob)
            if t2 is None:  # a sweep that overflows: the nodes kept, more damping
                mu_n *= 10
                better = np.zeros(n_int, dtype=bool)
                continue
            better = np.sum(t2.r**2, axis=1) < np.sum(r**2, axis=1)
            nodes[better] += dn[better, :, 0]
            mu_n = np.where(better, mu_n / 10, mu_n * 10)
        return nodes

    @staticmethod
    def join_nodes(pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                   steps: int = JOIN_STEPS) -> np.ndarray:
        """Stage 1's nodes made continuous at the parameters held (``offs`` and ``glob`` fixed): Gauss-Newton on the
        start states alone with continuity as a constraint, up to ``steps`` steps, each taken where it lowers the
        l1 merit (cost + nu |defects|) or halved up to three times; the Jacobians with respect to the start
        states alone (``evaluate(..., jac="state")``, a third to a fifth of the whole), the KKT system banded
        (:func:`~alpes_dyn.estimation.identification.kkt.kkt_from_blocks` with no global variable). Stops where the
        defects are below 1e-6 of ``c_scale``'s rule. A problem with per-interval torque corrections (``no``):
        the nodes as given. Why: a long record's start from its window
        (:mod:`~alpes_dyn.estimation.identification.long_record`).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (residuals, defects, their Jacobians and KKT matrices).
        nodes : numpy.ndarray, shape (S, nx)
            Each interval's start state ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m, held (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (log theta, p), the whitened line corrections (ncg), the drifts' knots (nd);
            held.
        steps : int, optional
            Gauss-Newton steps at most (default :data:`JOIN_STEPS`).

        Returns
        -------
        numpy.ndarray, shape (S, nx)
            The nodes made continuous (a copy), or ``nodes`` itself where there is nothing to join.
        """
        from .kkt import Shape, kkt_from_blocks

        nx, n_int = pb.nx, pb.n_int
        if pb.no or n_int < 2:
            return nodes
        shape = Shape(n_int, nx, nx, 0, pb.cut)
        c_scale = np.maximum(np.abs(nodes).max(axis=0), 1e-3)
        nodes = nodes.copy()
        e = pb.evaluate(nodes, offs, glob, jac="state")
        for _ in range(steps):
            if float(np.max(np.abs(e.c) / c_scale, initial=0.0)) < 1e-6:
                break
            Cr = np.zeros((n_int - 1, nx, 0))
            solve = kkt_from_blocks(e.J, e.Cv, Cr, shape, 1e-9, np.zeros(0), lambda: None)
            if solve is None:
                break
            gs = (e.r[:, None, :] @ e.J).reshape(-1)
            sol = solve(np.concatenate([-gs, -e.c.reshape(-1)]))
            d, lam = sol[:shape.nz].reshape(n_int, nx), sol[shape.nz:]
            nu = 1.5 * float(np.max(np.abs(lam), initial=0.0)) + 1e-12
            merit = e.cost + nu * float(np.sum(np.abs(e.c)))
            for alpha in (1.0, 0.5, 0.25, 0.125):
                trial = GaussNewton.trial(pb, nodes + alpha * d, offs, glob)
                if trial is not None and trial.cost + nu * float(np.sum(np.abs(trial.c))) < merit:
                    break
            else:
                break
            nodes += alpha * d
            e = trial = None
            e = pb.evaluate(nodes, offs, glob, jac="state")
        return nodes

    # --- the trust region ---------------------------------------------------------------------------------------

    @staticmethod
    def coef_cap(pb: ShootingProblem, coef_radius: float) -> float:
        """The line corrections' trust region per line, in whitened units: :data:`COEF_STEP_RECORD`'s rule
        (MAX_COEF_STEP sqrt(max(N / COEF_STEP_RECORD, 1))) times ``coef_radius``.

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (its N samples).
        coef_radius : float
            The multiple of the rule (1 at the start; up to :data:`MAX_COEF_GROWTH`, :meth:`next_radius`).

        Returns
        -------
        float
            The largest move of a whitened line coefficient per step, in prior standard deviations.
        """
        return MAX_COEF_STEP * coef_radius * math.sqrt(max(pb.N / COEF_STEP_RECORD, 1.0))

    @staticmethod
    def limited(pb: ShootingProblem, d: np.ndarray, coef_radius: float = 1.0) -> tuple[np.ndarray, np.ndarray, bool]:
        """A trust region (no jump into a far basin): log theta by at most :data:`MAX_LOG_STEP`, each line of the
        torque's line corrections within :data:`COEF_STEP_RECORD`'s rule times ``coef_radius``, the whole step
        scaled down. In stage 3 the local variables are scaled with the global ones: there, re-solving the nodes
        for a shortened parameter step (continuity a hard constraint), or damping the whole step, sent
        several +-20 % fingers to residuals far above the floor.

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        d : numpy.ndarray, shape (nz,)
            The Gauss-Newton step over the variables: the intervals' local variables (nv = S nb: start state and
            torque correction), then the global ones (ng: log theta, the line corrections, the drifts' knots).
        coef_radius : float, optional
            The multiple of :data:`COEF_STEP_RECORD`'s rule for the line corrections (default 1).

        Returns
        -------
        dv : numpy.ndarray, shape (S, nb)
            The local step, scaled down with the global one.
        dg : numpy.ndarray, shape (ng,)
            The global step.
        whole : bool
            Whether the step is whole (not scaled down).
        """
        p = pb.p
        dv, dg = d[:pb.nv].reshape(pb.n_int, pb.nb), d[pb.nv:pb.nz]
        big = max(float(np.max(np.abs(dg[:p]), initial=0.0)) / MAX_LOG_STEP,
                  float(np.max(np.abs(dg[p:p + pb.ncg]), initial=0.0)) / GaussNewton.coef_cap(pb, coef_radius))
        return (dv / big, dg / big, False) if big > 1.0 else (dv, dg, True)

    @staticmethod
    def next_radius(pb: ShootingProblem, d: np.ndarray, coef_radius: float, streak: int,
                    found: Any) -> tuple[float, int]:
        """The line corrections' trust region (a multiple of :data:`COEF_STEP_RECORD`'s rule) for the next step of
        stage 3, and the streak of steps they alone cut, after the step ``d`` cut by ``coef_radius`` and its line
        search ``found``: where the line corrections, not log theta, cut the step and the cut step was taken whole,
        the streak grows, and from :data:`CRAWL_STEPS` such steps in a row the region doubles (up to
        :data:`MAX_COEF_GROWTH`: a crawl down a valley the linearisation sees right); at any other step, one and
        no streak (the textbook rule, Nocedal and Wright ch. 4, on this one block, started late: doubling from
        the first such step sent a fit of the model's own structure on a path that met no stopping rule in 50
        iterations, where it converged in 16 at one standard deviation).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        d : numpy.ndarray, shape (nz,)
            The Gauss-Newton step before the trust region (local variables, then global ones, as in
            :meth:`limited`).
        coef_radius : float
            The multiple of :data:`COEF_STEP_RECORD`'s rule that cut ``d``.
        streak : int
            Steps in a row so far cut by the line corrections alone and taken whole.
        found : tuple or None
            :meth:`line_search`'s result for the step ((alpha, dv, dg, cost)), or None where it found none.

        Returns
        -------
        radius : float
            The multiple of the rule for the next step (1 to :data:`MAX_COEF_GROWTH`).
        streak : int
            The streak after this step (0 where the step does not count).
        """
        p = pb.p
        dg = d[pb.nv:pb.nz]
        coef = float(np.max(np.abs(dg[p:p + pb.ncg]), initial=0.0)) / GaussNewton.coef_cap(pb, coef_radius)
        if not (found is not None and found[0] == 1.0 and coef > 1.0
                and coef >= float(np.max(np.abs(dg[:p]), initial=0.0)) / MAX_LOG_STEP):
            return 1.0, 0
        streak += 1
        return (min(2.0 * coef_radius, MAX_COEF_GROWTH) if streak >= CRAWL_STEPS else coef_radius), streak

    # --- stage 2 ----------------------------------------------------------------------------------------------

    def homotopy(self, pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                 freeze: bool, first: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, Evaluation]:
        """Stage 2: continuity as a soft penalty, tightened tenfold per phase (a homotopy from the decoupled
        intervals to the shooting problem); ``freeze``: friction held. With the starting parameters wrong, a 100 ms
        interval of the finger (tiny inertias, a soft balance of springs and gravity) drifts by degrees and rad/s;
        imposing continuity at once lets Gauss-Newton trade the fit for the defects and stall far from the truth.
        ``first``: the phase to start from (0: weight 1; a start already close, :mod:`~alpes_dyn.estimation.identification.long_record`,
        skips the softest).
        (Its length: the loop of the phases and of Levenberg-Marquardt inside them, one block.)

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (residuals, defects, their Jacobians and KKT matrices).
        nodes : numpy.ndarray, shape (S, nx)
            Each interval's start state at the start (stage 1's) ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (log theta, p), the whitened line corrections (ncg), the drifts' knots (nd).
        freeze : bool
            Friction (the ``F_`` and ``sigma`` parameters) and the torque's line corrections held through the
            homotopy (the first start).
        first : int, optional
            The phase to start from, 0 to :data:`SOFT_PHASES` - 1 (default 0: the penalty's weight 1).

        Returns
        -------
        nodes, offs, glob : numpy.ndarray
            The variables at the end of the last phase (the shapes of the arguments).
        e : Evaluation
            The evaluation there, with its Jacobians.
        """
        nx, nv, n_int = pb.nx, pb.nv, pb.n_int
        e = pb.evaluate(nodes, offs, glob)
        defect0 = np.maximum(np.abs(e.c).max(axis=0), 1e-9)  # per state component
        # the softly-coupled problem lets friction absorb the defects (the friction driven far off and the fit to
        # another basin): during the homotopy only the springs, masses, gains and torque lines move; on the
        # first start not the torque lines either: their trust region (a standard deviation per step) shortened
        # every step to a small fraction and the springs stayed put (finger_edu with its springs off: held, they
        # move to their values)
        frozen = np.array([i for i, nm in enumerate(pb.sens.names) if freeze and nm.startswith(("F_", "sigma"))]
                          + (list(range(pb.p, pb.ng)) if freeze else []), dtype=int)  # friction waits for the hard phase
        for level in range(first, SOFT_PHASES):
            wv = 10.0**level / defect0  # 1 / sigma of each defect's components
            mu_s = 1e-3
            for _ in range(6):
                soft_cost = 0.5 * float(np.sum(e.r**2) + np.sum(e.rg**2) + np.sum((e.c * wv) ** 2))
                solve_H, solve_local, H_border = pb.penalized_solver(e, mu_s, wv, frozen)
                g = pb.gradient(e) + pb.continuity_t(e.Cv, e.Cr, e.c * wv**2)
                d = -solve_H(g)  # the least-squares solution where H is singular
                dv, dg, whole = self.limited(pb, d)
                if not whole:
                    # the global step shortened, the local variables solved again for it: with continuity a
                    # penalty the data hold the nodes, and they follow the parameters (scaled with them, the
                    # nodes crawled: the homotopy left large defects and stage 3 needed many iterations at a
                    # small fraction of the Gauss-Newton step)
                    try:
                        dv = solve_local(-g[:nv] - H_border @ dg).reshape(n_int, pb.nb)
                    except np.linalg.LinAlgError:
                        pass
                trial = self.trial(pb, nodes + dv[:, :nx], offs + dv[:, nx:], glob + dg)
                new_cost = math.inf if trial is None else 0.5 * float(np.sum(trial.r ** 2) + np.sum(trial.rg ** 2)
                                                                     + np.sum((trial.c * wv) ** 2))
                if np.isfinite(new_cost) and new_cost < soft_cost:
                    nodes, offs, glob = nodes + dv[:, :nx], offs + dv[:, nx:], glob + dg
                    e = trial = solve_H = solve_local = H_border = None  # freed before the next Jacobian
                    e = pb.evaluate(nodes, offs, glob)
                    mu_s = max(mu_s / 10.0, 1e-9)
                    if soft_cost - new_cost < 1e-3 * soft_cost:
                        break
                else:
                    mu_s *= 10.0
                    if mu_s > 1e6:
                        break
        return nodes, offs, glob, e

    # --- stage 3 ----------------------------------------------------------------------------------------------

    @staticmethod
    def line_search(pb: ShootingProblem, at: Evaluation, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                    dv: np.ndarray, dg: np.ndarray, merit: float, nu_merit: float, solve_K):
        """The step's length: 1, 1/2, 1/4, 1/10, 1/30 of (dv, dg) on the l1 merit cost + nu |c|_1, or (a
        filter's second chance, against the Maratos effect near the solution) a step that halves the defects
        while the cost stays put. Where the whole step (as the trust region left it) fails, first second-order
        corrections (Nocedal & Wright, 18.3), up to :data:`SOC_STEPS` in a row while each halves the defects: the
        step's own defects removed by a minimum-norm correction from the same factorised system ``solve_K``;
        the curvature of the shooting map makes a Gauss-Newton step raise the defects quadratically though the
        cost falls, and without the corrections the line search crawls.

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        at : Evaluation
            The evaluation at the current point (its cost and defects ``c``).
        nodes : numpy.ndarray, shape (S, nx)
            The current point's start states ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            The current point's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The current point's global variables: rho (log theta, p), the whitened line corrections (ncg), the
            drifts' knots (nd).
        dv : numpy.ndarray, shape (S, nb)
            The local step (start states, then torque corrections), as :meth:`limited` left it.
        dg : numpy.ndarray, shape (ng,)
            The global step, as :meth:`limited` left it.
        merit : float
            The l1 merit at the current point, cost + ``nu_merit`` |c|_1.
        nu_merit : float
            The merit's penalty on the defects (1.5 times the largest multiplier, at least the last one).
        solve_K : callable
            The factorised KKT system of the step (:meth:`~alpes_dyn.estimation.identification.shooting.
            ShootingProblem.kkt_solver`): right-hand side (nz + nc,) -> solution.

        Returns
        -------
        tuple or None
            (alpha, dv, dg, the cost there): the length, the step (corrected where a second-order correction was
            taken) and the cost at the accepted point; None where no candidate is accepted.
        """
        nx, nz, nv = pb.nx, pb.nz, pb.nv
        cost = at.cost
        candidates = [(1.0, dv, dg), (0.5, dv, dg), (0.25, dv, dg), (0.1, dv, dg), (0.03, dv, dg)]
        soc_done, k_try, c_last, c_at = 0, 0, math.inf, float(np.sum(np.abs(at.c)))
        while k_try < len(candidates):
            alpha, sv, sg = candidates[k_try]
            k_try += 1
            trial = GaussNewton.trial(pb, nodes + alpha * sv[:, :nx], offs + alpha * sv[:, nx:], glob + alpha * sg)
            if trial is None:  # a correction that overflowed a parameter (exp of its log: a LuGre fit's): no step
                continue
            cost_new, c_now = trial.cost, float(np.sum(np.abs(trial.c)))
            if cost_new + nu_merit * c_now < merit or (c_now < 0.5 * c_at and cost_new <= cost * (1.0 + 1e-6)):
                return alpha, sv, sg, cost_new
            if alpha == 1.0 and soc_done < SOC_STEPS and c_now <= 0.5 * c_last:
                soc_done, c_last = soc_done + 1, c_now
                try:
                    d2 = solve_K(np.concatenate([np.zeros(nz), -trial.c.reshape(-1)]))[:nz]
                except np.linalg.LinAlgError:
                    continue
                candidates.insert(k_try, (1.0, sv + d2[:nv].reshape(pb.n_int, pb.nb), sg + d2[nv:]))
        return None

    def stalled(self, history: list[float], cost: float) -> bool:
        """The accepted costs ``history`` down by at most max(tol ``cost``, 0.5) over the last five steps (chi^2 by 1
        in 5: the data's resolution).

        Parameters
        ----------
        history : list of float
            The costs (0.5 chi^2) of the accepted steps, oldest first.
        cost : float
            The current cost (0.5 chi^2).

        Returns
        -------
        bool
            True where more than five steps were taken and the last five lowered the cost by at most the bound.
        """
        return len(history) > 5 and history[-6] - history[-1] <= max(self.tol * cost, 0.5)

    @staticmethod
    def restore(pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray, at: Evaluation,
                solve_K, c_scale: np.ndarray, slack: float):
        """Continuity restored without a Gauss-Newton step: the minimum-norm correction that removes the defects
        ``at.c`` to first order (the second-order correction of :meth:`line_search`, from the same factorised KKT
        system ``solve_K``). Returns (nodes, offs, glob, the evaluation there) where the defects fall below 1e-6 of
        ``c_scale`` and the cost rises by at most ``slack``, else None. The evaluation's residuals, defects and states
        are the new point's, its Jacobians ``at``'s: the correction moves no parameter by a tenth of its standard
        error (the stopping rule that asks for it), so the Jacobians differ to second order in it, and the
        covariance and the verdict's projections taken with them are the same to that order; evaluating them again
        was the dearest evaluation of a fit (all the sensitivities of the whole record, twice in ``--effects
        auto``'s two fits).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        nodes : numpy.ndarray, shape (S, nx)
            The current point's start states ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            The current point's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The current point's global variables: rho (log theta, p), the whitened line corrections (ncg), the
            drifts' knots (nd).
        at : Evaluation
            The evaluation at the current point (its defects ``c``; its Jacobians kept in the result).
        solve_K : callable
            The factorised KKT system at the point (:meth:`~alpes_dyn.estimation.identification.shooting.
            ShootingProblem.kkt_solver`): right-hand side (nz + nc,) -> solution.
        c_scale : numpy.ndarray, shape (nx,)
            The defects' scale per state component (the nodes' largest magnitude, at least 1e-3; rad, rad/s).
        slack : float
            The most the cost (0.5 chi^2) may rise.

        Returns
        -------
        tuple or None
            (nodes, offs, glob, the evaluation there), or None as above.
        """
        nx, nz, nv = pb.nx, pb.nz, pb.nv
        try:
            d2 = solve_K(np.concatenate([np.zeros(nz), -at.c.reshape(-1)]))[:nz]
        except np.linalg.LinAlgError:
            return None
        dv, dg = d2[:nv].reshape(pb.n_int, pb.nb), d2[nv:]
        new = (nodes + dv[:, :nx], offs + dv[:, nx:], glob + dg)
        trial = GaussNewton.trial(pb, *new)
        if trial is None:  # a correction from a lost basin that overflows (a LuGre round's): nothing restored
            return None
        if float(np.max(np.abs(trial.c) / c_scale, initial=0.0)) >= 1e-6 or trial.cost > at.cost + slack:
            return None
        return (*new, dataclasses.replace(trial, J=at.J, Cv=at.Cv, Cr=at.Cr, normal=at.normal,
                                               point=at.point))

    @staticmethod
    def lost(pb: ShootingProblem, d: np.ndarray, it: int) -> str:
        """The reason of a start that lost its basin, naming the parameter whose step asks for the farthest move of
        log theta (:func:`~alpes_dyn.estimation.identification.runaway.friction_held` reads it).

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (its parameters' names).
        d : numpy.ndarray
            The Gauss-Newton step over the problem's variables (the states', then the parameters' log values).
        it : int
            The iteration at which the basin was lost.

        Returns
        -------
        str
            The reason, ``"lost basin: ... (iteration it; the farthest: NAME)"``.
        """
        far = pb.sens.names[int(np.argmax(np.abs(d[pb.nv:pb.nv + pb.p])))]
        return (f"lost basin: three Gauss-Newton steps in a row asked log theta to move by more than "
                f"{100.0 * MAX_LOG_STEP:g} (iteration {it}; the farthest: {far})")

    def constrained(self, pb: ShootingProblem, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                    e: Evaluation, c_scale: np.ndarray, bar: _Progress) -> SolverResult:
        """Stage 3: the shooting problem, continuity as constraints (constrained Gauss-Newton, l1 merit), to the
        stopping rule: continuous to 1e-6 (per state component, relative to ``c_scale``) and either the next step
        moving no parameter by more than a tenth of its standard error, or a predicted or realised (whole step)
        change of the cost below max(tol * cost, 0.05) (chi^2 by 0.1), or chi^2 down by less than 1 over five
        iterations. On noisy data (the residual at least half the encoder's quantisation floor), where the next
        step is within a tenth of a standard error, chi^2 has stalled with the step within one, or no step
        within half of one lowers the merit, continuity is restored (:meth:`restore`) and the fit ends there.
        (Its length: the stopping rule and the lost-basin rule read the iteration's own variables.)

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem (residuals, defects, their Jacobians and KKT matrices).
        nodes : numpy.ndarray, shape (S, nx)
            Each interval's start state at the start of the stage ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (log theta, p), the whitened line corrections (ncg), the drifts' knots (nd).
        e : Evaluation
            The evaluation at the start, with its Jacobians.
        c_scale : numpy.ndarray, shape (nx,)
            The defects' scale per state component (the stage-1 nodes' largest magnitude, at least 1e-3; rad,
            rad/s).
        bar : _Progress
            The progress line, advanced once per iteration.

        Returns
        -------
        SolverResult
            Where the stage ended: the variables, the evaluation, the iterations, converged and the reason.
        """
        nv, nz, p, nx, tol = pb.nv, pb.nz, pb.p, pb.nx, self.tol
        nu_merit, mu, converged, lost, it, radius, streak = 1.0, 1e-3, False, 0, 0, 1.0, 0
        history: list[float] = []
        reason = f"iteration cap: {self.max_iterations} Gauss-Newton iterations without meeting the stopping rule"
        for it in range(1, self.max_iterations + 1):
            solve_K = None  # the last iteration's factorisation freed before the next (a 60 s record's: 110 MB)
            cost = e.cost
            rhs = np.concatenate([-pb.gradient(e), -e.c.reshape(-1)])
            # the step, and the parameters' block of the inverse (their covariance up to the scale)
            solve_K = pb.kkt_solver(pb.normal_of(e), e.Cv, e.Cr, mu)  # once per iteration: step and correction
            sol = solve_K(np.column_stack([rhs, pb.unit_p]))
            sol, P_rho = sol[:, 0], sol[nv:nv + p, 1:]
            d, lam = sol[:nz], sol[nz:]
            viol = float(np.max(np.abs(e.c) / c_scale, initial=0.0))
            sd_rho = np.sqrt(np.maximum(np.diag(P_rho), 1e-300) * max(2.0 * cost / pb.dof, 1e-300))
            step_sigma = float(np.max(np.abs(d[nv:nv + p]) / sd_rho, initial=0.0))
            within = abs(float(rhs[:nz] @ d)) <= max(tol * cost, 0.05) or step_sigma < 0.1
            stalled = self.stalled(history, cost)
            noisy = 2.0 * cost > 0.25 * pb.dof  # residual at least half the quantisation floor: sigma is statistical
            if viol >= 1e-6 and noisy and (step_sigma < 0.1 or (stalled and step_sigma < 1.0)):
                # the fit is done but for continuity (steps shortened by the line search leave part of each
                # defect): the defects alone removed, from the same factorisation (on MuJoCo's stick-slip plants
                # the tail spent many iterations of failed line searches on tiny defects). Only on
                # noisy data: on noise-free data (exact recovery) the standard errors are the residual's, not the
                # sensor's, and Newton's own convergence is what takes the parameters to 1e-6.
                restored = self.restore(pb, nodes, offs, glob, e, solve_K, c_scale, max(tol * cost, 0.5))
                if restored is not None:
                    (nodes, offs, glob, e), converged = restored, True
                    reason = ("converged: the next step within the data's resolution" if step_sigma < 0.1 else
                              "converged: the cost no longer falls") + ", continuity restored"
                    break
            if viol < 1e-6 and within:
                # continuous, and Gauss-Newton predicts a decrease of chi^2 below 0.1 or no parameter moving by
                # a tenth of its standard error: the statistical resolution of the data
                converged = True
                reason = "converged: continuous, and the next step within the data's resolution"
                break
            nu_merit = max(nu_merit, 1.5 * float(np.max(np.abs(lam), initial=0.0)))
            merit, (dv, dg, full) = cost + nu_merit * float(np.sum(np.abs(e.c))), self.limited(pb, d, radius)
            found = self.line_search(pb, e, nodes, offs, glob, dv, dg, merit, nu_merit, solve_K)
            radius, streak = self.next_radius(pb, d, radius, streak, found)
            bar.update(1)
            if found is None and noisy and step_sigma < 0.5:
                # no step along a direction that moves no parameter by half a standard error: the data cannot tell
                # what is left from the noise (the stick-slip law's sharp sign makes the merit rough at that scale:
                # on MuJoCo's plants 6-9 line searches in a row failed there while the damping climbed from 1e-9)
                restored = self.restore(pb, nodes, offs, glob, e, solve_K, c_scale, max(tol * cost, 0.5))
                if restored is not None:
                    (nodes, offs, glob, e), converged = restored, True
                    reason = "converged: no step within half a standard error lowers the cost, continuity restored"
                    break
            if found is None:
                mu *= 10.0
                if mu > 1e8:
                    reason = (f"step failure: no step lowered the merit function (Levenberg-Marquardt damping "
                              f"above 1e8, iteration {it})")
                    break
                continue
            (alpha, dv, dg, cost_new), e, solve_K = found, None, None  # freed before the next (600 s: 180 + 80 MB)
            step_g = float(np.max(np.abs(alpha * dg), initial=0.0))
            nodes, offs, glob = nodes + alpha * dv[:, :nx], offs + alpha * dv[:, nx:], glob + alpha * dg
            e = pb.evaluate(nodes, offs, glob)
            mu = max(mu / 10.0, 1e-9) if alpha == 1.0 else min(mu * 3.0, 1e6)
            viol = float(np.max(np.abs(e.c) / c_scale, initial=0.0))
            small_change = alpha == 1.0 and abs(cost - cost_new) <= max(tol * cost, 0.05)  # chi^2 by less than 0.1
            history.append(cost_new)
            far = not full and float(np.max(np.abs(d[nv:nv + p]), initial=0.0)) > 100.0 * MAX_LOG_STEP
            lost = lost + 1 if far else 0
            if lost >= 3 and viol > 1e-3:
                # three Gauss-Newton steps in a row asking log theta to move by more than 30: the linearisation
                # has lost the basin (on one +-20 % finger a mass headed for 0, the step for 1e6): this start fails
                reason = self.lost(pb, d, it)
                break
            stalled = self.stalled(history, cost)
            if viol < 1e-6 and (small_change or stalled or step_g < tol):
                converged = True
                reason = "converged: continuous, and the cost no longer falls"
                break
        return SolverResult(nodes, offs, glob, e, it, converged, reason)

    # --- the two starts ---------------------------------------------------------------------------------------

    def solve(self, pb: ShootingProblem, nodes: np.ndarray | Callable[[], np.ndarray], offs: np.ndarray,
              glob: np.ndarray, warm: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
              warm_at: list[Evaluation] | None = None) -> SolverResult:
        """Stages 1-3 from ``nodes`` (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.initial_nodes`; or a
        function giving them, called only where no warm start converges: a run of the whole record): stage 1,
        then stages 2-3 with friction held during the homotopy, and again with it free where the first ends
        above :data:`BASIN_LIMIT` (each alone missed the right basin on one of five +-20 % fingers). ``warm``: the
        variables of another fit of the recording (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.warm_variables`):
        stage 3 from them first, kept where it converges within :data:`BASIN_LIMIT`, else stages 1-3 as above (the
        homotopy brings a start from the model's own response near the data; a converged fit of a neighbouring
        model already is: a round of ``--effects auto`` from the last round's trajectory reaches the same values in
        less time).
        ``warm_at``: [the :class:`~alpes_dyn.estimation.identification.shooting.Evaluation` at ``warm`` with its
        Jacobians] where the caller has it (a long record's window start, :mod:`~alpes_dyn.estimation.identification.long_record`:
        one evaluation of the whole record fewer; stage 3 from there at most :data:`WINDOW_ITERATIONS`); taken out
        of the list, so that no reference outlives its use. The result's ``iterations`` count every start.

        Parameters
        ----------
        pb : ShootingProblem
            The fit's problem.
        nodes : numpy.ndarray, shape (S, nx), or callable
            The intervals' start states to start from (rad, rad/s), or a function of no argument returning them.
        offs : numpy.ndarray, shape (S, no)
            Each interval's starting constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The starting global variables: rho (log theta, p), the whitened line corrections (ncg), the drifts'
            knots (nd).
        warm : tuple of numpy.ndarray, optional
            (nodes, offs, glob) of another fit of the recording (default None: no warm start).
        warm_at : list of Evaluation, optional
            [the evaluation at ``warm`` with its Jacobians], emptied by the call (default None).

        Returns
        -------
        SolverResult
            The last start's result; ``iterations`` the total over the starts.
        """
        total_its = 0
        if warm is not None:
            bar = _Progress(self.max_iterations, "identify (warm start)", self.show)
            c_scale = np.maximum(np.abs(warm[0]).max(axis=0), 1e-3)
            cap, self.max_iterations = self.max_iterations, (min(self.max_iterations, WINDOW_ITERATIONS) if warm_at
                                                             else self.max_iterations)
            try:  # a long record's start from its window: given up after WINDOW_ITERATIONS
                # no *warm in the call: CPython packs starred arguments into a tuple that lives until the call
                # returns, and it held the window start's evaluation (its Jacobian: 190 MB at 600 s) through stage 3
                out = self.constrained(pb, warm[0], warm[1], warm[2],
                                       warm_at.pop() if warm_at else pb.evaluate(*warm), c_scale, bar)
            finally:
                self.max_iterations = cap
            bar.close()
            if out.converged and pb.encoder_rms(out.at.r) <= BASIN_LIMIT:
                return out
            total_its = out.iterations
        nodes = self.fit_nodes(pb, nodes() if callable(nodes) else nodes, offs, glob)
        c_scale = np.maximum(np.abs(nodes).max(axis=0), 1e-3)  # per state component
        bar = _Progress(self.max_iterations, "identify", self.show)
        first = (nodes.copy(), offs.copy(), glob.copy())  # both starts from the stage-1 nodes
        for freeze in (True, False):
            if not freeze:  # the second start has its own progress line (each start takes up to max_iterations)
                bar.close()
                bar = _Progress(self.max_iterations, "identify (second start)", self.show)
            start = [a.copy() for a in first]
            nd, of, gl, e = self.homotopy(pb, *start, freeze)
            out = self.constrained(pb, nd, of, gl, e, c_scale, bar)
            total_its += out.iterations
            if pb.encoder_rms(out.at.r) <= BASIN_LIMIT:
                break
        bar.close()
        out.iterations = total_its
        return out
