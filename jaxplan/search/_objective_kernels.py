"""Compiled A* over (cell, incoming move) states: the exact minimum of a cost that sums moves, turns and cells.

A colony's path cost (`jaxplan.search.exact_objective`) is a weighted sum of three kinds of terms:

* per move k: ``w_len · step[k]`` (metres);
* per pair of consecutive moves (m, k) with m ≠ k: ``w_angle · angle[m, k] + w_turn`` (a heading change in
  radians, and one turn);
* per path cell c, start and goal included: ``cell[c]``.

The turn terms depend on the move a cell was entered by, so the search runs over states
``s = c · (K + 1) + m + 1`` (cell c entered by move m; ``m = −1``: the start, entered by no move).
All terms are >= 0, so A* with a consistent heuristic (``w_len`` times a straight-line lower bound
of the remaining length) settles each state at its exact cost. The first goal state settled is
the optimum.

Move rules, beside the map's (``valid``): with ``goal_first`` an adjacent goal must be taken
(chu2024's ant hook gives it absolute priority), and on a ``turn_rule`` cell entered by move m
the move ``right[m]`` a quarter turn to the right is forced when it is allowed (chu2024's
right-hand rule), as `jaxplan.aco`'s walk applies them.

Written with numba like `jaxplan.grid`'s A*/Dijkstra loops (sequential, branchy, tiny per step);
cached on disk, GIL released, so batches of queries run on threads.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
from numba import njit

from jaxplan.core.compile_cache import on_first_use
from jaxplan.grid import cell_heuristic, heap_pop, heap_push, heap_room

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below


@njit(cache=True, nogil=True)
def state_search(index, valid, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first,
                 width, hkind, h_scale, source, target, g, parent, closed):
    """A* from ``source`` to ``target`` over (cell, incoming move) states.

    Args:
      index, valid: ``[C, K]`` the map's moves (`jaxplan.grid.Neighbours`).
      step: ``f64[K]`` move lengths (m); angle: ``f64[K, K]`` |heading change| (rad); right: ``i64[K]``
        the move a quarter turn right of each move.
      cell: ``f64[C]`` cost of a path cell; turn_rule: ``bool[C]`` right-turn cells (ignored when all False).
      w_len, w_angle, w_turn: weights per metre, per radian of heading change, per turn.
      goal_first: whether an adjacent goal must be taken.
      width: map columns; hkind, h_scale: heuristic kind and its factor (``w_len`` × metres per cell).
      g, parent, closed: work arrays of ``C · (K + 1)`` states (``parent`` all −2 and ``closed`` all False on
        entry). The heap is allocated here and doubled when full (a state can be pushed once per improvement).

    Returns:
      ``(cost, goal_state, expanded)``: cost inf and goal_state −1 when the target cannot be reached.
    """
    K = index.shape[1]
    S = K + 1
    tx = target % width
    ty = target // width
    s0 = source * S
    hf = np.empty(1024, np.float64)
    hv = np.empty(1024, np.int64)
    g[s0] = cell[source]
    parent[s0] = -1
    size = heap_push(hf, hv, 0, g[s0] + h_scale * cell_heuristic(hkind, source % width, source // width, tx, ty), s0)
    expanded = 0
    while size > 0:
        s = hv[0]
        size = heap_pop(hf, hv, size)
        if closed[s]:
            continue
        closed[s] = True
        expanded += 1
        u = s // S
        m = s - u * S - 1
        gu = g[s]
        if u == target:
            return gu, s, expanded
        # Allowed moves from this state: the map's, then the colony's rules.
        only = -1
        if goal_first:
            for k in range(K):
                if valid[u, k] and index[u, k] == target:
                    only = k
        if only < 0 and m >= 0 and turn_rule[u] and valid[u, right[m]]:
            only = right[m]
        for k in range(K):
            if not valid[u, k] or (only >= 0 and k != only):
                continue
            v = index[u, k]
            t = v * S + k + 1
            if closed[t]:
                continue
            cost = gu + w_len * step[k] + cell[v]
            if m >= 0 and m != k:
                cost += w_angle * angle[m, k] + w_turn
            if parent[t] == -2 or cost < g[t]:
                g[t] = cost
                parent[t] = s
                hf, hv = heap_room(hf, hv, size)
                size = heap_push(hf, hv, size, cost + h_scale * cell_heuristic(hkind, v % width, v // width, tx, ty), t)
    return np.inf, -1, expanded


@njit(cache=True, nogil=True)
def _work(n_states):
    parent = np.empty(n_states, np.int64)
    parent[:] = -2  # -2: never reached; -1: the start state
    return np.empty(n_states, np.float64), parent, np.zeros(n_states, np.bool_)


@njit(cache=True, nogil=True)
def one_search(index, valid, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first, width, hkind,
               h_scale, source, target):
    """`state_search` with fresh work arrays. Returns ``(cost, cells of the path in order, expanded)``."""
    C, K = index.shape
    n_states = C * (K + 1)
    g, parent, closed = _work(n_states)
    cost, s, expanded = state_search(index, valid, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn,
                                     goal_first, width, hkind, h_scale, source, target, g, parent, closed)
    n = 0
    t = s
    while t >= 0:
        n += 1
        t = parent[t]
    cells = np.empty(n, np.int64)
    t = s
    i = n - 1
    while t >= 0:
        cells[i] = t // (K + 1)
        i -= 1
        t = parent[t]
    return cost, cells, expanded


@njit(cache=True, nogil=True)
def _chunk(index, valid, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first, width, hkind,
           h_scale, sources, targets, lo, hi, out):
    """Optimal costs of pairs ``lo:hi`` (``w_len`` and ``h_scale`` per pair, ``[N]``; the rest shared)."""
    C, K = index.shape
    n_states = C * (K + 1)
    for i in range(lo, hi):
        g, parent, closed = _work(n_states)
        out[i] = state_search(index, valid, step, angle, right, cell, turn_rule, w_len[i], w_angle, w_turn,
                              goal_first, width, hkind, h_scale[i], sources[i], targets[i], g, parent, closed)[0]


def many_searches(index: np.ndarray, valid: np.ndarray, step: np.ndarray, angle: np.ndarray, right: np.ndarray,
                  cell: np.ndarray, turn_rule: np.ndarray, w_len: np.ndarray, w_angle: float, w_turn: float,
                  goal_first: bool, width: int, hkind: int, h_scale: np.ndarray, sources: np.ndarray,
                  targets: np.ndarray) -> np.ndarray:
    """Optimal costs ``f64[N]`` of N pairs, on `numba.get_num_threads` Python threads (the kernel releases the GIL)."""
    n = len(sources)
    out = np.empty(n, np.float64)
    workers = max(1, min(n, int(numba.get_num_threads())))
    bounds = [(c * n // workers, (c + 1) * n // workers) for c in range(workers)]

    def run(b):
        _chunk(index, valid, step, angle, right, cell, turn_rule, w_len, w_angle, w_turn, goal_first, width, hkind,
               h_scale, sources, targets, b[0], b[1], out)

    if workers == 1:
        run(bounds[0])
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(run, bounds))
    return out
