"""Whether a parameter file may be used: a file written by ``alpes-dyn identify --force`` records
``trustworthy = false`` for the chains whose fit did not converge or whose model is not adequate
(``[identification.<chain>]``, :attr:`~alpes_dyn.model.params.HandParams.untrusted`); the commands and loaders that
use a file's values (``estimate``, ``codegen``, ``control``; ``estimate_recording``, ``run_control``,
``run_hand_control``, ``scenario_filter``, ``block_controller``) refuse it with one line giving the reason it
records, unless forced (:func:`check_trusted`)."""

from __future__ import annotations

from typing import Any

from ..errors import ModelError
from .params import HandParams

__all__ = ["check_trusted", "fitted_friction", "untrusted_reason"]


def untrusted_reason(record: dict[str, Any]) -> str:
    """Why a fit's record (:data:`IDENTIFICATION_FIELDS`, or a spec's ``[identified]``) is not to be trusted, in its
    own words: the fit that did not converge (its stop reason), the adequacy verdict.

    Parameters
    ----------
    record : dict
        The fit's record (``converged``, ``stop``, ``adequate``, ``verdict``).

    Returns
    -------
    str
        The reasons, ``"; "``-joined (``"marked trustworthy = false"`` where the record gives none).
    """
    why = ([f"the fit did not converge ({record.get('stop', '')})"] if record.get("converged") is False else []) + (
        [record.get("verdict") or "the model is not adequate"] if record.get("adequate") is False else [])
    return "; ".join(why) or "marked trustworthy = false"


def check_trusted(params: HandParams, force: bool = False, name: str = "params",
                  hint: str = "force=True uses it anyway") -> str:
    """Refuse a parameter file marked not trustworthy (:attr:`HandParams.untrusted`) unless ``force``.

    Parameters
    ----------
    params : HandParams
        The loaded file.
    force : bool
        Use it anyway: the note of what is not to be trusted is returned instead.
    name : str
        The field or option the error names (``params``, ``--params``).
    hint : str
        How to force it, at the end of the line (the API's ``force=True``, the CLI's ``--force``).

    Returns
    -------
    str
        ``""`` for a trusted file; when forced, one line: ``<path> is NOT trustworthy (<chain>: <why>)``.

    Raises
    ------
    ModelError
        ``<name>: <path> is marked not trustworthy (<chain>: <why>); <hint>``, the reason as the file records it.
    """
    why = {chain: untrusted_reason(params.identification[chain]) for chain in params.untrusted}
    if not why:
        return ""
    where = repr(params.path) if params.path else "the parameter set"
    text = "; ".join(f"{c}: {w}" for c, w in why.items())
    if not force:
        raise ModelError(f"{name}: {where} is marked not trustworthy ({text}); {hint}")
    return f"{where} is NOT trustworthy ({text})"


def fitted_friction(params: HandParams, chain: str) -> bool | None:
    """Whether the model fitted to ``chain`` had friction (eq. 2.6-2.7), as its ``[identification.<chain>]``
    record says (``identify`` writes ``friction``): what ``estimate`` and ``codegen`` give the observer's model
    unless ``--friction`` / ``--no-friction`` override it.

    Parameters
    ----------
    params : HandParams
        The loaded file.
    chain : str
        ``finger`` (a finger model of the shared values), a finger's name (its own record, else the shared
        ``finger`` one, whose values it takes) or ``thumb``.

    Returns
    -------
    bool or None
        The record's ``friction``; None where the file has no record for the chain or the record does not say
        (a file written by hand, the shipped one, or by an ``identify`` before the field).
    """
    for key in (chain, "finger") if chain not in ("finger", "thumb") else (chain,):
        said = params.identification.get(key, {}).get("friction")
        if said is not None:
            return bool(said)
    return None
