"""The held-out recording's check of a fit (:func:`~alpes_dyn.estimation.identification.identification.identify`'s
``validation``), and the pieces it shares with the fit: the torque projected on the excitation's lines, the parts of
a recording whose excitation restarts, the rest a finger starts from."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ...model.robot import Model
from ...model.transmission import torque_before
from ...simulation.sensitivity import SensitivityModel
from ..experiments.recording import Recording, excitation_parts
from .adequacy import Validation, compare
from .runs import split
from .torque_lines import line_basis

__all__ = ["project_torque", "parts", "validate", "rest_guess"]


def project_torque(t: np.ndarray, torque: np.ndarray, frequencies: Sequence[float],
                   starts: Sequence[int] | None = None) -> np.ndarray:
    """The least-squares fit of each torque column (N, m) on 1, sin(2 pi f t), cos(2 pi f t) for f in
    ``frequencies`` (Hz), per part (``starts``, :func:`~alpes_dyn.estimation.identification.torque_lines.line_basis`;
    default one): the excitation without the measurement noise off its lines.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        The sample times, s.
    torque : numpy.ndarray, shape (N, m)
        The recorded torque, N m.
    frequencies : Sequence[float]
        The excitation's lines, Hz.
    starts : Sequence[int] or None, optional
        The parts' first rows (default None: one part).

    Returns
    -------
    numpy.ndarray, shape (N, m)
        The projected torque, N m.
    """
    Q = np.linalg.qr(line_basis(t, frequencies, starts))[0]
    return Q @ (Q.T @ np.asarray(torque, dtype=float))


def parts(bounds: np.ndarray, n: int) -> np.ndarray:
    """The residual's (n rows, one per sample) parts whose excitation restarts (``bounds``:
    :func:`~alpes_dyn.estimation.experiments.recording.excitation_parts`): their first rows, then n.

    Parameters
    ----------
    bounds : numpy.ndarray
        The parts' first samples (:func:`~alpes_dyn.estimation.experiments.recording.excitation_parts`).
    n : int
        The residual's rows.

    Returns
    -------
    numpy.ndarray
        The first rows of the parts that start before n, then n.
    """
    return np.append(bounds[bounds < n], n)


def validate(model: Model, sens: SensitivityModel, theta: np.ndarray, recording: tuple[Recording, str],
              excitation: Sequence[float] | None, prefix_s: float, offset: np.ndarray | None = None,
              compliance: np.ndarray | None = None) -> Validation:
    """:func:`validate_run` of each run of the held-out recording (module runs), each from its own initial state;
    of several, the worst run's fit % and NRMSE per encoder, the RMS residual over all the scored samples.

    Parameters
    ----------
    model : Model
        The fitted model's structure.
    sens : SensitivityModel
        The fit's sensitivity model.
    theta : numpy.ndarray, shape (p,)
        The fitted parameters, in the fit's units.
    recording : tuple[Recording, str]
        The held-out recording and its path (as the report names it).
    excitation : Sequence[float] or None
        The excitation's lines, Hz, the torque is projected on (None: the torque as recorded).
    prefix_s : float
        The first seconds of each run on which its initial state is estimated, s.
    offset : numpy.ndarray, shape (m,), optional
        The fitted encoder offsets, rad (default None: none).
    compliance : numpy.ndarray, shape (m,), optional
        The fitted tendon compliances, rad/(N m) (default None: none).

    Returns
    -------
    Validation
        Fit % and NRMSE per encoder, the RMS residual.
    """
    rec, path = recording
    vals = [validate_run(model, sens, theta, (r, path), excitation, prefix_s, offset, compliance) for r in split(rec)]
    if len(vals) == 1:
        return vals[0]
    n = np.array([v.samples for v in vals])
    rms = float(np.sqrt(np.sum(n * np.array([v.residual_rms for v in vals]) ** 2) / n.sum()))
    return Validation(fit_percent=np.min([v.fit_percent for v in vals], axis=0),
                      nrmse=np.max([v.nrmse for v in vals], axis=0), residual_rms=rms, prefix_s=vals[0].prefix_s,
                      samples=int(n.sum()), recording_path=path)


def validate_run(model: Model, sens: SensitivityModel, theta: np.ndarray, recording: tuple[Recording, str],
                  excitation: Sequence[float] | None, prefix_s: float, offset: np.ndarray | None = None,
                  compliance: np.ndarray | None = None) -> Validation:
    """:func:`~alpes_dyn.estimation.identification.adequacy.compare` of the fitted model on a held-out recording, its
    torque projected on the excitation's lines as in the fit, the initial state estimated on the first
    ``prefix_s`` seconds (one shooting interval); ``offset`` (m,) rad: the fitted encoder offsets, the same
    sensors' (taken off the held-out encoder), and ``compliance`` (m,) rad/(N m): the fitted tendon stretch
    C u, u the held-out torque as the fit takes it (taken off too)."""
    rec, path = recording
    held = rec.n_samples - 1  # one run here (split); a turned one's orientations each on its lines
    U = rec.torque[:-1] if excitation is None else project_torque(rec.t[:-1], rec.torque[:-1], excitation,
                                                                   parts(excitation_parts(rec), held)[:-1])
    G = rec.gravity[:-1] if rec.gravity is not None else np.broadcast_to(model.gravity, (rec.n_samples - 1, 3))
    tr = model.transmission
    step = 2 * np.pi / tr.counts_per_rev
    prefix = max(2, int(round(prefix_s / rec.dt)))  # checked against the length in identify
    enc = rec.encoder if offset is None else rec.encoder - np.asarray(offset) / step
    if compliance is not None and np.any(compliance != 0):
        enc = enc - torque_before(np.concatenate([U, U[-1:]])) * np.asarray(compliance) / step
    q0 = rest_guess(model, U[0], enc[0] * step) if rec.gravity is None else np.zeros(model.n)
    val = compare(sens, theta, np.concatenate([q0, np.zeros(model.n)]), U, G, enc,
                  tr.curve if tr.curved else np.asarray(tr.S, dtype=float), step, prefix, path)
    val.prefix_s = prefix * rec.dt
    return val


def rest_guess(model: Model, u: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """The static equilibrium under the motor torques ``u`` (m,), N m (S^T u, or rho(q)^T u where the ratios change
    with q), the joints without spring (the thumb's ab/adduction, which its own motor holds) held where the first
    encoder reading ``y0`` puts them.

    Parameters
    ----------
    model : Model
        The model.
    u : numpy.ndarray, shape (m,)
        The motor torques, N m.
    y0 : numpy.ndarray, shape (m,)
        The first encoder reading, rad.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The joint angles at rest, rad.
    """
    held = model.springless_joints
    if not held:
        return model.static_equilibrium(None, tau_m=u)
    q = np.zeros(model.n)
    idx = [model.joint_index(j) for j in held]
    q[idx] = (np.linalg.pinv(model.transmission.S) @ y0)[idx]
    return model.static_equilibrium(None, q, fixed=held, tau_m=u)
