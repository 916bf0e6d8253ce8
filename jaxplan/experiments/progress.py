"""Progress of a long run on stderr: one rewritten line on a terminal, one line per chunk otherwise."""

from __future__ import annotations

import math
import sys
import time

__all__ = ["clock", "Progress"]

def clock(s: float) -> str:
    """Seconds as ``H:MM:SS``."""
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class Progress:
    """``NAME: done/total trials (pct) | chunk k/K | elapsed | left ~`` on stderr (one rewritten line on a TTY)."""

    def __init__(self, name: str, total: int, done: int, chunks: int, enabled: bool):
        self.name, self.total, self.start_done, self.chunks, self.enabled = name, total, done, chunks, enabled
        self.t0 = time.perf_counter()
        self.tty = sys.stderr.isatty()

    def update(self, done: int, chunk: int, what: str) -> None:
        if not self.enabled:
            return
        el = time.perf_counter() - self.t0
        new = done - self.start_done
        left = el / new * (self.total - done) if new else float("nan")
        msg = (f"{self.name}: {done}/{self.total} trials ({done / max(self.total, 1):.0%}) | chunk {chunk}/"
               f"{self.chunks} {what} | elapsed {clock(el)} | left ~{clock(left) if math.isfinite(left) else '?'}")
        print(("\r" + msg.ljust(110)) if self.tty else msg, end="" if self.tty else "\n", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.enabled and self.tty:
            print(file=sys.stderr, flush=True)
