"""The ants' walk of one iteration as native code (numba): every run, colony and ant, from the start until goal,
dead end or step limit, shared out over the cores with `prange`.

Each kernel is the exact counterpart of `jaxplan.aco._walk.walk` (same uniforms, same float32 sums in the
same order, same dead-end rules; see `jaxplan.aco._walk_numba` for the contract). `walk_all` and
`loop_counters` are the body of the walk's FFI handler (`jaxplan.aco._walk_ffi`). Not cached on their own:
the handler that compiles them in is (see `jaxplan.aco._walk_ffi`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from jaxplan.aco._walk import COMPACT_FACTOR, COMPACT_MIN_ANTS, DEAD_END, GOAL, STEP_LIMIT, WALKING
from jaxplan.aco._walk_numba_intrinsics import TINY, draw8, exp_xla, move_between, uniform, visited3x3
from jaxplan.aco._walk_numba_update import N_STATS, ant_stats

__all__ = ["MODES", "DIE", "RETREAT", "ALERT", "NO_HOOK", "HOOK_RULES", "HOOK_TABLE", "walk_all", "loop_counters"]

DIE, RETREAT, ALERT = 0, 1, 2
MODES = {"die": DIE, "retreat": RETREAT, "alert": ALERT}
"""The dead-end rules' codes (`jaxplan.aco._walk.DEAD_END_RULES`)."""
NO_HOOK, HOOK_RULES, HOOK_TABLE = 0, 1, 2
"""The walk's ``has_hook`` codes: no hook (one weight table), chu2024's hook (logit tables chosen by the ant's
previous move, with its move rules), logit tables chosen by the previous move without move rules
(``heuristic="objective"`` of the other colonies)."""

_F = np.float32
_NEG_INF = np.float32(-np.inf)


@njit(nogil=True)
def _finish_ant(a, n, t, status, cells, moves, n_out, status_out, steps_out, movef, cellf, K, stats):
    """Writes ant ``a``'s counters and, while its path is still in cache, its path statistics. Only an
    ant at the goal has a cost (the colony gives the others cost inf and never reads their
    statistics), so the others' stay zero: most ants of early iterations stop at the step limit,
    and summing their long paths cost a third of the walk."""
    n_out[a] = n
    status_out[a] = status
    steps_out[a] = t
    if status == GOAL:
        ant_stats(a, cells, moves, n, movef, cellf, K, stats)
    else:
        for i in range(N_STATS):
            stats[i, a] = _F(0.0)


