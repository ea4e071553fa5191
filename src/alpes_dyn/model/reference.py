"""The report's closed-form expressions, used by the cross-checks of ``alpes-dyn report``.

These are written from the report's text, independently of Pinocchio and ADAM.
"""

from __future__ import annotations

import numpy as np

__all__ = ["report_jacobian"]


def report_jacobian(L: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Fingertip Jacobian of a planar finger, report Section 2.2, (3, n), m.

    Row x: -sum_{j>=i} L_j sin(q_1 + ... + q_j); row y: 0; row z: sum_{j>=i} L_j cos(q_1 + ... + q_j).

    Parameters
    ----------
    L : numpy.ndarray, shape (n,)
        The phalanges' lengths, m.
    q : numpy.ndarray, shape (n,)
        Joint angles, rad.

    Returns
    -------
    numpy.ndarray, shape (3, n)
        The Jacobian, m/rad.
    """
    L = np.asarray(L, dtype=float)
    th = np.cumsum(np.asarray(q, dtype=float))
    sx = np.cumsum((-L * np.sin(th))[::-1])[::-1]
    cz = np.cumsum((L * np.cos(th))[::-1])[::-1]
    return np.vstack([sx, np.zeros_like(sx), cz])
