"""Frames of a :class:`~alpes_dyn.model.robot.Model`: tip lookup, placements, Jacobians and the contact torque J^T F.

A mixin of :class:`~alpes_dyn.model.robot.Model` (one concept: where the frames are and how a force at them acts on the
joints, eq. 2.9, 2.12-2.13); it reads the model's ``pin_model``, ``pin_data``, ``tips``, ``tips_named``, ``name``,
``n``, its frame table ``_frames`` and its argument check :meth:`~alpes_dyn.model.robot.Model.vector`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from ..checks import as_float_array
from ..errors import InputError, ModelError
from .contact import REFERENCE_FRAMES, Contact, as_contacts

__all__ = ["FrameKinematics"]

_WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class FrameKinematics:
    """Frame kinematics and contact torques of a model (mixed into :class:`~alpes_dyn.model.robot.Model`)."""

    @property
    def default_tip(self) -> str:
        """The tip used where none is given: the first of :attr:`tips`; :class:`~alpes_dyn.ModelError` where there
        is none, or where the URDF has several leaf frames and neither the spec nor the layout names the tips."""
        if not self.tips:
            raise ModelError("model has no tip frame; pass a frame name (the command line's --tip, or control's --frame)")
        if not self.tips_named:
            raise ModelError(f"tip: model {self.name!r} names no tip and its URDF has {len(self.tips)} leaf frames "
                             f"({', '.join(self.tips)}); name it: tips = [\"<frame>\"] in the spec, or tip=<frame> "
                             "(the command line's --tip)")
        return self.tips[0]

    def frame_id(self, tip: str | None) -> int:
        """Pinocchio's index of a frame.

        Parameters
        ----------
        tip : str or None
            The frame's name (None: :attr:`default_tip`).

        Returns
        -------
        int

        Raises
        ------
        ModelError
            An unknown frame, or None where the model has no default tip.
        """
        if tip is None:
            tip = self.default_tip
        try:
            return self._frames[tip]
        except (KeyError, TypeError):
            raise ModelError(f"unknown tip/frame {tip!r} (tips: {', '.join(self.tips)})") from None

    def _force(self, F: object) -> np.ndarray:
        if F is None:
            return np.zeros(3)
        a = as_float_array(F, "F", "F_z or 3 numbers Fx, Fy, Fz")
        if a.shape == ():
            return np.array([0.0, 0.0, float(self.vector(np.atleast_1d(a), "F", 1)[0])])  # F_z only (eq. 2.13)
        return self.vector(a, "F", 3)

    def fingertip_position(self, q: np.ndarray, tip: str | None = None) -> np.ndarray:
        """Position of a tip frame in the base frame (forward kinematics).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        tip : str, optional
            The frame (default: :attr:`default_tip`).

        Returns
        -------
        numpy.ndarray
            (3,), m.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        ModelError
            An unknown frame.
        """
        q = self.vector(q, "q")
        fid = self.frame_id(tip)
        pin.framesForwardKinematics(self.pin_model, self.pin_data, q)
        return self.pin_data.oMf[fid].translation.copy()

    def fingertip_jacobian(self, q: np.ndarray, tip: str | None = None) -> np.ndarray:
        """Linear velocity Jacobian J of a tip frame in the base frame (Section 2.2, eq. 2.12: v = J qd).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        tip : str, optional
            The frame (default: :attr:`default_tip`).

        Returns
        -------
        numpy.ndarray
            (3, n), m/rad.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        ModelError
            An unknown frame.
        """
        q = self.vector(q, "q")
        fid = self.frame_id(tip)
        return pin.computeFrameJacobian(self.pin_model, self.pin_data, q, fid, _WORLD)[:3].copy()

    def frame_placement(self, q: np.ndarray, frame: str) -> tuple[np.ndarray, np.ndarray]:
        """Orientation and position of a frame in the base frame.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        frame : str
            The frame's name.

        Returns
        -------
        R : numpy.ndarray
            (3, 3) rotation, the frame's axes in base axes.
        p : numpy.ndarray
            (3,) position, m.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        ModelError
            An unknown frame.
        """
        q = self.vector(q, "q")
        fid = self.frame_id(frame)
        pin.framesForwardKinematics(self.pin_model, self.pin_data, q)
        M = self.pin_data.oMf[fid]
        return M.rotation.copy(), M.translation.copy()

    def frame_jacobian(self, q: np.ndarray, frame: str | None = None, reference: str = "local_world_aligned",
                       dim: int = 6) -> np.ndarray:
        """Jacobian of a frame as Pinocchio's ``getFrameJacobian``.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        frame : str, optional
            The frame (default: :attr:`default_tip`).
        reference : str
            ``"local_world_aligned"`` (default; the frame origin's velocity in base axes), ``"local"`` (frame axes)
            or ``"world"`` (spatial velocity at the base origin), see
            :data:`~alpes_dyn.model.contact.REFERENCE_FRAMES`.
        dim : int
            6 (default): linear and angular rows; 3: linear rows only.

        Returns
        -------
        numpy.ndarray
            (dim, n): [linear (m/rad); angular (1)] rows.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        ModelError
            An unknown frame or reference, or a ``dim`` other than 3 or 6.
        """
        q = self.vector(q, "q")
        fid = self.frame_id(frame)
        if reference not in REFERENCE_FRAMES:
            raise ModelError(f"reference: unknown {reference!r} (expected one of {', '.join(REFERENCE_FRAMES)})")
        if dim not in (3, 6) or isinstance(dim, bool):
            raise ModelError(f"dim: expected 3 (linear rows) or 6 (linear and angular), got {dim!r}")
        J = pin.computeFrameJacobian(self.pin_model, self.pin_data, q, fid, REFERENCE_FRAMES[reference])
        return J[:dim].copy()

    def contact_torque(self, q: np.ndarray, F: object = None, tip: str | None = None,
                       contacts: Any = None) -> np.ndarray:
        """The joint torques of the contact forces: the sum of J_c^T F_c over the contacts (eq. 2.9).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        F : float, array_like or dict, optional
            One force at ``tip``: (3,), N, base axes (a scalar means [0, 0, F_z], eq. 2.13; None: zero). Several:
            the stacked forces/wrenches of ``contacts``, (sum of their dims,); or a dict {frame: force (3,) or
            wrench (6,)} in base axes.
        tip : str, optional
            The frame of one force (default: :attr:`default_tip`).
        contacts : sequence of Contact or str, optional
            Several contacts (:class:`~alpes_dyn.model.contact.Contact` or frame names), F their stacked values.

        Returns
        -------
        numpy.ndarray
            (n,), N m.

        Raises
        ------
        InputError
            ``q`` or F not of its shape, NaN, inf or over 2^40.
        ModelError
            An unknown frame, or ``contacts`` given together with a dict F.
        """
        if isinstance(F, dict):
            if contacts is not None:
                raise ModelError("contacts: give either contacts= with a stacked F or F as a dict, not both")
            for f, x in F.items():
                if np.size(x) not in (3, 6):
                    raise InputError(f"F[{f!r}]: expected a force (3 values) or a wrench (6), got {np.size(x)} values")
            contacts = tuple(Contact(f, int(np.size(x))) for f, x in F.items())
            try:
                F = np.concatenate([np.ravel(np.asarray(x, dtype=float)) for x in F.values()]) if F else np.zeros(0)
            except (TypeError, ValueError):
                raise InputError(f"F: expected numbers for every frame, got {F!r}") from None
        if contacts is None:
            return self.fingertip_jacobian(q, tip).T @ self._force(F)
        cts = as_contacts(contacts)
        F = self.vector(F, "F", sum(c.dim for c in cts))
        q = self.vector(q, "q")
        out = np.zeros(self.n)
        k = 0
        for c in cts:
            J = pin.computeFrameJacobian(self.pin_model, self.pin_data, q, self.frame_id(c.frame),
                                         REFERENCE_FRAMES[c.reference])
            out += J[: c.dim].T @ F[k: k + c.dim]
            k += c.dim
        return out