def _walk_ant_for(moves_per_cell: int):
    """`walk_ant` compiled for ``moves_per_cell`` moves per cell (0: any, read from ``nbr``). With K a
    compile-time constant the move loops unroll, which makes the 8-connected step faster."""

    # One function of ~110 lines on purpose: the step loop is the hot path, and numba keeps the reference
    # counting of array arguments inside a loop that calls a helper (inlined or not) on every step.
    @njit(nogil=True)
    def walk_ant(a, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                 max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                 steps_out, penalty, marks, stats, seen, p, ok, is_goal):
        """Walks ant ``a`` to its end and sums its path statistics if it reached the goal (zeros
        otherwise); ``seen`` is the chunk's tabu, stamped with ``a + 1`` (never cleared). Path slots
        past the final ``n`` are left as they are."""
        K = moves_per_cell if moves_per_cell else nbr.shape[1]
        L = max_steps
        s0 = start[a]
        g = goal[a]
        r0 = row0[a]
        c0 = cell0[a]
        sd = seed[a]
        loc = local[a]
        stamp = a + 1
        alerting = mode == ALERT
        pos = s0
        prev = -1
        n = 0
        status = WALKING
        cells[a, 0] = s0
        seen[s0] = stamp
        t = 0
        while t < L:
            # Allowed moves: inside the map, not tabu, not a pseudo-obstacle of the run. Written
            # without short-circuits: the branches would be unpredictable.
            row = r0 + pos
            if not has_hook:
                # Weights and their running sums (`draw`'s: Σp left to right, 0 + p[0] is p[0] exactly).
                # A disallowed move adds w·0 = +0 (w is finite), the same sum as skipping it, but without
                # a branch: which neighbours are free or visited is data-dependent, and the mispredicted
                # branches of the `w if allowed else 0` form cost about half of the step.
                acc = _F(0.0)
                for k in range(K):
                    nb = nbr[pos, k]
                    safe = max(nb, 0)
                    o = (nb >= 0) & (seen[safe] != stamp)
                    if alerting:
                        o = o & (alert[c0 + safe] == 0)
                    acc = acc + (table[row, k] + TINY) * _F(o)
                    p[k] = acc
            else:
                for k in range(K):
                    nb = nbr[pos, k]
                    safe = max(nb, 0)
                    o = (nb >= 0) & (seen[safe] != stamp)
                    if alerting:
                        o = o & (not alert[c0 + safe])
                    ok[k] = o
                if has_hook == HOOK_RULES:
                    # chu2024's hook: an adjacent goal wins (judged on the moves allowed so far), else
                    # on a right-turn cell the quarter turn right of the heading is forced when allowed.
                    any_goal = False
                    for k in range(K):
                        is_goal[k] = ok[k] and nbr[pos, k] == g
                        any_goal = any_goal or is_goal[k]
                    if any_goal:
                        for k in range(K):
                            ok[k] = is_goal[k]
                    elif prev >= 0 and turn_rule[pos]:
                        right = right_turn[prev]
                        if ok[right]:
                            for k in range(K):
                                ok[k] = k == right
                mx = _NEG_INF
                vrow = (prev + 1) * K
                for k in range(K):
                    v = hook_l[hook_v[vrow + k], row, k] if ok[k] else _NEG_INF
                    p[k] = v
                    mx = max(mx, v)
                shift = mx if np.isfinite(mx) else _F(0.0)
                acc = _F(0.0)
                for k in range(K):
                    # An allowed move whose logit is -inf gets exp(-inf) = 0, then the floor.
                    acc = acc + (exp_xla(p[k] - shift) + TINY if ok[k] else _F(0.0))
                    p[k] = acc
            # Inverse CDF with one uniform, as `draw`: k = number of the running sums of the first
            # K - 1 weights at or below u·Σp.
            total = p[K - 1]
            threshold = uniform(sd, t, loc) * total
            k = 0
            for j in range(K - 1):
                k += p[j] <= threshold
            t += 1  # the ant was walking during this step
            if total > 0:
                new = nbr[pos, k]
                moves[a, n] = k  # the move between slots n and n + 1, as `walk` derives it
                n += 1
                cells[a, n] = new
                seen[new] = stamp
                prev = k
                pos = new
                if new == g:
                    status = GOAL
                    break
                continue
            # Stuck: no allowed move.
            if alerting:
                # chu2024's dead-end alert: only one open move (the way back, ignoring this ant's tabu).
                open_moves = 0
                for j in range(K):
                    nb = nbr[pos, j]
                    open_moves += (nb >= 0) & (not alert[c0 + max(nb, 0)])
                if open_moves <= 1 and pos != s0 and pos != g:
                    marks[c0 + pos] = True
            if mode == DIE or n == 0:
                status = DEAD_END
                break
            back = cells[a, n - 1]
            if penalise:
                penalty[(r0 + back) * K + move_between(back, pos, width, lut)] += 1.0
            if has_hook:
                prev = move_between(cells[a, n - 2], back, width, lut) if n >= 2 else -1
            pos = back
            n -= 1
        if status == WALKING:
            status = STEP_LIMIT
        _finish_ant(a, n, t, status, cells, moves, n_out, status_out, steps_out, movef, cellf, K, stats)

    return walk_ant


# 8-connected grids (every preset but opt_ant) get the unrolled copy; 4- and 16-connected ones the
# general walk (a third copy would lengthen the one-off numba compile of a fresh install).
_walk_ant, _walk_ant_8 = _walk_ant_for(0), _walk_ant_for(8)


@njit(nogil=True)
def _pair_tables(lut, width):
    """Flat offsets of the 8 moves on the map (``off``) and on the tabu grid padded by one cell on every
    side (``offp``), and ``lut9 [512]``: the moves (bit k) into the cells of a 3x3 block pattern
    (bit ``3 * (dy + 1) + dx + 1``, as `visited3x3` reads it)."""
    off = np.zeros(8, np.int64)
    offp = np.zeros(8, np.int64)
    bit = np.zeros(8, np.int64)
    for idx in range(25):
        k = lut[idx]
        if k >= 0:
            dx, dy = idx % 5 - 2, idx // 5 - 2
            off[k] = dx + dy * width
            offp[k] = dx + dy * (width + 2)
            bit[k] = 3 * (dy + 1) + dx + 1
    lut9 = np.zeros(512, np.uint8)
    for b in range(512):
        m = 0
        for k in range(8):
            m |= ((b >> bit[k]) & 1) << k
        lut9[b] = m
    return off, offp, lut9


