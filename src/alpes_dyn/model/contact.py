"""Contacts at frames: a force or a wrench, in one of Pinocchio's reference frames (eq. 2.9, 2.12, 2.13).

A :class:`Contact` names where a contact acts and how its force is expressed; its joint torque is J^T F with J
the frame Jacobian in the same reference (:meth:`alpes_dyn.Model.contact_torque`, and the symbolic and
state-space paths, which take the same objects).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pinocchio as pin

from ..errors import ModelError

__all__ = ["Contact", "REFERENCE_FRAMES", "as_contacts"]

REFERENCE_FRAMES: dict[str, pin.ReferenceFrame] = {
    "world": pin.ReferenceFrame.WORLD, "local": pin.ReferenceFrame.LOCAL,
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
}
"""Pinocchio's reference frames by name: a frame's velocity (v, w) or a wrench (f, tau) expressed
``"local"`` in the frame's own axes at its origin, ``"local_world_aligned"`` at its origin in the base
(world) axes, ``"world"`` at the base origin in the base axes (spatial velocity)."""


@dataclass(frozen=True)
class Contact:
    """A contact at a frame: a force (``dim=3``, N, applied at the frame origin) or a wrench
    (``dim=6``: [force (N); torque (N m)], Pinocchio's order) expressed in ``reference``
    (:data:`REFERENCE_FRAMES`; default ``"local_world_aligned"``: base axes, as eq. 2.13).
    Its joint torque is J^T F with J the frame Jacobian in the same reference (eq. 2.9)."""

    frame: str
    dim: int = 3
    reference: str = "local_world_aligned"

    def __post_init__(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise ModelError(f"contact frame: expected a frame name, got {self.frame!r}")
        if self.dim not in (3, 6) or isinstance(self.dim, bool):
            raise ModelError(f"contact {self.frame!r}: dim must be 3 (force) or 6 (wrench), got {self.dim!r}")
        if self.reference not in REFERENCE_FRAMES:
            raise ModelError(f"contact {self.frame!r}: unknown reference {self.reference!r} "
                             f"(expected one of {', '.join(REFERENCE_FRAMES)})")

    @property
    def names(self) -> tuple[str, ...]:
        """Labels of its components: F_x_<frame>, ... and, for a wrench, M_x_<frame>, ..."""
        comps = ("F_x", "F_y", "F_z", "M_x", "M_y", "M_z")[: self.dim]
        return tuple(f"{c}_{self.frame}" for c in comps)


def as_contacts(contacts: Any) -> tuple[Contact, ...]:
    """A tuple of :class:`Contact` from Contacts and frame names (a name is a 3-D force in base axes).

    Parameters
    ----------
    contacts : Contact or str or sequence of them
        The contacts.

    Returns
    -------
    tuple of Contact
        In order.
    """
    if isinstance(contacts, (str, Contact)):
        contacts = (contacts,)
    if not isinstance(contacts, (list, tuple)):
        raise ModelError(f"contacts: expected a list of Contact or frame names, got {contacts!r}")
    out = tuple(c if isinstance(c, Contact) else Contact(c) for c in contacts)
    frames = [c.frame for c in out]
    dup = next((f for f in frames if frames.count(f) > 1), None)
    if dup is not None:
        raise ModelError(f"contacts: frame {dup!r} appears twice")
    return out
