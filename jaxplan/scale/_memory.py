"""How many bytes a batched configuration needs, and a guard that refuses one that does not fit.

A sweep of thousands of scenarios × seeds fails late and badly when it runs out of memory
(the kernel kills the process, or XLA aborts mid-run). `plan_batch` therefore estimates the
working memory of its compiled program from the configuration's sizes before it allocates
anything, and refuses a batch above the limit with the largest batch that would fit (and, as a single run
cannot be split, the largest ant or sample count when not even one run fits, `Knob`); so do
`solve_tsp` (`tsp_memory`), a tuning population, and an experiment's chunks (navigation:
`episode_memory`) and trials (`table_memory`), before their first step.

The estimate counts the arrays that scale with the batch (each with the number of copies the
compiled program keeps alive at once, read off its buffer assignment) plus the per-map tables;
it does not count the process itself (Python, JAX, numba and the compiled code). Against the rise
of the peak RSS during a run of an already compiled program it is an upper bound, not far above
(the measured factors: docs/decisions.md); `tests/test_scale.py` checks the bound on real runs.
"""

from __future__ import annotations

import math
import os
from typing import Callable, NamedTuple

__all__ = ["MemoryEstimate", "MemoryLimitError", "Knob", "largest_count", "aco_memory", "dwa_memory", "tsp_memory",
           "episode_memory", "table_memory", "memory_limit", "check_memory"]

_F32 = 4
_I32 = 4
# Live copies of a pheromone-sized [B, S, C, K] f32 array inside one iteration of the colony's
# scan: six covers every case measured (the peak RSS of praco's five colonies on a 100x100 map
# came to about six such arrays; tests/test_scale.py).
_TAU_COPIES = 6
# The walk's path buffers are produced and consumed inside one iteration; XLA keeps at most
# two generations alive (this iteration's and the scan carry's best-so-far extraction).
_PATH_COPIES = 2
# Floats per rollout pose of a DWA fan while a control step is evaluated (pose, critics, clearances and their
# temporaries), an upper bound of what navigate_batch's episodes were measured to use (docs/decisions.md).
_FAN_FLOATS = 7


