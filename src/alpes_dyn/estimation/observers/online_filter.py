"""One filter step per call in compiled C, for a loop at the sample rate: :class:`OnlineFilter`, what
:meth:`KalmanFilter.online <alpes_dyn.estimation.observers.observers.KalmanFilter.online>` returns."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InputError

__all__ = ["OnlineFilter"]


class OnlineFilter:
    """One filter step per call, in compiled C, for a loop at the sample rate (:meth:`KalmanFilter.online`).

    :meth:`step` copies w and y into a preallocated buffer, calls the compiled predict-update step once
    and returns the new estimate z as a view of the filter's buffer (valid until the next step: copy it to
    keep it); :attr:`P` is the covariance. No allocation and no check per step beyond the shapes of w and
    y (numpy's assignment): what a 1 kHz loop from Python can afford. Its time per step:
    ``benchmarks/results/observer_step.json`` (its rows' ``online_us``).

    Parameters
    ----------
    filt : KalmanFilter
        The filter whose compiled predict-update step it calls (built with its C loop:
        :meth:`KalmanFilter.online <alpes_dyn.estimation.observers.observers.KalmanFilter.online>` makes one).
    z : array_like
        The initial estimate (nz,) [q; qd; theta] (rad, rad/s, the parameters' units).
    P : array_like
        Its covariance (nz, nz).
    """

    def __init__(self, filt: Any, z: np.ndarray, P: np.ndarray) -> None:
        self.filter = filt
        self._loop = filt._loop or filt._online_loop  # held: its library and its parameters' buffer
        nz, nw, ny = filt.nz, filt.nw, filt.ny
        self.nz, self.nw, self.ny = nz, nw, ny
        ns = nz + nz * nz
        self._X = np.zeros((1, 2, ns))
        self._X[0, 0, :nz] = z
        self._X[0, 0, nz:] = np.asarray(P, dtype=float).reshape(-1, order="F")
        self._W = np.zeros((1, 1, nw + ny))
        loop = filt._loop or filt._online_loop
        assert loop is not None
        self._fn = loop._fn
        self._pp = loop._pp  # the model's numbers (the loop holds their buffer)
        self._wp = self._W.ctypes.data_as(loop._dp)
        self._xp = self._X.ctypes.data_as(loop._dp)
        self._s, self._next = self._X[0, 0], self._X[0, 1]
        self._w, self._y = self._W[0, 0, :nw], self._W[0, 0, nw:]
        self._zview = self._s[:nz]
        self._zview.flags.writeable = False

    @property
    def z(self) -> np.ndarray:
        """(nz,) the current estimate [q; qd; theta] (a read-only view)."""
        return self._zview

    @property
    def P(self) -> np.ndarray:
        """(nz, nz) its covariance (a copy)."""
        return self._s[self.nz:].reshape(self.nz, self.nz, order="F").copy()

    def step(self, w: Any, y: Any) -> np.ndarray:
        """Predict with the input held over the period, update with the measurement at its end.

        Parameters
        ----------
        w : array_like
            (nw,) the known input.
        y : array_like
            (ny,) the measurement.

        Returns
        -------
        ndarray
            The estimate z (nz,) (a read-only view, valid until the next step).
        """
        try:
            self._w[:] = w
            self._y[:] = y
        except (ValueError, TypeError):
            raise InputError(f"w, y: expected {self.nw} and {self.ny} numbers, got {np.shape(w)} and {np.shape(y)}") \
                from None
        if self._fn(self._wp, self._xp, self._pp, 1, 1, 0, 1, 1) != 0:
            raise InputError(f"{self.filter.kind}: the compiled step failed")
        self._s[:] = self._next
        return self._zview
