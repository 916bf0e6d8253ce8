"""The planner registry (docs/guide/planners.md), at the bottom of the planners' import graph.

Every planner has the signature ``fn(grid, start, goal, seed, **params) -> PlanResult``
and registers its defaults with `register_planner` when its module is imported; `resolve`
merges a call's overrides into them and rejects unknown names, so a typo never silently
falls back to a default. A planner that runs a whole batch of scenarios × seeds in one call (the
colonies) registers that too (``batch``, with its memory estimate); `run_planner_batch` calls it, and
plans every other planner scenario by scenario. The registry sees the planners whose modules have been
imported: the front door `jaxplan.plan` / `jaxplan.plan_batch` / `jaxplan.planners` (`jaxplan.planning`)
imports every planner jaxplan ships first.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping

import numpy as np
from jax.sharding import Mesh
from numpy.typing import ArrayLike

from jaxplan.core.names import did_you_mean
from jaxplan.core.progress import ProgressBar
from jaxplan.grid import GridMap
from jaxplan.result import BatchResult, PlanResult
from jaxplan.scale import MemoryEstimate, auto_mesh, check_memory, table_memory

__all__ = ["PlannerSpec", "BatchFn", "MemoryFn", "Seeds", "register_planner", "registered", "resolve", "run_planner",
           "run_planner_batch", "plan_memory", "result_memory", "check_seeds", "seed_count"]

Seeds = int | Iterable[int]
"""Seeds of a batch: one integer, or an iterable of non-negative integers (``range(4)``, ``[0, 3]``)."""

BatchFn = Callable[..., BatchResult]
"""A planner's own batch: ``batch(grid, starts int[N, 2], goals int[N, 2], seeds, params, *, mesh, progress)
-> BatchResult``, ``params`` resolved and checked, ``mesh`` as `jaxplan.plan_batch` takes it."""

MemoryFn = Callable[[GridMap, Mapping[str, Any], int], MemoryEstimate]
"""A batched planner's working memory: ``memory(grid, params, runs) -> MemoryEstimate``."""


@dataclass(frozen=True)
class PlannerSpec:
    """A registered planner.

    Attributes:
      name: registry name (``jp.plan(..., planner=name)``).
      fn: ``fn(grid, start, goal, seed, **params) -> PlanResult``.
      defaults: every parameter the planner accepts, with its default.
      description: one line, citing the seed paper where there is one.
      validate: optional ``validate(params) -> None`` raising ``ValueError`` on a bad value.
      batch: optional `BatchFn`: every scenario × seed in one call (else `run_planner_batch` loops over ``fn``).
      memory: optional `MemoryFn` of ``batch`` (else the result table's size).
      deterministic: the planner ignores its seed, so one plan per scenario serves every seed.
    """

    name: str
    fn: Callable[..., PlanResult]
    defaults: Mapping[str, Any]
    description: str
    validate: Callable[[Mapping[str, Any]], None] | None = field(default=None, compare=False)
    batch: BatchFn | None = field(default=None, compare=False)
    memory: MemoryFn | None = field(default=None, compare=False)
    deterministic: bool = False


_REGISTRY: dict[str, PlannerSpec] = {}


def register_planner(
    name: str,
    fn: Callable[..., PlanResult],
    defaults: Mapping[str, Any],
    description: str,
    validate: Callable[[Mapping[str, Any]], None] | None = None,
    *,
    batch: BatchFn | None = None,
    memory: MemoryFn | None = None,
    deterministic: bool = False,
) -> PlannerSpec:
    """Adds a planner to the registry (at import time of the module that defines it).

    Args:
      name, fn, defaults, description, validate, batch, memory, deterministic: as the fields of `PlannerSpec`.

    Returns:
      The registered `PlannerSpec`; a name registered before raises ``ValueError``.
    """
    if name in _REGISTRY:
        raise ValueError(f"planner {name!r} is already registered")
    spec = PlannerSpec(name, fn, MappingProxyType(dict(defaults)), description, validate, batch, memory,
                       deterministic)
    _REGISTRY[name] = spec
    return spec


