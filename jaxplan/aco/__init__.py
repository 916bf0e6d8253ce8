"""Ant colony optimisation: one vectorised engine, the papers' variants as rule presets."""

from jaxplan.aco._colony import Colony, ColonyState, RunConfig, RunOutput, run, run_batch
from jaxplan.aco._context import GoalTables, MapTables, goal_tables, map_tables
from jaxplan.aco._planners import (
    COLONIES,
    STATIC_PARAMS,
    UNIT_PARAMS,
    BatchResult,
    aco_defaults,
    cached_map_tables,
    plan_batch,
    plan_memory,
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

__all__ = [
    "METRICS", "TSP_MIN_ANTS_PER_DEVICE", "TSPConfig", "candidate_lists",
    "TSPOutput", "TSPProblem", "TSP_PLANNERS", "TSP_STATIC_PARAMS", "TourResult", "load_tour",
    "load_tsplib", "resolve_tsp", "run_tsp", "solve_tsp", "tour_length", "tsp_config", "tsp_defaults", "tsp_distances",
    "two_opt",
    "Ants", "BatchResult", "COLONIES", "Colony", "ColonyState", "GoalTables", "MapTables", "RunConfig", "RunOutput",
    "STATIC_PARAMS", "UNIT_PARAMS", "aco_defaults", "cached_map_tables", "goal_tables", "map_tables",
    "plan_batch", "plan_memory", "run", "run_batch", "seed_keys", "sharing_cores", "split_params", "draw",
    "hash_uniform", "walk",
]
