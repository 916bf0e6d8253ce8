"""Timing helpers shared by the benchmark scripts (run as `python benchmarks/bench_*.py`).

The same script gives figures several times apart on two of "the same" cloud VMs (the same
marketing name of CPU either way; docs/benchmarks.md has the numbers), and a VM's host may lend
its cores to other guests during a run. So each benchmark prints `machine_line` (CPU generation
and vector ISA, not only the marketing name; from the library's one provenance record,
`jaxplan.core.provenance`) and, when it ends, `Steal.summary` (the share of CPU time the
hypervisor gave to others while it ran): figures from different runs compare only when both agree.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any, Callable

from jaxplan.core.provenance import cpu_info, machine_line

__all__ = ["median_time", "cpu_info", "machine_line", "Steal"]


def median_time(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time (s) of ``repeat`` calls of ``fn``."""
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def _cpu_ticks() -> tuple[int, int] | None:
    """(steal, total) jiffies of all CPUs since boot, or None off Linux."""
    try:
        parts = Path("/proc/stat").read_text().splitlines()[0].split()
        ticks = [int(x) for x in parts[1:9]]  # user nice system idle iowait irq softirq steal
        return ticks[7], sum(ticks)
    except (OSError, IndexError, ValueError):  # no /proc, or a kernel without the steal column
        return None


class Steal:
    """Share of CPU time the hypervisor gave to other guests between construction and `summary`."""

    def __init__(self) -> None:
        self._start = _cpu_ticks()

    def fraction(self) -> float | None:
        end = _cpu_ticks()
        if self._start is None or end is None or end[1] <= self._start[1]:
            return None
        return (end[0] - self._start[0]) / (end[1] - self._start[1])

    def summary(self, fraction: float | None = None) -> str:
        """``fraction``: a value `fraction` returned before (so a printed and a stored figure agree)."""
        f = self.fraction() if fraction is None else fraction
        if f is None:
            return "CPU steal during the run: not measurable here"
        note = " (the host lent these cores to other guests: figures are low)" if f > 0.02 else ""
        return f"CPU steal during the run: {100 * f:.1f} %{note}"


def blocking(fn: Callable, args: tuple) -> Callable[[], Any]:
    """A zero-argument call of ``fn(*args)`` that waits for JAX's asynchronous results (what `median_time` times)."""
    import jax

    return lambda: jax.block_until_ready(fn(*args))