def registered() -> dict[str, PlannerSpec]:
    """The planners registered so far by name, with their defaults and descriptions (`jaxplan.planners` lists
    every planner jaxplan ships)."""
    return dict(_REGISTRY)


def _check_numbers(name: str, params: Mapping[str, Any]) -> None:
    for k, v in params.items():
        if isinstance(v, float) and math.isnan(v):
            raise ValueError(f"planner {name!r}: parameter {k!r} is NaN")


def resolve(planner: str, overrides: Mapping[str, Any]) -> tuple[PlannerSpec, dict[str, Any]]:
    """The spec of ``planner`` and its parameters with ``overrides`` applied and checked."""
    spec = _REGISTRY.get(planner)
    if spec is None:
        raise ValueError(f"unknown planner {planner!r}{did_you_mean(str(planner), _REGISTRY)} "
                         f"(registered: {', '.join(sorted(_REGISTRY))})")
    unknown = sorted(set(overrides) - set(spec.defaults))
    if unknown:
        # Each unknown name with its own suggestion: ``iteration=10`` reads "did you mean 'iterations'?".
        named = "; ".join(f"{k!r}{did_you_mean(str(k), spec.defaults)}" for k in unknown)
        raise ValueError(
            f"planner {planner!r} has no parameter(s) {named} "
            f"(it accepts: {', '.join(sorted(spec.defaults)) or 'none'})"
        )
    params = {**spec.defaults, **overrides}
    _check_numbers(planner, params)
    if spec.validate is not None:
        spec.validate(params)
    return spec, params


def run_planner(grid: GridMap, start: ArrayLike, goal: ArrayLike, planner: str = "astar", seed: int = 0,
                **overrides: Any) -> PlanResult:
    """Plans one path with an already registered planner (the dispatch behind `jaxplan.plan`).

    Args and returns as `jaxplan.plan`; for modules inside jaxplan that import their planners' modules.
    """
    if not isinstance(grid, GridMap):
        raise TypeError(f"grid must be a GridMap (see jp.load_map / jp.grid_from_array), got {type(grid).__name__}")
    spec, params = resolve(planner, overrides)
    return spec.fn(grid, start, goal, seed, **params)


def check_seeds(seeds: Seeds) -> np.ndarray:
    """``int64[R]`` the seeds of a batch, checked: at least one, each a non-negative integer below ``2**32``
    (``ValueError`` otherwise)."""
    s = np.atleast_1d(np.asarray(list(seeds) if not isinstance(seeds, (int, np.integer)) else [seeds]))
    if s.size == 0:
        raise ValueError("seeds must hold at least one seed")
    if not np.issubdtype(s.dtype, np.integer) or (s < 0).any():
        raise ValueError(f"seeds must be non-negative integers, got {s.tolist()}")
    if (s >= 2**32).any():
        raise ValueError(f"seeds must be below 2**32, got {int(s.max())}")
    return s.astype(np.int64)


def seed_count(seeds: Seeds) -> int:
    """How many seeds ``seeds`` holds, without building a list of a huge range (the memory guard runs first)."""
    if isinstance(seeds, (int, np.integer)):
        return 1
    try:
        return len(seeds)  # type: ignore[arg-type]
    except TypeError:
        return len(list(seeds))


def result_memory(runs: int, path_cells: int) -> MemoryEstimate:
    """A `BatchResult` of ``runs`` scenarios × seeds planned one by one: one reference and five numbers per run,
    and its path padded to ``path_cells`` cells."""
    return table_memory(runs, {"results": 8 + 5 * 8, "paths": path_cells * 2 * 8})


