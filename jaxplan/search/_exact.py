"""Exact planners: A* and Dijkstra on the grid's move rules, registered with `jaxplan.registry`.

The searches themselves (the move graph, the compiled A*/Dijkstra loops, batched lengths and
distance fields) live in `jaxplan.grid` (`search_graph`, `shortest_path`, `shortest_lengths`,
`distance_from`), below the planners, because maps and metrics need them too.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.grid import GridMap, check_connectivity, search_graph, shortest_path
from jaxplan.metrics import count_turns
from jaxplan.registry import register_planner
from jaxplan.result import PlanResult

__all__ = ["astar", "dijkstra", "path_cost"]


def path_cost(path: ArrayLike, resolution: float = 1.0) -> float:
    """Summed step lengths (m) of a cell path ``[L, 2]``."""
    p = np.asarray(path, dtype=np.float64)
    if len(p) < 2:
        return 0.0
    return float(np.hypot(*np.diff(p, axis=0).T).sum() * resolution)


def _exact(name: str, heuristic: bool, grid: GridMap, start: ArrayLike, goal: ArrayLike, connectivity: int,
           vehicle_height: float | None) -> PlanResult:
    t0 = time.perf_counter()
    graph = search_graph(grid, connectivity, vehicle_height)
    path, length, expanded = shortest_path(graph, start, goal, heuristic)
    if path is None:
        return PlanResult.failure(name, time.perf_counter() - t0, expanded=expanded)
    return PlanResult.found(name, path, length, count_turns(path), time.perf_counter() - t0, expanded=expanded)


def astar(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, connectivity: int = 8, vehicle_height: float | None = None
) -> PlanResult:
    """Optimal path by A* (octile heuristic for 8-connected moves, Manhattan for 4, Euclidean for 16).

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells; a blocked or outside cell raises ``ValueError``.
      connectivity: 4, 8 or 16.
      vehicle_height: cells with ``clearance_height <= vehicle_height`` are blocked.

    Returns:
      `PlanResult` (``success=False``, ``length=inf`` if the goal cannot be reached).
    """
    return _exact("astar", True, grid, start, goal, connectivity, vehicle_height)


def dijkstra(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, connectivity: int = 8, vehicle_height: float | None = None
) -> PlanResult:
    """Optimal path by Dijkstra's algorithm (A* without heuristic); same contract as `astar`."""
    return _exact("dijkstra", False, grid, start, goal, connectivity, vehicle_height)


def _validate_exact(params: Mapping[str, Any]) -> None:
    check_connectivity(params["connectivity"])
    vh = params["vehicle_height"]
    if vh is not None and (not np.isfinite(vh) or vh < 0):
        raise ValueError(f"vehicle_height must be a finite height >= 0 in metres, got {vh!r}")


def _ignoring_seed(search: Callable[..., PlanResult]) -> Callable[..., PlanResult]:
    """``search(grid, start, goal, **params)`` as a registered planner ``fn(grid, start, goal, seed, **params)``."""
    return lambda grid, start, goal, seed, **p: search(grid, start, goal, **p)


def _register() -> None:
    defaults = {"connectivity": 8, "vehicle_height": None}
    for name, search, description in (
        ("astar", astar, "A*: exact shortest path (octile/Manhattan/Euclidean heuristic), no corner cutting"),
        ("dijkstra", dijkstra, "Dijkstra: exact shortest path without heuristic (reference for A*)"),
    ):
        register_planner(name, _ignoring_seed(search), defaults, description, _validate_exact, deterministic=True)


_register()
