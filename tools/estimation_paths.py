"""Rewrite the module paths of ``alpes_dyn.estimation`` from before its split into rooms (issue 36) in given files.

For a branch started before the split: after ``git merge``, take the branch's side of a conflicted file
(``git checkout --theirs FILE`` or ``--ours``, whichever holds the branch's work), run this on it, check the diff.
It rewrites as below and leaves a path already new as it is, but for one case it cannot tell: a bare
``alpes_dyn.estimation.observers`` (``.identification``, ``.cexport``) with no attribute after it, which was the module
and is now the room, is read as the old module (check those lines in the diff):

* dotted paths -- ``alpes_dyn.estimation.adapt``, ``..estimation.replay``, ``~alpes_dyn.estimation.kkt.factorize``,
  ``alpes_dyn.estimation.identification.identify`` -- to the module in its room
  (``alpes_dyn.estimation.experiments.adapt``, ..., ``alpes_dyn.estimation.identification.identification.identify``);
* file paths ``estimation/adapt.py`` -> ``estimation/experiments/adapt.py``;
* ``from alpes_dyn.estimation import adequacy, trim`` -> one import per room;
* in a module of a room (``src/alpes_dyn/estimation/<room>/*.py``), the relative imports: ``from ..errors`` ->
  ``from ...errors`` (the floors are one level further up), ``from .replay`` -> ``from ..observers.replay`` where the
  sibling now lives in another room.

    python tools/estimation_paths.py FILE [FILE ...]        # rewrite in place, print the files changed
    python tools/estimation_paths.py --check FILE [...]     # exit 1 where a file would change

Delete this with the old paths' deprecation (``alpes_dyn.estimation.MOVED``), in the next release.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOMS: dict[str, tuple[str, ...]] = {
    "experiments": ("recording", "design", "draws", "excursion", "multisine", "trim", "experiment", "adapt",
                    "hand_experiment"),
    "observers": ("observers", "covariance", "blocks", "scenario", "replay"),
    "identification": ("identification", "kkt", "shooting", "gauss_newton", "bounds", "fit_result",
                       "identified_spec", "adequacy", "harmonics", "observer_check", "effects"),
    "cexport": ("cexport", "cexport_ekf", "cexport_chains"),
}
ROOM_OF = {m: room for room, mods in ROOMS.items() for m in mods}
_NAMES = "|".join(sorted(ROOM_OF, key=len, reverse=True))
_ROOM_NAMES = "|".join(ROOMS)


def _dotted(m: re.Match) -> str:
    return f"estimation.{ROOM_OF[m.group(1)]}.{m.group(1)}"


def _from_import(m: re.Match) -> str:
    """``from alpes_dyn.estimation import a, b as c``: one import per room; names not modules left as they are."""
    prefix, names, tail = m.group(1), m.group(2), m.group(3)
    items = [x.strip() for x in names.split(",") if x.strip()]
    if not all(it.split(" as ")[0].strip() in ROOM_OF for it in items):
        return m.group(0)  # a name of the package (identify, ...) or a room: already new
    rooms: dict[str, list[str]] = {}
    for it in items:
        rooms.setdefault(ROOM_OF[it.split(" as ")[0].strip()], []).append(it)
    indent = re.match(r"\s*", prefix).group(0)
    lines = [f"{prefix.strip()}.{room} import {', '.join(its)}" for room, its in rooms.items()]
    return indent + ("\n" + indent).join(lines) + tail


def rewrite_paths(text: str) -> str:
    """The dotted and file paths, and ``from alpes_dyn.estimation import <modules>``."""
    # estimation.<module>, not where it is a room already: followed by .<a module of a room> (observers.replay) or
    # by `` import <a module of a room>`` (from alpes_dyn.estimation.observers import replay)
    text = re.sub(rf"(?<![\w/])estimation\.({_NAMES})\b(?!/)(?!\.(?:{_NAMES})\b)(?! import (?:{_NAMES})\b)", _dotted,
                  text)
    text = re.sub(rf"estimation/({_NAMES})\.py\b", lambda m: f"estimation/{ROOM_OF[m.group(1)]}/{m.group(1)}.py", text)
    return re.sub(r"^([ \t]*from (?:alpes_dyn|\.+)\.?estimation) import ([\w ,]+?)([ \t]*(?:#.*)?)$", _from_import,
                  text, flags=re.M)


def rewrite_relative(text: str, room: str) -> str:
    """The relative imports of a module of ``room``: the floors one level up, a sibling in another room."""
    def one(m: re.Match) -> str:
        dots, mod = m.group(1), m.group(2)
        head = mod.split(".")[0]
        if len(dots) == 1 and head in ROOM_OF and ROOM_OF[head] != room:
            return f"from ..{ROOM_OF[head]}.{mod} import"
        if len(dots) == 2 and head not in ROOMS:
            return f"from ...{mod} import"
        return m.group(0)
    return re.sub(r"from (\.+)([\w.]+) import", one, text)


def rewrite(path: Path) -> str:
    """The text of ``path`` with the old paths rewritten."""
    text = path.read_text(encoding="utf-8")
    parts = path.resolve().parts
    if path.suffix == ".py" and len(parts) > 3 and parts[-4:-2] == ("alpes_dyn", "estimation") and parts[-2] in ROOMS:
        text = rewrite_relative(text, parts[-2])
    return rewrite_paths(text)


def main(argv: list[str]) -> int:
    check = "--check" in argv
    files = [Path(a) for a in argv if a != "--check"]
    changed = []
    for path in files:
        new = rewrite(path)
        if new != path.read_text(encoding="utf-8"):
            changed.append(path)
            if not check:
                path.write_text(new, encoding="utf-8")
    for path in changed:
        print(path)
    return 1 if check and changed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