def plan_memory(grid: GridMap, planner: str, runs: int, **overrides: Any) -> MemoryEstimate:
    """Estimated working memory (bytes) of `jaxplan.plan_batch` over ``runs`` = scenarios × seeds of ``planner``.

    A planner with its own batch (the ACO planners: `jaxplan.scale.aco_memory` of the colony — pheromone, ant
    paths, tables): its registered estimate. Any other planner: its result table, with paths of at most
    ``4·(H + W)`` cells (the exact path length is known only after planning; `run_planner_batch` checks again with
    it before it allocates the paths).
    """
    spec, p = resolve(planner, overrides)
    if spec.memory is not None:
        return spec.memory(grid, p, runs)
    return result_memory(runs, 4 * (grid.shape[0] + grid.shape[1]))


def run_planner_batch(grid: GridMap, starts: ArrayLike, goals: ArrayLike, planner: str, seeds: Seeds = range(1), *,
                      mesh: Mesh | str | None = "auto", progress: bool = False, **overrides: Any) -> BatchResult:
    """Plans every scenario with every seed with an already registered planner (the dispatch behind
    `jaxplan.plan_batch`; args and returns as there).

    A planner with its own ``batch`` runs it; the others run scenario by scenario on the host (a deterministic
    one once per scenario, its plan repeated across the seeds).
    """
    if not isinstance(grid, GridMap):
        raise TypeError(f"grid must be a GridMap (see jp.load_map / jp.grid_from_array), got {type(grid).__name__}")
    spec, p = resolve(planner, overrides)
    s, g = np.asarray(starts), np.asarray(goals)
    auto_mesh(mesh, 1)  # a bad mesh argument fails for every planner, before any work
    if spec.batch is not None:
        return spec.batch(grid, s, g, seeds, p, mesh=mesh, progress=progress)
    what = f"planner {planner!r} on a {grid.shape[0]}x{grid.shape[1]} map"
    check_memory(result_memory(len(s) * seed_count(seeds), 1), what, unit="runs (scenarios x seeds)")
    seed_list = [int(x) for x in ([seeds] if isinstance(seeds, (int, np.integer)) else seeds)]
    R = len(check_seeds(seed_list))
    t0 = time.perf_counter()
    with ProgressBar(planner, len(s) * (1 if spec.deterministic else R), unit="plans", enabled=progress) as bar:
        def one(a: np.ndarray, b: np.ndarray, seed: int) -> PlanResult:
            r = spec.fn(grid, a, b, seed, **p)
            bar.update(advance=1)
            return r

        if spec.deterministic:  # one plan per scenario serves every seed
            results = [[r] * R for r in [one(a, b, 0) for a, b in zip(s, g, strict=True)]]
        else:  # sampling planners (rrt_star, mrbs_rrt) depend on the seed
            results = [[one(a, b, seed) for seed in seed_list] for a, b in zip(s, g, strict=True)]
    dt = time.perf_counter() - t0
    P = max((len(r.path) for row in results for r in row), default=1)
    check_memory(result_memory(len(results) * R, max(P, 1)), what, unit="runs (scenarios x seeds)")
    paths = np.full((len(results), R, max(P, 1), 2), -1, np.int64)
    for i, row in enumerate(results):
        for j, r in enumerate(row):
            paths[i, j, : len(r.path)] = r.path

    def col(f: Callable[[PlanResult], Any]) -> np.ndarray:
        return np.array([[f(r) for r in row] for row in results]).reshape(len(results), R)

    return BatchResult(
        paths=paths, n_cells=col(lambda r: len(r.path)), length=col(lambda r: r.length), cost=col(lambda r: r.cost),
        turns=col(lambda r: r.turns), success=col(lambda r: r.success), converged=col(lambda r: 0),
        history=np.zeros((len(results), R, 0)), diversity=np.zeros((len(results), R, 0)),
        successes=np.zeros((len(results), R, 0), np.int64), time_s=dt, compile_s=0.0, planner=planner,
    )
