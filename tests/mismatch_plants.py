"""Recordings of finger plants that differ from the fitted model's structure (for the adequacy tests and
their threshold measurements): our own simulator, one effect the fitted model lacks at a time."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, _simulate, _schedule, experiment
from alpes_dyn.estimation.experiments.recording import Recording
from alpes_dyn.model.params import HandParams, Param, with_values

KINDS = ("match", "rotor", "tilt", "offset", "tendon", "coulomb")


def _sensors(rec: Recording, qm: np.ndarray, design: ExperimentDesign, seed: int) -> Recording:
    """The experiment's sensors on the motor angle qm (N+1, m) rad: 0.5 count of noise, quantised."""
    rng = np.random.default_rng(seed + 1000)
    step = 2 * math.pi / 4096
    enc = np.round((qm + design.encoder_noise_counts * step * rng.standard_normal(qm.shape)) / step)
    return dataclasses.replace(rec, encoder=enc)


def mismatched(kind: str, true: HandParams, model: str = "finger3", duration: float = 2.0,
               seed: int = 0, dither: float | None = None, amplitude_fraction: float | None = None) -> Recording:
    """A recording of the documented experiment on ``true`` with one effect the model lacks:

    * ``match``: none (the model's own structure);
    * ``rotor``: a rotor inertia 1e-6 kg m^2 (ten times the file's J_m, N^2 J_m on each joint);
    * ``tilt``: the palm tilted 3 degrees in the finger's plane, the recording without gravity columns;
    * ``offset``: the encoder reads 20 counts too many;
    * ``tendon``: an elastic tendon, the encoder ahead of the joints by tau_m / k_t, k_t such that the
      stretch is 3 % of the motor's motion;
    * ``coulomb``: dry friction three times stronger with a sharp sign (v_s 0.02 rad/s, the model 0.1).

    ``dither``, ``amplitude_fraction``: the design's (default: the documented one's).
    """
    design = ExperimentDesign(duration=duration)
    if dither is not None:
        design = dataclasses.replace(design, dither=dither)
    if amplitude_fraction is not None:
        design = dataclasses.replace(design, amplitude_fraction=amplitude_fraction)
    if kind == "match":
        return experiment(model, true, design, seed=seed)
    if kind == "tilt":
        a = math.radians(3.0)
        d = dataclasses.replace(design, orientations=((9.81 * math.sin(a), 0.0, -9.81 * math.cos(a)),))
        return dataclasses.replace(experiment(model, true, d, seed=seed), gravity=None)
    if kind == "offset":
        rec = experiment(model, true, design, seed=seed)
        return dataclasses.replace(rec, encoder=rec.encoder + 20.0)
    clean = experiment(model, true, dataclasses.replace(design, torque_noise=0.0, encoder_noise_counts=0.0), seed=seed)
    u = clean.torque
    noisy_u = u + design.torque_noise * np.random.default_rng(seed).standard_normal(u.shape)
    rec = dataclasses.replace(clean, torque=noisy_u)
    t, seg, G = _schedule(design)
    if kind == "tendon":
        tr = ad.Model.alpes(model, friction=True, params=true).transmission
        qm = clean.true_q @ tr.S.T
        stretch = 0.03 * np.std(qm, axis=0) / np.std(u, axis=0) * (u - u.mean(axis=0))
        return _sensors(rec, qm + stretch, design, seed)
    if kind == "rotor":
        plant = ad.Model.alpes(model, friction=True, rotor_inertia=True,
                               params=with_values(true, {"transmission.J_m": dataclasses.replace(
                                   true.raw["transmission.J_m"], value=1e-6)}))
    elif kind == "coulomb":
        Fs = true.chain("finger").F_s * 3.0
        upd = {"finger.F_s": dataclasses.replace(true.raw["finger.F_s"], value=Fs),
               "friction.smooth_velocity": dataclasses.replace(true.raw["friction.smooth_velocity"], value=0.02)}
        plant = ad.Model.alpes(model, friction=True, params=with_values(true, upd))
        design = dataclasses.replace(design, substeps=8)
    else:
        raise ValueError(kind)
    x = _simulate(plant, design, u, G, seg)
    qm = x[:, : plant.n] @ plant.transmission.S.T
    return _sensors(dataclasses.replace(rec, true_q=x[:, : plant.n].copy()), qm, design, seed)
