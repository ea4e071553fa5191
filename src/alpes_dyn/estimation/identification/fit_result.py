"""The result of a fit (:func:`~alpes_dyn.estimation.identification.identification.identify`): its estimates and
diagnostics, and the parameter file they make (:func:`identified_params`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ModelError
from ...model.params import HandParams, Param, with_values, write_params
from ...model.robot import Model
from ...symbolic.parametric import parameter_catalogue
from .adequacy import Adequacy, _finite
from .bounds import Z_INTERVAL, describe

__all__ = ["IdentificationResult", "StandardErrors", "identified_params"]


@dataclass
class StandardErrors:
    """How a fit's standard errors were made (:mod:`~alpes_dyn.estimation.identification.robust_covariance`):
    ``classical`` (p,) s^2 (J'J)^-1's, ``robust`` (p,) the HAC sandwich's (both in the parameters' units, inf where
    the recording does not see one), ``robust_larger`` (p,) bool where the robust one is reported (the larger),
    ``method`` the sandwich (:class:`~alpes_dyn.estimation.identification.robust_covariance.RobustCovariance`);
    ``law_spread`` (p,) where the model-form error was added (:mod:`~alpes_dyn.estimation.identification.law_spread`:
    |theta - theta_other law|, in the parameters' units), else None; ``model_form`` (p,) the model-form term of (S2)
    there (c_kind |theta|, the parameters' units), else None."""

    classical: np.ndarray
    robust: np.ndarray
    robust_larger: np.ndarray
    method: Any = None
    law_spread: np.ndarray | None = None
    model_form: np.ndarray | None = None

    RULE = "max(classical, robust) per parameter"

    def kind(self, i: int) -> str:
        """``"robust"`` or ``"classical"``: which one parameter ``i`` reports.

        Parameters
        ----------
        i : int
            The parameter's index.

        Returns
        -------
        str
            ``"robust"`` or ``"classical"``.
        """
        return "robust" if self.robust_larger[i] else "classical"

    def summary(self, names: tuple[str, ...]) -> str:
        """One line for the fit's table and file: the rule, the sandwich, the parameters whose robust error is
        reported.

        Parameters
        ----------
        names : tuple[str, ...]
            The parameters' names, in the fit's order.

        Returns
        -------
        str
            The line.
        """
        which = [n for n, b in zip(names, self.robust_larger) if b]
        how = self.method.describe() if self.method is not None else "HAC sandwich"
        law = "" if self.law_spread is None else ", with the other friction law's fit's difference added"
        law += "" if self.model_form is None else " and the memoryless laws' model-form error"
        return (f"std = {self.RULE}{law} ({how}); robust for {', '.join(which)}" if which
                else f"std = {self.RULE}{law} ({how}); classical for all")

    def to_dict(self) -> dict[str, Any]:
        out = {"rule": self.RULE}
        if self.law_spread is not None:
            out["law_spread"] = [float(x) for x in self.law_spread]
        if self.model_form is not None:
            out["model_form"] = [float(x) for x in self.model_form]
        if self.method is not None:
            out.update(self.method.to_dict())
        return out


@dataclass
class IdentificationResult:
    """Estimates and diagnostics of :func:`identify`.

    Attributes
    ----------
    names: parameter names (p,). values, std, initial: (p,) in their units. units: (p,).
    correlation: (p, p). residual_rms: RMS encoder residual, counts. iterations, converged.
    seconds: wall time of the fit; compile_seconds: of it, compiling the sensitivity code (0 when
    cached). states: (S, 2n) fitted states at the shooting nodes; node_times (S,) s. solution: the shooting
    variables, to start another fit from. standard_errors: how ``std`` was made (classical and robust, which one
    each parameter reports: :class:`StandardErrors`); ``std`` and ``correlation`` are of the covariance reported.
    """

    names: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    initial: np.ndarray
    units: tuple[str, ...]
    correlation: np.ndarray
    residual_rms: float
    iterations: int
    converged: bool
    seconds: float
    compile_seconds: float
    states: np.ndarray
    node_times: np.ndarray
    model: Model = field(repr=False)
    recording_path: str = ""
    reason: str = ""
    residual: np.ndarray | None = field(default=None, repr=False)
    adequacy: Adequacy | None = None
    solution: Any = field(default=None, repr=False, compare=False)
    """The fit's shooting variables (:class:`~alpes_dyn.estimation.identification.held.ShootingSolution`) for a warm
    start of another fit of the same recording (``identify(..., start=result)``); not written to the file."""
    not_identified: dict[str, str] = field(default_factory=dict)
    """The parameters fitted first but not identified (outside their physical range, at a bound, or their 95 %
    interval past 0: :mod:`~alpes_dyn.estimation.identification.bounds`), name -> why (with the effect the data do not
    support): held in the fit kept, never written to a file."""
    torque_delay: int | None = None
    """Whole samples by which the recorded torque was read earlier for this fit (the ``delay`` effect of
    :func:`~alpes_dyn.estimation.identification.effects.fit_effects`: the recorded torque found lagging the motor's),
    None where the fit did not try one; written to the file as ``transmission.torque_delay``."""
    model_error: float | None = None
    """The observer's model error calibrated on the fit's record, in units of each joint's F_s
    (:func:`~alpes_dyn.estimation.identification.noise_calibration.calibrate_model_error`, by the observer check);
    None where not calibrated; written to the file as ``friction.model_error``."""
    observer_law: str | None = None
    """The observer's friction law the observer check chose by measurement
    (:func:`~alpes_dyn.estimation.identification.law_choice.choose_law`, one of
    :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`); None where no choice was made; written to the file as
    ``friction.observer_law``."""
    drift: dict[str, Any] | None = None
    """With ``identify(drift=...)``: the fitted drifts (:mod:`~alpes_dyn.estimation.identification.drift`),
    ``{"knots_s": [...] (K+1,) s of recorded time, "counts": {motor: [...] (K+1,) counts, 0 at the first knot}}`` (the
    encoder offsets', with ``"offset"``) and ``"torque_scale": {motor: [...] (K+1,), 1 at the first knot}`` (the
    torque constants' scale relative to the first sample's, with ``"gain"``); else None."""
    standard_errors: StandardErrors | None = field(default=None, repr=False)

    @property
    def trustworthy(self) -> bool:
        """Converged, and the model adequate to the recording (:attr:`adequacy`)."""
        return bool(self.converged and (self.adequacy is None or self.adequacy.adequate))

    def status(self) -> str:
        """One line: why the fit is (not) to be trusted."""
        parts = [] if self.converged else [f"the fit did not converge ({self.reason})"]
        if self.adequacy is not None and not self.adequacy.adequate:
            parts.append(self.adequacy.summary())
        text = "; ".join(parts) if parts else "converged; " + (self.adequacy.summary() if self.adequacy else "")
        return text + (f"; {describe(self.not_identified)}" if self.not_identified else "")

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``alpes-dyn identify --json`` (an unbounded std, a parameter the data do not see, is null)."""
        return {
            "parameters": {n: {"value": _finite(v), "std": _finite(s), "initial": _finite(i), "unit": u,
                               **self._std_fields(k)}
                           for k, (n, v, s, i, u) in enumerate(zip(self.names, self.values, self.std, self.initial,
                                                                   self.units))},
            "standard_errors": self.standard_errors.to_dict() if self.standard_errors is not None else None,
            "residual_rms": _finite(self.residual_rms), "residual_unit": "counts", "iterations": self.iterations,
            "converged": self.converged, "reason": self.reason, "trustworthy": self.trustworthy,
            "seconds": self.seconds, "compile_seconds": self.compile_seconds, "model": self.model.name,
            "adequacy": self.adequacy.to_dict() if self.adequacy is not None else None,
            "not_identified": dict(self.not_identified), "drift": self.drift, "torque_delay": self.torque_delay,
            "model_error": self.model_error, "observer_law": self.observer_law,
        }

    def _std_fields(self, k: int) -> dict[str, Any]:
        """Parameter ``k``'s classical and robust standard errors and which one ``std`` is (none without them)."""
        se = self.standard_errors
        if se is None:
            return {}
        return {"std_classical": _finite(se.classical[k]), "std_robust": _finite(se.robust[k]), "std_from": se.kind(k)}

    def params(self, base: HandParams | None = None, chain: str | None = None) -> HandParams:
        """The parameter set with the fitted values (see :func:`identified_params`).

        Parameters
        ----------
        base : HandParams or None, optional
            The parameter file the fit's values go into (default: the model's).
        chain : str or None, optional
            The chain the values are of (default: the model's :attr:`~alpes_dyn.Model.chain`).

        Returns
        -------
        HandParams
            ``base`` with the fitted values, each ``identified``.
        """
        return identified_params(self, base, chain)

    def write(self, path: str | Path, base: HandParams | None = None, chain: str | None = None) -> Path:
        """Write the identified parameter file (the base file with each fitted value ``identified``).

        Parameters
        ----------
        path : str or Path
            The TOML file.
        base : HandParams or None, optional
            The parameter file the fit's values go into (default: the model's).
        chain : str or None, optional
            The chain the values are of (default: the model's :attr:`~alpes_dyn.Model.chain`).

        Returns
        -------
        Path
            The file written.
        """
        header = (f"Identified by alpes_dyn from {_printable(self.recording_path) or 'a recording'} "
                  f"(model {self.model.name}, residual {self.residual_rms:.3g} counts RMS)")
        if not self.trustworthy:
            header += f"\nNOT TRUSTWORTHY (written with --force): {_printable(self.status())}"
        return write_params(self.params(base, chain), path, header=header)


def identified_params(result: IdentificationResult, base: HandParams | None = None,
                      chain: str | None = None) -> HandParams:
    """``base`` (default: the model's parameter file) with the fitted values of a chain, each marked
    ``source = "identified"`` with its standard error.

    Where they go (``chain``, default the model's :attr:`~alpes_dyn.Model.chain`):

    * a finger model without a chain: the shared ``[finger]`` values -- K_i -> ``finger.K``, m_i ->
      ``finger.m`` and ``finger.I`` (scaled with the mass), F_s_i, F_v_i -> ``finger.F_s``, ``finger.F_v``;
    * a finger model with ``chain`` a finger's name: that finger's own values ``[finger.<name>]`` (the
      fields fitted, the others untouched);
    * the thumb model (``chain`` ``"thumb"``): ``[thumb]`` -- K, m, I, F_s, F_v of its flexion joints,
      ``base_mass`` (m_thumb_abd), ``abduction_K``, ``abduction_F_s``, ``abduction_F_v``;
    * a rotor inertia ``J_m_<motor>`` (one motor's): ``transmission.J_m``;
    * the LuGre law's ``sigma0``, ``sigma1``: ``friction.sigma0``, ``friction.sigma1``, with ``friction.law =
      "lugre"``; the creep law's ``creep_kappa``, ``creep_rate``: ``friction.creep_kappa``, ``friction.creep_rate``,
      with ``friction.law = "creep"``;
    * the chain's tendon compliance ``tendon_compliance_<motor>``: ``transmission.tendon_compliance`` (the
      ab/adduction gear's stays in the result); its sheath friction ``capstan_<motor>``: ``transmission.capstan``
      (likewise);
    * the rig's side, read back by every command that takes the file: the chain's encoder zero
      ``encoder_offset_<motor>`` (rad of the motor): ``encoder_offset`` of the chain's section (``[finger]``,
      ``[finger.<name>]``, ``[thumb]``; the thumb's ab/adduction motor's ``thumb.abduction_encoder_offset``); the
      palm's tilt ``tilt_x``, ``tilt_y``: ``environment.gravity``, the model's file's gravity turned by it
      (:func:`~alpes_dyn.symbolic.parametric.tilted_gravity`, its standard error through the tilt's covariance;
      with the hand's chains, the last finger's; not the thumb's, whose angles are in its own base frame, yawed
      from the palm's: they stay in the result); the torque delay :attr:`IdentificationResult.torque_delay`:
      ``transmission.torque_delay`` (samples; the rig's current sensing, one for every motor: a fit that tried none
      leaves the file's). A chain's encoder zero the fit did not fit is taken out of the file (the fit assumed
      none).

    ``input_gain`` (the torque sensor's scale: multiply the torque constant by it) stays in the result (and
    ``identify --json``), not in the file.

    Parameters
    ----------
    result : IdentificationResult
        The fit.
    base : HandParams or None, optional
        The parameter file the values go into (default: the model's).
    chain : str or None, optional
        The chain (default: the model's :attr:`~alpes_dyn.Model.chain`).

    Returns
    -------
    HandParams
        ``base`` with the fitted values.
    """
    p, chain, thumb = _destination(result, base, chain)
    reason = _provenance(result)
    own = p.chain("finger" if chain is None else chain)
    arrays, stds, touched, scalars = _fitted_values(result, own, p, thumb)
    sec = "thumb" if thumb else ("finger" if chain is None else f"finger.{chain}")
    upd = _array_params(p, sec, arrays, stds, touched, reason)
    upd.update(_scalar_params(p, scalars, reason))
    upd.update(_rig_params(result, p, sec, reason))
    stale = [k for k in (f"{sec}.encoder_offset",) + (("thumb.abduction_encoder_offset",) if thumb else ())
             if k in p.raw and k not in upd]
    if stale:  # the chain's zero of an earlier recording, which this fit did not assume (it fitted with none)
        p = dataclasses.replace(p, raw={k: v for k, v in p.raw.items() if k not in stale})
    key = "thumb" if thumb else ("finger" if chain is None else chain)
    return with_values(p, upd, identification={key: _record(result)})


_UNITS = {"K": "N m/rad", "m": "kg", "I": "kg m^2", "F_s": "N m", "F_v": "N m s/rad", "abduction_K": "N m/rad",
          "base_mass": "kg", "abduction_F_s": "N m", "abduction_F_v": "N m s/rad"}
"""The units of the parameter file's fields that a fit writes."""


def _destination(result: IdentificationResult, base: HandParams | None, chain: str | None
                 ) -> tuple[HandParams, str | None, bool]:
    """(the parameter set written into, the chain, whether it is the thumb's), checked: a model with a file, of a
    finger or the thumb, a chain of its kind."""
    p = base if base is not None else result.model.params
    if p is None:
        raise ModelError("identified parameters: the model has no parameter file; pass base=")
    model = result.model
    if model.name not in ("finger2", "finger3", "thumb"):
        raise ModelError(f"identified parameters: writing a parameter file is supported for finger2, finger3 and "
                         f"thumb, not {model.name!r}")
    if chain is None:
        chain = model.chain
    thumb = model.name == "thumb"
    if thumb and chain != "thumb":
        raise ModelError(f"chain: the thumb model's values go to the thumb, not {chain!r}")
    if not thumb and chain is not None and chain not in p.finger_names:
        raise ModelError(f"chain: unknown finger {chain!r} (expected one of {', '.join(p.finger_names)})")
    return p, chain, thumb


def _provenance(result: IdentificationResult) -> str:
    """The ``reason`` written with every identified value: the recording, the residual, the verdict, the parameters
    without a standard error."""
    reason = (f"identified from {_printable(result.recording_path) or 'a recording'} by multiple shooting "
              f"({result.residual_rms:.3g} counts RMS residual)")
    if not result.trustworthy:
        reason += f"; NOT TRUSTWORTHY: {result.status()}"
    unbounded = [n_ for n_, sd in zip(result.names, result.std) if not math.isfinite(sd)]
    if unbounded:  # not seen by this recording: the value is its start, no standard error to write
        reason += f"; no standard error for {', '.join(unbounded)} (not seen by the recording)"
    return reason


def _fitted_values(result: IdentificationResult, own: Any, p: HandParams, thumb: bool
                   ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], set[str], dict[str, tuple[float, Any]]]:
    """The chain's per-joint fields with the fitted values (K, m with I scaled with it, F_s, F_v: values and
    standard errors, (k,) each, and the fields touched) and the scalar fields fitted (field -> (value, std)):
    the thumb's ab/adduction joint, J_m, the tendon compliance. The recording's own parameters (encoder offsets,
    tilt, input gain) and the ab/adduction gear's compliance are left out."""
    model = result.model
    k = own.n
    arrays = {"K": own.K.copy(), "m": own.m.copy(), "I": own.I.copy(),
              "F_s": (own.F_s if own.F_s is not None else np.full(k, p.F_s)).copy(),
              "F_v": (own.F_v if own.F_v is not None else np.full(k, p.F_v)).copy()}
    stds = {kind: np.zeros(k) for kind in arrays}
    scalars: dict[str, tuple[float, Any]] = {}  # thumb scalars: field -> (value, std)
    touched = set()
    cat = {pp.name: pp for pp in parameter_catalogue(model)}
    flexion = [j for j in model.joint_names if j != "thumb_abd"]
    for name, value, sd in zip(result.names, result.values, result.std):
        if name in result.not_identified:
            continue  # not identified (outside its physical range, or not told from 0): never written
        pp = cat.get(name)
        if pp is not None and pp.kind in ("encoder_offset", "tilt", "input_gain"):
            continue  # the rig's side (_rig_params), and the torque sensor's scale (not in the file)
        if pp is not None and pp.kind in ("tendon_compliance", "capstan"):
            if pp.motor.endswith("_abduction"):
                continue  # the ab/adduction gear's stretch or friction: of this rig's gear, kept in the result
            scalars[pp.kind] = (float(value), _sd(sd))
            continue
        if pp is not None and pp.kind in ("sigma0", "sigma1", "creep_kappa", "creep_rate"):  # a law's, every joint's
            scalars[pp.kind] = (float(value), _sd(sd))
            continue
        if pp is not None and pp.kind == "J_m":
            if sum(cat.get(n_) is not None and cat[n_].kind == "J_m" for n_ in result.names) > 1:
                raise ModelError("identified parameters: the file has one rotor inertia transmission.J_m for "
                                 "every motor; fit one motor's J_m")
            scalars["J_m"] = (float(value), _sd(sd))
            continue
        if pp is None or pp.kind not in ("K", "m", "F_s", "F_v"):
            raise ModelError(f"identified parameters: {name!r} has no place in the parameter file")
        if thumb and pp.joint == "thumb_abd":
            field_ = {"K": "abduction_K", "m": "base_mass", "F_s": "abduction_F_s", "F_v": "abduction_F_v"}[pp.kind]
            scalars[field_] = (float(value), _sd(sd))
            continue
        i = flexion.index(pp.joint)
        if pp.kind == "m":
            scale = value / arrays["m"][i]
            arrays["I"][i] *= scale
            stds["I"][i] = arrays["I"][i] * sd / value
            touched.add("I")
        arrays[pp.kind][i] = value
        stds[pp.kind][i] = sd
        touched.add(pp.kind)
    return arrays, stds, touched, scalars


def _array_params(p: HandParams, sec: str, arrays: dict[str, np.ndarray], stds: dict[str, np.ndarray],
                  touched: set[str], reason: str) -> dict[str, Param]:
    """The per-joint fields touched as ``identified`` :class:`Param` of section ``sec`` (their description the
    file's; no std for a field with one unseen entry)."""
    upd = {}
    for kind in touched:
        old = p.raw.get(f"{sec}.{kind}") or p.raw.get(f"finger.{kind}")
        desc = old.description if old is not None else f"per-joint {kind}"
        std = stds[kind] if np.isfinite(stds[kind]).all() else None  # one unseen entry: no std for the field
        upd[f"{sec}.{kind}"] = Param(arrays[kind], _UNITS[kind], "identified", reason, desc, std)
    return upd


def _scalar_params(p: HandParams, scalars: dict[str, tuple[float, Any]], reason: str) -> dict[str, Param]:
    """The scalar fields fitted as ``identified`` :class:`Param`: ``transmission.tendon_compliance``,
    ``transmission.J_m`` and the thumb's ab/adduction fields."""
    upd = {}
    for field_, (value, sd) in scalars.items():
        if field_ == "tendon_compliance":
            old = p.raw.get("transmission.tendon_compliance")
            upd["transmission.tendon_compliance"] = Param(
                value, "rad/(N m)", "identified", reason, old.description if old is not None else
                "the flexion tendons' stretch seen by the encoder per N m of motor torque (y_k = S q_k + C tau_m,k-1)", sd)
            continue
        if field_ == "capstan":
            old = p.raw.get("transmission.capstan")
            upd["transmission.capstan"] = Param(
                value, "-", "identified", reason, old.description if old is not None else
                "mu theta of the flexion tendons' sheath friction (the joints get "
                "tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c))", sd)
            continue
        if field_ in ("sigma0", "sigma1"):  # with the law they belong to
            unit, what = ("N m/rad", "stiffness") if field_ == "sigma0" else ("N m s/rad", "damping")
            old = p.raw.get(f"friction.{field_}")
            upd[f"friction.{field_}"] = Param(value, unit, "identified", reason, old.description if old is not None
                                              else f"the LuGre law's bristle {what}, every joint's", sd)
            upd["friction.law"] = Param("lugre", "-", "identified", reason, "the joints' friction law")
            continue
        if field_ in ("creep_kappa", "creep_rate"):  # with the law they belong to
            unit, what = ("-", "band inertia (in units of each joint's own)") if field_ == "creep_kappa" else \
                ("1/s", "band rate")
            old = p.raw.get(f"friction.{field_}")
            upd[f"friction.{field_}"] = Param(value, unit, "identified", reason, old.description if old is not None
                                              else f"the creep law's {what}, every joint's", sd)
            upd["friction.law"] = Param("creep", "-", "identified", reason, "the joints' friction law")
            continue
        if field_ == "J_m":
            old = p.raw.get("transmission.J_m")
            upd["transmission.J_m"] = Param(value, "kg m^2", "identified", reason,
                                            old.description if old is not None else "rotor inertia J_m (eq. 2.8)", sd)
            continue
        old = p.raw.get(f"thumb.{field_}")
        desc = old.description if old is not None else f"ab/adduction joint's {field_.removeprefix('abduction_')}"
        upd[f"thumb.{field_}"] = Param(value, _UNITS[field_], "identified", reason, desc, sd)
    return upd


def _rig_params(result: IdentificationResult, p: HandParams, sec: str, reason: str) -> dict[str, Param]:
    """The rig's side of a fit as ``identified`` :class:`Param`: the encoders' zeros (``<sec>.encoder_offset``, the
    thumb's ab/adduction motor's ``thumb.abduction_encoder_offset``), the gravity turned by a finger's fitted tilt
    (``environment.gravity``), the torque delay (``transmission.torque_delay``); each only where fitted and
    identified: a zero or an angle whose 95 % interval reaches past 0 (:data:`~.bounds.Z_INTERVAL` standard errors,
    none where the recording does not see it) is not written (the rig's, never held by the fit: the data cannot tell
    it from none, and a wrong zero costs the observer more than none)."""
    fitted = {n: (float(v), float(sd)) for n, v, sd in zip(result.names, result.values, result.std)
              if n not in result.not_identified and (not n.startswith(("encoder_offset_", "tilt_"))
                                                     or abs(v) > Z_INTERVAL * sd)}
    upd: dict[str, Param] = {}
    for motor in result.model.transmission.motor_names:
        if f"encoder_offset_{motor}" not in fitted:
            continue
        value, sd = fitted[f"encoder_offset_{motor}"]
        name = "thumb.abduction_encoder_offset" if motor.endswith("_abduction") else f"{sec}.encoder_offset"
        upd[name] = Param(value, "rad", "identified", reason,
                          f"the zero of the {motor} motor's encoder, rad of the motor: y = S q + offset", _sd(sd))
    angles = [n for n in ("tilt_x", "tilt_y") if n in fitted]
    if angles and sec != "thumb":  # (the thumb's angles are in its own base frame, yawed from the palm's)
        g0 = (result.model.params or p).gravity  # the file's gravity the fit's model was built from
        g, std = _turned_gravity(g0, {n: fitted[n] for n in angles},
                                 np.asarray(result.correlation, dtype=float)[np.ix_(
                                     *[[result.names.index(n) for n in angles]] * 2)])
        words = ", ".join(f"{n} = {fitted[n][0]:.6g} rad" for n in angles)
        upd["environment.gravity"] = Param(g, "m/s^2", "identified", f"{reason}; the file's gravity turned by the "
                                           f"palm's tilt fitted, {words}", "gravity in the hand's base frame, as "
                                           "identified (the palm's tilt on the file's orientation)", std)
    if result.torque_delay is not None:
        upd["transmission.torque_delay"] = Param(int(result.torque_delay), "samples", "identified", reason,
                                                 "the recorded motor torque's lag behind the motor's, whole samples")
    if result.model_error is not None:
        upd["friction.model_error"] = Param(float(result.model_error), "F_s", "identified", f"{reason}; calibrated "
                                            "on the record: the EKF's consistency (noise_calibration)",
                                            "the observer's model error: a white torque per sample of this times "
                                            "each joint's F_s")
    law = getattr(result, "observer_law", None)
    if law is not None:
        upd["friction.observer_law"] = Param(str(law), "-", "identified", f"{reason}; chosen by the "
                                             "observer check among the candidate laws (law_choice)",
                                             "the observers' dry-friction law on this file")
    return upd


def _turned_gravity(g0: Any, tilt: dict[str, tuple[float, float]], correlation: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray | None]:
    """(R^T g0 (3,), m/s^2, the gravity ``g0`` turned by the tilt fitted,
    :func:`~alpes_dyn.symbolic.parametric.tilted_gravity`; its standard error (3,), the tilt's covariance carried
    through the rotation's Jacobian (central differences of 1e-7 rad), or None where a tilt has none). ``tilt``:
    ``tilt_x`` and/or ``tilt_y`` -> (value, std), rad; ``correlation``: theirs, in that order."""
    from ...symbolic.parametric import tilted_gravity

    names = list(tilt)

    def turned(delta: dict[str, float]) -> np.ndarray:
        a = {n: tilt.get(n, (0.0, 0.0))[0] + delta.get(n, 0.0) for n in ("tilt_x", "tilt_y")}
        return np.asarray(tilted_gravity(np.asarray(g0, dtype=float), a["tilt_x"], a["tilt_y"]), dtype=float)

    h = 1e-7
    J = np.column_stack([(turned({n: h}) - turned({n: -h})) / (2 * h) for n in names])
    sds = np.asarray([tilt[n][1] for n in names])
    cov = np.outer(sds, sds) * correlation
    std = np.sqrt(np.clip(np.diag(J @ cov @ J.T), 0.0, None)) if np.isfinite(cov).all() else None
    return turned({}), std


def _sd(sd: float) -> float | None:
    """A standard error to write: None where the recording does not see the parameter (inf)."""
    return float(sd) if math.isfinite(sd) else None


def _printable(text: str) -> str:
    """``text`` with control characters replaced by '?' (it goes into a file's header and fields)."""
    return "".join(c if c.isprintable() else "?" for c in str(text))


def _record(result: IdentificationResult) -> dict[str, Any]:
    """The ``[identification.<chain>]`` record of a fit (:data:`~alpes_dyn.model.params.IDENTIFICATION_FIELDS`)."""
    rec: dict[str, Any] = {"model": result.model.name, "recording": _printable(result.recording_path),
                           "converged": bool(result.converged), "stop": _printable(result.reason),
                           "trustworthy": result.trustworthy, "friction": bool(result.model.extras.has_friction)}
    if math.isfinite(result.residual_rms):
        rec["residual_rms"] = float(result.residual_rms)
    a = result.adequacy
    if a is not None:
        rec.update(adequate=bool(a.adequate), verdict=_printable(a.summary()), likely_missing=list(a.likely_missing))
        if math.isfinite(a.floor.total):
            rec["sensor_floor"] = float(a.floor.total)
    if result.standard_errors is not None:
        rec["standard_errors"] = _printable(result.standard_errors.summary(result.names))
    if result.not_identified:
        rec["not_identified"] = [_printable(f"{n}: {why}") for n, why in result.not_identified.items()]
    return rec
