"""No lab notes in ``src/`` (issue 52): no line of the library cites a date, a machine load or a seed number. A
docstring says what a thing is; the measurements that justify a choice belong in the benchmarks' records
(``benchmarks/results/*.json``), cited by name."""

from __future__ import annotations

import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "alpes_dyn"

NOTE = re.compile(
    r"\b20\d\d-\d\d-\d\d\b"  # a date
    r"|\bloads? (?:of |about |near |around |~)?\d"  # a machine load ("load 1.8-2.6", "load about 1.5")
    r"|(?<!-)\bseeds? \d"  # a seed number ("seed 13", "seeds 40-43"); not a command line's --seed 1
    r"|(?<!-)\bdraws? \d+ ?-\d")  # draws named by their seeds ("draws 1-30"); not a count ("--draws 8")
"""What a lab note looks like."""

# The modules whose notes are still to be moved to the benchmarks' records, with how many lines: the count only
# falls (test_the_allow_list_only_shrinks), no module joins.
NOT_YET: dict[str, int] = {}


def notes() -> dict[str, list[tuple[int, str]]]:
    """Module path (relative to src/alpes_dyn) -> its lines (number, text) that look like a lab note."""
    out: dict[str, list[tuple[int, str]]] = {}
    for path in sorted(SRC.rglob("*.py")):
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if NOTE.search(line):
                out.setdefault(str(path.relative_to(SRC)), []).append((i, line.strip()))
    return out


def test_no_dates_loads_or_seed_numbers_in_src():
    found = notes()
    over = {m: lines for m, lines in found.items() if len(lines) > NOT_YET.get(m, 0)}
    assert not over, "lab notes in src/: " + "; ".join(f"{m}:{i}: {t[:80]}" for m, ls in over.items() for i, t in ls)


def test_the_allow_list_only_shrinks():
    found = notes()
    stale = {m: n for m, n in NOT_YET.items() if len(found.get(m, ())) < n}
    assert not stale, f"fewer notes than allowed: lower NOT_YET to {({m: len(found.get(m, ())) for m in stale})}"


def test_the_pattern_finds_each_kind():
    """The three kinds are found, in the forms the library used; a command line's ``--seed 1`` is not a note."""
    for text in ("(finger3 seed 21, 2026-12-05, load 5)", "seeds 40-43", "load about 1.5", "2026-12-03",
                 "load 1.8-2.6", "finger3's draws 1-30"):
        assert NOTE.search(text), text
    for text in ("alpes-dyn sweep --seed 1 -o x.csv", "the loads of the joints", "a seed >= 0",
                 "alpes-dyn sweep --draws 8 --seed 1", "the test draws 1,500"):
        assert not NOTE.search(text), text


TIMING = re.compile(
    r"\btook (?:about |~|only )?\d"  # a run's time or size ("took 30 s", "took about 25 s")
    r"|\b\d+-core machine"  # the machine it was measured on
    r"|\bon a (?:loaded|busy|quiet) machine")
"""What a measurement argued in a docstring looks like: it belongs in a benchmark record, cited by its file and key."""


def test_no_timings_in_src():
    """Times and sizes measured on a machine are not argued in ``src/`` (issue 52: cite the benchmark record)."""
    found = [f"{path.relative_to(SRC)}:{i}: {line.strip()[:80]}" for path in sorted(SRC.rglob("*.py"))
             for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if TIMING.search(line)]
    assert not found, "measurements in src/ (cite the benchmark record): " + "; ".join(found)


def test_the_timing_pattern_finds_each_kind():
    for text in ("gcc took 30 s", "it took about 25 s of gcc", "(2-core machine)", "measured on a loaded machine"):
        assert TIMING.search(text), text
    for text in ("the fit took the pair whose chord", "a machine with 2 cores", "took its worst joint",
                 "``benchmarks/results/observer_step.json`` (its rows' ``c_us``)"):
        assert not TIMING.search(text), text
