"""The hand's sensors as blocks of :func:`alpes_dyn.simulation.loop.run_loop`: each reads one signal and writes
its reading, with its own Gaussian noise drawn from its own random stream.

* :class:`Encoder`: a motor angle (rad) plus ``noise_counts`` counts of noise, quantised to 2 pi / counts_per_rev
  (the reading in rad, or in counts with an offset of the encoder's zero);
* :class:`TorqueSensor`: a motor torque (N m) from its current, times ``gain`` (1 + a torque constant's error),
  plus ``noise`` N m of white noise;
* :class:`ForceSensor`: a FlexiForce: the contact force (N) plus ``noise`` N, quantised to ``resolution`` N, >= 0.

Noise: a sensor draws its whole record of standard normal numbers from ``rng`` (a ``numpy.random.Generator``)
when the loop starts (``draws`` rows, default one per reading), scaled by its standard deviation, so that its
readings do not depend on when the loop steps it. Give each sensor its own stream (``rng=np.random.default_rng(
[seed, i])``) and a new sensor changes no other sensor's noise; sensors sharing one generator draw in the order of
the composition's list (what the library's scenarios do, so that a seed gives the runs it gave before).

A sensor reads at the samples (``timing="sample"``: the signal at t_k, the reading at t_k) or over the periods
(``timing="period"``: the signal over [t_k, t_k+1) -- a torque held or applied over it -- the reading a period
signal).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from .loop import Block

__all__ = ["Sensor", "Encoder", "TorqueSensor", "ForceSensor", "TIMINGS"]

TIMINGS: tuple[str, ...] = ("sample", "period")


def _nonnegative(x: Any, name: str, unit: str) -> float:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)) \
            or not math.isfinite(x) or x < 0:
        raise InputError(f"{name}: expected a non-negative number of {unit}, got {x!r}")
    return float(x)


def _positive(x: Any, name: str, unit: str) -> float:
    if _nonnegative(x, name, unit) <= 0:
        raise InputError(f"{name}: expected a positive number of {unit}, got {x!r}")
    return float(x)


class Sensor(Block):
    """A sensor reading ``signal`` into ``reading`` (see the module docstring).

    Parameters
    ----------
    signal : str
        The name of the signal read.
    reading : str
        The name of the reading written.
    std : float, optional
        The noise's standard deviation, in the signal's units (default 0: no noise; still drawn when ``rng`` is
        given).
    rng : numpy.random.Generator or None, optional
        The noise's generator (default None: no noise drawn).
    shape : tuple of int, optional
        One reading's shape (default (): a scalar).
    draws : int or None, optional
        Rows of noise drawn at the start (default None: one per reading); more rows than readings are drawn and
        left unused (a scenario's old draw kept).
    timing : str, optional
        ``"sample"`` (default) or ``"period"`` (:data:`TIMINGS`).
    name : str or None, optional
        The block's name (default None: ``reading``).

    Raises
    ------
    InputError
        A bad name, timing, generator, draw count, noise or shape, named.
    """

    has_response = True

    def __init__(self, signal: str, reading: str, *, std: float = 0.0, rng: np.random.Generator | None = None,
                 shape: tuple[int, ...] = (), draws: int | None = None, timing: str = "sample",
                 name: str | None = None) -> None:
        if not isinstance(signal, str) or not isinstance(reading, str) or not signal or not reading:
            raise InputError(f"signal, reading: expected signal names, got {signal!r} and {reading!r}")
        if timing not in TIMINGS:
            raise InputError(f"timing: expected one of {', '.join(TIMINGS)}, got {timing!r}")
        if rng is not None and not isinstance(rng, np.random.Generator):
            raise InputError(f"rng: expected a numpy.random.Generator or None, got {type(rng).__name__}")
        if draws is not None and (isinstance(draws, bool) or not isinstance(draws, (int, np.integer)) or draws < 0):
            raise InputError(f"draws: expected an integer >= 0 or None, got {draws!r}")
        self.std = _nonnegative(std, "std", "the signal's units")
        try:
            shape = tuple(int(d) for d in shape)
        except (TypeError, ValueError):
            raise InputError(f"shape: expected a tuple of sizes, got {shape!r}") from None
        if any(d < 0 for d in shape):
            raise InputError(f"shape: expected sizes >= 0, got {shape!r}")
        self.rng, self.shape, self.draws, self.timing = rng, tuple(shape), draws, timing
        self.name = name or reading
        self.signal, self.reading = signal, reading
        if timing == "sample":
            self.inputs, self.outputs = (signal,), (reading,)
            self.output = self._read  # type: ignore[method-assign]
        else:
            self.update_inputs, self.period_outputs = (signal,), (reading,)
            self.update = self._read  # type: ignore[method-assign]

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        rows = n_periods + int(final) if self.timing == "sample" else n_periods
        self._rows = rows
        draws = rows if self.draws is None else int(self.draws)
        if self.rng is None:
            self.noise = np.zeros((max(draws, rows), *self.shape))
        else:
            self.noise = self.std * self.rng.standard_normal((draws, *self.shape))
        if self.noise.shape[0] < rows:
            raise InputError(f"draws: {self.name!r} reads {rows} times but draws {self.noise.shape[0]} noise rows")
        # a scalar sensor reads Python floats at each sample (the same numbers, faster than numpy scalars)
        self._row = self.noise.tolist() if self.shape == () else self.noise

    def measure(self, x: Any, noise: Any) -> Any:
        """The reading of the true value ``x`` with the noise ``noise`` (whole records too).

        Parameters
        ----------
        x : float or numpy.ndarray
            The true value(s), in the signal's units: one reading, or a record (one row per reading).
        noise : float or numpy.ndarray
            The noise drawn for them, same shape, in the signal's units.

        Returns
        -------
        float or numpy.ndarray
            The reading(s).
        """
        raise NotImplementedError

    def _shape_error(self, got: tuple[int, ...]) -> InputError:
        return InputError(f"shape: sensor {self.name!r} reads {self.signal!r} of shape {got}, not its shape "
                          f"{self.shape}")

    def _read(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        """The reading at sample k (``output``) or over period k (``update``), per the sensor's timing."""
        x = u[self.signal]
        if k == 0 and np.shape(x) != self.shape:
            raise self._shape_error(np.shape(x))
        return {self.reading: self.measure(x, self._row[k])}

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        x = np.asarray(u[self.signal])[: self._rows]
        if x.shape[1:] != self.shape:
            raise self._shape_error(x.shape[1:])
        return {self.reading: self.measure(x, self.noise[: self._rows])}


class Encoder(Sensor):
    """A motor encoder: ``signal`` (rad of motor shaft) + ``noise_counts`` counts of Gaussian noise, quantised to
    ``step`` = 2 pi / counts_per_rev: round((q + n) / step) step (rad), or ``counts=True`` round((q + n) / step +
    offset) (counts, the zero ``offset`` counts off).

    Parameters
    ----------
    signal : str
        The name of the signal read (rad of motor shaft).
    reading : str
        The name of the reading written (rad, or counts with ``counts``).
    counts_per_rev : float
        The encoder's counts per motor revolution (> 0).
    noise_counts : float, optional
        The Gaussian noise's standard deviation, counts (default 0).
    counts : bool, optional
        Read in counts (default False: in rad).
    offset : float, optional
        The zero's offset, counts (default 0).
    **kw
        :class:`Sensor`'s other arguments (``rng``, ``shape``, ``draws``, ``timing``, ``name``).
    """

    def __init__(self, signal: str, reading: str, counts_per_rev: float, *, noise_counts: float = 0.0,
                 counts: bool = False, offset: float = 0.0, **kw: Any) -> None:
        cpr = _positive(counts_per_rev, "counts_per_rev", "counts")
        self.step = 2.0 * np.pi / cpr
        self.noise_counts = _nonnegative(noise_counts, "noise_counts", "counts")
        if not isinstance(offset, (int, float, np.integer, np.floating)) or isinstance(offset, bool) \
                or not math.isfinite(offset):
            raise InputError(f"offset: expected a finite number of counts, got {offset!r}")
        self.counts, self.offset = bool(counts), float(offset)
        super().__init__(signal, reading, std=self.noise_counts * self.step, **kw)

    def measure(self, x: Any, noise: Any) -> Any:
        v = (x + noise) / self.step
        if self.offset != 0.0:
            v = v + self.offset
        if isinstance(v, float):  # one motor (np.float64 too): Python's round, the same half-to-even as numpy's
            r = round(float(v))
            return float(r) if self.counts else r * self.step
        return np.round(v) if self.counts else np.round(v) * self.step


class TorqueSensor(Sensor):
    """A motor torque from its current: ``gain`` x ``signal`` (N m) + ``noise`` N m of white noise (``gain`` = 1
    + the torque constant's error).

    Parameters
    ----------
    signal : str
        The name of the signal read.
    reading : str
        The name of the reading written.
    noise : float, optional
        The white noise's standard deviation, N m (default 0).
    gain : float, optional
        The gain (> 0; default 1).
    **kw
        :class:`Sensor`'s other arguments (``rng``, ``shape``, ``draws``, ``timing``, ``name``).
    """

    def __init__(self, signal: str, reading: str, *, noise: float = 0.0, gain: float = 1.0, **kw: Any) -> None:
        if isinstance(gain, bool) or not isinstance(gain, (int, float, np.integer, np.floating)) \
                or not (math.isfinite(gain) and gain > 0):
            raise InputError(f"gain: expected a positive finite number, got {gain!r}")
        self.gain = float(gain)
        super().__init__(signal, reading, std=noise, **kw)

    def measure(self, x: Any, noise: Any) -> Any:
        return (self.gain * x if self.gain != 1.0 else x) + noise


class ForceSensor(Sensor):
    """A FlexiForce: max(0, round((F + n) / resolution) resolution), N (a scalar force: the sensor reads >= 0).

    Parameters
    ----------
    signal : str
        The name of the signal read.
    reading : str
        The name of the reading written.
    noise : float, optional
        The noise's standard deviation, N (default 0).
    resolution : float, optional
        The quantisation step, N (> 0; default 4.4 / 1024).
    **kw
        :class:`Sensor`'s other arguments (``rng``, ``shape``, ``draws``, ``timing``, ``name``).
    """

    def __init__(self, signal: str, reading: str, *, noise: float = 0.0, resolution: float = 4.4 / 1024,
                 **kw: Any) -> None:
        self.resolution = _positive(resolution, "resolution", "N")
        super().__init__(signal, reading, std=noise, **kw)

    def measure(self, x: Any, noise: Any) -> Any:
        r = self.resolution
        if isinstance(x, (float, np.floating)) or np.ndim(x) == 0:
            return max(0.0, round(float((float(x) + noise) / r)) * r)
        return np.maximum(0.0, np.round((x + noise) / r) * r)