@njit(nogil=True)
def _start_ant(a, start, goal, row0, seed, local, width, cells, seen):
    """Puts ant ``a`` on its start for `_walk_pair8` (path slot 0, tabu stamp ``a + 1`` on the padded
    grid ``seen``) and returns its lane's registers ``(pos, pp, goal, row0, seed, local, stamp)``:
    ``pp`` is the start's index on the padded grid. Called once per ant, not per step."""
    pos = np.int64(start[a])
    pp = pos + (pos // width) * 2 + width + 3
    stamp = np.int32(a + 1)
    cells[a, 0] = pos
    seen[pp] = stamp
    return pos, pp, np.int64(goal[a]), np.int64(row0[a]), seed[a], np.int64(local[a]), stamp


@njit(nogil=True)
def _walk_pair8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
                movef, cellf, cells, moves, n_out, status_out, steps_out, penalty, stats):
    """`walk_ant` for the common case (8 moves, no hook, ``die`` or ``retreat``), two ants at a time.

    Ants c, c + n_chunks, ... walk in two interleaved lanes: the step of one ant is a chain of
    dependent loads and float adds (its latency, not its instruction count, sets its time), so a
    second, independent ant in the same loop body fills the waiting core. The step is also shorter than
    `walk_ant`'s: each lane's tabu is a grid padded by one cell, whose 3x3 block around the ant is read as
    three vector compares (`visited3x3`); ``vbits`` holds each cell's allowed moves as bits; the weights,
    their running sums and the inverse-CDF draw are one vector sequence (`draw8`). Same draws, same bits as `walk_ant`.

    Moves come from ``lut`` and ``width`` (``nbr`` is not read): the neighbour table must be the
    grid's own, where a valid move k from cell c leads to ``c + off[k]`` (`neighbour_table`'s).

    The two lanes' steps are written out twice on purpose: a shared step function inlined by numba
    keeps reference counting of its array arguments inside the loop (calls on every step, slower
    than the single-ant walk), and a non-inlined one costs a call per step.
    """
    A = start.shape[0]
    wp = width + 2
    size = (vbits.shape[0] // width + 2) * wp + 2
    seen0 = np.zeros(size, np.int32)
    seen1 = np.zeros(size, np.int32)
    off, offp, lut9 = _pair_tables(lut, width)
    L = max_steps
    nxt = np.int64(c)
    a0 = nxt
    nxt += n_chunks
    a1 = nxt
    nxt += n_chunks
    live0, live1 = a0 < A, a1 < A
    pos0 = pp0 = n0 = t0 = g0 = r0_0 = loc0 = np.int64(0)
    pos1 = pp1 = n1 = t1 = g1 = r0_1 = loc1 = np.int64(0)
    sd0 = sd1 = np.uint32(0)
    st0 = st1 = np.int32(0)
    if live0:
        pos0, pp0, g0, r0_0, sd0, loc0, st0 = _start_ant(a0, start, goal, row0, seed, local, width, cells, seen0)
    if live1:
        pos1, pp1, g1, r0_1, sd1, loc1, st1 = _start_ant(a1, start, goal, row0, seed, local, width, cells, seen1)
    while live0 or live1:
        s0 = s1 = WALKING
        if live0:
            allowed = np.uint32(vbits[pos0]) & ~np.uint32(lut9[visited3x3(seen0, pp0 - wp - 1, wp, st0)])
            k, total = draw8(table, r0_0 + pos0, allowed, uniform(sd0, t0, loc0))
            t0 += 1
            if total > 0:  # as walk_ant: a NaN weight (0·log 0 under β = 0) makes the ant stuck, not move blind
                pos0 += off[k]
                pp0 += offp[k]
                moves[a0, n0] = k
                n0 += 1
                cells[a0, n0] = pos0
                seen0[pp0] = st0
                if pos0 == g0:
                    s0 = GOAL
            elif mode == DIE or n0 == 0:
                s0 = DEAD_END
            else:  # retreat over the last move
                mv = np.int64(moves[a0, n0 - 1])
                if penalise:
                    penalty[(r0_0 + cells[a0, n0 - 1]) * 8 + mv] += 1.0
                pos0 -= off[mv]
                pp0 -= offp[mv]
                n0 -= 1
            if s0 == WALKING and t0 >= L:
                s0 = STEP_LIMIT
        if live1:
            allowed = np.uint32(vbits[pos1]) & ~np.uint32(lut9[visited3x3(seen1, pp1 - wp - 1, wp, st1)])
            k, total = draw8(table, r0_1 + pos1, allowed, uniform(sd1, t1, loc1))
            t1 += 1
            if total > 0:
                pos1 += off[k]
                pp1 += offp[k]
                moves[a1, n1] = k
                n1 += 1
                cells[a1, n1] = pos1
                seen1[pp1] = st1
                if pos1 == g1:
                    s1 = GOAL
            elif mode == DIE or n1 == 0:
                s1 = DEAD_END
            else:
                mv = np.int64(moves[a1, n1 - 1])
                if penalise:
                    penalty[(r0_1 + cells[a1, n1 - 1]) * 8 + mv] += 1.0
                pos1 -= off[mv]
                pp1 -= offp[mv]
                n1 -= 1
            if s1 == WALKING and t1 >= L:
                s1 = STEP_LIMIT
        if live0 and s0 != WALKING:
            _finish_ant(a0, n0, t0, s0, cells, moves, n_out, status_out, steps_out, movef, cellf, 8, stats)
            a0 = nxt
            nxt += n_chunks
            live0 = a0 < A
            if live0:
                n0 = t0 = np.int64(0)
                pos0, pp0, g0, r0_0, sd0, loc0, st0 = _start_ant(a0, start, goal, row0, seed, local, width,
                                                                   cells, seen0)
        if live1 and s1 != WALKING:
            _finish_ant(a1, n1, t1, s1, cells, moves, n_out, status_out, steps_out, movef, cellf, 8, stats)
            a1 = nxt
            nxt += n_chunks
            live1 = a1 < A
            if live1:
                n1 = t1 = np.int64(0)
                pos1, pp1, g1, r0_1, sd1, loc1, st1 = _start_ant(a1, start, goal, row0, seed, local, width,
                                                                   cells, seen1)


@njit(nogil=True)
def _walk_chunk(c, n_chunks, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                status_out, steps_out, part, marks, stats):
    """Walks ants c, c + n_chunks, ... one after another (a sequential function: called from a
    parallel loop, its array set-up must not become a parallel region of its own)."""
    A = start.shape[0]
    C, K = nbr.shape
    if K == 8 and not has_hook and mode != ALERT and max_steps > 0:
        _walk_pair8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
                    movef, cellf, cells, moves, n_out, status_out, steps_out, part, stats)
        return
    seen = np.zeros(C, np.int32)
    p = np.empty(K, np.float32)
    ok = np.empty(K, np.bool_)
    is_goal = np.empty(K, np.bool_)
    for a in range(c, A, n_chunks):
        if K == 8:
            _walk_ant_8(a, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                        alert, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                        status_out, steps_out, part, marks, stats, seen, p, ok, is_goal)
        else:
            _walk_ant(a, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                      alert, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                      status_out, steps_out, part, marks, stats, seen, p, ok, is_goal)


