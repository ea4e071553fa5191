"""Write ``docs/benchmarks.rst`` and the README's headline table from ``benchmarks/results/`` (issue 36).

A figure is written once: by the benchmark that measured it (``python benchmarks/record.py NAME ARGS``, which
keeps the script's ``--json`` object with the date, the load, the cores, the compile cache's state and the
commit). This script turns those files into the documentation's page (one section per benchmark: what it compares,
from the script's own docstring; the conditions; the figures, from ``benchmarks/_summaries.py``) and the README's
block between ``<!-- headline:start -->`` and ``<!-- headline:end -->``. ``--check`` writes nothing and exits 1
where either file differs from what the results give (``tests/test_benchmark_page.py`` runs it in CI).

    python docs/make_benchmarks.py            # write both
    python docs/make_benchmarks.py --check    # compare only
"""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
RESULTS = BENCH / "results"
PAGE = ROOT / "docs" / "benchmarks.rst"
README = ROOT / "README.md"
START, END = "<!-- headline:start -->", "<!-- headline:end -->"

# the helpers imported from benchmarks/, whose path is taken off again: left on sys.path, its scripts would hide
# packages of their names for whoever imports this module (benchmarks/control.py hid python-control from a test run
# in the same process after tests/test_benchmark_page.py)
sys.path.insert(0, str(BENCH))
try:
    from _handwritten import PAGE as HAND_PAGE  # noqa: E402
    from _handwritten import README_ROWS as HAND_ROWS  # noqa: E402
    from _summaries import HEADLINE_ORDER, HEADLINES, ORDER, SUMMARIES  # noqa: E402
finally:
    sys.path.remove(str(BENCH))


def scripts() -> list[str]:
    """The benchmark scripts' names (``benchmarks/*.py`` but the helpers: names starting with ``_``, ``record``)."""
    return sorted(p.stem for p in BENCH.glob("*.py") if not p.stem.startswith("_") and p.stem != "record")


def what_it_compares(name: str) -> str:
    """What ``benchmarks/<name>.py`` compares, from its docstring on one line: the title paragraph, and the next one
    where it is a whole sentence (ends with a full stop; one that introduces a list is left to the script)."""
    doc = ast.get_docstring(ast.parse((BENCH / f"{name}.py").read_text())) or ""
    paras = [" ".join(p.split()) for p in doc.split("\n\n") if p.strip()]
    keep = paras[:1] + [p for p in paras[1:2] if p.endswith(".")]
    return " ".join(keep)


def load(name: str, results: Path = RESULTS) -> dict | None:
    """The record ``benchmarks/record.py`` kept for ``name`` in ``results``, or None where there is none. A run of
    the same script with other arguments may be kept beside it as ``NAME.PART.json`` (``record.py --output``: e.g.
    ``force_realism.hand.json``), cited by the hand-written text until a summary reads it."""
    path = results / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else None


def generated(name: str, results: Path = RESULTS) -> dict | None:
    """``name``'s record where the page's text comes from it (recorded and summarised), else None."""
    rec = load(name, results)
    return rec if rec is not None and name in SUMMARIES else None


def stale_handwritten(results: Path = RESULTS) -> list[str]:
    """The entries of ``benchmarks/_handwritten.py`` the generated text has replaced (to delete)."""
    return sorted(n for n in set(HAND_PAGE) | set(HAND_ROWS) if generated(n, results) is not None
                  and (n in HAND_PAGE or n in HEADLINES))


def conditions(rec: dict) -> str:
    """The run's conditions as a sentence: date, load at start and end, cores, cache, wall time, commit."""
    a, b = rec["load"]
    args = " ".join(rec["arguments"])
    cmd = f"``python benchmarks/{rec['benchmark']}.py{' ' + args if args else ''}``"
    return (f"{cmd}: {rec['date'].replace('T', ' ').replace('+00:00', ' UTC')}, load {a:.1f} at the start and "
            f"{b:.1f} at the end on {rec['cores']} cores, compile cache {rec['cache']} "
            f"({'compiles excluded where the script says so' if rec['cache'] == 'warm' else 'first compiles included'}), "
            f"{rec['seconds']:.0f} s in all, commit {rec['commit']}")


def _order() -> list[str]:
    names = scripts()
    return [n for n in ORDER if n in names] + [n for n in names if n not in ORDER]


