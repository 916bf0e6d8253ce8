"""Ants walking in parallel: inverse-CDF sampling, bit-packed tabu, dead-end rules.

All ants of all colonies advance together, one `lax.while_loop` step per move, as
``[A, K]`` array operations (A ants, K moves). The loop ends when every ant has
stopped or after ``max_steps`` steps. Memory is bounded by the bit-packed tabu
(``A * ceil(C / 32)`` words) and the path buffers (``A * (max_steps + 1)``):
1,024 ants on brc202d (254,930 cells, 2,048 steps) need about 45 MB.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp

__all__ = ["Ants", "walk", "draw", "hash_uniform", "move_lut", "moves_between", "WALKING", "GOAL", "DEAD_END",
           "STEP_LIMIT", "DEAD_END_RULES"]

WALKING, GOAL, DEAD_END, STEP_LIMIT = 0, 1, 2, 3
# Compact the walking ants into a quarter-size loop once most have stopped (from this many ants).
COMPACT_MIN_ANTS, COMPACT_FACTOR = 512, 4
DEAD_END_RULES = ("die", "retreat", "alert")


class Ants(NamedTuple):
    """Paths of one iteration's ants.

    Attributes:
      cells: ``i32[A, L + 1]`` visited cells; entries past ``n`` are unspecified (stale or never written).
      moves: ``i8[A, L]`` move index taken at each step; entries from ``n`` on are unspecified.
      n: ``i32[A]`` number of moves in the final path.
      status: ``i32[A]``: 1 goal reached, 2 stopped at a dead end, 3 step limit.
      penalty: ``f32[C * K]`` or ``None``: count of retreats over each edge (yu2020's
        dead-corner penalty), summed over ants of each colony: ``f32[S, C * K]``.
      ant_steps: ``i32[A]`` loop steps during which each ant was walking (throughput counter).
      loop_steps: ``i32`` iterations of the step loop (``A * loop_steps`` step slots).
      slots: ``i32`` ant slots the loop processed (``A`` per step, ``A/4`` once compacted).
      marks: ``bool[B * C]`` (``dead_end="alert"``): cells found to be true dead ends
        (no allowed move but the way back), to become pseudo-obstacles of their run.
      stats: ``f32[N_STATS, A]`` path statistics (`jaxplan.aco._walk_numba.path_stats`), from the
        numba walk; None from `walk`.
    """

    cells: jnp.ndarray
    moves: jnp.ndarray
    n: jnp.ndarray
    status: jnp.ndarray
    penalty: jnp.ndarray | None
    ant_steps: jnp.ndarray
    loop_steps: jnp.ndarray
    marks: jnp.ndarray | None = None
    slots: jnp.ndarray | None = None
    stats: jnp.ndarray | None = None


def draw(p: jnp.ndarray, nb: jnp.ndarray, u: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """Inverse-CDF draw of one move per ant from unnormalised weights ``p [A, K]``.

    Uses one uniform ``u [A]`` in [0, 1) per ant and picks the first move whose
    cumulative weight exceeds ``u * Σp``; zero-weight moves are never chosen. The
    loop over the K moves is unrolled (K is small and static): on a CPU this is
    several times faster than `cumsum` and a reduction over a minor axis of size K.

    Returns:
      ``(k, target, any)``: move index ``i32[A]``, the chosen target ``nb[a, k]`` and
      whether the ant had any move (Σp > 0).
    """
    K = p.shape[1]
    # Work on [K, A]: slicing one move for all ants is then a contiguous row. On a CPU the
    # strided [A, K] slices were ~8x slower than the transpose they save.
    pt = p.T
    total = pt[0]
    for j in range(1, K):
        total = total + pt[j]
    threshold = u * total
    # k = first move whose cumulative weight exceeds the threshold = number of cumulative
    # weights at or below it. One output per fusion: XLA recomputes a shared chain in every
    # fusion that needs one of its results, so `new` is gathered from k instead.
    acc = pt[0]
    k = (acc <= threshold).astype(jnp.int32)
    for j in range(1, K - 1):
        acc = acc + pt[j]
        k = k + (acc <= threshold).astype(jnp.int32)
    new = jnp.take_along_axis(nb, k[:, None], axis=1)[:, 0]
    return k, new, total > 0


def hash_uniform(seed: jnp.ndarray, t: jnp.ndarray, ant: jnp.ndarray) -> jnp.ndarray:
    """Counter-based uniforms in [0, 1): the lowbias32 integer hash of (seed, step, ant).

    Threading a JAX PRNG key through the step loop costs more than the step itself on a
    CPU (threefry is a loop of its own); a stateless hash of the step and ant indices,
    seeded from the iteration's key, gives one independent-looking uniform per ant and
    step in a handful of fused integer operations.
    """
    x = ant.astype(jnp.uint32) * jnp.uint32(0x9E3779B9) ^ (t.astype(jnp.uint32) * jnp.uint32(0x85EBCA6B) + seed)
    x = x ^ (x >> 16)
    x = x * jnp.uint32(0x7FEB352D)
    x = x ^ (x >> 15)
    x = x * jnp.uint32(0x846CA68B)
    x = x ^ (x >> 16)
    return (x >> 8).astype(jnp.float32) * jnp.float32(1.0 / (1 << 24))


def move_lut(offsets: jnp.ndarray) -> jnp.ndarray:
    """``i32[25]``: index of the move (dx, dy) at ``(dy + 2) * 5 + dx + 2``, −1 if none."""
    k = offsets.shape[0]
    slots = (offsets[:, 1] + 2) * 5 + offsets[:, 0] + 2
    return jnp.full((25,), -1, jnp.int32).at[slots].set(jnp.arange(k, dtype=jnp.int32))


def moves_between(a: jnp.ndarray, b: jnp.ndarray, width: int, lut: jnp.ndarray) -> jnp.ndarray:
    """Move index from flat cells ``a`` to ``b`` (same shapes), −1 where not a move."""
    dx = b % width - a % width
    dy = b // width - a // width
    inside = (jnp.abs(dx) <= 2) & (jnp.abs(dy) <= 2)
    return jnp.where(inside, lut[jnp.clip((dy + 2) * 5 + dx + 2, 0, 24)], -1)


def walk(
    nbr: jnp.ndarray,
    table: jnp.ndarray,
    start: jnp.ndarray,
    goal: jnp.ndarray,
    row0: jnp.ndarray,
    cell0: jnp.ndarray,
    seed: jnp.ndarray,
    local: jnp.ndarray,
    alert: jnp.ndarray | None,
    *,
    max_steps: int,
    width: int,
    lut: jnp.ndarray,
    dead_end: str,
    penalty_size: int = 0,
    hook: Callable | None = None,
) -> Ants:
    """Walks A ants at once; each ant carries the indices of its run and colony.

    Ants of different runs (scenarios × seeds × colonies) share one loop, so a whole
    batch advances as one array program with a single, unbatched loop condition.

    Args:
      nbr: ``i32[C, K]`` target cell of each move, −1 where the move is not allowed.
      table: ``f32[G * C, K]`` per colony-of-a-run g and cell: without ``hook``, move
        weights τ^α·η^β normalised so each cell's largest is 1 (0 where not allowed);
        with ``hook``, the logits the hook adds to.
      start, goal: ``i32[A]`` each ant's start and goal cells.
      row0: ``i32[A]`` offset ``g * C`` of the ant's colony in ``table`` (and in the penalty).
      cell0: ``i32[A]`` offset ``b * C`` of the ant's run in per-run cell arrays (``alert``, hook fields).
      seed: ``u32[A]`` the run's seed for this iteration; local: ``i32[A]`` the ant's index
        within its run. Uniforms depend only on these, so a run draws the same numbers
        whatever else shares the batch.
      alert: ``bool[B * C]`` pseudo-obstacles of each run, or None.
      max_steps, width: static sizes (``width`` = map columns).
      lut: `move_lut` of the map's moves.
      dead_end: ``"die"``, ``"retreat"`` (step back, keep the dead cell tabu) or ``"alert"``
        (step back as well, and report true dead ends in ``marks``).
      penalty_size: if > 0, count retreats per edge into ``f32[penalty_size]`` (``G * C * K``).
      hook: optional ``hook(pos, prev, nb, ok, logits, goal, cell0) -> (logits, ok)`` adding
        state-dependent logits or restricting moves (opt_ant's heuristic and right-hand rule).

    Returns:
      `Ants` (``penalty`` flat ``[G * C * K]``).
    """
    L = max_steps
    A = start.shape[0]
    C, K = nbr.shape
    n_words = (C + 31) // 32
    ar = jnp.arange(A)
    one = jnp.uint32(1)
    bits = jnp.zeros((A, n_words), jnp.uint32)
    bits = bits.at[ar, start >> 5].set(jnp.left_shift(one, (start & 31).astype(jnp.uint32)))
    cells = jnp.zeros((A, L + 1), jnp.int32).at[:, 0].set(start)
    penalty = jnp.zeros((penalty_size,), jnp.float32) if penalty_size else None
    marks = None
    if dead_end == "alert":
        assert alert is not None, "dead_end='alert' needs the alert table"
        marks = jnp.zeros(alert.shape, bool)
    tiny = jnp.finfo(jnp.float32).tiny
    # Per-ant scalars travel as one [5, A] array (position, previous move, path depth, status,
    # steps walked): XLA then updates them in one fused kernel instead of one per field.
    zeros = jnp.zeros((A,), jnp.int32)
    st0 = jnp.stack([start, zeros - 1, zeros, zeros, zeros])
    consts0 = jnp.stack([start, goal, row0, cell0, jax.lax.bitcast_convert_type(seed, jnp.int32), local])

    def loop(carry, consts, keep_going):
        """Runs the step loop over the ants in ``carry`` while ``keep_going(st)`` holds."""
        start, goal, row0, cell0, seed_i, local = consts
        seed = jax.lax.bitcast_convert_type(seed_i, jnp.uint32)
        ar_ = jnp.arange(consts.shape[1])

        def cond(carry):
            t, st, *_ = carry
            return (t < L) & keep_going(st)

        def body(carry):
            t, st, bits, cells, (penalty, marks) = carry
            pos, prev, n, status, counted = st
            walking = status == WALKING
            nb = nbr[pos]  # [A, K]
            safe = jnp.maximum(nb, 0)
            words = jnp.take_along_axis(bits, safe >> 5, axis=1)
            seen = (jnp.right_shift(words, (safe & 31).astype(jnp.uint32)) & one).astype(bool)
            ok = (nb >= 0) & ~seen & walking[:, None]
            if alert is not None:
                ok = ok & ~alert[cell0[:, None] + safe]
            row = table[row0 + pos]
            if hook is None:
                # A minimum-normal floor keeps allowed moves drawable when all their weights underflowed.
                p = jnp.where(ok, row + tiny, 0.0)
            else:
                logits, ok = hook(pos, prev, nb, ok, row, goal, cell0)
                logits = jnp.where(ok, logits, -jnp.inf)
                mx = jnp.max(logits, axis=1, keepdims=True)
                p = jnp.where(ok, jnp.exp(logits - jnp.where(jnp.isfinite(mx), mx, 0.0)) + tiny, 0.0)
            k, new, fwd = draw(p, nb, hash_uniform(seed, t, local))
            n_new = jnp.where(fwd, n + 1, n)
            word = new >> 5
            bit = jnp.left_shift(one, (new & 31).astype(jnp.uint32))
            bits = bits.at[ar_, jnp.where(fwd, word, n_words)].set(bits[ar_, word] | bit, mode="drop")
            pos_new = jnp.where(fwd, new, pos)
            prev_new = jnp.where(fwd, k, prev)
            stuck = walking & ~fwd
            if marks is not None:
                # chu2024's dead-end alert: a cell whose only allowed move (ignoring the ant's own
                # tabu) leads back is a dead end for every later ant of the run.
                open_moves = jnp.sum((nb >= 0) & ~alert[cell0[:, None] + safe], axis=1)
                dead = stuck & (open_moves <= 1) & (pos != start) & (pos != goal)
                marks = marks.at[jnp.where(dead, cell0 + pos, marks.shape[0])].set(True, mode="drop")
            if dead_end in ("retreat", "alert"):
                back = stuck & (n > 0)
                prev_cell = cells[ar_, jnp.maximum(n - 1, 0)]
                if penalty is not None:
                    edge = (row0 + prev_cell) * K + moves_between(prev_cell, pos, width, lut)
                    penalty = penalty.at[jnp.where(back, edge, penalty_size)].add(1.0, mode="drop")
                pos_new = jnp.where(back, prev_cell, pos_new)
                if hook is not None:
                    before = cells[ar_, jnp.maximum(n - 2, 0)]
                    undone = jnp.where(n >= 2, moves_between(before, prev_cell, width, lut), -1)
                    prev_new = jnp.where(back, undone, prev_new)
                n_new = jnp.where(back, n - 1, n_new)
                dies = stuck & (n == 0)
            else:
                dies = stuck
            slot = jnp.where(fwd, n_new, L + 1)
            if dead_end in ("retreat", "alert"):
                # Make the write depend on the reads of `cells` above, so XLA orders it after them
                # and updates the buffer in place instead of copying it every step.
                slot = jnp.where(prev_cell < 0, L + 1, slot)
            cells = cells.at[ar_, slot].set(new, mode="drop")
            status = jnp.where(dies, DEAD_END, status)
            status = jnp.where(fwd & (new == goal), GOAL, status)
            counted = counted + walking.astype(jnp.int32)
            st = jnp.stack([pos_new, prev_new, n_new, status, counted])
            return (t + 1, st, bits, cells, (penalty, marks))

        return jax.lax.while_loop(cond, body, carry)

    carry: tuple[Any, ...] = (jnp.int32(0), st0, bits, cells, (penalty, marks))
    small = A // COMPACT_FACTOR
    if A >= COMPACT_MIN_ANTS:
        # Ants that stopped still occupy their slot in every later step. Once no more than
        # A/4 are walking, continue with only those (walking ants first, in their original
        # order), then write their state back: same results, a quarter of the work per step.
        carry = loop(carry, consts0, lambda st: jnp.sum(st[3] == WALKING) > small)
        t, st, bits, cells, extra = carry
        t_full = t
        idx = jnp.argsort(st[3] != WALKING, stable=True)[:small]
        sub = (t, st[:, idx], bits[idx], cells[idx], extra)
        t, st_s, _, cells_s, extra = loop(sub, consts0[:, idx], lambda st: jnp.any(st[3] == WALKING))
        carry = (t, st.at[:, idx].set(st_s), None, cells.at[idx].set(cells_s), extra)
        slots = t_full * A + (t - t_full) * small
    else:
        carry = loop(carry, consts0, lambda st: jnp.any(st[3] == WALKING))
        slots = carry[0] * A
    t, st, _, cells, (penalty, marks) = carry
    pos, prev, n, status, counted = st
    status = jnp.where(status == WALKING, STEP_LIMIT, status)
    moves = jnp.maximum(moves_between(cells[:, :-1], cells[:, 1:], width, lut), 0).astype(jnp.int8)
    return Ants(cells=cells, moves=moves, n=n, status=status, penalty=penalty,
                ant_steps=counted, loop_steps=t, marks=marks, slots=slots)
