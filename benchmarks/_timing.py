"""Timing and machine-description helpers shared by the benchmark scripts (run as `python benchmarks/bench_*.py`).

The same script gives figures 2-4x apart on two of "the same" cloud VMs (2 cores named
"AMD EPYC" either way; measured in two sessions of this project: 45 vs 94 M ant-steps/s,
73 vs 335 M DWA points/s), and a VM's host may lend its cores to other guests during a run.
So each benchmark prints `machine_line` (CPU generation and vector ISA, not only the
marketing name) and, when it ends, `Steal.summary` (the share of CPU time the hypervisor
gave to others while it ran): figures from different runs compare only when both agree.
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from pathlib import Path
from typing import Callable


def median_time(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time (s) of ``repeat`` calls of ``fn``."""
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def cpu_info() -> dict:
    """CPU model name, family/model/stepping, widest vector ISA and cores (Linux's /proc/cpuinfo)."""
    info = {"model_name": platform.processor() or platform.machine(), "family": None, "model": None,
            "stepping": None, "isa": "unknown", "cores": os.cpu_count()}
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return info
    fields: dict[str, str] = {}
    for line in text.splitlines():
        if not line.strip():
            break  # the first processor's block describes them all here
        key, _, value = line.partition(":")
        fields[key.strip()] = value.strip()
    info["model_name"] = fields.get("model name", info["model_name"])
    for key, name in (("cpu family", "family"), ("model", "model"), ("stepping", "stepping")):
        if fields.get(key, "").isdigit():
            info[name] = int(fields[key])
    flags = set(fields.get("flags", "").split())
    info["isa"] = ("AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "AVX" if "avx" in flags
                   else "no AVX" if flags else "unknown")
    return info


def machine_line() -> str:
    """One line naming the CPU well enough to tell two VMs with the same model name apart."""
    c = cpu_info()
    gen = f" (family {c['family']}, model {c['model']})" if c["family"] is not None else ""
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = c["cores"]
    return f"{c['model_name']}{gen}, {c['isa']}, {c['cores']} cores ({usable} usable)"


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
