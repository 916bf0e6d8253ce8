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

__all__ = ["median_time", "cpu_info", "machine_line", "Steal", "Record", "RESULTS"]


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


RESULTS = Path(__file__).resolve().parent / "results"
"""Where each benchmark run's JSON record goes (docs/benchmarks.md is generated from these files)."""


class Record:
    """The JSON record of one benchmark run: ``benchmarks/results/<bench>-<date>-<HHMM>-<rev>[-quick].json``.

    A benchmark makes one at its start (the machine line, load and steal are taken then), fills named tables as it
    prints them, and writes the file at its end; ``python benchmarks/run_all.py --page`` renders the newest table
    of each name into docs/benchmarks.md. The file holds ``bench``, ``command``, ``started_utc``, ``wall_s``,
    ``machine_line``, ``machine`` (the provenance record), ``load_avg``, ``steal``, ``options`` and ``tables``:
    each ``{"name", "title", "columns", "rows", "notes"}``, a row a list of cells (numbers or text) under
    ``columns``. The start time is in the name, so two runs of different sections on one day both stay.

    Args:
      bench: the script's name without ``.py`` (``"bench_dwa"``).
      options: the run's parsed options (``vars(args)``); paths become strings.
      quick: a smoke-sized run (the page prefers full runs).
    """

    def __init__(self, bench: str, options: dict[str, Any], *, quick: bool = False) -> None:
        import datetime as dt
        import os
        import sys

        self.bench, self.quick = bench, quick
        self.options = {k: (str(v) if isinstance(v, Path) else v) for k, v in options.items()}
        self.command = " ".join(["python", f"benchmarks/{bench}.py", *sys.argv[1:]])
        self.started = dt.datetime.now(dt.timezone.utc)
        self.load_avg = list(os.getloadavg()) if hasattr(os, "getloadavg") else None
        self.tables: list[dict[str, Any]] = []
        self.extra: dict[str, Any] = {}  # further top-level fields (a benchmark's raw measurements)
        self._steal = Steal()
        self._t0 = time.perf_counter()

    def table(self, name: str, columns: list[str], title: str = "") -> list[list[Any]]:
        """A new table ``name`` (unique within the benchmark: the page shows the newest table of each name) with
        ``columns``; returns its list of rows, to append to (each a list of cells, one per column)."""
        rows: list[list[Any]] = []
        self.tables.append({"name": name, "title": title or name, "columns": list(columns), "rows": rows,
                            "notes": []})
        return rows

    def note(self, text: str) -> None:
        """A sentence under the last table (what a column means, a target met or missed)."""
        self.tables[-1]["notes"].append(text)

    def write(self, path: str | Path | None = None) -> Path:
        """Writes the record atomically (to ``path``, default `RESULTS`) and returns the path."""
        import json
        import sys

        from jaxplan.core.io import atomic_write
        from jaxplan.core.provenance import provenance

        rec = provenance(devices="jax" in sys.modules)  # lists the devices only if the bench started JAX
        steal = self._steal.fraction()
        rev = (rec["git_revision"] or "norev")[:7]
        data = {
            "bench": self.bench, "command": self.command, "quick": self.quick,
            "started_utc": self.started.isoformat(timespec="seconds"),
            "wall_s": time.perf_counter() - self._t0, "machine_line": machine_line(), "machine": rec,
            "load_avg": self.load_avg, "steal": steal, "options": self.options,
            "tables": [t for t in self.tables if t["rows"]], **self.extra,
        }
        name = f"{self.bench}-{self.started:%Y-%m-%d-%H%M}-{rev}{'-quick' if self.quick else ''}.json"
        out = Path(path) if path is not None else RESULTS / name
        out.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(out, json.dumps(data, indent=1, default=_plain) + "\n")
        print(f"JSON: {out}")
        return out


def _plain(x: Any) -> Any:
    """JSON for numpy scalars and arrays (a bench's cells are often numpy numbers)."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"not JSON: {type(x).__name__}")
