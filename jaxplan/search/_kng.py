"""Key-node-guided A* (li2026, Eq. 13–15): the exact A* path reduced to its key nodes.

li2026 computes the direction of each path segment (Eq. 13–14), the angle difference
between adjacent segments (Eq. 15), deletes the nodes whose angle difference is under
20° and hands the remaining key nodes to DWA as sub-goals. jaxplan applies the rule of
`jaxplan.smoothing.key_nodes` to the A* path: the heading change of a
vertex is measured from the last *kept* node (so slow drifts add up instead of being
dropped one small step at a time), a vertex is also kept when dropping it would make
the straight segment from the last key node collide, and if the result had more sharp
turns (>= 45°) than the A* path, the A* path is kept (``info["fallback"]``). So every
consecutive pair of key nodes is line-of-sight free under the exact segment test, and the
key nodes are a subsequence of the A* path. On 8-connected paths every turn is a multiple
of 45°, so at 20° only collinear vertices go (the turn count stays A*'s); the threshold
bites on 16-connected paths (18.4° turns) and at larger thresholds.

The pass is a numba loop with the sampling planners' float64 segment test
(`jaxplan.search._sampling`), not the JAX smoother itself: a per-plan job of microseconds
would otherwise pay a JAX compilation (seconds) for every new map shape and path-length
bucket. The tests check that both give the same key nodes.

`PlanResult`: ``path`` = the key-node cells ``int64[K, 2]`` (not 8-connected: consecutive
nodes are joined by straight, collision-free segments); ``length``/``cost`` = the key-node
polyline's length in metres (at most the A* length); ``turns`` = the polyline's turning
vertices; ``info["grid_path"]`` = the full A* path, ``info["grid_length"]`` its length.
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from jaxplan.core.compile_cache import on_first_use
from jaxplan.grid import GridMap, passable
from jaxplan.metrics import count_sharp_turns, count_turns, path_length
from jaxplan.result import PlanResult
from jaxplan.search._exact import _validate_exact, astar
from jaxplan.search._sampling import _clear, _threshold

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = ["astar_kng", "key_node_path"]


@njit(cache=True, nogil=True)
def _key_node_mask(blocked, pts, min_turn, thr):
    """``bool[L]``: which vertices of ``pts f64[L, 2]`` (cell coordinates) are key nodes.

    Vertex j is dropped when its heading change, from the direction (last key node → j) to
    the direction (j → j + 1), is under ``min_turn`` (rad; undefined = 0 for repeated
    points) and the segment from the last key node to j + 1 is free (`_clear`, threshold
    ``thr`` cells). The same rule as `jaxplan.smoothing.key_nodes`.
    """
    L = pts.shape[0]
    keep = np.ones(L, np.bool_)
    ax, ay = pts[0, 0], pts[0, 1]
    for j in range(1, L - 1):
        px, py, nx, ny = pts[j, 0], pts[j, 1], pts[j + 1, 0], pts[j + 1, 1]
        a0, a1, b0, b1 = px - ax, py - ay, nx - px, ny - py
        na, nb = math.hypot(a0, a1), math.hypot(b0, b1)
        if na == 0.0 or nb == 0.0:
            small = True
        else:
            small = math.acos(min(max((a0 * b0 + a1 * b1) / (na * nb), -1.0), 1.0)) < min_turn
        if small and _clear(blocked, ax, ay, nx, ny, thr):
            keep[j] = False
        else:
            ax, ay = px, py
    return keep


def key_node_path(free: np.ndarray, path: np.ndarray, threshold_deg: float = 20.0) -> tuple[np.ndarray, bool]:
    """Key nodes of a collision-free cell path ``int[L, 2]`` on the map ``free bool[H, W]``.

    Returns ``(nodes int64[K, 2], fallback)``: the key nodes, or the path itself with
    ``fallback=True`` if the key nodes would have more sharp turns than the path.
    """
    path = np.asarray(path, np.int64).reshape(-1, 2)
    keep = _key_node_mask(~np.asarray(free, dtype=bool), path.astype(np.float64), math.radians(threshold_deg),
                          _threshold(0.0, np.shape(free)))
    nodes = path[keep]
    if count_sharp_turns(nodes) > count_sharp_turns(path):
        return path, True
    return nodes, False


def _check_kng(params: Mapping[str, Any]) -> None:
    """Validates `astar_kng`'s parameters (the threshold in degrees, then A*'s)."""
    t = params["threshold_deg"]
    if isinstance(t, bool) or not isinstance(t, (int, float, np.integer, np.floating)):
        raise ValueError(f"threshold_deg must be a number of degrees, got {t!r}")
    if not math.isfinite(float(t)) or not 0.0 < float(t) <= 180.0:
        raise ValueError(f"threshold_deg must be an angle in (0, 180] degrees, got {t!r}")
    _validate_exact(params)


def astar_kng(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, seed: int = 0, *, threshold_deg: float = 20.0,
    connectivity: int = 8, vehicle_height: float | None = None,
) -> PlanResult:
    """A* followed by key-node guidance (li2026).

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells; a blocked or outside cell raises ``ValueError``.
      seed: ignored (the planner is deterministic); kept for the common signature.
      threshold_deg: nodes whose heading change is under this angle are dropped (20° in li2026).
      connectivity: 4, 8 or 16 (A*'s moves).
      vehicle_height: cells with ``clearance_height <= vehicle_height`` are blocked, for A*
        and for the line-of-sight test between key nodes.

    Returns:
      `PlanResult` as in the module docstring; ``success=False`` if the goal is unreachable.
    """
    _check_kng({"threshold_deg": threshold_deg, "connectivity": connectivity, "vehicle_height": vehicle_height})
    t0 = time.perf_counter()
    exact = astar(grid, start, goal, connectivity=connectivity, vehicle_height=vehicle_height)
    if not exact.success:
        return PlanResult.failure("astar_kng", time.perf_counter() - t0, expanded=exact.info["expanded"],
                                  reason="goal not reachable from start")
    # Line of sight is judged on the map the vehicle sees (low tunnels count as blocked).
    nodes, fallback = key_node_path(passable(grid, vehicle_height), exact.path, float(threshold_deg))
    res = float(grid.resolution)
    length = path_length(nodes, res)
    return PlanResult.found("astar_kng", nodes, length, count_turns(nodes), time.perf_counter() - t0,
                            grid_path=exact.path, grid_length=exact.length, expanded=exact.info["expanded"],
                            removed=len(exact.path) - len(nodes), fallback=fallback)


def _register() -> None:
    from jaxplan.registry import register_planner

    register_planner(
        "astar_kng",
        lambda grid, start, goal, seed, **p: astar_kng(grid, start, goal, seed, **p),
        {"threshold_deg": 20.0, "connectivity": 8, "vehicle_height": None},
        "KNG-A* (li2026): A* path reduced to key nodes (heading change >= 20 deg, line of sight kept)",
        _check_kng,
        deterministic=True,
    )


_register()