class MemoryEstimate(NamedTuple):
    """Bytes a configuration needs: ``total`` and its ``parts`` (name -> bytes), plus the batch
    (``runs`` = scenarios × seeds, or robots) it was computed for and the bytes per element."""

    total: int
    parts: dict
    runs: int
    per_run: float

    def largest_batch(self, limit: int) -> int:
        """The largest batch (same configuration) whose estimate stays within ``limit`` bytes."""
        fixed = self.total - self.per_run * self.runs
        return max(0, int((limit - fixed) // max(self.per_run, 1.0)))


class MemoryLimitError(MemoryError):
    """A batch whose estimated memory exceeds the limit (raised before anything is allocated)."""


class Knob(NamedTuple):
    """A count inside each batch element that the user chose (ants per colony, samples per control step), for a
    refusal to name the largest value that fits: when not even one element of the batch fits, "split the batch"
    cannot help (a single run cannot be split) and this count is what to lower.

    Attributes:
      name: what the count counts, as the user sets it (``"ants"``, ``"samples"``).
      now: its current value.
      estimate: the same batch's estimate with the count set to its argument (non-decreasing in it).
    """

    name: str
    now: int
    estimate: Callable[[int], MemoryEstimate]


def largest_count(knob: Knob, limit: int) -> int:
    """The largest value of ``knob`` in ``[0, knob.now]`` whose estimate stays within ``limit`` bytes (bisection on
    the non-decreasing estimate; 0 when not even a count of 1 fits)."""
    lo, hi = 0, int(knob.now)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if knob.estimate(mid).total <= limit:
            lo = mid
        else:
            hi = mid - 1
    return lo


def _size(nbytes: float) -> str:
    """A JAXPLAN_MEMORY_LIMIT value at least ``nbytes``: whole GiB (``49G``), or MiB below 1 GiB."""
    if nbytes >= 2**30:
        return f"{math.ceil(nbytes / 2**30)}G"
    return f"{max(1, math.ceil(nbytes / 2**20))}M"


def aco_memory(cells: int, moves: int, runs: int, colonies: int, ants: int, max_steps: int, iterations: int,
               *, keep_pheromone: bool = False, hook: bool = False, penalty: bool = False, alert: bool = False,
               jax_walk: bool = False, threads: int = 2, objective_variants: int = 0) -> MemoryEstimate:
    """Estimated working memory (bytes) of one `plan_batch` call of an ACO planner.

    Args:
      cells, moves: C = H·W and K (8 or 16) of the map.
      runs: B = scenarios × seeds; colonies, ants: S and m per run; max_steps: L; iterations: I.
      keep_pheromone: the final ``[B, S, C, K]`` pheromone is returned.
      hook: chu2024's walk hook (two ``[B·S·C, K]`` logit tables per iteration).
      penalty: yu2020's per-edge retreat counts.
      alert: chu2024's dead-end alert (``bool[B, C]`` marks).
      jax_walk: the JAX step loop (bit-packed tabu per ant) instead of the numba walk
        (one ``int32[C]`` stamp array per thread).
      threads: the numba walk's threads.
      objective_variants: V > 0 for ``heuristic="objective"``: the colony's cost-to-go (``f64[B, C, K]`` on the
        host while it is built, ``f32`` on the device), V ``[B·C, K]`` β·log η tables and V (instead of
        chu2024's two) ``[B·S·C, K]`` logit tables per iteration.
    """
    B, S, m, C, K, L, I = runs, colonies, ants, cells, moves, max_steps, iterations
    A = B * S * m
    edge = B * S * C * K * _F32
    parts = {
        "pheromone": _TAU_COPIES * edge,
        "heuristic": B * C * K * _F32 + 2 * B * C * _F32,  # log η per edge, goal distance per cell
        "ant paths": _PATH_COPIES * A * ((L + 1) * _I32 + L + 12 * _I32),  # cells, moves, per-ant scalars/stats
        "best paths": 2 * B * S * ((L + 1) * _I32 + L),
        "history": 4 * B * I * _F32,
        "map tables": C * K * (2 * _I32 + 1) + C * 12 * _F32,
    }
    if keep_pheromone:
        parts["returned pheromone"] = edge
    if objective_variants:
        parts["objective cost-to-go"] = B * C * K * (8 + _F32) + objective_variants * B * C * K * _F32
        parts["hook logits"] = objective_variants * edge
    elif hook:
        parts["hook logits"] = 2 * edge
    if penalty:
        parts["retreat counts"] = edge
    if alert:
        parts["dead-end marks"] = 2 * B * C
    parts["tabu"] = A * math.ceil(C / 32) * 4 if jax_walk else threads * C * _I32
    total = int(sum(parts.values()))
    fixed = parts["map tables"] + (0 if jax_walk else parts["tabu"])
    return MemoryEstimate(total, parts, runs, (total - fixed) / max(runs, 1))


def dwa_memory(robots: int, samples: int, steps: int, *, keep_rollouts: bool = False, obstacles: int = 0,
               chunk: int | None = 128, map_cells: int = 0) -> MemoryEstimate:
    """Estimated working memory (bytes) of one `dwa_control_batch` call.

    Each robot's S samples carry a rotor, running clearance minima and critic values
    (about 16 floats per sample); with ``keep_rollouts`` every ``[S, T, 3]`` pose is kept.
    Robots are processed ``chunk`` at a time, so only a chunk's rollouts are live at once.
    """
    live = robots if chunk is None else min(robots, chunk)
    per_sample = 16 * _F32 + obstacles * 4 * _F32
    parts = {
        "samples": live * samples * per_sample,
        "outputs": robots * samples * 4 * _F32,
        "map tables": 4 * map_cells * _F32,
    }
    if keep_rollouts:
        parts["rollouts"] = robots * samples * steps * 3 * _F32
    total = int(sum(parts.values()))
    return MemoryEstimate(total, parts, robots, (total - parts["map tables"]) / max(robots, 1))


def tsp_memory(cities: int, colonies: int, ants: int, iterations: int, runs: int = 1, *,
               local_search: bool = False) -> MemoryEstimate:
    """Estimated working memory (bytes) of ``runs`` TSP colony runs in one call (`jaxplan.solve_tsp`'s program;
    an experiment's TSP chunk vmaps it over its seeds).

    Per run: the ``[S, n, n]`` pheromone, its logits, weights and deposits (`_TAU_COPIES` live copies),
    each ant's ``[n]`` probabilities, prefix sums and visited marks in the construction loop, and with 2-opt
    local search each ant's ``[n, n]`` move table (about five live copies); per call the ``[n, n]`` distance,
    log-heuristic and diagonal tables.
    """
    n, S, A = cities, colonies, colonies * ants
    parts = {
        "pheromone": runs * _TAU_COPIES * S * n * n * _F32,
        "ant tours": runs * 6 * A * n * _F32,
        "history": runs * iterations * _F32,
        "distance tables": 3 * n * n * _F32 + n * n,
    }
    if local_search:
        parts["2-opt move tables"] = runs * 5 * A * n * n * _F32
    total = int(sum(parts.values()))
    return MemoryEstimate(total, parts, runs, (total - parts["distance tables"]) / max(runs, 1))


def episode_memory(robots: int, steps: int, samples: int, *, rollout_steps: int = 20, discs: int = 0,
                   waypoints: int = 16, map_cells: int = 0) -> MemoryEstimate:
    """Estimated working memory (bytes) of ``robots`` navigation episodes of ``steps`` control steps in one
    call (`jaxplan.navigate_batch`: robots = scenarios × seeds; `navigate_multi`: × robots per team).

    Per robot: the live control step's DWA fan — ``samples`` rollouts of ``rollout_steps`` poses with their
    critics and clearances (`_FAN_FLOATS` floats per pose; the discs add little) — which dominates; the
    trajectory (state, control and flags per control step, and the host's float64 copies for the metrics:
    40 floats per step); the waypoints and the discs' routes. Per call: the map's clearance and planning
    tables. Against the measured peak RSS rise it is an upper bound, not far above (docs/decisions.md).
    """
    fan = samples * (rollout_steps * _FAN_FLOATS + 16 + 4 * discs) * _F32
    parts = {
        "dwa fans": robots * fan,
        "trajectories": robots * (steps + 1) * 40 * _F32,
        "waypoints and discs": robots * (waypoints * 2 + discs * 64) * _F32,
        "map tables": 8 * map_cells * _F32,
    }
    total = int(sum(parts.values()))
    return MemoryEstimate(total, parts, robots, (total - parts["map tables"]) / max(robots, 1))


def table_memory(runs: int, per_run: dict, fixed: dict | None = None) -> MemoryEstimate:
    """A `MemoryEstimate` from bytes per batch element (``per_run``: name -> bytes of one element) and bytes
    that do not grow with the batch (``fixed``): for host-side tables (trials, results) and any batch whose
    arrays are simple to count."""
    parts = {k: int(v * runs) for k, v in per_run.items()}
    parts.update({k: int(v) for k, v in (fixed or {}).items()})
    total = int(sum(parts.values()))
    return MemoryEstimate(total, parts, runs, float(sum(per_run.values())))


def memory_limit() -> int:
    """The byte limit for one batched call: ``$JAXPLAN_MEMORY_LIMIT`` (bytes, or with a K/M/G/T
    suffix), else 80 % of the memory the system reports available now."""
    raw = os.environ.get("JAXPLAN_MEMORY_LIMIT")
    if raw:
        return _parse_bytes(raw)
    avail = _available_bytes()
    return int(0.8 * avail) if avail else 2**62


def _parse_bytes(text: str) -> int:
    t = text.strip().upper().removesuffix("B")
    scale = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}.get(t[-1:], 1)
    digits = t[:-1] if t[-1:] in "KMGT" else t
    try:
        value = float(digits) * scale
    except ValueError:
        raise ValueError(f"JAXPLAN_MEMORY_LIMIT must be a byte count such as 8G or 500M, got {text!r}") from None
    if not value > 0 or not math.isfinite(value):
        raise ValueError(f"JAXPLAN_MEMORY_LIMIT must be positive, got {text!r}")
    return int(value)


def _available_bytes() -> int:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 0


def check_memory(estimate: MemoryEstimate, what: str, limit: int | None = None, unit: str = "runs",
                 advice: str = "Split the batch", knob: Knob | None = None, single: str = "") -> None:
    """Raises `MemoryLimitError` if ``estimate`` exceeds ``limit``, naming what fits.

    The message names the largest batch that fits ("at most K {unit} fit") and then what to change: ``advice``
    (the batch's own knobs: fewer scenarios, seeds or robots) when some of the batch fits; when not even one
    element fits, splitting cannot help, so it names the largest ``knob`` count that fits ("use at most N ants
    (now M)") or, without a knob, ``single`` (what makes one element large). Last, the limit to set if the machine
    has the memory: the estimate rounded up, which is above the current limit.
    """
    limit = memory_limit() if limit is None else int(limit)
    if estimate.total <= limit:
        return
    top = sorted(estimate.parts.items(), key=lambda kv: -kv[1])[:3]
    biggest = ", ".join(f"{k} {v / 2**30:.2f} GiB" for k, v in top)
    fits = estimate.largest_batch(limit)
    change = []
    if fits >= 1:
        change.append(advice)
    if knob is not None:
        n = largest_count(knob, limit)
        if n >= 1:
            change.append(f"use at most {n} {knob.name} (now {knob.now})" + (f" with all {estimate.runs} {unit}"
                                                                            if fits >= 1 else ""))
        elif fits == 0:
            change.append(f"not even 1 of the {knob.name} fits: the rest of the configuration alone is too large")
    elif fits == 0 and single:
        change.append(single)
    head = f"at most {fits} {unit} fit" + (" (a single one cannot be split)" if fits == 0 else "")
    todo = "; or ".join(change)
    raise MemoryLimitError(
        f"{what} needs about {estimate.total / 2**30:.2f} GiB ({biggest}) for {estimate.runs} {unit}, above the "
        f"limit of {limit / 2**30:.2f} GiB; {head}." + (f" {todo[:1].upper()}{todo[1:]}." if todo else "")
        + f" If the machine has that much free memory, raise the limit: JAXPLAN_MEMORY_LIMIT={_size(estimate.total)}")
