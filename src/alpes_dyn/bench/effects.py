"""The effects of a real hand on a MuJoCo plant: what they are (:class:`PlantEffects`), their MJCF side, and the
default set of a real hand (:func:`real_hand_effects`).

The effects (:class:`PlantEffects`, each off by default):

* ``stiction``: stick-slip dry friction, MuJoCo's ``frictionloss`` F_s with a stiff constraint
  (:data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST`); off, the free plant's joints get the library's own smooth law
  F_s tanh(v / v_s) + F_v v (:class:`~alpes_dyn.model.extras.JointExtras`), added to MuJoCo's passive forces
  by a callback at every RK4 stage (:func:`~alpes_dyn.bench.mujoco_plant.passive_forces`): the plant then has the
  fitted model's friction structure;
* ``soft_stiction``: MuJoCo's ``frictionloss`` F_s with MuJoCo's own default constraint (``solreffriction``
  0.02 s, ``solimpfriction`` 0.9 0.95 0.001, nothing written): a dry friction that creeps under a torque below F_s
  (0.4 rad/s on finger3 at 0.8 F_s) and slides against F_s; not with ``stiction``;
* ``tendon_stiffness`` / ``tendon_damping``: the series-elastic, pull-only tendon with a rotor per motor
  (its inertia J_m on the motor side); the encoder measures the rotor;
* ``tendon_rotor``: the rotor inertia on the rigid tendon (J_m S^T S on the joints' mass matrix);
* ``tilt``: the palm tilted in the finger's plane (rad), unknown to the user;
* ``torque_constant_error`` e: the torque reading is (1 + e) times the true torque (a torque constant e off);
* ``encoder_offset``: the encoder's zero off by this many counts;
* ``tendon_dead_band`` (m, with ``tendon_stiffness``): the cable's slack at the motor shaft, a dead band on the
  tendon's stretch (the cable pulls k_t max(e - delta, 0)): 0.5 degree of backlash at the shaft is
  ``r_m * radians(0.5)``;
* ``torque_delay``: the torque measured this many whole samples late (the current's filter and the bus).

The default set of a real hand (:func:`real_hand_effects`, ``alpes-dyn control --plant-effects all``, the realism
study's ``all`` case, :func:`alpes_dyn.studies.realism.cases`): every effect above -- stick-slip, the
:data:`CABLE_STIFFNESS` cable with its rotor (the mode damped :data:`ZETA`) and :data:`SLACK_DEG` of slack, the palm
:data:`TILT_DEG` off, the torque constant :data:`KT_ERROR` off, the encoder :data:`OFFSET_COUNTS` off, the torque
:data:`DELAY_SAMPLES` late.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..model.mjcf import STICTION_TIMECONST, tilted_gravity
from ..model.params import load_params

__all__ = ["PlantEffects", "MAX_TORQUE_DELAY", "delayed", "effects_mjcf_kwargs", "plant_gravity", "cable_damping",
           "cable_slack", "real_hand_effects", "CABLE_STIFFNESS", "ZETA", "TILT_DEG", "KT_ERROR", "OFFSET_COUNTS",
           "SLACK_DEG", "DELAY_SAMPLES"]


def _number(x: object) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class PlantEffects:
    """The unmodelled effects of a real hand on a MuJoCo plant (see the module docstring); SI units.

    Attributes
    ----------
    stiction : float or None
        Time constant (s) of MuJoCo's dry-friction constraint, or None (the library's smooth law, or
        ``soft_stiction``).
    soft_stiction : bool
        MuJoCo's dry friction with its default, soft constraint (module docstring); with ``stiction`` None.
    tendon_stiffness : float or None
        k_t (N/m) of a series-elastic tendon, or None (rigid).
    tendon_damping : float
        c_t (N s/m) of the series-elastic tendon.
    tendon_rotor : bool
        The rotor's inertia on the rigid tendon.
    tilt : float
        The palm's tilt in the finger's plane, rad.
    torque_constant_error : float
        e: the torque reading (1 + e) times the true torque, in (-0.5, 0.5).
    encoder_offset : float
        The encoder's zero error, counts.
    tendon_dead_band : float
        The cable's slack, m (with ``tendon_stiffness``).
    torque_delay : int
        Whole samples (0 to :data:`MAX_TORQUE_DELAY`) by which the torque reading lags the applied torque.
    """

    stiction: float | None = None
    tendon_stiffness: float | None = None
    tendon_damping: float = 0.0
    tendon_rotor: bool = False
    tilt: float = 0.0
    torque_constant_error: float = 0.0
    encoder_offset: float = 0.0
    tendon_dead_band: float = 0.0
    torque_delay: int = 0
    soft_stiction: bool = False

    @property
    def mujoco_friction(self) -> bool:
        """Whether MuJoCo's own dry friction (``frictionloss``, stiff or soft) is the plant's, not the library's
        smooth law."""
        return self.stiction is not None or bool(self.soft_stiction)

    def check(self) -> "PlantEffects":
        """Numbers in range (:class:`~alpes_dyn.InputError` naming the field); the MJCF options are checked by
        :func:`~alpes_dyn.model.mjcf.mjcf_string`."""
        if not (_number(self.torque_constant_error) and -0.5 < self.torque_constant_error < 0.5):
            raise InputError(f"torque_constant_error: expected a fraction in (-0.5, 0.5), got "
                             f"{self.torque_constant_error!r}")
        if not (_number(self.encoder_offset) and abs(self.encoder_offset) <= 1e6):
            raise InputError(f"encoder_offset: expected a finite number of counts, got {self.encoder_offset!r}")
        if not (isinstance(self.torque_delay, (int, np.integer)) and not isinstance(self.torque_delay, bool)
                and 0 <= self.torque_delay <= MAX_TORQUE_DELAY):
            raise InputError(f"torque_delay: expected a whole number of samples from 0 to {MAX_TORQUE_DELAY}, got "
                             f"{self.torque_delay!r}")
        if not isinstance(self.soft_stiction, (bool, np.bool_)):
            raise InputError(f"soft_stiction: expected True or False, got {self.soft_stiction!r:.40}")
        if self.soft_stiction and self.stiction is not None:
            raise InputError("soft_stiction: MuJoCo's default dry-friction constraint, or stiction's time constant, "
                             "not both")
        if self.tendon_dead_band and self.tendon_stiffness is None:
            raise InputError("tendon_dead_band: the cable's slack needs the series-elastic tendon (tendon_stiffness)")
        return self


MAX_TORQUE_DELAY = 100
"""The longest torque delay a plant takes, samples (0.1 s at 1 kHz: beyond, it is a wrong clock, not a filter)."""


def delayed(signal: np.ndarray, samples: int) -> np.ndarray:
    """``signal`` seen ``samples`` whole samples late (what a sensor that lags by a fixed number of samples reads
    from a held start).

    Parameters
    ----------
    signal : numpy.ndarray, shape (N+1, ...)
        The signal per sample (any unit), row k at sample k.
    samples : int
        The delay, whole samples (>= 0; 0: ``signal`` itself).

    Returns
    -------
    numpy.ndarray, shape of ``signal``
        Row k is row k - ``samples`` of ``signal``; the first ``samples`` rows repeat row 0.
    """
    if samples == 0:
        return signal
    out = np.empty_like(signal)
    out[samples:] = signal[:-samples]
    out[:samples] = signal[0]
    return out


def effects_mjcf_kwargs(effects: PlantEffects) -> dict[str, Any]:
    """The MJCF side of ``effects`` as keyword arguments of :func:`~alpes_dyn.model.mjcf.mjcf_string`.

    Parameters
    ----------
    effects : PlantEffects
        The plant's effects (checked: :meth:`PlantEffects.check`).

    Returns
    -------
    dict[str, Any]
        ``stiction``, ``tendon_stiffness``, ``tendon_damping``, ``tendon_dead_band``, ``tendon_rotor`` and ``tilt``,
        in the units of :class:`PlantEffects`.
    """
    e = effects.check()
    return {"stiction": e.stiction, "tendon_stiffness": e.tendon_stiffness, "tendon_damping": e.tendon_damping,
            "tendon_dead_band": e.tendon_dead_band, "tendon_rotor": e.tendon_rotor, "tilt": e.tilt}


def plant_gravity(gravity: np.ndarray, effects: PlantEffects | None) -> np.ndarray:
    """The plant's gravity: ``gravity`` turned by the effects' tilt (:func:`~alpes_dyn.model.mjcf.tilted_gravity`).

    Parameters
    ----------
    gravity : numpy.ndarray, shape (3,)
        The scene's gravity (palm down), m/s^2.
    effects : PlantEffects or None
        The plant's effects (its ``tilt``, rad); None: no tilt.

    Returns
    -------
    numpy.ndarray, shape (3,)
        The plant's gravity, m/s^2.
    """
    g = np.asarray(gravity, dtype=float)
    return g if effects is None or effects.tilt == 0 else tilted_gravity(g, effects.tilt)


CABLE_STIFFNESS = 39529.85937675223
"""k_t of a real hand's cable, N/m: what :func:`alpes_dyn.studies.realism.tendon_stiffness` derives from the
documented experiment on the shipped finger3 (the cable stretched by 3 % of the tendon's travel under the
experiment's mean tension; its rotor-on-cable mode about 200 Hz), kept here so that the bench floor holds it
(``tests/test_bench_standin.py`` checks the two agree)."""
ZETA = 0.2
"""The damping ratio of the rotor-on-cable mode (:func:`cable_damping`)."""
TILT_DEG = 3.0
"""deg: the palm's tilt in the finger's plane, unknown to the fits (a rig's level a few degrees off)."""
KT_ERROR = 0.05
"""The torque constant's relative error: the torque reading is 1.05 times the true torque."""
OFFSET_COUNTS = 4.0
"""counts: the encoder's zero error."""
SLACK_DEG = 0.5
"""deg: the cable's slack (backlash) at the motor shaft, a dead band r_m radians(SLACK_DEG) on the tendon's stretch."""
DELAY_SAMPLES = 1
"""The torque measured this many samples (1 ms) late."""


def cable_damping(tendon_stiffness: float) -> float:
    """The cable's damping that gives the rotor-on-cable mode (the shipped file's rotor J_m on r_m^2 k_t) the
    damping ratio :data:`ZETA`: c_t = 2 ZETA sqrt(k_t J_m) / r_m.

    Parameters
    ----------
    tendon_stiffness : float
        k_t, the cable's stiffness, N/m.

    Returns
    -------
    float
        c_t, N s/m.
    """
    p = load_params()
    return 2 * ZETA * math.sqrt(tendon_stiffness * p.J_m) / p.r_m


def cable_slack() -> float:
    """The cable's slack of a real hand, m: :data:`SLACK_DEG` of backlash at the motor shaft, r_m radians(SLACK_DEG)
    (the shipped file's motor radius r_m)."""
    return load_params().r_m * math.radians(SLACK_DEG)


def real_hand_effects(tendon_stiffness: float = CABLE_STIFFNESS, tendon_damping: float | None = None) -> PlantEffects:
    """The effects of a real hand (module docstring; ``alpes-dyn control --plant-effects all``): stick-slip
    (:data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST`), the series-elastic cable (``tendon_stiffness`` N/m,
    ``tendon_damping`` N s/m, default :func:`cable_damping`) with its rotor and :func:`cable_slack`, the palm
    :data:`TILT_DEG` off, the torque constant :data:`KT_ERROR` off, the encoder :data:`OFFSET_COUNTS` off, the torque
    :data:`DELAY_SAMPLES` late.

    Parameters
    ----------
    tendon_stiffness : float, optional
        The cable's stiffness, N/m.
    tendon_damping : float or None, optional
        Its damping, N s/m (default :func:`cable_damping` of the stiffness).

    Returns
    -------
    PlantEffects
        Every effect at once.
    """
    if not (_number(tendon_stiffness) and tendon_stiffness > 0):
        raise InputError(f"tendon_stiffness: expected a positive stiffness in N/m, got {tendon_stiffness!r}")
    c_t = cable_damping(tendon_stiffness) if tendon_damping is None else tendon_damping
    return PlantEffects(stiction=STICTION_TIMECONST, tendon_stiffness=float(tendon_stiffness), tendon_damping=c_t,
                        tilt=math.radians(TILT_DEG), torque_constant_error=KT_ERROR, encoder_offset=OFFSET_COUNTS,
                        tendon_dead_band=cable_slack(), torque_delay=DELAY_SAMPLES).check()
