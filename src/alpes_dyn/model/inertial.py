"""Physical validation of the inertials of a URDF (mass and rotational inertia of each link).

:func:`check_inertials` is run by every :class:`~alpes_dyn.Model` on its URDF. For each ``<link>``
with an ``<inertial>``:

* the mass and the six inertia entries (each given) and the ``<origin>``'s numbers are finite numbers as
  urdfdom reads them (no blank after a number, no ``1_0``): where urdfdom cannot read an inertial, Pinocchio
  builds the link massless without an error;
* the mass is >= 0; a link of zero mass must have a zero inertia too (a *massless* link, like a
  link without ``<inertial>``): a zero mass with a non-zero inertia is not a body;
* the rotational inertia (about the COM, kg m^2) is positive semidefinite: its principal moments
  I1 <= I2 <= I3 are >= 0 (a point mass, all zero, and a thin rod, I1 = 0, are allowed limits);
* ``mode="strict"`` (the default) also asks the triangle inequality I1 + I2 >= I3 that the
  principal moments of every real mass distribution satisfy (the rule of MuJoCo's compiler);
  ``mode="relaxed"`` skips it, for published descriptions that break it but whose dynamics is
  still well defined (e.g. the Allegro hand's URDF in example-robot-data, by up to 25 %).

Both comparisons allow for the rounding of the printed values: a tolerance of 1e-6 times the
larger of the trace and m (1 mm)^2. A mass matrix that is singular because a joint moves only
massless links is caught by the model itself (:class:`~alpes_dyn.Model`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from ..checks import urdf_number_problem
from ..errors import ModelError

__all__ = ["INERTIA_MODES", "check_inertials"]

INERTIA_MODES: tuple[str, ...] = ("strict", "relaxed")
_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _number(text: str | None, what: str) -> float:
    """An inertial's number as urdfdom reads it (:func:`~alpes_dyn.checks.urdf_number_problem`): where urdfdom
    cannot read one, Pinocchio builds the link massless without an error, so it is refused here, named."""
    if text is None:
        raise ModelError(f"{what}: missing (URDF readers then drop the link's whole inertial: give it)")
    try:
        x = float(text)
    except ValueError:
        raise ModelError(f"{what}: expected a number, got {text!r}") from None
    if not math.isfinite(x):
        raise ModelError(f"{what}: must be finite, got {text!r}")
    problem = urdf_number_problem(text)
    if problem is not None:
        raise ModelError(f"{what}: {text!r} {problem}")
    return x


def _check_origin(inertial: ET.Element, name: str) -> None:
    """The ``<origin xyz rpy>`` of an ``<inertial>``: three URDF numbers each (blank-separated), where given."""
    origin = inertial.find("origin")
    for attr in ("xyz", "rpy"):
        text = origin.get(attr) if origin is not None else None
        if text is None:
            continue
        parts = text.split()
        if len(parts) != 3:
            raise ModelError(f"{name}: inertial origin {attr}={text[:40]!r}: expected 3 numbers, got {len(parts)} "
                             "(URDF readers then drop the link's whole inertial)")
        for part in parts:
            _number(part, f"{name}: inertial origin {attr}")


def check_inertials(urdf: str, mode: str = "strict") -> None:
    """Raise :class:`~alpes_dyn.ModelError` naming the first link whose inertial is not physical.

    Parameters
    ----------
    urdf : str
        URDF text.
    mode : str, optional
        ``"strict"`` (default; with the triangle inequality) or ``"relaxed"`` (:data:`INERTIA_MODES`; see the
        module).

    Raises
    ------
    ModelError
        An unknown mode, or the first link whose inertial is not physical, named.
    """
    if mode not in INERTIA_MODES:
        raise ModelError(f"check_inertia: unknown mode {mode!r} (expected one of {', '.join(INERTIA_MODES)})")
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise ModelError(f"URDF is not well-formed XML ({exc})") from None
    for link in root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        name = f"link {link.get('name')!r}"
        mass_el = inertial.find("mass")
        m = _number(mass_el.get("value") if mass_el is not None else None, f"{name}: mass")
        if m < 0:
            raise ModelError(f"{name}: mass must be >= 0 kg, got {m:g}")
        _check_origin(inertial, name)
        el = inertial.find("inertia")  # absent: a point mass, as Pinocchio builds it (all six then 0)
        v = dict(zip(_KEYS, (_number(el.get(k), f"{name}: inertia {k}") if el is not None else 0.0 for k in _KEYS)))
        I = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]])
        if m == 0:
            if np.any(I != 0):
                raise ModelError(f"{name}: zero mass with a non-zero inertia (a massless link has both zero)")
            continue
        ev = np.linalg.eigvalsh(I)
        tol = 1e-6 * max(float(ev.sum()), m * 1e-6)
        moments = ", ".join(f"{x:.4g}" for x in ev)
        if ev[0] < -tol:
            raise ModelError(f"{name}: inertia is not positive semidefinite (principal moments {moments} kg m^2)")
        if mode == "strict" and ev[0] + ev[1] < ev[2] - tol:
            raise ModelError(f"{name}: principal moments {moments} kg m^2 break the triangle inequality "
                             "I1 + I2 >= I3 of a real body (check_inertia='relaxed' accepts them)")
