"""Compiled A*/Dijkstra loops over a flat neighbour table.

Exact search is a priority-queue program: sequential, branchy and tiny per step,
so it does not suit XLA (one `lax.while_loop` iteration per expansion costs more
than the whole expansion in compiled code). It is written here with numba, which
compiles these loops once per process (cached on disk) and releases the GIL, so
batches of queries run on all cores. Everything else in jaxplan is JAX.

Graph: node = flat cell index; ``index[c, k]``/``valid[c, k]`` are the moves of
`jaxplan.grid.Neighbours`; ``step[k]`` the move lengths in cells. Heuristics are
consistent lower bounds in cells: 0 (Dijkstra), Manhattan (4-connected), octile
(8-connected) or Euclidean (16-connected: every move is at least as long as its
displacement). With a consistent heuristic every expanded node has its exact
distance, so one search from a source serves several targets.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
from numba import njit

from jaxplan.core.compile_cache import on_first_use
from jaxplan.grid._search_parts import H_NONE, cell_heuristic

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

# Up to this many targets the heuristic is the minimum over targets; beyond, plain Dijkstra.
_MAX_HEURISTIC_TARGETS = 8


@njit(cache=True, nogil=True, inline="always")
def _before(f1, g1, f2, g2):
    # Order by f, then prefer the deeper node (larger g): fewer expansions on plateaus.
    return f1 < f2 or (f1 == f2 and g1 > g2)


@njit(cache=True, nogil=True)
def _push(hf, hg, hv, size, f, g, v):
    """Binary-heap insert; moves a hole up instead of swapping. Returns the new size."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if not _before(f, g, hf[p], hg[p]):
            break
        hf[i] = hf[p]
        hg[i] = hg[p]
        hv[i] = hv[p]
        i = p
    hf[i] = f
    hg[i] = g
    hv[i] = v
    return size + 1


