"""Table cells shared by the benchmark scripts (run as ``python benchmarks/<name>.py``: this folder is on the path)."""


def cell(x, fmt: str) -> str:
    """``x`` formatted with ``fmt`` (e.g. ``"7.2%"``), or ``n/a`` right-aligned to its width where ``x`` is None."""
    width = int(fmt.split(".")[0])
    return "n/a".rjust(width) if x is None else format(x, fmt)


def median_worst(st: dict, fmt: str = "5.2f") -> str:
    """A summary's ``{"median", "worst"}`` as ``median / worst`` formatted with ``fmt``, or ``--`` where none."""
    return "--" if st["median"] is None else f"{st['median']:{fmt}} / {st['worst']:{fmt}}"


def case_notes(s: dict) -> list[str]:
    """The lines under a realism case's row: its silent misses, its refusals (verdict) and the runs that raised."""
    return ([f"    silent miss seed {m['seed']}: EKF {m['ekf_deg']:.2f} deg, m {m['m_pct']:.1f} %"
             for m in s["silent_misses"]]
            + [f"    refused seed {r['seed']}: {r['verdict'][:150]}" for r in s["refusals"]]
            + [f"    raised seed {seed}: {err[:150]}" for seed, err in s["errors"]])
