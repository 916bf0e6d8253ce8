"""Numba pieces the grid searches share: the cell-distance lower bound of A* (`cell_heuristic`, used by
`jaxplan.grid`'s cell searches and `jaxplan.search.exact_objective`) and a binary min-heap over two parallel
arrays (keys ``hf``, values ``hv``) for the searches over (cell, incoming move) states
(`jaxplan.grid.state_cost_to_go`, `jaxplan.search.exact_objective`), which grows by doubling (`heap_room`). The
heap pops ties in no defined order; the cell searches of `jaxplan.grid._kernels` keep their own heap with a tie
rule (deeper nodes first), which decides which of several shortest paths they return."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from jaxplan.core.compile_cache import on_first_use

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = ["H_EUCLID", "H_MANHATTAN", "H_NONE", "H_OCTILE", "cell_heuristic", "heap_pop", "heap_push", "heap_room"]

H_NONE, H_MANHATTAN, H_OCTILE, H_EUCLID = 0, 1, 2, 3
"""`cell_heuristic` kinds: none (Dijkstra), 4-, 8- and 16-connected grids."""
_SQRT2M1 = math.sqrt(2.0) - 1.0


@njit(cache=True, nogil=True, inline="always")
def cell_heuristic(kind: int, x: int, y: int, tx: int, ty: int) -> float:
    """Lower bound of the remaining length in cells from (x, y) to (tx, ty), consistent for the connectivity's
    moves (``kind`` one of the ``H_*`` constants)."""
    dx = abs(x - tx)
    dy = abs(y - ty)
    if kind == H_MANHATTAN:
        return float(dx + dy)
    if kind == H_OCTILE:
        return float(max(dx, dy)) + _SQRT2M1 * float(min(dx, dy))
    if kind == H_EUCLID:
        return math.sqrt(float(dx * dx + dy * dy))
    return 0.0


@njit(cache=True, nogil=True)
def heap_push(hf: np.ndarray, hv: np.ndarray, size: int, f: float, v: int) -> int:
    """Inserts ``v`` keyed by ``f``. Returns the new size."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if hf[p] <= f:
            break
        hf[i] = hf[p]
        hv[i] = hv[p]
        i = p
    hf[i] = f
    hv[i] = v
    return size + 1


@njit(cache=True, nogil=True)
def heap_room(hf: np.ndarray, hv: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``(hf, hv)`` with room for one more entry: the same arrays, or copies twice as long when they are full
    (a search's frontier has no useful bound before it runs)."""
    if size < hf.shape[0]:
        return hf, hv
    hf2 = np.empty(2 * size, np.float64)
    hv2 = np.empty(2 * size, np.int64)
    hf2[:size] = hf
    hv2[:size] = hv
    return hf2, hv2


@njit(cache=True, nogil=True)
def heap_pop(hf: np.ndarray, hv: np.ndarray, size: int) -> int:
    """Removes the root (read it first). Returns the new size."""
    size -= 1
    f = hf[size]
    v = hv[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and hf[c + 1] < hf[c]:
            c += 1
        if hf[c] >= f:
            break
        hf[i] = hf[c]
        hv[i] = hv[c]
        i = c
    hf[i] = f
    hv[i] = v
    return size
