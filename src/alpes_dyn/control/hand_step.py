"""One sample of the whole hand's force loop, for a user's own 1 kHz loop: :class:`HandForceStep`.

The hand has six motors (:func:`~alpes_dyn.model.hand_chains.hand_chains`: index, middle, ring, little, the thumb's
flexion, then the thumb's ab/adduction). ``HandForceStep`` closes one force loop per flexion chain, each a
:class:`~alpes_dyn.control.step.ForceStep` of its own (its EKF with the contact force as an input, the effects'
compensation, the controller with the hand's gains), built once; the ab/adduction is held by a PD on its encoder.
It is the loop of :func:`~alpes_dyn.control.hand_loop.run_hand_control`, the hand grasping a cylinder:

* the contact: every chain's fingertip presses the object, each with its own FlexiForce (the hand loop's five
  sensors; ``force`` is (5,) N, the chains in the motors' order), as
  :class:`~alpes_dyn.bench.mujoco_hand.MujocoHand`'s ``"cylinder"`` scene reads them;
* each chain's model: :func:`~alpes_dyn.model.hand_chains.chain_model` of the parameter file palm down, the thumb's
  at the ab/adduction target (its EKF's with the file's friction, eq. 2.6-2.7);
* the gains: :func:`~alpes_dyn.control.hand_grasp.hand_gains` (:data:`.DEFAULT_GAINS` overridden by
  :data:`~alpes_dyn.control.hand_grasp.HAND_GAINS` and the controller's and the chain's own hand settings), then
  ``gains``;
* the contact normal of a chain at sample k: given to :meth:`HandForceStep.step` (``normals``, (5, 3), each in its
  chain's base frame: what the C step takes), or by default the cylinder's
  (:data:`~alpes_dyn.model.mjcf.CYLINDER`, :func:`~alpes_dyn.control.hand_grasp.cylinder_normal`) at the fingertip
  of the chain's estimate of sample k-1 (at k = 0, of its rest); the ``"pi"`` loops, without an estimate, at the
  rest's;
* the ab/adduction: :class:`~alpes_dyn.control.blocks.EncoderPD` on its encoder toward ``thumb_abduction`` rad
  (its target ramped up from 0 over ``abduction_ramp_s``), its command clipped to [-tau_max, tau_max]: its motor, a
  gear, pushes both ways (:attr:`~alpes_dyn.bench.mujoco_hand.MujocoHand.both_ways`), and must: the joint has no
  spring, and the thumb's pad pressing the cylinder pushes it open (clipped at 0, the MuJoCo stand-in's thumb went
  from 35 to 59 degrees, its chain model, taken at 35, off by as much).

Each chain's timing is :class:`~alpes_dyn.control.step.ForceStep`'s: the readings of tick k in, the command held
over [t_k, t_k+1) out.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from ..model.hand_chains import chain_model, hand_chains
from ..model.mjcf import palm_down_params
from ..model.params import HandParams, load_params
from ..model.trust import check_trusted
from .blocks import EncoderPD
from .hand_grasp import cylinder_in_chain, cylinder_normal, hand_gains
from .realism_loop import Compensation
from .step import ForceStep, LoopDesign, _checked_settings, _number

__all__ = ["HandForceStep", "ABDUCTION"]

ABDUCTION = "thumb_abduction"
"""The hand's sixth motor: the thumb's ab/adduction, held by a PD (no force loop)."""


class HandForceStep:
    """One sample of the whole hand's force loop: ``command = step.step(counts, torque, force, reference)``.

    Built once (each chain's EKF compiled or loaded from the cache here, never in :meth:`step`); see the module
    docstring for the contact, the normals and the ab/adduction.

    Parameters
    ----------
    params : str, Path, HandParams or None
        The hand's parameter file (None: the shipped one); turned palm down (the cylinder scene's orientation).
    controller : str
        ``"sensor"``, ``"sensorless"`` or ``"pi"`` (:data:`.CONTROLLERS`), every chain's.
    dt : float
        The sample period, s.
    thumb_abduction : float
        The ab/adduction's target, rad (35 degrees: the thumb's pad facing the cylinder); the thumb chain's model
        is taken there.
    abduction_kp, abduction_kd, abduction_filter_s : float
        The PD's gains, N m/rad and N m s/rad, and its velocity filter's time constant, s.
    abduction_ramp_s : float
        s: the PD's target ramped from 0 to ``thumb_abduction`` over it (a motor that cannot push back cannot
        brake an overshoot; 0: the target at once).
    gains : dict or None
        Overrides of the chains' controller settings (after :func:`~alpes_dyn.control.hand_grasp.hand_gains`).
    compensation : Compensation or None
        The effects' compensation, every chain's (its ``force_scale`` a number or a dict by chain).
    compiled : bool
        The EKFs compiled (C, cached); False: CasADi's virtual machine.
    torque_noise, encoder_noise_counts, force_noise, force_resolution, force_filter_s : float
        As :class:`~alpes_dyn.control.step.ForceStep`'s.
    observer_friction : bool
        The chains' EKFs run the file's friction.
    force : bool
        Use a parameter file marked not trustworthy.

    Attributes
    ----------
    chains : tuple of str
        The flexion chains, in the motors' order.
    motor_names : tuple of str
        The six motors: the chains', then ``"thumb_abduction"``.
    chain_steps : dict of str to ForceStep
        Each chain's step (its :meth:`~alpes_dyn.control.step.ForceStep.parts` give its settings).
    abduction : EncoderPD
        The ab/adduction's PD (its target, gains, filter weight, ratio; its state advances at each step).
    abduction_rad_per_count : float
        rad of the ab/adduction motor per count.
    tau_max : float
        The motor limit, N m: every chain's command lies in [0, tau_max], the ab/adduction's in [-tau_max,
        tau_max].

    Raises
    ------
    InputError
        A bad setting (one line naming it). ModelError: an unreadable or untrusted parameter file.
    """

    def __init__(self, params: Any = None, controller: str = "sensor", *, dt: float = 1e-3,
                 thumb_abduction: float = math.radians(35.0), abduction_kp: float = 0.5, abduction_kd: float = 0.01,
                 abduction_filter_s: float = 0.01, abduction_ramp_s: float = 1.0, gains: dict | None = None,
                 compensation: Compensation | None = None,
                 compiled: bool = True, torque_noise: float = 5e-4, encoder_noise_counts: float = 0.5,
                 force_noise: float = 0.005, force_resolution: float = 4.4 / 1024, force_filter_s: float = 0.01,
                 observer_friction: bool = True, force: bool = False) -> None:
        comp = _checked_settings(controller, compensation, gains)
        p = params if isinstance(params, HandParams) else load_params(params)
        check_trusted(p, bool(force))
        p = palm_down_params(p)
        dt = _number(dt, "dt", "seconds", positive=True)
        abd = _number(thumb_abduction, "thumb_abduction", "rad")
        if not p.abduction_lower <= abd <= p.abduction_upper:
            raise InputError(f"thumb_abduction: {abd:g} rad is outside the ab/adduction range "
                             f"[{p.abduction_lower:g}, {p.abduction_upper:g}] rad")
        pd = {k: _number(v, k, u, nonneg=True) for k, v, u in (
            ("abduction_kp", abduction_kp, "N m/rad"), ("abduction_kd", abduction_kd, "N m s/rad"),
            ("abduction_filter_s", abduction_filter_s, "seconds"), ("abduction_ramp_s", abduction_ramp_s, "seconds"))}
        noise = {k: _number(v, k, u, nonneg=True) for k, v, u in (
            ("torque_noise", torque_noise, "N m"), ("encoder_noise_counts", encoder_noise_counts, "counts"),
            ("force_noise", force_noise, "N"), ("force_resolution", force_resolution, "N"))}
        f_s = _number(force_filter_s, "force_filter_s", "seconds", nonneg=True)
        self.kind, self.dt, self.params, self.compensation = controller, dt, p, comp
        self.chains = hand_chains(p)
        self.motor_names = (*self.chains, ABDUCTION)
        self.tau_max = float(p.tau_max)
        self.chain_steps: dict[str, ForceStep] = {}
        self._cylinder: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for c in self.chains:
            model = comp.turned(chain_model(p, c, abd))
            observer = comp.turned(chain_model(p, c, abd, friction=True)) if observer_friction else None
            self._cylinder[c] = cylinder_in_chain(p, c, abd)
            q_rest = model.static_equilibrium(np.zeros(model.n))
            design = LoopDesign(model, cylinder_normal(model, q_rest, *self._cylinder[c]), self.tau_max,
                                hand_gains(controller, gains, c), params=p, contact_q=tuple(q_rest.tolist()),
                                observer_model=observer)
            chain_comp = comp if not isinstance(comp.force_scale, dict) else _one_scale(comp, c)
            self.chain_steps[c] = ForceStep.from_design(design, controller, dt, chain_comp, noise=noise,
                                                        force_filter_s=f_s, compiled=bool(compiled),
                                                        label=f"ekf_force_hand_step_{c}")
        self.abduction_rad_per_count = 2 * np.pi / self.chain_steps[self.chains[0]].counts_per_rev
        self.abduction_target, self.abduction_ramp_s = abd, pd["abduction_ramp_s"]
        self.abduction = EncoderPD(abd, pd["abduction_kp"], pd["abduction_kd"], dt / (pd["abduction_filter_s"] + dt),
                                   ratio=float(p.abduction_ratio), u_max=self.tau_max, reading="y", command="u")
        self.reset()

    def reset(self) -> None:
        """Back to the first sample: every chain's step reset (its EKF at the rest), the PD cleared."""
        for s in self.chain_steps.values():
            s.reset()
        self.abduction.start(0, self.dt, False)
        self.k = 0
        self._normals = np.array([s.parts().normal for s in self.chain_steps.values()])
        self._command = np.zeros(len(self.motor_names))

    def step(self, counts: Any, torque: Any, force: Any, reference: Any, normals: Any = None) -> np.ndarray:
        """One sample: the readings of tick k in, the (6,) motor commands (N m: the chains' in [0, tau_max], the
        ab/adduction's in [-tau_max, tau_max]) to hold over [t_k, t_k+1) out.

        Parameters
        ----------
        counts : array_like
            (6,) encoder counts at t_k, the motors' order (:attr:`motor_names`).
        torque : array_like
            (6,) motor torques the current sensors report at t_k, N m (the ab/adduction's is not read).
        force : array_like or None
            (5,) the fingertip sensors' normal forces at t_k, N, the chains' order; not read by ``"sensorless"``
            (None there).
        reference : float or array_like
            The force reference F_ref at t_k, N: one for every chain, or (5,).
        normals : array_like or None
            (5, 3) each chain's contact normal (its base frame, from the fingertip into the object); None: the
            cylinder's at the fingertip of the chain's last estimate (module docstring).

        Returns
        -------
        numpy.ndarray
            (6,) the commands, N m.

        Raises
        ------
        InputError
            A reading of the wrong shape or not finite, a zero normal, an EKF that diverged (one line naming it and
            the chain; the steps of the chains before it have advanced: :meth:`reset` to start again).
        """
        nc = len(self.chains)
        counts = _array(counts, (nc + 1,), "counts", "encoder counts")
        torque = _array(torque, (nc + 1,), "torque", "motor torques in N m")
        sensorless = self.kind == "sensorless"
        F = np.zeros(nc) if sensorless else _array(force, (nc,), "force", "fingertip forces in N")
        ref = np.broadcast_to(_array(reference, np.shape(reference) if np.ndim(reference) == 0 else (nc,),
                                     "reference", "force references in N"), (nc,))
        N = self._default_normals() if normals is None else _array(normals, (nc, 3), "normals", "contact normals")
        u = np.zeros(nc + 1)
        for i, (c, s) in enumerate(self.chain_steps.items()):
            try:
                u[i] = s.step(counts[i], torque[i], None if sensorless else float(F[i]), float(ref[i]), N[i])[0]
            except InputError as e:
                raise InputError(f"{c}: {e}") from None
        t_k, ramp = self.k * self.dt, self.abduction_ramp_s
        self.abduction.target = self.abduction_target * (min(1.0, t_k / ramp) if ramp > 0 else 1.0)
        pd = self.abduction.output(self.k, {"y": counts[nc] * self.abduction_rad_per_count})["u"]
        u[nc] = min(max(pd, -self.tau_max), self.tau_max)
        self._normals = N
        self._command = u
        self.k += 1
        return u.copy()

    def _default_normals(self) -> np.ndarray:
        """(5, 3) the cylinder's normal at each chain's fingertip of its last estimate (the pi loops: the rest's)."""
        if self.kind == "pi":
            return self._normals
        return np.array([cylinder_normal(s.model, s.estimate[0], *self._cylinder[c])
                         for c, s in self.chain_steps.items()])

    @property
    def normals(self) -> np.ndarray:
        """(5, 3) the contact normals of the last sample (each chain's base frame)."""
        return self._normals.copy()

    @property
    def command(self) -> np.ndarray:
        """(6,) the last commands, N m."""
        return self._command.copy()

    @property
    def state(self) -> np.ndarray:
        """The chains' [q_hat; qd_hat] of the last sample, concatenated in the chains' order (28,: 4 x 6 + 4)."""
        return np.concatenate([s.state for s in self.chain_steps.values()])

    @property
    def force_estimate(self) -> np.ndarray:
        """(5,) the forces the chains' controllers fed back at the last sample, N."""
        return np.array([s.force_estimate for s in self.chain_steps.values()])

    def __repr__(self) -> str:
        return f"HandForceStep(controller={self.kind!r}, dt={self.dt:g}, tau_max={self.tau_max:g}, sample {self.k})"


def _one_scale(comp: Compensation, chain: str) -> Compensation:
    """``comp`` with its per-chain ``force_scale`` reduced to ``chain``'s."""
    import dataclasses

    return dataclasses.replace(comp, force_scale=comp.scale_of(chain))


def _array(x: Any, shape: tuple, name: str, what: str) -> np.ndarray:
    """``x`` as a finite array of ``shape``; InputError naming ``name``."""
    try:
        v = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected {what}, got {x!r}") from None
    if v.shape != shape:
        raise InputError(f"{name}: expected {what} of shape {shape}, got shape {v.shape}")
    if not np.isfinite(v).all():
        raise InputError(f"{name}: expected finite {what}, got {v.tolist()!r}")
    return v