@njit(cache=True, nogil=True)
def _pop(hf, hg, hv, size):
    """Removes the root (read it first); sifts the last entry down a hole. Returns the new size."""
    size -= 1
    f = hf[size]
    g = hg[size]
    v = hv[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and _before(hf[c + 1], hg[c + 1], hf[c], hg[c]):
            c += 1
        if not _before(hf[c], hg[c], f, g):
            break
        hf[i] = hf[c]
        hg[i] = hg[c]
        hv[i] = hv[c]
        i = c
    hf[i] = f
    hg[i] = g
    hv[i] = v
    return size


@njit(cache=True, nogil=True)
def _search(index, valid, step, width, source, targets, hkind, stamp, g, seen, closed, tmark, parent, hf, hg, hv, out):
    """One search from ``source``; writes the distances of ``targets`` into ``out``.

    Work arrays ``g, seen, closed, tmark, parent`` are ``[C]`` and reused across calls:
    an entry belongs to this search only where its stamp array equals ``stamp``.
    With no targets the search runs until the queue is empty (a full Dijkstra).

    Returns the number of expanded nodes.
    """
    n_t = targets.shape[0]
    remaining = 0
    for t in range(n_t):
        c = targets[t]
        out[t] = np.inf
        if tmark[c] != stamp:
            tmark[c] = stamp
            remaining += 1
    use_h = hkind != H_NONE and 0 < n_t <= _MAX_HEURISTIC_TARGETS
    tx = np.empty(n_t, np.int64)
    ty = np.empty(n_t, np.int64)
    for t in range(n_t):
        tx[t] = targets[t] % width
        ty[t] = targets[t] // width
    sx = source % width
    sy = source // width

    h0 = 0.0
    if use_h:
        h0 = np.inf
        for t in range(n_t):
            h0 = min(h0, cell_heuristic(hkind, sx, sy, tx[t], ty[t]))
    g[source] = 0.0
    seen[source] = stamp
    parent[source] = source
    size = _push(hf, hg, hv, 0, h0, 0.0, source)
    expanded = 0
    n_k = index.shape[1]
    while size > 0:
        u = hv[0]
        gu = hg[0]
        size = _pop(hf, hg, hv, size)
        if closed[u] == stamp or gu > g[u]:
            continue
        closed[u] = stamp
        expanded += 1
        if n_t > 0 and tmark[u] == stamp:
            remaining -= 1
            if remaining == 0:
                break
        for k in range(n_k):
            if not valid[u, k]:
                continue
            v = index[u, k]
            if closed[v] == stamp:
                continue
            gv = gu + step[k]
            if seen[v] != stamp or gv < g[v]:
                seen[v] = stamp
                g[v] = gv
                parent[v] = u
                hv_ = 0.0
                if use_h:
                    vy = v // width
                    vx = v - vy * width
                    hv_ = np.inf
                    for t in range(n_t):
                        hv_ = min(hv_, cell_heuristic(hkind, vx, vy, tx[t], ty[t]))
                size = _push(hf, hg, hv, size, gv + hv_, gv, v)
    for t in range(n_t):
        c = targets[t]
        if closed[c] == stamp:
            out[t] = g[c]
    return expanded


@njit(cache=True, nogil=True)
def _work_arrays(n, capacity):
    """Fresh work arrays of `_search` for ``n`` nodes and a heap of ``capacity`` entries."""
    parent = np.empty(n, np.int32)
    parent[:] = -1
    return (
        np.empty(n, np.float64), np.zeros(n, np.int32), np.zeros(n, np.int32), np.zeros(n, np.int32), parent,
        np.empty(capacity, np.float64), np.empty(capacity, np.float64), np.empty(capacity, np.int32),
    )


@njit(cache=True, nogil=True)
def path_search(index, valid, step, width, source, target, hkind, capacity):
    """Single-pair search. Returns ``(distance in cells, parent[C], expanded)``;
    ``distance`` is inf when the target cannot be reached."""
    n = index.shape[0]
    g, seen, closed, tmark, parent, hf, hg, hv = _work_arrays(n, capacity)
    targets = np.array([target], dtype=np.int64)
    out = np.empty(1, np.float64)
    # np.int64 constants, not literals: a literal argument compiles `_search` once more per caller.
    expanded = _search(index, valid, step, width, source, targets, hkind, np.int64(1), g, seen, closed, tmark, parent,
                       hf, hg, hv, out)
    return out[0], parent, expanded


@njit(cache=True, nogil=True)
def full_distances(index, valid, step, source, capacity):
    """Dijkstra from ``source`` to every node: ``f64[C]`` distances in cells (inf unreachable)."""
    n = index.shape[0]
    g, seen, closed, tmark, parent, hf, hg, hv = _work_arrays(n, capacity)
    targets = np.empty(0, dtype=np.int64)
    out = np.empty(0, np.float64)
    _search(index, valid, step, np.int64(1), source, targets, np.int64(H_NONE), np.int64(1), g, seen, closed, tmark,
            parent, hf, hg, hv, out)
    dist = np.full(n, np.inf)
    for i in range(n):
        if closed[i] == 1:
            dist[i] = g[i]
    return dist


@njit(cache=True, nogil=True)
def _grouped_chunk(index, valid, step, width, hkind, sources, target_ptr, targets, lo, hi, capacity, out):
    """Searches from ``sources[lo:hi]`` with one set of work arrays (stamped, so nothing is
    cleared between searches); source s writes ``out[target_ptr[s]:target_ptr[s+1]]``."""
    g, seen, closed, tmark, parent, hf, hg, hv = _work_arrays(index.shape[0], capacity)
    for s in range(lo, hi):
        a = target_ptr[s]
        b = target_ptr[s + 1]
        _search(
            index, valid, step, width, sources[s], targets[a:b], hkind, s - lo + 1,
            g, seen, closed, tmark, parent, hf, hg, hv, out[a:b],
        )


def grouped_distances(index, valid, step, width, hkind, sources, target_ptr, targets, n_chunks, capacity):
    """Searches from each of ``sources``; source s serves ``targets[target_ptr[s]:target_ptr[s+1]]``.

    Sources are split into ``n_chunks`` contiguous chunks, run on `n_threads` Python threads
    (the compiled chunk releases the GIL). Threads rather than a numba ``prange``: the same
    speed, and a parallel loop would lengthen the first compilation.

    Returns ``f64[len(targets)]`` distances in cells (inf where unreachable).
    """
    n_src = int(sources.shape[0])
    out = np.empty(targets.shape[0], np.float64)
    bounds = [(c * n_src // n_chunks, (c + 1) * n_src // n_chunks) for c in range(max(1, int(n_chunks)))]
    bounds = [(lo, hi) for lo, hi in bounds if lo < hi]

    def run(b):
        _grouped_chunk(index, valid, step, width, hkind, sources, target_ptr, targets, b[0], b[1], capacity, out)

    workers = min(len(bounds), n_threads())
    if workers <= 1:
        for b in bounds:
            run(b)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(run, bounds))
    return out


def n_threads() -> int:
    return int(numba.get_num_threads())
