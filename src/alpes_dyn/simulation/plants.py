"""Plants as blocks of :func:`alpes_dyn.simulation.loop.run_loop`: the library's simulator, MuJoCo on an MJCF.

* :class:`SimulatorPlant`: a :class:`~alpes_dyn.Model` driven by its motor torques, integrated by the library's
  RK4 (:func:`~alpes_dyn.simulation.integrate.rk4_step_function`) at dt / ``substeps``, the torque held over each
  period; writes its state and its motor angles (what the encoders see, S q_k + C tau_m,k-1). Open loop it has a
  whole-record response: one :func:`~alpes_dyn.simulation.integrate.simulate` call.
* :class:`MujocoPlant`: MuJoCo stepping a model (e.g. the MJCF of :func:`~alpes_dyn.model.mjcf.mjcf_string`)
  ``substeps`` times per period; signals are its joints' qpos, its sensors' data and its actuators' controls,
  by name. The recording played back is :class:`alpes_dyn.estimation.observers.blocks.RecordingPlayback`.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import InputError
from ..model.robot import Model
from ..model.transmission import torque_before
from .integrate import as_statespace, rk4_step_function, simulate
from .loop import Block

__all__ = ["SimulatorPlant", "MujocoPlant"]


def _substeps(x: Any) -> int:
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or x < 1:
        raise InputError(f"substeps: expected an integer >= 1, got {x!r}")
    return int(x)


class SimulatorPlant(Block):
    """The library's simulator as the plant: x_k+1 = RK4^substeps(x_k, tau_k), tau_k held over [t_k, t_k+1).

    Parameters
    ----------
    model : alpes_dyn.Model
        The true model (with a tendon transmission).
    x0 : array_like, shape (2n,)
        The initial state [q; qd], rad, rad/s.
    substeps : int, optional
        RK4 steps per period (default 1).
    u : str, optional
        The signal of the motor torques (m,), N m, read (default ``"tau"``).
    x : str, optional
        The signal of the state (2n,), written (default ``"x"``).
    y : str, optional
        The signal of the motor angles (m,), rad, written (default ``"q_m"``): y_k = S q_k + C tau_m,k-1, the
        tendons' stretch under the torque held before t_k (:func:`~alpes_dyn.model.transmission.torque_before`;
        at t_0 the first torque's).
    joint_range : str, optional
        :func:`~alpes_dyn.simulation.integrate.simulate`'s check of the joint range (default ``"ignore"``).
    name : str, optional
        The block's name (default ``"plant"``).

    Raises
    ------
    InputError
        ``model`` not a Model with a tendon transmission, a bad ``x0`` or ``substeps``.
    """

    has_response = True

    def __init__(self, model: Model, x0: Any, *, substeps: int = 1, u: str = "tau", x: str = "x", y: str = "q_m",
                 joint_range: str = "ignore", name: str = "plant") -> None:
        if not isinstance(model, Model) or model.transmission is None:
            raise InputError("model: expected an alpes_dyn.Model with a tendon transmission")
        self.model, self.name = model, name
        self.x0 = model.vector(x0, "x0", 2 * model.n)
        self.substeps = _substeps(substeps)
        self.joint_range = joint_range
        self.u, self.x, self.y = u, x, y
        self.inputs = self.update_inputs = (u,)
        self.outputs = (x, y)

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.dt, self.n_periods = dt, n_periods
        self._x = self.x0.copy()
        self._before = None  # the torque held over the last period (None at t_0: the first one's)
        self._step = rk4_step_function(as_statespace(self.model, "motor", "encoder"), dt / self.substeps)

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        tr = self.model.transmission
        before = u[self.u] if self._before is None else self._before
        return {self.x: self._x, self.y: tr.encoder_angles(self._x[: self.model.n], before)}

    def update(self, k: int, u: dict[str, Any]) -> None:
        x = self._x
        for _ in range(self.substeps):
            x = self._step(x, u[self.u])
        self._x = np.array(x).reshape(-1)
        self._before = np.asarray(u[self.u], dtype=float).copy()

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """One :func:`simulate` call over the record.

        Parameters
        ----------
        u : dict of str to numpy.ndarray
            The signals read; the motor torques (N, m) or (N+1, m), N m, one row per sample (the last used by y
            only).

        Returns
        -------
        dict of str to numpy.ndarray
            The state and the motor angles, one row per sample.
        """
        U = np.asarray(u[self.u], dtype=float)
        N, sub = self.n_periods, self.substeps
        sim = simulate(self.model, self.x0, np.repeat(U[:N], sub, axis=0), N * self.dt, self.dt / sub, "rk4",
                       input="motor", output="encoder", joint_range=self.joint_range)
        X = sim.x[::sub][: U.shape[0]]
        return {self.x: X, self.y: self.model.transmission.encoder_angles(X[:, : self.model.n], torque_before(U))}


def _addresses(mj: Any, names: str | Sequence[str]) -> int | np.ndarray:
    """The sensordata address of a MuJoCo sensor (an int), or of each of several (an int array)."""
    try:
        if isinstance(names, str):
            return int(mj.sensor(names).adr[0])
        return np.array([int(mj.sensor(s).adr[0]) for s in names], dtype=int)
    except KeyError as exc:
        raise InputError(f"sensors: the MuJoCo model has no sensor {str(exc)}") from None


class MujocoPlant(Block):
    """MuJoCo as the plant: ``model`` (an ``mujoco.MjModel``) and ``data`` (its ``MjData``, in its initial state:
    set qpos and call ``mj_forward`` before the run; the block never resets it, so that a second run goes on from
    where the first stopped) stepped ``substeps`` times per period (``model.opt.timestep`` each: dt / substeps).

    Parameters
    ----------
    model : mujoco.MjModel
        The MuJoCo model.
    data : mujoco.MjData
        Its data, in its initial state.
    substeps : int, optional
        MuJoCo steps per period (default 1).
    joints : mapping of str to sequence of str, optional
        {signal: joint names}: qpos of those joints (rad), in that order, at t_k (default none).
    sensors : mapping, optional
        {signal: sensor name, or names}: their sensordata at t_k (a float, or an array; default none).
    actuators : mapping, optional
        {signal: actuator name(s), or None for all}: the controls set from the signal at t_k, held over the
        period (default none).
    period_sensors : mapping, optional
        {signal: sensor name(s)}: sensordata once the period's steps are done (what a sensor measured over the
        period: the torque applied), period signals (default none).
    nstep : bool, optional
        One ``mj_step(nstep=substeps)`` call per period instead of ``substeps`` calls (the same steps; default
        False).
    sample_sensors : bool, optional
        After the steps, recompute the position sensors at the new state (``mj_fwdPosition``, ``mj_sensorPos``:
        ``mj_step``'s sensors are those of the state before its last integration; default False).
    name : str, optional
        The block's name (default ``"mujoco"``).

    Raises
    ------
    InputError
        An unknown joint, sensor or actuator, or a bad ``substeps``.
    """

    def __init__(self, model: Any, data: Any, *, substeps: int = 1, joints: Mapping[str, Sequence[str]] = {},
                 sensors: Mapping[str, Any] = {}, actuators: Mapping[str, Any] = {},
                 period_sensors: Mapping[str, Any] = {}, nstep: bool = False, sample_sensors: bool = False,
                 name: str = "mujoco") -> None:
        import mujoco

        from ..model.mjcf import joint_permutation

        self.mujoco, self.mj, self.d, self.name = mujoco, model, data, name
        self.substeps = _substeps(substeps)
        self._joints = {s: joint_permutation(model, list(j)) for s, j in joints.items()}
        self._sensors = {s: _addresses(model, v) for s, v in sensors.items()}
        self._period = {s: _addresses(model, v) for s, v in period_sensors.items()}
        self._act = {}
        for s, a in actuators.items():
            try:
                self._act[s] = slice(None) if a is None else (int(model.actuator(a).id) if isinstance(a, str) else
                                                              np.array([model.actuator(x).id for x in a], dtype=int))
            except KeyError as exc:
                raise InputError(f"actuators: the MuJoCo model has no actuator {str(exc)}") from None
        self.nstep, self.sample_sensors = bool(nstep), bool(sample_sensors)
        self.outputs = (*self._joints, *self._sensors)
        self.period_outputs = tuple(self._period)
        self.update_inputs = tuple(self._act)

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        sd = self.d.sensordata
        out: dict[str, Any] = {s: self.d.qpos[p] for s, p in self._joints.items()}
        for s, a in self._sensors.items():
            out[s] = float(sd[a]) if isinstance(a, int) else sd[a]
        return out

    def update(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        mujoco, mj, d = self.mujoco, self.mj, self.d
        for s, a in self._act.items():
            d.ctrl[a] = u[s]
        if self.nstep:
            mujoco.mj_step(mj, d, nstep=self.substeps)
        else:
            for _ in range(self.substeps):
                mujoco.mj_step(mj, d)
        if self.sample_sensors:
            mujoco.mj_fwdPosition(mj, d)
            mujoco.mj_sensorPos(mj, d)
        sd = d.sensordata
        return {s: float(sd[a]) if isinstance(a, int) else sd[a] for s, a in self._period.items()}
