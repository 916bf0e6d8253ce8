"""Exact cost-to-go of a cost that sums moves, turns and cells, from every (cell, incoming move) state to a goal.

The colonies' costs (`jaxplan.search.exact_objective`'s table) are sums of

* per move k: ``w_len · step[k]`` (metres);
* per pair of consecutive moves (m, k) with m ≠ k: ``w_angle · angle[m, k] + w_turn``;
* per path cell c: ``cell[c]``,

so what is left of a path once an ant stands on cell v, having entered it by move k, depends only on
that state. `state_cost_to_go` gives it for every state at once: Dijkstra backwards from the goal over
``C · K`` states, with the same move rules as the forward search (``goal_first``: an adjacent goal must be
taken; on a ``turn_rule`` cell entered by move m the move a quarter turn right is forced when allowed).
It is the exact form of an ant's heuristic "cost of this move plus cost of the rest"
(`jaxplan.aco`'s ``heuristic="objective"``); the exact optimum from a start s is
``cell[s] + min_k (w_len·step[k] + cell[v_k] + h[v_k, k])`` over the moves allowed from s.

Here, below both `jaxplan.search` (which states the planners' costs) and `jaxplan.aco` (which walks with
the table), so that neither imports the other for it. Numba, cached on disk, GIL released.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from jaxplan.core.compile_cache import on_first_use
from jaxplan.grid._gridmap import GridMap, check_cells, passable
from jaxplan.grid._neighbours import neighbour_table
from jaxplan.grid._search_parts import heap_pop, heap_push, heap_room

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = ["state_cost_to_go"]


@njit(cache=True, nogil=True)
def _backward(index, valid, offsets, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first, width,
              target, out):
    """Fills ``out f64[C, K]`` (see `state_cost_to_go`) for one target cell."""
    C, K = index.shape
    height = C // width
    out[:] = np.inf
    closed = np.zeros(C * K, np.bool_)
    # The move an adjacent goal is taken by (goal_first), per cell; -1 where the goal is not adjacent.
    goal_move = np.full(C, -1, np.int64)
    if goal_first:
        for u in range(C):
            for k in range(K):
                if valid[u, k] and index[u, k] == target:
                    goal_move[u] = k
    hf = np.empty(1024, np.float64)
    hv = np.empty(1024, np.int64)
    size = 0
    for k in range(K):
        out[target, k] = 0.0
        size = heap_push(hf, hv, size, 0.0, target * K + k)
    while size > 0:
        t = hv[0]
        size = heap_pop(hf, hv, size)
        if closed[t]:
            continue
        closed[t] = True
        v = t // K
        kk = t - v * K
        h = out[v, kk]
        # The cell u the move kk came from.
        ux = v % width - offsets[kk, 0]
        uy = v // width - offsets[kk, 1]
        if ux < 0 or ux >= width or uy < 0 or uy >= height:
            continue
        u = uy * width + ux
        if u == target or not valid[u, kk] or index[u, kk] != v:
            continue
        if goal_move[u] >= 0 and goal_move[u] != kk:
            continue
        base = h + w_len * step[kk] + cell[v]
        for m in range(K):  # u entered by move m
            if turn_rule[u] and valid[u, right[m]] and goal_move[u] < 0 and right[m] != kk:
                continue
            s = u * K + m
            if closed[s]:
                continue
            cost = base
            if m != kk:
                cost += w_angle * angle[m, kk] + w_turn
            if cost < out[u, m]:
                out[u, m] = cost
                hf, hv = heap_room(hf, hv, size)
                size = heap_push(hf, hv, size, cost, s)


@njit(cache=True, nogil=True)
def _chunk(index, valid, offsets, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first, width,
           targets, lo, hi, out):
    for i in range(lo, hi):
        _backward(index, valid, offsets, step, angle, right, cell, turn_rule, w_len[i], w_angle, w_turn, goal_first,
                  width, targets[i], out[i])


def state_cost_to_go(grid: GridMap, goals: ArrayLike, connectivity: int = 8, vehicle_height: float | None = None, *,
                     w_len: ArrayLike = 1.0, w_angle: float = 0.0, w_turn: float = 0.0, cell: ArrayLike | None = None,
                     goal_first: bool = False, turn_rule: ArrayLike | None = None) -> np.ndarray:
    """Exact cost-to-go ``f64[N, C, K]`` to each goal from every state (cell v, entered by move k).

    ``h[i, v, k]`` is the least cost of the rest of a path to ``goals[i]`` for an ant on v that entered it by
    move k (slot k of `neighbour_table`): its later moves, turns (the first one relative to k) and the cells
    they enter, v's own cell cost excluded (already paid); 0 on the goal; inf where the goal cannot be reached
    (or the state cannot occur). Work: ``O(C·K²·log)`` per goal; the goals run on `numba.get_num_threads` threads.

    Args:
      grid: the map; goals: ``int[N, 2]`` passable cells ``(x, y)``.
      connectivity, vehicle_height: the move rules (as `neighbour_table`).
      w_len: weight per metre, a scalar or one per goal ``[N]``; w_angle: per radian of heading change;
        w_turn: per turn; cell: ``f[C]`` cost of entering each cell (zeros when None), all >= 0.
      goal_first: an adjacent goal must be taken (chu2024); turn_rule: ``bool[C]`` cells with chu2024's
        forced right turn (none when None).

    Raises:
      ValueError: a goal outside the map or blocked; a negative or non-finite weight.
    """
    ok = passable(grid, vehicle_height)
    g = check_cells(grid, goals, "goals", ok)
    W = grid.width
    C = grid.n_cells
    nb = neighbour_table(grid, connectivity, vehicle_height)
    offs = nb.offsets.astype(np.int64)
    K = len(offs)
    heading = np.arctan2(offs[:, 1].astype(np.float64), offs[:, 0].astype(np.float64))
    angle = np.abs((heading[None, :] - heading[:, None] + np.pi) % (2 * np.pi) - np.pi)
    right = (np.arange(K) + K // 4) % K
    step = np.hypot(offs[:, 0], offs[:, 1]) * float(grid.resolution)
    N = len(g)
    wl = np.broadcast_to(np.asarray(w_len, np.float64), (N,)).copy()
    cellc = np.zeros(C) if cell is None else np.asarray(cell, np.float64).reshape(C)
    rule = np.zeros(C, bool) if turn_rule is None else np.asarray(turn_rule, bool).reshape(C)
    for name, v in (("w_len", wl), ("w_angle", np.asarray(w_angle)), ("w_turn", np.asarray(w_turn)),
                    ("cell", cellc)):
        if not (np.isfinite(v).all() and (v >= 0).all()):
            raise ValueError(f"state_cost_to_go: {name} must be finite and >= 0")
    out = np.empty((N, C, K), np.float64)
    if N == 0:
        return out
    targets = (g[:, 1] * W + g[:, 0]).astype(np.int64)
    args = (nb.index.astype(np.int64), nb.valid, offs, step, angle, right.astype(np.int64), cellc, rule, wl,
            float(w_angle), float(w_turn), bool(goal_first), W, targets)
    workers = max(1, min(N, int(numba.get_num_threads())))
    bounds = [(c * N // workers, (c + 1) * N // workers) for c in range(workers)]
    if workers == 1:
        _chunk(*args, 0, N, out)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(lambda b: _chunk(*args, b[0], b[1], out), bounds))
    return out
