"""The identification experiment's settings (:class:`ExperimentDesign`):
what :mod:`alpes_dyn.estimation.experiments.experiment` designs, trims and simulates, each field checked with one line
naming it."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ...checks import as_float_array
from ...errors import InputError
from ...limits import check_duration, check_not_subnormal
from .recording import GRAVITY, GRAVITY_TOLERANCE, gravity_norm_off

__all__ = ["ExperimentDesign"]


@dataclass(frozen=True)
class ExperimentDesign:
    """Settings of the identification experiment (see the module docstring); SI units."""

    duration: float = 4.0
    dt: float = 1e-3
    substeps: int = 4
    frequencies: tuple[float, ...] = (0.3, 0.7, 1.3, 2.1, 3.7, 5.3, 7.9, 11.3)
    torque_bias: float | None = None
    torque_amplitude: float | None = None
    margin: float = 0.05
    orientations: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, -9.81),)
    camera_times: tuple[float, ...] = ()
    camera_noise: float = math.radians(0.1)
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    trim_bias: bool = True
    amplitude_fraction: float = 0.5
    dither: float = 20.0
    dither_frequency: float = 20.0
    stick_seconds: float = 0.0
    stick_swing: float = 8.0

    @property
    def lines(self) -> tuple[float, ...]:
        """The excitation's lines, Hz: the multisine's ``frequencies`` and, with a dither, its frequency (what
        :func:`~alpes_dyn.estimation.identification.identification.identify`'s ``excitation`` takes for this
        experiment)."""
        return tuple(float(f) for f in self.frequencies) + ((float(self.dither_frequency),) if self.dither > 0 else ())

    @property
    def n_samples(self) -> int:
        """The excitation's samples, N + 1 (the stiction ramp's, :attr:`stick_samples`, come after them)."""
        return int(round(self.duration / self.dt)) + 1

    @property
    def stick_samples(self) -> int:
        """The samples of the slow stiction ramp recorded after the excitation (0 without it: ``stick_seconds``
        0), held out of the fit and judged on by the observer check
        (:func:`~alpes_dyn.estimation.experiments.stick_ramp.stick_ramp`)."""
        return int(round(self.stick_seconds / self.dt)) if self.stick_seconds > 0 else 0

    def check(self) -> "ExperimentDesign":
        """This design, every field checked (InputError naming the first bad one): real numbers only (a bool,
        a string or a complex number is refused, not read as 1 s or its real part), in their ranges."""
        for name in ("duration", "dt", "margin", "camera_noise", "encoder_noise_counts", "torque_noise",
                     "amplitude_fraction", "dither", "dither_frequency", "torque_bias", "torque_amplitude",
                     "stick_seconds", "stick_swing"):
            v = getattr(self, name)
            if v is None and name in ("torque_bias", "torque_amplitude"):
                continue
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise InputError(f"{name}: expected a real number, got {type(v).__name__} {v!r:.40}")
            try:
                check_not_subnormal(float(v), name)  # 1e-320: below the smallest normal float
            except OverflowError:
                raise InputError(f"{name}: expected a real number, got an integer too large for a float") from None
        for name in ("frequencies", "orientations", "camera_times"):
            as_float_array(getattr(self, name), name, "real numbers")
        if not isinstance(self.trim_bias, (bool, np.bool_)):
            raise InputError(f"trim_bias: expected True or False, got {self.trim_bias!r:.40}")
        check_duration(self.duration, "duration")
        if not (math.isfinite(self.dt) and 0 < self.dt <= 0.1):
            raise InputError(f"dt: expected a sample period in (0, 0.1] s, got {self.dt!r}")
        N = round(self.duration / self.dt) if math.isfinite(self.duration) else -1
        if N < 100 or abs(N * self.dt - self.duration) > 1e-9 * self.duration:
            raise InputError(f"duration: expected a whole number of at least 100 samples of {self.dt:g} s, "
                             f"got {self.duration!r}")
        if N > 2_000_000:
            raise InputError(f"duration: {self.duration:g} s is more than 2e6 samples")
        if isinstance(self.substeps, bool) or not isinstance(self.substeps, int) or not 1 <= self.substeps <= 64:
            raise InputError(f"substeps: expected an integer in [1, 64], got {self.substeps!r}")
        f = np.asarray(self.frequencies, dtype=float)
        if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(f >= 0.5 / self.dt):
            raise InputError(f"frequencies: expected positive frequencies below Nyquist, got {self.frequencies!r}")
        g = np.asarray(self.orientations, dtype=float)
        if g.ndim != 2 or g.shape[1] != 3 or g.shape[0] < 1 or not np.isfinite(g).all():
            raise InputError(f"orientations: expected gravity vectors (3 numbers each), got {self.orientations!r}")
        if (N + 1) // g.shape[0] < 100:  # each orientation's run identified on its own lines (torque_lines)
            raise InputError(f"duration: {self.duration:g} s gives {(N + 1) // g.shape[0]} samples to each of the "
                             f"{g.shape[0]} orientations; each needs at least 100")
        off = gravity_norm_off(g)
        if off.size:
            raise InputError(f"orientations: gravity vector {g[off[0]].tolist()} has norm {np.linalg.norm(g[off[0]]):g} "
                             f"m/s^2; expected {GRAVITY:g} m/s^2 within {100 * GRAVITY_TOLERANCE:g} % (a recording's gravity "
                             "columns are checked so)")
        if not (isinstance(self.dither, (int, float)) and math.isfinite(self.dither) and 0 <= self.dither <= 100):
            raise InputError(f"dither: expected a number in [0, 100] (times each joint's breakaway torque), got "
                             f"{self.dither!r}")
        fd = self.dither_frequency
        if self.dither > 0 and not (isinstance(fd, (int, float)) and math.isfinite(fd) and 0 < fd < 0.5 / self.dt
                                    and not np.any(np.isclose(f, fd))):
            raise InputError(f"dither_frequency: expected a frequency below Nyquist and off the multisine's lines, "
                             f"got {fd!r} Hz")
        if not (math.isfinite(self.amplitude_fraction) and 0 < self.amplitude_fraction <= 1):
            raise InputError(f"amplitude_fraction: expected a number in (0, 1], got {self.amplitude_fraction!r}")
        self._check_stick()
        for name in ("encoder_noise_counts", "torque_noise", "camera_noise", "margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(f"{name}: expected a non-negative number, got {v!r}")
        for t in self.camera_times:
            if not (math.isfinite(t) and 0 <= t <= self.duration):
                raise InputError(f"camera_times: {t!r} is outside [0, {self.duration:g}] s")
        return self

    def _check_stick(self) -> None:
        """``stick_seconds`` (0, or a whole number of at least 100 samples up to 600 s) and ``stick_swing`` (in
        [0, 100] breakaway torques) checked, InputError naming the field."""
        s = self.stick_seconds
        if not (math.isfinite(s) and 0 <= s <= 600):
            raise InputError(f"stick_seconds: expected 0 (no stiction ramp) or a duration in s up to 600, got {s!r}")
        n = round(s / self.dt)
        if s > 0 and (n < 100 or abs(n * self.dt - s) > 1e-9 * s):
            raise InputError(f"stick_seconds: expected a whole number of at least 100 samples of {self.dt:g} s, "
                             f"got {s!r}")
        if not (math.isfinite(self.stick_swing) and 0 <= self.stick_swing <= 100):
            raise InputError(f"stick_swing: expected a number in [0, 100] (times each motor's breakaway torque), got "
                             f"{self.stick_swing!r}")


def _checked_design(design: object) -> ExperimentDesign:
    """``design`` (None: the documented one) checked: an :class:`ExperimentDesign`, every field in range."""
    if design is None:
        return ExperimentDesign().check()
    if not isinstance(design, ExperimentDesign):
        raise InputError(f"design: expected an ExperimentDesign, got {type(design).__name__}")
    return design.check()
