"""A tendon's cable as a spring on the motor shaft: its stiffness, damping and play, per motor (issue 16).

The cable of motor k, wound on a shaft of radius r_m, stretches by e = r_m theta_m - sum_i r_i q_i (m); on the motor
shaft that is phi = theta_m - S_k q (rad), and the cable pulls the rotor back with

    T_m = k_m max(phi - delta, 0) + c_m dphi/dt      (N m; pull only beyond the play delta)

with k_m = k_t r_m^2 (N m/rad) for a cable of stiffness k_t (N/m, EA/L), c_m = c_t r_m^2 and delta the play. Its
quasi-static limit is the compliance C = 1 / k_m that :class:`~alpes_dyn.Transmission` holds
(``tendon_compliance``) and identification fits; :class:`ElasticTendon.of` reads it back from a model. Used by the
series-elastic system with the rotor as a state (:mod:`alpes_dyn.symbolic.elastic_tendon`) and by the MJCF exports
(:func:`~alpes_dyn.model.mjcf_export.model_mjcf`'s ``tendon=``, :func:`~alpes_dyn.model.mjcf.mjcf_string`'s
``tendon_stiffness=``), so that both are the same system.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..checks import as_float_array
from ..errors import InputError

__all__ = ["ElasticTendon"]


def _per_motor(x: Any, m: int, name: str, unit: str, positive: bool) -> np.ndarray:
    """``x`` as (m,) finite floats, each > 0 (``positive``) or >= 0; one number is every motor's."""
    if isinstance(x, (bool, np.bool_)):
        raise InputError(f"{name}: expected a number of {unit}, got {x!r}")
    a = as_float_array(x, name, f"numbers of {unit}")
    a = np.full(m, float(a)) if a.ndim == 0 else a
    if a.shape != (m,) or not np.isfinite(a).all() or not (np.all(a > 0) if positive else np.all(a >= 0)):
        raise InputError(f"{name}: expected {m} finite {'positive' if positive else 'non-negative'} numbers of "
                         f"{unit} (one per motor), got {np.atleast_1d(a).tolist()!r}")
    return a


