"""Native kernels of the colony's update on the CPU: each ant's path statistics and the pheromone deposits,
visiting only the valid steps of the paths instead of whole ``[A, L]`` buffers (for either walk).

`ant_stats` is also called by the native walk (`jaxplan.aco._walk_numba_kernels`) as soon as an ant stops;
`stats_all`, `deposit_paths` and `penalise` are the bodies of the FFI handlers (`jaxplan.aco._walk_ffi`).
Not cached on their own: the handlers that compile them in are (see `jaxplan.aco._walk_ffi`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["N_STATS", "ant_stats", "stats_all", "deposit_paths", "penalise"]

_F = np.float32

# Rows of the statistics output (`jaxplan.aco._rules.PathStats` fields, in order).
N_STATS = 7


@njit(nogil=True, inline="always")
def ant_stats(a, cells, moves, n, movef, cellf, K, stats):
    """`jaxplan.aco._rules.path_stats` of ant ``a`` (moves ``[0, n)``, cells ``[0, n]``) into ``stats[:, a]``.

    float32 sums from the first step to the last. ``movef``: ``f32[K + K * K]`` move lengths, then
    |heading change| per pair of moves; ``cellf``: ``f32[3, C]`` clearance, risk, height.
    """
    length = _F(0.0)
    turns = _F(0.0)
    heading = _F(0.0)
    # Branch-free: whether a step turns is data-dependent (a branch on it mispredicts often), and
    # keeping the heading adds its |change| of exactly 0, which leaves the float32 sum unchanged.
    before = np.int64(moves[a, 0]) if n > 0 else 0
    for t in range(n):
        mv = np.int64(moves[a, t])
        length += movef[mv]
        turns += _F(mv != before)
        heading += movef[K + before * K + mv]
        before = mv
    inv_clear = _F(0.0)
    risk = _F(0.0)
    h_sum = _F(0.0)
    for t in range(n + 1):
        c = cells[a, t]
        inv_clear += _F(1.0) / cellf[0, c]
        risk += cellf[1, c]
        h_sum += cellf[2, c]
    count = _F(n + 1)
    mean_h = h_sum / count
    msd = _F(0.0)
    for t in range(n + 1):
        d = cellf[2, cells[a, t]] - mean_h
        msd += d * d
    stats[0, a] = length
    stats[1, a] = turns
    stats[2, a] = heading
    stats[3, a] = inv_clear
    stats[4, a] = risk
    stats[5, a] = msd / count
    stats[6, a] = count


@njit(nogil=True)
def _stats_chunk(c, n_chunks, cells, moves, n, movef, cellf, K, stats):
    for a in range(c, n.shape[0], n_chunks):
        ant_stats(a, cells, moves, n[a], movef, cellf, K, stats)


@njit(nogil=True, parallel=True)
def _stats_chunks(n_chunks, cells, moves, n, movef, cellf, K, stats):
    for c in prange(n_chunks):
        _stats_chunk(c, n_chunks, cells, moves, n, movef, cellf, K, stats)


@njit(nogil=True)
def stats_all(cells, moves, n, movef, cellf, K, n_chunks, stats):
    """`ant_stats` of every ant (for paths walked in JAX: the same numbers as the numba walk's)."""
    if n_chunks == 1:
        _stats_chunk(0, 1, cells, moves, n, movef, cellf, K, stats)
    else:
        _stats_chunks(n_chunks, cells, moves, n, movef, cellf, K, stats)


@njit(nogil=True)
def deposit_paths(tau, cells, moves, n, amount, colony, CK, K):
    """``tau[colony[p] * CK + cells[p, t] * K + moves[p, t]] += amount[p]`` for ``t < n[p]``, path by path,
    step by step (the order of XLA's scatter-add over the same ``[P, L]`` updates). A zero amount is
    skipped: adding +0 to a non-negative τ changes nothing, and failed ants deposit 0."""
    for q in range(n.shape[0]):
        w = amount[q]
        if w == _F(0.0):
            continue
        base = np.int64(colony[q]) * CK
        for t in range(n[q]):
            tau[base + np.int64(cells[q, t]) * K + np.int64(moves[q, t])] += w


@njit(nogil=True)
def penalise(tau, counts, keep):
    """yu2020's dead-corner penalty: ``tau[e] *= keep ** counts[e]`` where an edge was retreated over.

    A pass over the counts, with a power only where one is non-zero (XLA's `jnp.power` over every
    edge was a noticeable share of praco's iteration; libm's powf may differ from XLA's in the last
    bit).
    """
    for e in range(counts.shape[0]):
        c = counts[e]
        if c != _F(0.0):
            tau[e] = tau[e] * keep ** c
