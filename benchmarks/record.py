"""Run one benchmark with ``--json`` and keep its result, with the conditions it was measured in (issue 36).

Every figure of the documentation's benchmark page (``docs/benchmarks.rst``) and of the README's headline table
is generated from the files this script writes in ``benchmarks/results/`` (``docs/make_benchmarks.py``), so a
figure is written once: by the benchmark that measured it. Each file holds the script's JSON object under
``result`` and beside it what a reader needs to weigh it:

``benchmark``, ``arguments``
    the script's name and the arguments it was run with (``--json`` added);
``date``
    UTC, ISO 8601, when the run started; ``seconds``: its wall time;
``load``
    the machine's 1-minute load average at the start and the end (``os.getloadavg``), and ``cores``;
``cache``
    ``warm`` where the compiled-code cache (:func:`alpes_dyn.simulation.codegen.cache_dir`) held libraries when
    the run started, else ``cold``: whether compiles are in the times;
``commit``
    the checkout's ``git describe --always --dirty``, or null outside a git checkout.

A run that fails (non-zero exit, or no JSON object on its last line) writes nothing and exits 1 with the
script's last lines; the file is replaced only once the new one is complete (written beside it, then renamed).

    python benchmarks/record.py NAME [ARGS...]      # e.g. realism --seeds 401-420 --cases all --no-rigid
    python benchmarks/record.py NAME --output FILE [ARGS...]
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def _cache_state() -> str:
    """``warm`` if the compiled-code cache holds a shared library, else ``cold``."""
    try:
        from alpes_dyn.simulation.codegen import cache_dir
        d = cache_dir()
    except Exception:  # noqa: BLE001 -- no usable cache folder: every run compiles
        return "cold"
    return "warm" if d.is_dir() and any(d.rglob("*.so")) else "cold"


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(HERE), "describe", "--always", "--dirty"], capture_output=True,
                             text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def record(name: str, args: list[str], output: Path | None = None) -> Path:
    """Run ``benchmarks/<name>.py --json ARGS``, write its result with the run's conditions to ``output``
    (default ``benchmarks/results/<name>.json``) and return the path; :class:`RuntimeError` with the script's
    last lines where it fails."""
    script = HERE / f"{name}.py"
    if not script.is_file() or name.startswith("_") or name == "record":
        raise ValueError(f"benchmark: no script benchmarks/{name}.py")
    output = output or RESULTS / f"{name}.json"
    argv = [a for a in args if a != "--json"]
    meta = {"benchmark": name, "arguments": argv, "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "cores": os.cpu_count(), "cache": _cache_state(), "commit": _commit()}
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(script), "--json", *argv], capture_output=True, text=True)
    lines = proc.stdout.strip().splitlines()
    try:
        result = json.loads(lines[-1]) if proc.returncode == 0 and lines else None
    except json.JSONDecodeError:
        result = None
    if not isinstance(result, dict):
        tail = "\n".join((proc.stderr.strip().splitlines() or lines)[-5:])
        raise RuntimeError(f"{name}: exit {proc.returncode}, no JSON object on the last line:\n{tail}")
    meta.update({"seconds": round(time.perf_counter() - t0, 1), "load": [round(load0, 2), round(os.getloadavg()[0], 2)],
                 "result": result})
    output.parent.mkdir(parents=True, exist_ok=True)
    tmp = output.with_suffix(output.suffix + ".part")
    tmp.write_text(json.dumps(meta, indent=1, sort_keys=False) + "\n")
    tmp.replace(output)
    return output


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    name, rest = argv[0], argv[1:]
    output = None
    if "--output" in rest:
        i = rest.index("--output")
        if i + 1 >= len(rest):
            print("record.py: --output needs a file", file=sys.stderr)
            return 2
        output = Path(rest[i + 1])
        del rest[i:i + 2]
    try:
        path = record(name, rest, output)
    except (ValueError, RuntimeError) as e:
        print(f"record.py: {e}", file=sys.stderr)
        return 1 if isinstance(e, RuntimeError) else 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
