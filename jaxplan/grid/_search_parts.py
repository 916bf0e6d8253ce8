"""Numba pieces the grid searches share: the cell-distance lower bound of A* (`cell_heuristic`, used by
`jaxplan.grid`'s cell searches and `jaxplan.search.exact_objective`) and a binary min-heap over two parallel
arrays (keys ``hf``, values ``hv``) for the searches over (cell, incoming move) states
(`jaxplan.grid.state_cost_to_go`, `jaxplan.search.exact_objective`). The heap pops ties in no defined order;
the cell searches of `jaxplan.grid._kernels` keep their own heap with a tie rule."""

from __future__ import annotations

import math

from numba import njit

from jaxplan.core.compile_cache import on_first_use

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = ["H_EUCLID", "H_MANHATTAN", "H_NONE", "H_OCTILE", "cell_heuristic", "heap_pop", "heap_push"]

H_NONE, H_MANHATTAN, H_OCTILE, H_EUCLID = 0, 1, 2, 3
"""`cell_heuristic` kinds: none (Dijkstra), 4-, 8- and 16-connected grids."""
_SQRT2M1 = math.sqrt(2.0) - 1.0


@njit(cache=True, nogil=True, inline="always")
def cell_heuristic(kind, x, y, tx, ty):
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
def heap_push(hf, hv, size, f, v):
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
def heap_pop(hf, hv, size):
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
