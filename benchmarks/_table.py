"""Table cells shared by the benchmark scripts (run as ``python benchmarks/<name>.py``: this folder is on the path)."""


def cell(x, fmt: str) -> str:
    """``x`` formatted with ``fmt`` (e.g. ``"7.2%"``), or ``n/a`` right-aligned to its width where ``x`` is None."""
    width = int(fmt.split(".")[0])
    return "n/a".rjust(width) if x is None else format(x, fmt)
