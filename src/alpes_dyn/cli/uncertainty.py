"""What ``alpes-dyn estimate`` says of its own uncertainty: each joint's sigma, its observability by the encoders
along the motion, the NEES where the recording has true joints, the NIS of a recording's innovations (the table's
lines and the JSON's keys)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def _uncertainty(est, filt, inputs: np.ndarray, true_q: np.ndarray | None, start: float, joints: tuple[str, ...],
                 limit_deg: float, whole: bool = True, measurement: np.ndarray | None = None,
                 spread=None, band=None) -> tuple[dict, list[str]]:
    """What ``estimate`` says of its own uncertainty: each joint's reported sigma along the run after ``start`` s
    (median and worst), each joint's observability by the encoders along the estimated motion
    (:func:`~alpes_dyn.analysis.joint_observability.joint_observability`: flagged above ``limit_deg``), the sigma it
    reports per joint (:func:`reported_sigma`: the data's bound where a joint is flagged), and with
    true joints the NEES and its band (:func:`~alpes_dyn.estimation.observers.consistency.nees`; the band from the
    filter's own error model when one filter ran the whole record, ``whole``); given the ``measurement`` the filter
    read (N, m) and one filter over the whole record, the NIS of its innovations and its band, which needs no true
    joints (:func:`~alpes_dyn.estimation.observers.innovation.nis`). Given the ``spread`` between the friction laws
    (a :class:`~alpes_dyn.estimation.observers.law_sigma.LawSigma`, ``estimate --law-spread``), the sigma and the
    NEES are the estimate's with it added to each joint's variance (the NEES's samples then taken as independent:
    the filter's error model is its own P's), the NIS the filter's own; the same with the ``band`` of the dry
    friction (a :class:`~alpes_dyn.estimation.observers.band_sigma.BandSigma`, ``estimate --data``'s default; both
    added where both are given). Returns (the JSON's keys, the table's lines)."""
    from ..analysis.joint_observability import joint_observability
    from ..estimation.observers.consistency import joint_sigma, nees

    n, deg = len(joints), np.degrees
    own = est
    whole_nees = whole and spread is None and band is None
    for term in (spread, band):
        est = est if term is None else term.widened(est)
    med, worst = joint_sigma(est, n, start)
    obs = joint_observability(filt.model.system.model, est.z, inputs, filt.dt, filt.R, limit=np.radians(limit_deg))
    flags = obs.unobserved
    sigma = reported_sigma(worst, obs)
    obj: dict = {"q_std_median_deg": deg(med).tolist(), "q_std_worst_deg": deg(worst).tolist(),
                 "q_sigma_deg": deg(sigma).tolist(),
                 "observability": obs.to_dict(), "unobserved": list(flags), "nees": None, "nis": None,
                 "law_spread": None, "band_sigma": None}
    lines = [f"  {'sigma median/worst [deg]:':30s}"
             + "  ".join(f"{j} {deg(a):.3f}/{deg(b):.3f}" for j, a, b in zip(joints, med, worst)),
             f"  {'sigma reported [deg]:':30s}"
             + "  ".join(f"{j} {deg(s):.3g}{NOT_OBSERVED_NOTE if j in flags else ''}" for j, s in zip(joints, sigma)),
             f"  {f'observed within [deg]:':30s}"
             + "  ".join(f"{j} {deg(b):.3f}{' NOT OBSERVED' if j in flags else ''}" for j, b in zip(joints, obs.best))
             + f" (best {obs.window:g} s window)"]
    if spread is not None:
        obj["law_spread"] = spread.to_dict(int(round(start / (est.t[1] - est.t[0]))) if est.t.size > 1 else 0)
        lines.append(f"  {'friction laws spread [deg]:':30s}"
                     + "  ".join(f"{j} {s:.3f}" for j, s in zip(joints, obj["law_spread"]["spread_rms_deg"]))
                     + f" (RMS; the {spread.kept} law against {', '.join(spread.others)}: in the sigma)")
    if band is not None:
        obj["band_sigma"] = band.to_dict(int(round(start / (est.t[1] - est.t[0]))) if est.t.size > 1 else 0)
        lines.append(f"  {'friction band sigma [deg]:':30s}"
                     + "  ".join(f"{j} {s:.3f}" for j, s in zip(joints, obj["band_sigma"]["band_rms_deg"]))
                     + f" (RMS; a friction torque of {band.fraction:g} F_s held at rest: in the sigma)")
    if true_q is not None:
        r = nees(est, true_q, filt if whole_nees else None, inputs if whole_nees else None, start=start)
        obj["nees"] = r.to_dict()
        lines.append(f"  {'NEES of the joints:':30s}{r.value:.3g} (95 % band {r.low:.3g}-{r.high:.3g} for {r.dof} "
                     f"joints, {r.effective:.3g} independent samples; the series itself shows {r.measured:.3g}): "
                     f"{r.verdict}")
    if measurement is not None and whole:
        from ..estimation.observers.innovation import nis

        v = nis(own, measurement, filt, inputs, start=start)
        obj["nis"] = v.to_dict()
        lines.append(f"  {'NIS of the encoders:':30s}{v.value:.3g} (95 % band {v.low:.3g}-{v.high:.3g}, "
                     f"{v.effective:.4g} independent samples): {v.verdict}")
    if flags:
        lines.append(f"  WARNING: {', '.join(flags)} not observed by this motion: the encoders pin "
                     f"{'it' if len(flags) == 1 else 'them'} no closer than "
                     f"{deg(min(obs.best[joints.index(j)] for j in flags)):.3g} degrees (limit {limit_deg:g}, "
                     f"--sigma-limit): the estimate there is the model's guess, not a measurement")
    return obj, lines


NOT_OBSERVED_NOTE = " (not observed: the data's bound)"


def reported_sigma(worst: np.ndarray, obs) -> np.ndarray:
    """(n,) rad: each joint's sigma as ``estimate`` reports it: the filter's worst sqrt(P_ii) (``worst``), raised for
    a joint the motion does not observe to the smallest error standard deviation any window of the recording allows
    it (``obs``, a :class:`~alpes_dyn.analysis.joint_observability.JointObservability`: its ``best``). The filter's
    own P there is its model's guess, not the data's: a springless pair seen through its sum and held by dry
    friction keeps the split the smooth law's damping pins in the model but not in the plant (Menagerie's Shadow
    finger on MuJoCo: the filter's 0.26 degree against a 1.6-degree error; the bound 3.4 degrees)."""
    flagged = np.array([j in obs.unobserved for j in obs.joints])
    return np.where(flagged, np.maximum(worst, obs.best), worst)


def _sigma_limit(value: float | None) -> float:
    """``--sigma-limit`` in degrees (default 1), checked: a finite number in (0, 180]."""
    from ..analysis.joint_observability import UNOBSERVED_LIMIT

    if value is None:
        return float(np.degrees(UNOBSERVED_LIMIT))
    if not (np.isfinite(value) and 0 < value <= 180):
        raise InputError(f"--sigma-limit: expected degrees in (0, 180], got {value!r}")
    return float(value)
