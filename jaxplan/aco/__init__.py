"""Ant colony optimisation: one vectorised engine, the papers' variants as rule presets.

The colonies register with `jaxplan.registry` together with their batch (every scenario × seed in one compiled
call): ``jaxplan.plan_batch(..., planner="iaco")`` runs it. ``jaxplan.aco.plan_batch`` (the previous release's
home, default planner ``"aco"``) still works for one release with a `DeprecationWarning`.
"""

from __future__ import annotations

from typing import Any

from jaxplan.aco._colony import Colony, ColonyState, RunConfig, RunOutput, run, run_batch
from jaxplan.aco._context import GoalTables, MapTables, goal_tables, map_tables
from jaxplan.aco._objective import CostWeights, cost_weights
from jaxplan.aco._planners import (
    COLONIES,
    STATIC_PARAMS,
    UNIT_PARAMS,
    aco_defaults,
    cached_map_tables,
    seed_keys,
    split_params,
)
from jaxplan.aco._tsp import (
    TSP_MIN_ANTS_PER_DEVICE,
    TSP_PLANNERS,
    TSP_STATIC_PARAMS,
    TourResult,
    TSPConfig,
    TSPOutput,
    candidate_lists,
    resolve_tsp,
    run_tsp,
    solve_tsp,
    tsp_config,
    tsp_defaults,
    two_opt,
)
from jaxplan.aco._tsplib import METRICS, TSPProblem, load_tour, load_tsplib, tour_length, tsp_distances
from jaxplan.aco._walk import Ants, draw, hash_uniform, walk
from jaxplan.aco._walk_numba import sharing_cores
from jaxplan.core.deprecation import warn_deprecated
from jaxplan.registry import plan_memory, run_planner_batch
from jaxplan.result import BatchResult

__all__ = [
    "METRICS", "TSP_MIN_ANTS_PER_DEVICE", "TSPConfig", "candidate_lists",
    "TSPOutput", "TSPProblem", "TSP_PLANNERS", "TSP_STATIC_PARAMS", "TourResult", "load_tour",
    "load_tsplib", "resolve_tsp", "run_tsp", "solve_tsp", "tour_length", "tsp_config", "tsp_defaults", "tsp_distances",
    "two_opt",
    "Ants", "BatchResult", "COLONIES", "Colony", "ColonyState", "CostWeights", "cost_weights", "GoalTables",
    "MapTables", "RunConfig", "RunOutput",
    "STATIC_PARAMS", "UNIT_PARAMS", "aco_defaults", "cached_map_tables", "goal_tables", "map_tables",
    "plan_memory", "run", "run_batch", "seed_keys", "sharing_cores", "split_params", "draw",
    "hash_uniform", "walk",
]


def _plan_batch(grid: Any, starts: Any, goals: Any, planner: str = "aco", seeds: Any = range(1), *, mesh: Any = "auto",
                progress: bool = False, **overrides: Any) -> BatchResult:
    """The previous release's ``jaxplan.aco.plan_batch`` (default planner ``"aco"``): `jaxplan.plan_batch`."""
    return run_planner_batch(grid, starts, goals, planner, seeds, mesh=mesh, progress=progress, **overrides)


def __getattr__(name: str) -> Any:
    if name == "plan_batch":
        warn_deprecated("jaxplan.aco.plan_batch is deprecated; use jaxplan.plan_batch(grid, starts, goals, "
                        "planner=..., seeds=...) (it serves every planner; its default planner is 'astar')")
        return _plan_batch
    raise AttributeError(f"module 'jaxplan.aco' has no attribute {name!r}")
