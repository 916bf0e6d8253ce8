"""The ants' walk of one iteration as native code (numba): every run, colony and ant, from the start until goal,
dead end or step limit, shared out over the cores with `prange`.

Each kernel is the exact counterpart of `jaxplan.aco._walk.walk` (same uniforms, same float32 sums in the
same order, same dead-end rules; see `jaxplan.aco._walk_numba` for the contract). `walk_all` and
`loop_counters` are the body of the walk's FFI handler (`jaxplan.aco._walk_ffi`). Not cached on their own:
the handler that compiles them in is (see `jaxplan.aco._walk_ffi`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numba import njit, prange

from jaxplan.aco._walk import COMPACT_FACTOR, COMPACT_MIN_ANTS, DEAD_END, GOAL, STEP_LIMIT, WALKING
from jaxplan.aco._walk_numba_intrinsics import LANES, TINY, exp_xla, move_between, tabu_draw_lanes, uniform
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


def _walk_ant_for(moves_per_cell: int) -> Callable:
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
def _lane_offsets(lut, width):
    """Flat offsets of the 8 moves on the map (``off``) and on the tabu grid padded by one cell on every
    side (``offp``), for `_walk_lanes8`."""
    off = np.zeros(8, np.int64)
    offp = np.zeros(8, np.int64)
    for idx in range(25):
        k = lut[idx]
        if k >= 0:
            dx, dy = idx % 5 - 2, idx // 5 - 2
            off[k] = dx + dy * width
            offp[k] = dx + dy * (width + 2)
    return off, offp


@njit(nogil=True, inline="always")
def _lane_take(lane, a, start, goal, row0, local, seed, width, size, ant, pos, pp, row, n_, t_, goal_, row0_,
               local_, seed_, stamp, u, cells, seen):
    """Lane ``lane`` of `_walk_lanes8` starts ant ``a``: its state from the ant's inputs, its first uniform,
    its start cell recorded and stamped in the lane's tabu region (``size`` cells of the grid padded by one)."""
    p = np.int64(start[a])
    ant[lane] = a
    pos[lane] = p
    pp[lane] = lane * size + p + (p // width) * 2 + width + 3
    row[lane] = row0[a] + p
    n_[lane] = 0
    t_[lane] = 0
    goal_[lane] = goal[a]
    row0_[lane] = row0[a]
    local_[lane] = local[a]
    seed_[lane] = seed[a]
    stamp[lane] = a + 1
    u[lane] = uniform(seed_[lane], 0, local_[lane])
    cells[a, 0] = p
    seen[pp[lane]] = a + 1


@njit(nogil=True)
def _walk_lanes8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
                 movef, cellf, cells, moves, n_out, status_out, steps_out, penalty, stats):
    """`walk_ant` for the common case (8 moves, no hook, ``die`` or ``retreat``), `LANES` ants at a time.

    Ants c, c + n_chunks, ... walk in `LANES` lanes; a lane whose ant stops takes the chunk's next ant. One
    round steps every lane: `tabu_draw_lanes` does the tabu test and the draw of all lanes as vector
    gathers and float32 vector sums, then a scalar pass moves each lane's ant (or steps it back, or
    stops it). The one-ant step is a chain of dependent loads and float additions whose latency, not its
    instruction count, sets its time; in lanes the chain is paid once per round. Each lane's tabu is its
    own region of one grid padded by one cell (so a move's neighbour is a fixed offset), stamped with
    ``a + 1`` (never cleared). Same draws, same bits as `walk_ant`: the lanes' ants are independent.

    Moves come from ``lut`` and ``width`` (``nbr`` is not read): the neighbour table must be the
    grid's own, where a valid move k from cell c leads to ``c + off[k]`` (`neighbour_table`'s).
    """
    A = start.shape[0]
    wp = width + 2
    size = (vbits.shape[0] // width + 2) * wp
    seen = np.zeros(LANES * size, np.int32)
    vbits32 = vbits.astype(np.int32)
    off, offp = _lane_offsets(lut, width)
    L = max_steps
    ant = np.zeros(LANES, np.int64)
    pos = np.zeros(LANES, np.int64)
    pp = np.zeros(LANES, np.int64)  # pos on the padded grid, in the lane's region of ``seen``
    row = np.zeros(LANES, np.int64)  # row0 + pos: the row of ``table``
    n_ = np.zeros(LANES, np.int64)
    t_ = np.zeros(LANES, np.int64)
    goal_ = np.zeros(LANES, np.int64)
    row0_ = np.zeros(LANES, np.int64)
    local_ = np.zeros(LANES, np.int64)
    seed_ = np.zeros(LANES, np.uint32)
    stamp = np.zeros(LANES, np.int32)
    u = np.zeros(LANES, np.float32)  # the uniform of the lane's next step
    k_ = np.zeros(LANES, np.int64)
    total_ = np.zeros(LANES, np.float32)
    live = np.zeros(LANES, np.bool_)
    nxt = np.int64(c)
    n_live = 0
    for lane in range(LANES):
        pp[lane] = lane * size + wp + 1  # an idle lane reads a valid cell of its own region
        live[lane] = nxt < A
        if live[lane]:
            n_live += 1
            _lane_take(lane, nxt, start, goal, row0, local, seed, width, size, ant, pos, pp, row, n_, t_, goal_,
                       row0_, local_, seed_, stamp, u, cells, seen)
        nxt += n_chunks
    while n_live > 0:
        tabu_draw_lanes(table, seen, vbits32, offp, pp, stamp, row, pos, u, k_, total_)
        for lane in range(LANES):
            if not live[lane]:
                continue
            a = ant[lane]
            p = pos[lane]
            q = pp[lane]
            n = n_[lane]
            t = t_[lane] + 1  # the ant was walking during this step
            r0 = row0_[lane]
            k = k_[lane]
            status = WALKING
            if total_[lane] > 0:  # as walk_ant: a NaN weight (0·log 0 under β = 0) makes the ant stuck
                p += off[k]
                q += offp[k]
                moves[a, n] = k
                n += 1
                cells[a, n] = p
                seen[q] = stamp[lane]
                if p == goal_[lane]:
                    status = GOAL
            elif mode == DIE or n == 0:
                status = DEAD_END
            else:  # retreat over the last move
                mv = np.int64(moves[a, n - 1])
                if penalise:
                    penalty[(r0 + cells[a, n - 1]) * 8 + mv] += 1.0
                p -= off[mv]
                q -= offp[mv]
                n -= 1
            if status == WALKING and t >= L:
                status = STEP_LIMIT
            if status == WALKING:
                pos[lane] = p
                pp[lane] = q
                row[lane] = r0 + p
                n_[lane] = n
                t_[lane] = t
                u[lane] = uniform(seed_[lane], t, local_[lane])
                continue
            _finish_ant(a, n, t, status, cells, moves, n_out, status_out, steps_out, movef, cellf, 8, stats)
            live[lane] = nxt < A
            if live[lane]:  # the lane takes the chunk's next ant
                _lane_take(lane, nxt, start, goal, row0, local, seed, width, size, ant, pos, pp, row, n_, t_, goal_,
                           row0_, local_, seed_, stamp, u, cells, seen)
                nxt += n_chunks
            else:
                n_live -= 1
                pos[lane] = 0
                row[lane] = 0
                pp[lane] = lane * size + wp + 1


@njit(nogil=True)
def _walk_chunk(c, n_chunks, nbr, table, hook_l, hook_v, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                status_out, steps_out, part, marks, stats):
    """Walks ants c, c + n_chunks, ... one after another (a sequential function: called from a
    parallel loop, its array set-up must not become a parallel region of its own)."""
    A = start.shape[0]
    C, K = nbr.shape
    if K == 8 and not has_hook and mode != ALERT and max_steps > 0:
        _walk_lanes8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
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
