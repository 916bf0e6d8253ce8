"""A binary min-heap over two parallel arrays (keys ``hf``, values ``hv``) for numba kernels: the Dijkstra and
A* searches over (cell, incoming move) states (`jaxplan.grid.state_cost_to_go`,
`jaxplan.search.exact_objective`) share it. Ties pop in no defined order; callers that need a tie rule (the
cell searches of `jaxplan.grid._kernels`) keep their own."""

from __future__ import annotations

from numba import njit

__all__ = ["heap_pop", "heap_push"]


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
