"""The move graph of a map and exact distances on it: search graphs, distance fields, shortest paths.

The move rules are those of `jaxplan.grid.neighbour_table` (no corner cutting;
16-connected moves need the crossed cells free), so lengths equal the optimal
lengths of MovingAI scenario files for 8-connected maps. The searches run in the
compiled loops of `jaxplan.grid._kernels`. They live in `grid`, below the planners,
because maps need them: distance fields (`goal_distance_field`, the ACO's geodesic
heuristic), generators' reachability checks and the optimality reference of the
metrics. The planners `astar`/`dijkstra` (`jaxplan.search`) wrap `shortest_path`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.core.cache import digest, memoize
from jaxplan.grid import _kernels as K
from jaxplan.grid._gridmap import GridMap, check_cell, check_pairs, passable
from jaxplan.grid._neighbours import Neighbours, neighbour_table
from jaxplan.grid._search_parts import H_EUCLID, H_MANHATTAN, H_NONE, H_OCTILE

__all__ = ["SearchGraph", "search_graph", "shortest_path", "shortest_lengths", "distance_from"]

_HEURISTIC = {4: H_MANHATTAN, 8: H_OCTILE, 16: H_EUCLID}


class SearchGraph(NamedTuple):
    """A map prepared for exact search: its move table, in cell units, plus what the kernels need.

    Build once with `search_graph` and reuse for many queries.
    """

    grid: GridMap
    moves: Neighbours
    step_cells: np.ndarray  # f64[K] move lengths in cells
    passable: np.ndarray  # bool[H, W]
    capacity: int  # heap size that cannot overflow: valid moves + 1
    vehicle_height: float | None


def _graph_key(grid: GridMap, connectivity: int, vehicle_height: float | None) -> tuple:
    return (digest(passable(grid, vehicle_height)), float(grid.resolution), int(connectivity))


def search_graph(grid: GridMap, connectivity: int = 8, vehicle_height: float | None = None) -> SearchGraph:
    """Prepares (or fetches from a small memo keyed by the passable cells) the search graph of ``grid``."""
    return _search_graph(grid, connectivity, vehicle_height)._replace(grid=grid)


@memoize(maxsize=8, key=_graph_key)  # repeated `jp.plan` calls on one map do not rebuild the move table
def _search_graph(grid: GridMap, connectivity: int, vehicle_height: float | None) -> SearchGraph:
    moves = neighbour_table(grid, connectivity, vehicle_height)
    return SearchGraph(
        grid=grid,
        moves=moves,
        step_cells=np.hypot(moves.offsets[:, 0], moves.offsets[:, 1]).astype(np.float64),
        passable=passable(grid, vehicle_height),
        capacity=int(moves.valid.sum()) + 1,
        vehicle_height=vehicle_height,
    )


def _walk_back(parent: np.ndarray, goal: int, width: int) -> np.ndarray:
    chain = [goal]
    node = goal
    while parent[node] != node:
        node = int(parent[node])
        chain.append(node)
    flat = np.array(chain[::-1], dtype=np.int64)
    return np.stack([flat % width, flat // width], axis=1)


def shortest_path(
    graph: SearchGraph, start: ArrayLike, goal: ArrayLike, heuristic: bool = True
) -> tuple[np.ndarray | None, float, int]:
    """One shortest path by A* (``heuristic``: octile for 8-connected moves, Manhattan for 4, Euclidean
    for 16) or Dijkstra (``heuristic=False``).

    Args:
      graph: the map's `SearchGraph` (its connectivity decides the heuristic).
      start, goal: ``(x, y)`` cells; a blocked or outside cell raises ``ValueError``.

    Returns:
      ``(path int64[L, 2] or None if unreachable, length in metres (inf if unreachable), expanded nodes)``.
    """
    grid = graph.grid
    s = check_cell(grid, start, "start", graph.passable)
    g = check_cell(grid, goal, "goal", graph.passable)
    W = grid.width
    hkind = _HEURISTIC[graph.moves.connectivity] if heuristic else H_NONE
    dist, parent, expanded = K.path_search(
        graph.moves.index, graph.moves.valid, graph.step_cells, W,
        s[1] * W + s[0], g[1] * W + g[0], hkind, graph.capacity,
    )
    if not np.isfinite(dist):
        return None, float("inf"), int(expanded)
    return _walk_back(parent, g[1] * W + g[0], W), float(dist) * float(grid.resolution), int(expanded)


def shortest_lengths(
    grid: GridMap,
    starts: ArrayLike,
    goals: ArrayLike,
    connectivity: int = 8,
    vehicle_height: float | None = None,
) -> np.ndarray:
    """Exact shortest-path lengths (m) for many start–goal pairs at once.

    Moves are symmetric, so each pair is searched from whichever of its two ends
    is shared by more pairs: rows are grouped by that end, and one A* per group
    (heuristic = nearest of the group's targets) settles all its targets. Groups
    run in parallel on all cores.

    Args:
      grid: the map.
      starts, goals: ``int[N, 2]`` cells ``(x, y)``.
      connectivity: 4, 8 or 16.
      vehicle_height: cells too low for the vehicle are blocked.

    Returns:
      ``f64[N]`` lengths in metres; ``inf`` where the goal cannot be reached.
    """
    graph = search_graph(grid, connectivity, vehicle_height)
    s, g = check_pairs(grid, starts, goals, graph.passable, distinct=False)
    n = len(s)
    if n == 0:
        return np.zeros(0)
    W = grid.width
    fs, fg = s[:, 1] * W + s[:, 0], g[:, 1] * W + g[:, 0]
    # Search from the end that more rows share (fewer, larger groups).
    count = np.bincount(np.concatenate([fs, fg]), minlength=grid.n_cells)
    from_start = count[fs] >= count[fg]
    src = np.where(from_start, fs, fg)
    dst = np.where(from_start, fg, fs)
    order = np.argsort(src, kind="stable")
    src_sorted, dst_sorted = src[order], dst[order]
    sources, first = np.unique(src_sorted, return_index=True)
    ptr = np.append(first, n).astype(np.int64)
    n_chunks = int(min(len(sources), 8 * K.n_threads()))
    d = K.grouped_distances(
        graph.moves.index, graph.moves.valid, graph.step_cells, W, _HEURISTIC[connectivity],
        sources.astype(np.int64), ptr, dst_sorted.astype(np.int64), n_chunks, graph.capacity,
    )
    out = np.empty(n)
    out[order] = d * float(grid.resolution)
    return out


def distance_from(
    grid: GridMap, cell: ArrayLike, connectivity: int = 8, vehicle_height: float | None = None
) -> np.ndarray:
    """``f64[H, W]`` exact distance (m) from ``cell`` to every cell; inf where unreachable."""
    graph = search_graph(grid, connectivity, vehicle_height)
    x, y = check_cell(grid, cell, "cell", graph.passable)
    d = K.full_distances(graph.moves.index, graph.moves.valid, graph.step_cells, y * grid.width + x, graph.capacity)
    return (d * float(grid.resolution)).reshape(grid.shape)
