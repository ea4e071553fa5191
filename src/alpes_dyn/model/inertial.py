"""Physical validation of the inertials of a URDF (mass and rotational inertia of each link).

:func:`check_inertials` is run by every :class:`~alpes_dyn.Model` on its URDF. For each ``<link>``
with an ``<inertial>``:

* the mass and the six inertia entries are finite numbers;
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

from ..errors import ModelError

__all__ = ["INERTIA_MODES", "check_inertials"]

INERTIA_MODES: tuple[str, ...] = ("strict", "relaxed")
_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _number(text: str | None, what: str) -> float:
    try:
        x = float(text if text is not None else "0")
    except ValueError:
        raise ModelError(f"{what}: expected a number, got {text!r}") from None
    if not math.isfinite(x):
        raise ModelError(f"{what}: must be finite, got {text!r}")
    return x


def check_inertials(urdf: str, mode: str = "strict") -> None:
    """Raise :class:`~alpes_dyn.ModelError` naming the first link whose inertial is not physical.

    Parameters
    ----------
    urdf: URDF text. mode: ``"strict"`` (with the triangle inequality) or ``"relaxed"``; see the module.
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
        el = inertial.find("inertia")
        v = dict(zip(_KEYS, (_number(el.get(k) if el is not None else None, f"{name}: inertia {k}") for k in _KEYS)))
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