@dataclass(frozen=True)
class ElasticTendon:
    """Each motor's cable, seen on the motor shaft (arrays (m,), one per motor of the model).

    Attributes
    ----------
    stiffness: k_m, N m/rad of motor shaft (> 0): ``k_t r_m^2`` for a cable of stiffness k_t (N/m) on a shaft of
        radius r_m (:meth:`from_cable`).
    damping: c_m, N m s/rad (>= 0).
    dead_band: delta, rad of motor shaft (>= 0): the stretch below which the cable is slack (0: taut at zero
        stretch, MuJoCo's ``springlength="-1 0"``).
    """

    stiffness: np.ndarray
    damping: np.ndarray
    dead_band: np.ndarray

    @classmethod
    def from_cable(cls, n_motors: int, cable_stiffness: Any, shaft_radius: float, cable_damping: Any = 0.0,
                   dead_band: Any = 0.0) -> "ElasticTendon":
        """The tendon of a cable of stiffness k_t (N/m, EA/L) and damping c_t (N s/m) wound on a motor shaft of
        radius r_m (m), with a dead band of ``dead_band`` m of cable: k_m = k_t r_m^2, c_m = c_t r_m^2,
        delta = dead_band / r_m. The same numbers as :func:`~alpes_dyn.model.mjcf.mjcf_string`'s
        ``tendon_stiffness`` and ``tendon_damping``.

        Parameters
        ----------
        n_motors : int
            m, the number of motors (>= 1).
        cable_stiffness : float or array_like of shape (m,)
            k_t, N/m (EA/L, > 0), one per motor or one for all.
        shaft_radius : float
            r_m, m (> 0).
        cable_damping : float or array_like of shape (m,), optional
            c_t, N s/m (>= 0; default 0).
        dead_band : float or array_like of shape (m,), optional
            The cable's play, m of cable (>= 0; default 0).

        Returns
        -------
        ElasticTendon
            The tendon on the motor shaft.

        Raises
        ------
        InputError
            A value not of its form, named.
        """
        if not isinstance(n_motors, (int, np.integer)) or isinstance(n_motors, bool) or n_motors < 1:
            raise InputError(f"n_motors: expected a positive integer, got {n_motors!r}")
        r = _per_motor(shaft_radius, 1, "shaft_radius", "m", True)[0]
        k_t = _per_motor(cable_stiffness, n_motors, "cable_stiffness", "N/m", True)
        c_t = _per_motor(cable_damping, n_motors, "cable_damping", "N s/m", False)
        band = _per_motor(dead_band, n_motors, "dead_band", "m", False)
        return cls(k_t * r**2, c_t * r**2, band / r)

    @classmethod
    def of(cls, model: Any, damping: Any = 0.0, dead_band: Any = 0.0) -> "ElasticTendon":
        """The cable of each of ``model``'s motors from its quasi-static compliance, written once in the spec
        (``[[motor]]``'s ``tendon_compliance``) or the parameter file (``transmission.tendon_compliance``), as
        ``alpes-dyn identify`` fits and writes it: k_m = 1 / C (each C > 0). ``damping`` c_m (N m s/rad) and
        ``dead_band`` delta (rad of motor shaft), per motor or one for all, are the rotor's dynamics that the
        quasi-static limit does not see (default 0).

        Parameters
        ----------
        model : alpes_dyn.Model
            A model with motors, each with a tendon compliance C > 0 (rad/(N m)).
        damping : float or array_like of shape (m,), optional
            c_m, N m s/rad, per motor or one for all (default 0).
        dead_band : float or array_like of shape (m,), optional
            delta, rad of motor shaft, per motor or one for all (default 0).

        Returns
        -------
        ElasticTendon
            The tendon.

        Raises
        ------
        InputError
            A model without motors, a rigid tendon (C = 0), or a bad value, named.
        """
        tr = getattr(model, "transmission", None)
        if tr is None:
            raise InputError("model: expected an alpes_dyn Model with motors")
        C = np.asarray(tr.tendon_compliance, dtype=float)
        if not np.all(C > 0):
            bad = tr.motor_names[int(np.flatnonzero(~(C > 0))[0])]
            raise InputError(f"tendon_compliance: motor {bad!r} has a rigid tendon (C = 0); the series-elastic "
                             "tendon needs each motor's compliance C > 0 (rad/(N m): the spec's tendon_compliance, "
                             "or an identified file's)")
        m = tr.n_motors
        return cls(1.0 / C, _per_motor(damping, m, "damping", "N m s/rad", False),
                   _per_motor(dead_band, m, "dead_band", "rad", False))

    def __post_init__(self) -> None:
        k = as_float_array(self.stiffness, "stiffness", "numbers of N m/rad")
        m = 1 if k.ndim == 0 else k.shape[0]
        object.__setattr__(self, "stiffness", _per_motor(k, m, "stiffness", "N m/rad", True))
        object.__setattr__(self, "damping", _per_motor(self.damping, m, "damping", "N m s/rad", False))
        object.__setattr__(self, "dead_band", _per_motor(self.dead_band, m, "dead_band", "rad", False))

    @property
    def n_motors(self) -> int:
        return int(self.stiffness.shape[0])

    @property
    def compliance(self) -> np.ndarray:
        """(m,) C = 1 / k_m, rad/(N m): the quasi-static stretch per motor torque
        (:attr:`~alpes_dyn.Transmission.tendon_compliance`)."""
        return 1.0 / self.stiffness

    def tension(self, stretch: Any, rate: Any, xp: Any = np) -> Any:
        """T_m = k_m max(phi - delta, 0) + c_m dphi/dt (m,), N m on the motor shaft, for the stretch phi and its
        rate.

        Parameters
        ----------
        stretch : numpy.ndarray or casadi.SX, shape (m,)
            phi, the cable's stretch, rad of motor shaft.
        rate : numpy.ndarray or casadi.SX, shape (m,)
            dphi/dt, rad/s.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        k, c, band = self.stiffness, self.damping, self.dead_band
        if xp is not np:  # CasADi: constant columns
            k, c, band = xp.DM(k), xp.DM(c), xp.DM(band)
        return k * xp.fmax(stretch - band, 0) + c * rate
