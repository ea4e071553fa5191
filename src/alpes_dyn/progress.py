"""A minimal progress bar on stderr, shared by the compiled loops and the identification."""

from __future__ import annotations

import sys
import time

__all__: list[str] = []

class _Progress:
    """A minimal progress bar on stderr (no dependency): ``[#####     ] 50% 1.2 s``."""

    def __init__(self, total: int, label: str, enabled: bool) -> None:
        self.total, self.label, self.enabled = total, label, enabled
        self.t0 = time.perf_counter()
        self.done = 0

    def update(self, n: int) -> None:
        self.done += n
        if self.enabled:
            frac = self.done / self.total
            bar = "#" * int(30 * frac)
            sys.stderr.write(f"\r{self.label} [{bar:<30s}] {100 * frac:3.0f}% {time.perf_counter() - self.t0:6.1f} s")
            sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()
