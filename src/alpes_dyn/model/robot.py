"""Numeric rigid-body dynamics of a fixed-base URDF tree, with the Alpes extras (Pinocchio).

The model solves eq. 2.10 of the report,

    (A(q) + I_a) qdd + C(q, qd) qd + F_v qd + f_s + G(q) = Gamma + J^T F,

with A from CRBA, C the Christoffel-consistent Coriolis matrix (A_dot - 2C skew-symmetric),
G = gravity + springs (eq. 2.11, 2.14), I_a = diag(armature) + S^T diag(J_m) S (eq. 2.8: a joint-side
inertia on the diagonal, Pinocchio's ``armature``, plus each motor's rotor inertia J_m on its tendon
coordinate q_m = S q, which couples every pair of joints the tendon drives; constant, so C is unchanged),
friction eq. 2.6-2.7 and the contact torque J^T F of eq. 2.9 with F a linear force at a tip frame,
expressed in the base frame (default F = [0, 0, F_z], eq. 2.13).

Following Pinocchio, a :class:`Model` owns one ``pinocchio.Model`` and one ``pinocchio.Data``;
it is not thread-safe (use :meth:`Model.copy` per thread).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Sequence

import numpy as np
import pinocchio as pin

from .description import Layout, check_model_name, layout, model_params, urdf_string
from ..checks import as_float_array
from ..limits import _NRM2, check_physical, hot_magnitude_error
from ..errors import InputError, ModelError
from .extras import JointExtras
from ..fileio import read_text
from .inertial import check_inertials
from .ratio_curve import check_ratio_range
from .mimic import MimicCoupling, refuse_mimic_names
from .robot_checks import (_build_pinocchio, _check_mass_matrix, _check_positive, _check_random_args, _tips,
                           newton_equilibrium)  # noqa: F401  (newton_equilibrium: importable from here, as before)
from .params import HandParams, load_params
from .spec import TransmissionSpec, alpes_spec, alpes_transmission, load_spec
from .transmission import Transmission
from .contact import REFERENCE_FRAMES, Contact, as_contacts  # noqa: F401  (importable from here, as before)
from .frames import FrameKinematics
from .terms import _F64, _HOT, _ND, DynamicsTerms

__all__ = ["Model", "DEFAULT_GRAVITY"]

DEFAULT_GRAVITY = np.array([0.0, 0.0, -9.81])
_TINY = 2.0**-1000  # |x| * _TINY < 2e7 for every finite float64 x


def _spec_and_extras(urdf: str, spec: TransmissionSpec | str | Path | JointExtras | None,
                     extras: JointExtras | None) -> tuple[TransmissionSpec | None, JointExtras | None]:
    """:class:`Model`'s spec and extras arguments read: a spec's path loaded, the former positional order
    ``Model(urdf, extras, ...)`` understood, a wrong type or a spec with extras refused, the URDF text checked."""
    if isinstance(spec, JointExtras):  # the former positional order Model(urdf, extras, ...)
        spec, extras = None, spec if extras is None else extras
    if isinstance(spec, (str, Path)):
        spec = load_spec(spec)
    if spec is not None and not isinstance(spec, TransmissionSpec):
        raise ModelError(f"spec: expected a TransmissionSpec or the path of its TOML file, got {type(spec).__name__}")
    if spec is not None and extras is not None:
        raise ModelError("extras: given together with a spec, which holds them already")
    if not isinstance(urdf, str) or "<robot" not in urdf:
        raise ModelError("urdf: expected URDF text containing a <robot> element")
    return spec, extras


class Model(DynamicsTerms, FrameKinematics):
    """Dynamics of a fixed-base tree of 1-DoF joints (an Alpes model or any URDF).

    Parameters
    ----------
    urdf : str
        URDF text (not a path; see :meth:`from_urdf_file`).
    spec : TransmissionSpec, str or pathlib.Path, optional
        What the URDF cannot hold: motors and their joints with ratios, encoder, per-joint springs,
        friction, rotor inertia (:class:`~alpes_dyn.model.spec.TransmissionSpec`, or the path of its TOML
        file; default: none of them). The Alpes models are built through it (:meth:`alpes`).
    gravity : array_like, optional
        Gravity vector in the base frame, m/s^2, shape (3,) (default: the spec's, else (0, 0, -9.81)).
    name : str, optional
        A label (default: the spec's name, else the robot name of the URDF).
    layout : Layout, optional
        Set by :meth:`alpes`: the chains of an Alpes model.
    params : HandParams, optional
        Set by :meth:`alpes`: the parameter file's values.
    spring : str, optional
        Label of the spring law (default: the spec's, else ``"none"``).
    extras : JointExtras, optional
        Springs, friction, rotor inertia as arrays (n,) in joint order, instead of a spec (no motors).
    check_inertia : str
        ``"relaxed"`` (default) or ``"strict"``: how the URDF's inertials are validated
        (:func:`alpes_dyn.model.inertial.check_inertials`: masses and inertias positive (semi)definite;
        strict adds the triangle inequality, which real URDFs such as the Allegro hand's break).

    Raises
    ------
    ModelError
        A URDF Pinocchio cannot read or without a ``<robot>``, a spec that does not match its joints or frames, a
        gravity not 3 finite physical numbers (or different from the spec's), extras of the wrong shape or a
        negative armature, a singular A(q) + I_a (a joint that moves only massless links), a moment arm of 0 in a
        joint's range.

    All vectors are 1-D float arrays of length ``n`` (joints in :attr:`joint_names` order), in SI
    units (rad, rad/s, rad/s^2, N m, N).

    Joint order. Pinocchio's: depth first from the root, a joint's whole subtree before its next
    sibling, siblings in the order the URDF parser (urdfdom) keeps them, which is by child link name
    -- not the order of the URDF file, nor an anatomical one (the Alpes hand comes as index, little,
    middle, ring, thumb). Motors (:attr:`motor_names`) keep the order of the transmission, tips
    (:attr:`tip_names`) the order given by the layout or spec (else the URDF's, leaf frames in
    Pinocchio's frame order). Use :meth:`joint_index` rather than positions.

    Mimic joints (a URDF ``<mimic>``): constraints, not joints; :attr:`joint_names` and q are the independent
    joints' (:attr:`mimic`, :mod:`alpes_dyn.model.mimic`), A, C, G and the Jacobians restricted to them.

    Default tip (:attr:`default_tip`): the first of :attr:`tips` where the spec (``tips = [...]``) or the layout
    names them, or where the URDF has a single leaf frame; a URDF with several leaves and no tip named has none
    (UR5's leaves are ``base``, ``ee_link``, ``tool0``: its first leaf, the base, is no tip), and what needs
    the default tip raises :class:`~alpes_dyn.ModelError` naming the leaves and how to name one.
    """

    def __init__(self, urdf: str, spec: TransmissionSpec | str | Path | None = None,
                 gravity: Sequence[float] | None = None, name: str | None = None, layout: Layout | None = None,
                 params: HandParams | None = None, spring: str | None = None, *,
                 extras: JointExtras | None = None, check_inertia: str = "relaxed") -> None:
        """See the class. The parts are built in the order the later ones read them: the Pinocchio model and the
        joints, the spec's values on them, the gravity, the joint extras, the caches and tips, the transmission."""
        spec, extras = _spec_and_extras(urdf, spec, extras)
        self._given_extras = extras
        self.urdf: str = urdf
        self.mimic: MimicCoupling | None  # the URDF's <mimic> joints, q_full = G q + o (model.mimic), else None
        self.pin_model, self.mimic = _build_pinocchio(urdf)
        check_inertials(urdf, check_inertia)
        self.check_inertia = check_inertia
        n = self.pin_model.nv
        self.n: int = n
        self.joint_names: tuple[str, ...] = self.mimic.names if self.mimic else tuple(self.pin_model.names[1:])
        self.spec: TransmissionSpec | None = spec
        if spec is not None:
            extras, gravity = self._spec_on_joints(spec, gravity)
        self.name: str = name or (spec.name if spec is not None and spec.name else None) or self.pin_model.name
        self.layout = layout
        self.params = params
        self.spring = spring if spring is not None else (spec.spring if spec is not None else "none")
        self.gravity: np.ndarray = self._set_gravity(gravity)
        self.extras: JointExtras = self._set_extras(extras)
        self.pin_data: pin.Data = self.pin_model.createData()
        _check_mass_matrix(self.pin_model, self.pin_data, self.joint_names)
        self._set_caches()
        self.tips: tuple[str, ...] = _tips(self.pin_model, spec, layout)
        self.tips_named: bool = (spec is not None and spec.tips is not None) or layout is not None or len(self.tips) <= 1
        """Whether :attr:`default_tip` is defined: tips named by the spec or layout, or a URDF with one leaf."""
        self.transmission: Transmission | None = spec.transmission(self.joint_names) if spec is not None else None
        if spec is None and layout is not None and params is not None:  # the former Model(urdf, extras, ..., layout, params)
            self.transmission = alpes_transmission(layout, self.joint_names, params.transmission_ratio,
                                                         params.abduction_ratio, params.encoder_counts)
        check_ratio_range(self.transmission, self.lower, self.upper, self.joint_names)  # a moment arm of 0
        self.rotor_matrix: np.ndarray = self._set_rotor()
        """S^T diag(J_m) S (n, n), kg m^2: the motors' rotor inertia on the joints (eq. 2.8; zeros without)."""

    def _spec_on_joints(self, spec: TransmissionSpec, gravity: Sequence[float] | None
                        ) -> tuple[JointExtras, Sequence[float] | None]:
        """The spec checked against the URDF's joints and frames (a mimic joint it names refused): its joint extras
        and the gravity to use (the argument, else the spec's; both given and different: ModelError)."""
        if self.mimic is not None:
            refuse_mimic_names(spec, self.mimic)
        spec.check(self.joint_names, [f.name for f in self.pin_model.frames])
        extras = spec.extras(self.joint_names)
        if gravity is not None and spec.gravity is not None and not np.array_equal(
                np.asarray(gravity, dtype=float), np.asarray(spec.gravity)):
            raise ModelError("gravity: given both as an argument and in the spec, with different values")
        return extras, spec.gravity if gravity is None else gravity

    def _set_gravity(self, gravity: Sequence[float] | None) -> np.ndarray:
        """The gravity (3,), m/s^2 (default :data:`DEFAULT_GRAVITY`), checked finite and physical, set on the
        Pinocchio model (and on a mimic model's full one); returned as :attr:`gravity`'s copy."""
        try:
            g = DEFAULT_GRAVITY if gravity is None else as_float_array(gravity, "gravity", "3 finite numbers")
        except InputError as exc:
            raise ModelError(str(exc)) from None
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ModelError(f"gravity: expected 3 finite numbers, got {np.asarray(gravity).tolist()!r}")
        check_physical(g, "gravity", "m/s^2", "any", ModelError)  # a gravity of 1e300 m/s^2, a subnormal 1e-320
        out = g.copy()
        self.pin_model.gravity.linear = g
        if self.mimic is not None:
            self.mimic.full_model.gravity.linear = g
        return out

    def _set_extras(self, extras: JointExtras | None) -> JointExtras:
        """The joint extras (springs, armature, friction; zeros without), each of shape (n,), the armature >= 0 and
        set on the Pinocchio model."""
        n = self.n
        if extras is not None and not isinstance(extras, JointExtras):
            raise ModelError(f"extras: expected JointExtras, got {type(extras).__name__}")
        extras = extras if extras is not None else JointExtras.zeros(n)
        for fname in ("stiffness", "armature", "coulomb", "viscous"):
            a = getattr(extras, fname)
            if np.shape(a) != (n,):
                raise ModelError(f"extras.{fname}: expected shape ({n},), got {np.shape(a)}")
        if np.any(extras.armature < 0):
            raise ModelError("extras.armature: must be >= 0")
        self.pin_model.armature = np.asarray(extras.armature, dtype=float).copy()
        return extras

    def _set_caches(self) -> None:
        """What the hot paths read at each call: the springs, the index of the mass matrix's lower triangle, the
        state's shape, the overflow guard, the frames by name."""
        n = self.n
        self._k = np.asarray(self.extras.stiffness, dtype=float)
        self._spring = self.extras.has_spring
        self._friction = self.extras.has_friction
        self._lower = np.tril_indices(n, -1)
        self._shape = (n,)
        self._tiny = np.full(n, _TINY)  # x . tiny is finite iff x is, and never overflows (no numpy warning)
        self._frames = {f.name: i for i, f in enumerate(self.pin_model.frames)}

    def _set_rotor(self) -> np.ndarray:
        """The transmission's rotor inertia on the joints, S^T diag(J_m) S (n, n) read-only (zeros without), and how
        the dynamics add it: dense (CRBA and a solve) where there is one or a mimic joint, by the tree's
        ancestry where it couples only a joint with its ancestors; the sum A + R checked positive definite."""
        n, tr = self.n, self.transmission
        self._rotor = tr is not None and bool(np.any(tr.rotor_inertia != 0))
        R = tr.rotor_matrix if self._rotor else np.zeros((n, n))
        R.flags.writeable = False
        self._rotor_upper = np.triu(R)
        ids = [self.pin_model.getJointId(j) for j in self.joint_names]  # Pinocchio's ids (a mimic joint has one)
        sup = [set(self.pin_model.supports[ids[j]]) for j in range(n)]  # joint j's ancestors and itself
        self._rotor_curved = self._rotor and tr.curved  # rho(q)^T J_m rho(q) and its velocity product, per call
        self._rotor_tree = (self.mimic is None and not self._rotor_curved
                            and all(ids[i] in sup[j] for i, j in zip(*np.nonzero(self._rotor_upper))))
        self._dense = self._rotor or self.mimic is not None  # CRBA and a dense solve (no ABA on a mimic model)
        if self._rotor:
            _check_positive(self.pin_model, self.pin_data, R)
        return R

    def __reduce__(self) -> tuple:
        """Pickled (and deep-copied) as its description: the URDF, the spec as TOML, the gravity, the layout and the
        parameter file's values; rebuilt on load (a new Pinocchio model and data)."""
        spec = self.spec.to_toml() if self.spec is not None else None
        return (_restore_model, (self.urdf, spec, self.gravity.tolist(), self.name, self.layout, self.params,
                                 self.spring, self._given_extras if spec is None else None, self.check_inertia))

    # ------------------------------------------------------------------ construction
    @classmethod
    def alpes(cls, model: str = "finger3", spring: str = "torsional", friction: bool = False,
              rotor_inertia: bool = False, params: HandParams | str | Path | None = None,
              chain: str | None = None) -> "Model":
        """An Alpes model built from the parameter file.

        Parameters
        ----------
        model : str
            ``"finger2"``, ``"finger3"`` (default), ``"hand"`` or ``"thumb"``.
        spring : str
            ``"torsional"`` (default), ``"report"`` (eq. 2.14 literally) or ``"none"``.
        friction : bool
            Joint friction of eq. 2.6-2.7 with the file's values (default False).
        rotor_inertia : bool
            The motors' rotor inertia of eq. 2.8 with the file's values (default False).
        params : HandParams, str or pathlib.Path, optional
            The parameter file (its values or its path; default: the one shipped with the package). A file
            marked not trustworthy is kept (:attr:`HandParams.untrusted`; the loaders that use its values refuse
            it, :func:`~alpes_dyn.model.trust.check_trusted`).
        chain : str, optional
            A finger model built from that finger of the hand (a name of ``palm.finger_names``: the shared
            ``[finger]`` values with its own ``[finger.<name>]`` ones); :attr:`chain` keeps it and :attr:`params`
            the whole file.

        Returns
        -------
        Model

        Raises
        ------
        ModelError
            An unknown model, spring law or chain, or a parameter file that does not load.
        """
        check_model_name(model)
        p = params if isinstance(params, HandParams) else load_params(params)
        pc = model_params(model, p, chain)
        lay = layout(model, pc, None)
        if chain is not None:
            lay = dataclasses.replace(lay, chain=chain)
        spec = alpes_spec(lay, pc, spring, friction, rotor_inertia)
        return cls(urdf_string(model, pc), spec, name=model, layout=lay, params=p)

    @property
    def chain(self) -> str | None:
        """The hand's chain this model is: a finger's name for a finger model built with ``chain=``,
        ``"thumb"`` for the thumb model, else None (a finger model of the shared ``[finger]`` values)."""
        if self.layout is None:
            return None
        return "thumb" if self.layout.model == "thumb" else self.layout.chain

    @classmethod
    def from_mjcf(cls, mjcf: str | Path, hold: Sequence[str] = (), **kwargs) -> "Model":
        """A MuJoCo model read as a :class:`Model` (needs ``mujoco``): its tree as a URDF, its tendons, springs,
        armature and friction as a spec (:func:`alpes_dyn.model.mjcf_import.mjcf_to_urdf`).

        Parameters
        ----------
        mjcf : str or pathlib.Path
            MJCF text or the path of its file.
        hold : sequence of str
            Hinges welded at their reference angle, their actuators dropped (default none).
        **kwargs
            Passed to :class:`Model` (e.g. ``gravity``, ``name``, ``check_inertia``).

        Returns
        -------
        Model

        Raises
        ------
        ModelError
            What the import cannot represent (:mod:`alpes_dyn.model.mjcf_import` names the element), or an MJCF
            MuJoCo refuses.
        """
        from .mjcf_import import mjcf_model

        return mjcf_model(cls, mjcf, hold, **kwargs)

    def to_mjcf(self, **kwargs) -> str:
        """MJCF text of this model for MuJoCo: its tree, inertias, limits, springs, armature, friction, motors as
        fixed tendons with motor actuators, rotor inertia, tip sites and gravity; :meth:`from_mjcf` reads it back.

        Parameters
        ----------
        **kwargs
            The keywords of :func:`alpes_dyn.model.mjcf_export.model_mjcf` (its options of the export).

        Returns
        -------
        str
            The MJCF text.

        Raises
        ------
        ModelError
            What MJCF cannot hold of this model (:func:`~alpes_dyn.model.mjcf_export.model_mjcf` names it).
        """
        from .mjcf_export import model_mjcf

        return model_mjcf(self, **kwargs)

    def subtree(self, motors: str | Sequence[str]) -> "Model":
        """The sub-model on the branches from the base that ``motors`` drive, with every motor that drives one of
        their joints; the other branches removed from the URDF and the spec
        (:func:`alpes_dyn.model.subtree.subtree_model`: why they cannot change the kept joints' dynamics on a
        fixed base, and what is refused).

        Parameters
        ----------
        motors : str or sequence of str
            A motor name or a list of them (of :attr:`motor_names`).

        Returns
        -------
        Model

        Raises
        ------
        ModelError
            An unknown motor, or a model the cut cannot keep whole (:func:`~alpes_dyn.model.subtree.subtree_model`).
        """
        from .subtree import subtree_model

        return subtree_model(self, motors)

    @classmethod
    def from_urdf_file(cls, path: str | Path, spec: TransmissionSpec | str | Path | None = None, **kwargs) -> "Model":
        """Load any fixed-base URDF file (e.g. one of example-robot-data) with an optional spec.

        Parameters
        ----------
        path : str or pathlib.Path
            The URDF file.
        spec : TransmissionSpec, str or pathlib.Path, optional
            A :class:`~alpes_dyn.model.spec.TransmissionSpec` or the path of its TOML file; without one the model
            has no motors, springs, friction or rotor inertia.
        **kwargs
            Passed to :class:`Model` (e.g. ``gravity``, ``name``, ``check_inertia``).

        Returns
        -------
        Model

        Raises
        ------
        ModelError
            A file that cannot be read, or what :class:`Model` refuses.
        """
        return cls(read_text(path, "URDF file", ModelError), spec, **kwargs)

    def copy(self, gravity: Sequence[float] | None = None, params: HandParams | None = None) -> "Model":
        """An independent model (own Pinocchio data), e.g. for another thread.

        Parameters
        ----------
        gravity : array_like, optional
            (3,), m/s^2: the same robot in another orientation (the spec's gravity replaced too); default this
            model's.
        params : HandParams, optional
            The parameter file's values the copy keeps in :attr:`params` (default this model's). Only what is read
            from :attr:`params` when used changes (e.g. ``friction.law``: :func:`~alpes_dyn.model.friction.creep_of`,
            :func:`~alpes_dyn.model.friction.lugre_of`); the links, springs and friction values stay this model's.

        Returns
        -------
        Model

        Raises
        ------
        ModelError
            A gravity not 3 finite physical numbers.
        """
        g = self.gravity if gravity is None else gravity
        p = self.params if params is None else params
        if self.spec is not None:
            spec = self.spec
            if gravity is not None and spec.gravity is not None:
                spec = dataclasses.replace(spec, gravity=None)
            return Model(self.urdf, spec, g, self.name, self.layout, p, self.spring, check_inertia=self.check_inertia)
        return Model(self.urdf, None, g, self.name, self.layout, p, self.spring, extras=self.extras,
                     check_inertia=self.check_inertia)

    def __repr__(self) -> str:
        return f"Model({self.name!r}, n={self.n}, spring={self.spring!r}, tips={list(self.tips)})"

    # ------------------------------------------------------------------ names
    @property
    def motor_names(self) -> tuple[str, ...]:
        """Motor names in transmission order (empty without a transmission)."""
        return self.transmission.motor_names if self.transmission is not None else ()

    @property
    def tip_names(self) -> tuple[str, ...]:
        """Tip frame names (the same as :attr:`tips`); the first is the default tip."""
        return tuple(self.tips)

    def joint_index(self, name: str) -> int:
        """Position of a joint in :attr:`joint_names` (and in q, v, tau, the rows of A...).

        Parameters
        ----------
        name : str
            The joint's name.

        Returns
        -------
        int

        Raises
        ------
        ModelError
            An unknown joint (the message lists them).
        """
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise ModelError(f"unknown joint {name!r} (joints: {', '.join(self.joint_names)})") from None

    def motor_index(self, name: str) -> int:
        """Position of a motor in :attr:`motor_names` (and in tau_m, the encoder vector q_m).

        Parameters
        ----------
        name : str
            The motor's name.

        Returns
        -------
        int

        Raises
        ------
        ModelError
            An unknown motor (the message lists them).
        """
        try:
            return self.motor_names.index(name)
        except ValueError:
            raise ModelError(f"unknown motor {name!r} (motors: {', '.join(self.motor_names) or 'none'})") from None

    # ------------------------------------------------------------------ input checks
    def vector(self, x: object, name: str, n: int | None = None) -> np.ndarray:
        """``x`` as a checked float vector: the argument check of every method (a float64 array of the right shape
        is returned as it is, no copy).

        Parameters
        ----------
        x : array_like
            The vector.
        name : str
            Its name in the error message.
        n : int, optional
            Its length (default the model's, :attr:`n`).

        Returns
        -------
        numpy.ndarray
            (n,) float64.

        Raises
        ------
        InputError
            ``x`` not n numbers, or an entry NaN, inf or over :data:`~alpes_dyn.limits.MAX_HOT_MAGNITUDE` (2^40) in
            magnitude; the message names ``name``.
        """
        n = self.n if n is None else n
        if x.__class__ is _ND and x.dtype is _F64 and x.shape == (n,):  # fast path, no copy
            a = x
            if _NRM2(a) < _HOT:  # one BLAS call: finite and bounded
                return a
        else:
            a = as_float_array(x, name, f"{n} numbers")
            if a.shape != (n,):
                raise InputError(f"{name}: expected shape ({n},), got {a.shape}")
        if not np.isfinite(a).all():
            raise InputError(f"{name}: contains NaN or inf ({a.tolist()})")
        err = hot_magnitude_error(a, name)
        if err is not None:
            raise err
        return a

    # ------------------------------------------------------------------ helpers
    @property
    def springless_joints(self) -> tuple[str, ...]:
        """Joints without a spring (stiffness 0, e.g. the thumb's ab/adduction, which its own motor holds)."""
        return tuple(j for j, k in zip(self.joint_names, self.extras.stiffness) if k == 0)

    @property
    def lower(self) -> np.ndarray:
        """Joint lower limits from the URDF (rad)."""
        return self.pin_model.lowerPositionLimit.copy()

    @property
    def upper(self) -> np.ndarray:
        """Joint upper limits from the URDF (rad)."""
        return self.pin_model.upperPositionLimit.copy()

    def random_state(self, rng: np.random.Generator | int | None, speed: float = 2.0,
                     size: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """A random state (q, v): q uniform within the joint limits (+-pi where a limit is missing or huge), v
        uniform in [-speed, speed].

        Parameters
        ----------
        rng : numpy.random.Generator, int or None
            The generator, or a seed (an integer >= 0, or None for fresh entropy) given to
            ``numpy.random.default_rng``.
        speed : float
            The velocities' bound, rad/s (default 2, >= 0).
        size : int, optional
            The number of states drawn at once (default: one).

        Returns
        -------
        q, v : numpy.ndarray
            Shapes (n,), or (size, n); rad and rad/s.

        Raises
        ------
        InputError
            A ``rng`` that is neither, a negative or non-finite ``speed``, a ``size`` not an integer >= 0.
        """
        rng, speed, size = _check_random_args(rng, speed, size)
        lo, hi = self.lower, self.upper
        lo = np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.pi)
        hi = np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.pi)
        shape = self.n if size is None else (size, self.n)
        return rng.uniform(lo, hi, size=None if size is None else shape), rng.uniform(-speed, speed, shape)


def _restore_model(urdf: str, spec: str | None, gravity: list[float], name: str, layout: Layout | None,
                   params: HandParams | None, spring: str, extras: JointExtras | None, check_inertia: str) -> Model:
    """The :class:`Model` that :meth:`Model.__reduce__` described."""
    ts = TransmissionSpec.from_toml(spec) if spec is not None else None
    return Model(urdf, ts, gravity=gravity, name=name, layout=layout, params=params, spring=spring, extras=extras,
                 check_inertia=check_inertia)