@njit(nogil=True, parallel=True)
def _walk_chunks(n_chunks, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                 alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                 status_out, steps_out, parts, marks, stats):
    """The chunks in parallel: this loop is the kernel's only parallel region (each region is a
    fork and a join of numba's threads, which costs a scheduler time slice on a busy machine)."""
    for c in prange(n_chunks):
        part = parts[c] if penalise else parts[0]
        _walk_chunk(c, n_chunks, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed,
                    local, alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves,
                    n_out, status_out, steps_out, part, marks, stats)


@njit(nogil=True)
def walk_all(nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert, vbits,
             max_steps, width, lut, mode, has_hook, penalise, n_chunks, movef, cellf, cells, moves, n_out, status_out,
             steps_out, penalty, marks, stats):
    """Walks every ant; chunk c takes ants c, c + n_chunks, ... (interleaved: ants of every run
    and colony are spread over the chunks, which evens out their different walk lengths). One
    chunk runs without numba's thread pool."""
    marks[:] = 0
    parts = np.zeros((n_chunks if penalise else 1, penalty.shape[0]), np.float32)
    if n_chunks == 1:
        _walk_chunk(0, 1, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                    alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                    status_out, steps_out, parts[0], marks, stats)
    else:
        _walk_chunks(n_chunks, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                     alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                     status_out, steps_out, parts, marks, stats)
    # Counts of +1.0 are exact in float32 (below 2^24), so the chunk order does not matter.
    penalty[:] = 0.0
    if penalise:
        for c in range(n_chunks):
            penalty += parts[c]


@njit(nogil=True)
def loop_counters(steps, max_steps, out):
    """``out[:] = (loop_steps, slots)`` the JAX step loop reports for ants that walked ``steps [A]`` steps.

    The loop runs until every ant has stopped; from `COMPACT_MIN_ANTS` ants on it continues with
    A / `COMPACT_FACTOR` slots once no more than that many are walking. int32 (wrapping) like `walk`'s.
    """
    A = steps.shape[0]
    loop = 0
    for a in range(A):
        loop = max(loop, np.int64(steps[a]))
    if A >= COMPACT_MIN_ANTS:
        small = A // COMPACT_FACTOR
        hist = np.zeros(max_steps + 1, np.int64)
        for a in range(A):
            hist[steps[a]] += 1
        t_full = max_steps
        walking = A
        for t in range(max_steps):
            walking -= hist[t]  # ants with more than t steps
            if walking <= small:
                t_full = t
                break
        loop = max(loop, t_full)
        slots = t_full * A + (loop - t_full) * small
    else:
        slots = loop * A
    out[0] = np.int32(loop)
    out[1] = np.int32(slots)