def _section(name: str, results: Path) -> list[str]:
    """One benchmark's section: the title, what it compares, then its recorded figures or the hand-written ones."""
    title = f"``{name}.py``"
    out = [title, "-" * len(title), "", what_it_compares(name), ""]
    rec, gen = load(name, results), generated(name, results)
    if gen is not None:
        bullets = [f"* {x}" for x in SUMMARIES[name](gen["result"])]
        out += ["Measured with " + conditions(gen) + ".", "", *bullets, ""]
        for path in sorted(results.glob(f"{name}.*.json")):  # its other records (NAME.PART.json), each summarised
            key = path.name[: -len(".json")]
            if key in SUMMARIES:
                part = json.loads(path.read_text())
                out += [f"And ``{key[len(name) + 1:]}``, measured with " + conditions(part) + ".", "",
                        *[f"* {x}" for x in SUMMARIES[key](part["result"])], ""]
        return out
    if rec is not None:
        out += [f"*Recorded in* ``benchmarks/results/{name}.json`` *({rec['date'][:10]}) but not yet summarised in* "
                "``benchmarks/_summaries.py``.", ""]
    else:
        out += ["*Not yet recorded by* ``benchmarks/record.py``.", ""]
    if name in HAND_PAGE:
        out += ["The figures as last written by hand: " + HAND_PAGE[name], ""]
    return out


def page(results: Path = RESULTS) -> str:
    """The whole of ``docs/benchmarks.rst`` from the records in ``results``."""
    out = ["Benchmarks", "==========", "",
           ".. This page is generated by docs/make_benchmarks.py from benchmarks/results/*.json: do not edit it;",
           "   run the benchmark with benchmarks/record.py, then the generator.", "",
           "Each script of ``benchmarks/`` prints a table, or one JSON object with ``--json`` (``pip install "
           "\".[bench]\"``). Its latest run, kept by ``benchmarks/record.py`` in ``benchmarks/results/``, gives every "
           "figure below, with the conditions it was measured in: the machine's load (2 cores, often shared with "
           "other jobs: times under load are longer, ratios within one run hold better) and whether the compiled-code "
           "cache was empty (the first compiles are then in the times). Speed goals are ratios against a baseline run "
           "in the same process. The page is written by ``python docs/make_benchmarks.py``; "
           "``tests/test_benchmark_page.py`` fails where it and the records disagree.", ""]
    for name in _order():
        out += _section(name, results)
    return "\n".join(out).rstrip() + "\n"


def headline_block(results: Path = RESULTS) -> str:
    """The README's table of headline figures, one row per name of ``HEADLINE_ORDER``: from its record where it is
    recorded and has a figure in ``HEADLINES``, else the hand-written row of ``benchmarks/_handwritten.py``."""
    rows = ["| what | figure (latest measured) | benchmark |", "| --- | --- | --- |"]
    for name in HEADLINE_ORDER:
        rec = load(name, results)
        if rec is not None and name in HEADLINES:
            what, figure = HEADLINES[name]
            a, b = rec["load"]
            when = f"{rec['date'][:10]}, load {a:.1f}-{b:.1f}, cache {rec['cache']}"
            rows.append(f"| {what} | {figure(rec['result'])} ({when}) | [`{name}.py`](benchmarks/{name}.py) |")
        elif name in HAND_ROWS:
            rows.append(HAND_ROWS[name])
    return "\n".join([START, *rows, END])


def readme(text: str, results: Path = RESULTS) -> str:
    """``text`` (the README) with its headline block replaced; ValueError where the markers are missing."""
    i, j = text.find(START), text.find(END)
    if i < 0 or j < i:
        raise ValueError(f"README.md: the markers {START} ... {END} are missing")
    return text[:i] + headline_block(results) + text[j + len(END):]


def stale(results: Path = RESULTS) -> list[Path]:
    """The files (the page, the README) that differ from what the records in ``results`` give."""
    want = {PAGE: page(results), README: readme(README.read_text(), results)}
    return [p for p, text in want.items() if p.read_text() != text]


def main(argv: list[str]) -> int:
    check = "--check" in argv
    want = {PAGE: page(), README: readme(README.read_text())}
    differ = [p for p, text in want.items() if p.read_text() != text]
    for n in stale_handwritten():
        print(f"benchmarks/_handwritten.py: the entry {n!r} is replaced by its record: delete it")
    if check:
        for p in differ:
            print(f"{p.relative_to(ROOT)} differs from what benchmarks/results/ gives: "
                  "run python docs/make_benchmarks.py")
        return 1 if differ else 0
    for p in differ:
        p.write_text(want[p])
        print(f"wrote {p.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
