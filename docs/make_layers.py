"""Draw ``docs/_static/layers.png``, the floors of alpes_dyn, from the package as it is.

One band per floor (the floors of ``tests/test_architecture.py``, the ground at the bottom), one box per module
inside it (a floor split into sub-packages, estimation's, room by room, each labelled), its width the module's share of the floor's lines, labelled with its name and line count; the number
of imports from each floor to each floor below is written on the right. Run from the repository's root:

    python docs/make_layers.py
"""

from __future__ import annotations

import ast
import sys
from collections import Counter
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "alpes_dyn"
sys.path.insert(0, str(ROOT / "tests"))
from test_architecture import ESTIMATION_ROOMS, FLOORS, floor_of, module_imports  # noqa: E402

BASE = ("errors", "checks", "limits", "fileio", "progress", "rebuild", "_moved")
ROOMS = {"estimation": ESTIMATION_ROOMS}
"""Floors split into sub-packages: their rooms in order (drawn side by side, labelled, shaded in turn)."""


def modules() -> dict[str, list[tuple[str, int]]]:
    """floor -> [(module, lines)], the package's front door and the old-path shims left out."""
    out: dict[str, list[tuple[str, int]]] = {f: [] for f in FLOORS}
    for path in sorted(PACKAGE.rglob("*.py")):
        dotted = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if dotted == "__init__" or dotted.endswith("__main__"):
            continue
        text = path.read_text(encoding="utf-8")
        if "." not in dotted and dotted not in BASE and dotted not in FLOORS and "_moved" in text:
            continue  # an old 0.1 module path, an alias of its new place
        try:
            floor = floor_of(dotted)
        except AssertionError:
            continue
        parts = dotted.split(".")
        if parts[-1] == "__init__" and len(parts) > 2:
            continue  # a sub-package's docstring (estimation's rooms)
        name = "/".join(parts[1:]) if len(parts) > 2 else parts[-1]  # a room's module: "room/module"
        out[floor].append((name, len(text.splitlines())))
    return out


def arrows() -> Counter:
    """(floor, lower floor) -> number of module imports between them."""
    count: Counter = Counter()
    for path in PACKAGE.rglob("*.py"):
        me = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        if me == "__init__":
            continue
        try:
            mine = floor_of(me)
        except AssertionError:
            continue
        for target in module_imports(path):
            try:
                theirs = floor_of(target)
            except AssertionError:
                continue
            if theirs != mine:
                count[(mine, theirs)] += 1
    return count


def main() -> None:
    mods, links = modules(), arrows()
    fig, ax = plt.subplots(figsize=(16, 10))
    floors = [f for f in FLOORS if mods[f]]
    h, gap = 1.0, 0.35
    for level, floor in enumerate(floors):
        y = level * (h + gap)
        # modules by size; in a floor with rooms (sub-packages), room by room in the floor's order of rooms
        rank = {r: i for i, r in enumerate(ROOMS.get(floor, ()))}
        items = sorted(mods[floor], key=lambda m: (rank.get(m[0].split("/")[0], -1) if "/" in m[0] else -1, -m[1]))
        total = sum(n for _, n in items)
        ax.add_patch(Rectangle((0, y), 100, h, facecolor="#e8eef5", edgecolor="#2a5d9f", lw=1.5))
        label = "base" if floor == "base" else f"{floor}/"
        ax.text(0.5, y + h - 0.12, f"{label}  {total} lines", fontsize=11, weight="bold", va="top")
        x, room = 0.5, None
        for name, n in items:
            w = 99.0 * n / total
            here = name.split("/")[0] if "/" in name else None
            if here != room:
                room = here
                if here is not None:
                    ax.text(x + 0.3, y + 0.02, f"{here}/", fontsize=8, style="italic", va="bottom", color="#2a5d9f")
            shade = "#c3d5e8" if here is None or rank.get(here, 0) % 2 == 0 else "#d9c9e6"
            ax.add_patch(Rectangle((x, y + 0.2), w - 0.2, h - 0.57, facecolor=shade, edgecolor="white", lw=1.0))
            if w > 3.2:
                label = name.split("/")[-1]
                ax.text(x + 0.3, y + h - 0.42, f"{label}\n{n}", fontsize=7.5 if w > 6 else 6, va="top")
            x += w
        below = ", ".join(f"{t}: {links[(floor, t)]}" for t in reversed(floors[:level]) if links[(floor, t)])
        if below:
            ax.text(100.8, y + h / 2, f"imports from\n{below}", fontsize=7.5, va="center")
    ax.set_xlim(0, 118)
    ax.set_ylim(-0.2, len(floors) * (h + gap))
    ax.axis("off")
    ax.set_title("alpes_dyn: the floors, the ground at the bottom; a module imports its own floor and the floors "
                 "below (tests/test_architecture.py). Box width: the module's lines in its floor.", fontsize=11)
    out = ROOT / "docs" / "_static" / "layers.png"
    fig.savefig(out, dpi=100, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
