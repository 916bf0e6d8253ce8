"""The ants' walk as one native call per iteration (numba), for the CPU backend.

`jaxplan.aco._walk.walk` advances all ants together, one `lax.while_loop` step per
move; on a CPU each step is ~15 small XLA kernels (gathers, scatters) of 1.5–20 µs,
so the loop costs far more than the arithmetic it does. Here the whole walk of one
iteration (every run, colony and ant, from the start until goal, dead end or step
limit) is one compiled call: each ant walks to the end on its own, the ants are shared
out over the cores with `prange`. The JAX program calls it as an XLA FFI custom call (a
numba `cfunc` registered with `jax.ffi`; CPU only), so the iterations' `lax.scan`, the
move tables and the rules stay in JAX, and the JAX walk stays the one for GPUs. Two more
native kernels serve the colony's update on the CPU (for either walk): `path_stats` and
`deposit` visit only the valid steps of the paths instead of whole ``[A, L]`` buffers.

The result equals `walk`'s bit for bit: the same counter-based uniforms (`hash_uniform`,
one per ant and step), the same float32 inverse-CDF sums in the same order, the same
dead-end rules, paths (up to ``n``; slots past it are left unwritten), penalty counts, dead-end
marks and throughput counters (``loop_steps`` and ``slots`` are those the JAX loop,
with its compaction, would report). With a walk hook (chu2024's `opt_ant`) the hook's
state-dependent logits come from a table precomputed in JAX (`hook_logits`: one value
per cell and move for "keeps the previous heading" and one for "turns"); the step then
only needs the exponential of the logits relative to their maximum, computed with XLA's
own float32 exp algorithm (`_exp_xla`), so this case is bit-identical too.

Ants of one iteration never see each other's moves (the dead-end marks become
pseudo-obstacles only from the next iteration), so walking them one after another
gives the same paths as walking them in lockstep.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import os
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numba
import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic

from jaxplan.aco._walk import COMPACT_FACTOR, COMPACT_MIN_ANTS, DEAD_END, GOAL, STEP_LIMIT, WALKING, Ants

__all__ = ["WALK_BACKENDS", "N_STATS", "HookTables", "StatTables", "resolve_backend", "stat_tables", "walk", "move_bits",
           "path_stats", "deposit"]

WALK_BACKENDS = ("jax", "numba", "auto")
_MODES = {"die": 0, "retreat": 1, "alert": 2}
_DIE, _RETREAT, _ALERT = 0, 1, 2

_F = np.float32
_TINY = np.finfo(np.float32).tiny  # as `walk`: keeps allowed moves drawable when their weights underflowed
_M32 = np.uint64(0xFFFFFFFF)
_H1, _H2, _H3, _H4 = np.uint64(0x9E3779B9), np.uint64(0x85EBCA6B), np.uint64(0x7FEB352D), np.uint64(0x846CA68B)
_S8, _S15, _S16 = np.uint64(8), np.uint64(15), np.uint64(16)
_INV24 = np.float32(1.0 / (1 << 24))
_NEG_INF = np.float32(-np.inf)


class HookTables(NamedTuple):
    """What the numba walk needs for chu2024's hook (`jaxplan.aco._rules.hook_opt_ant`).

    Attributes:
      logits: ``f32[2, G * C, K]`` the hook's logits of each colony's cell and move:
        ``[0]`` when the move changes the ant's heading, ``[1]`` when it keeps it.
      right_turn: ``i32[K]`` the move a quarter turn to the right of each move.
      turn_rule: ``bool[C]`` right-hand-rule cells.
    """

    logits: jnp.ndarray
    right_turn: jnp.ndarray
    turn_rule: jnp.ndarray


def resolve_backend(name: str) -> str:
    """``"jax"`` or ``"numba"``: ``"auto"`` picks numba when JAX computes on the CPU."""
    if name not in WALK_BACKENDS:
        raise ValueError(f"walk_backend must be one of {WALK_BACKENDS}, got {name!r}")
    if name == "auto":
        return "numba" if jax.default_backend() == "cpu" else "jax"
    return name


# ---------------------------------------------------------------------------------------------
# Scalar pieces, each the exact counterpart of a `walk` array operation.


@intrinsic
def _fma32(typingctx, a, b, c):
    """float32 fused multiply-add (one rounding), as LLVM emits it for XLA's contracted a*b + c."""
    sig = types.float32(types.float32, types.float32, types.float32)

    def codegen(context, builder, signature, args):
        f = ir.FloatType()
        fn = builder.module.declare_intrinsic("llvm.fma", [f], fnty=ir.FunctionType(f, [f, f, f]))
        return builder.call(fn, args)

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _uniform(seed, t, ant):
    """`hash_uniform` for one (seed, step, ant): lowbias32, in uint64 arithmetic masked to 32 bits."""
    x = ((np.uint64(ant) * _H1) & _M32) ^ ((np.uint64(t) * _H2 + np.uint64(seed)) & _M32)
    x = x ^ (x >> _S16)
    x = (x * _H3) & _M32
    x = x ^ (x >> _S15)
    x = (x * _H4) & _M32
    x = x ^ (x >> _S16)
    return np.float32(x >> _S8) * _INV24


@njit(cache=True, nogil=True, inline="always")
def _move_between(a, b, width, lut):
    """`moves_between` for two flat cells: the move index from ``a`` to ``b``, −1 if none."""
    dx = b % width - a % width
    dy = b // width - a // width
    if abs(dx) > 2 or abs(dy) > 2:
        return -1
    return lut[(dy + 2) * 5 + dx + 2]


@njit(cache=True, nogil=True, inline="always")
def _exp_xla(x):
    """float32 e^x exactly as XLA's CPU backend (jaxlib 0.10) computes it.

    Only the hook path needs an exponential inside the step, and libm's expf differs from
    XLA's in the last bit for about 1 % of arguments, which would change a few draws. XLA
    emits Cephes' polynomial (``xla/backends/cpu/codegen/polynomial_approximations.cc``) and
    LLVM contracts every multiply-add into an FMA; results below 2^-126 are flushed to zero
    (XLA runs with FTZ). ``tests/test_walk_numba.py`` checks this against `jnp.exp`.
    """
    x = min(max(x, _F(-87.8)), _F(88.8))
    n = np.float32(np.floor(_fma32(x, _F(1.44269504088896341), _F(0.5))))
    n = min(max(n, _F(-127.0)), _F(127.0))
    r = _fma32(-_F(0.693359375), n, x)
    r = _fma32(-_F(-2.12194440e-4), n, r)
    z = _fma32(r, _F(1.9875691500e-4), _F(1.3981999507e-3))
    z = _fma32(z, r, _F(8.3334519073e-3))
    z = _fma32(z, r, _F(4.1665795894e-2))
    z = _fma32(z, r, _F(1.6666665459e-1))
    z = _fma32(z, r, _F(5.0000001201e-1))
    z = _fma32(z, r * r, r)
    z = _F(1.0) + z
    # 2^n from its biased exponent: 0.0 for n = -127.
    e = z * _u2f(np.uint32((np.int32(n) + 127) << 23))
    return e if not e < _TINY else _F(0.0)


@intrinsic
def _u2f(typingctx, x):
    """float32 with the given uint32 bit pattern."""
    sig = types.float32(types.uint32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())

    return sig, codegen


_I32 = ir.IntType(32)


def _splat(builder, value, vtype):
    """A vector of ``vtype`` with every lane ``value``."""
    v = builder.insert_element(ir.Constant(vtype, None), value, ir.Constant(_I32, 0))
    return builder.shuffle_vector(v, ir.Constant(vtype, None), ir.Constant(ir.VectorType(_I32, vtype.count),
                                                                             [0] * vtype.count))


@intrinsic
def _visited3x3(typingctx, seen, i, row, stamp):
    """``uint32``: bit ``3 * r + c`` set where ``seen[i + r * row + c] == stamp`` (r, c in 0..2): the 3x3
    block of a padded tabu grid whose top-left is ``i``, each of its rows read as one 4-lane vector
    compare (the 4th lane is ignored; the grid needs one slot of slack at its end)."""
    sig = types.uint32(seen, types.int64, types.int64, types.int32)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        vt = ir.VectorType(_I32, 4)
        target = _splat(builder, args[3], vt)
        out = ir.Constant(_I32, 0)
        for r in range(3):
            ptr = builder.gep(data, [builder.add(args[1], builder.mul(args[2], ir.Constant(ir.IntType(64), r)))])
            hit = builder.icmp_signed("==", builder.load(builder.bitcast(ptr, vt.as_pointer()), align=4), target)
            bits = builder.and_(builder.zext(builder.bitcast(hit, ir.IntType(4)), _I32), ir.Constant(_I32, 7))
            out = builder.or_(out, builder.shl(bits, ir.Constant(_I32, 3 * r)))
        return out

    return sig, codegen


@intrinsic
def _draw8(typingctx, table, row, allowed, u):
    """``(k, total)``, `draw` for one ant on an 8-connected grid: the weights ``table[row, j] + TINY`` of
    the moves j whose bit is set in ``allowed`` (0 for the others) summed left to right in float32
    (``total`` is the last running sum) and ``k`` the number of the first seven running sums at or
    below ``u * total``, found as the first one above it (the sums never decrease) with one vector
    compare. Same bits as the scalar loops of `walk_ant`."""
    sig = types.Tuple((types.int64, types.float32))(table, types.int64, types.uint32, types.float32)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        f32 = ir.FloatType()
        vt, it = ir.VectorType(f32, 8), ir.VectorType(_I32, 8)
        ptr = builder.gep(data, [builder.mul(args[1], ir.Constant(ir.IntType(64), 8))])
        w = builder.fadd(builder.load(builder.bitcast(ptr, vt.as_pointer()), align=4),
                         ir.Constant(vt, [float(_TINY)] * 8))
        on = builder.icmp_unsigned("!=", builder.and_(_splat(builder, args[2], it),
                                                      ir.Constant(it, [1 << j for j in range(8)])),
                                   ir.Constant(it, [0] * 8))
        w = builder.select(on, w, ir.Constant(vt, [0.0] * 8))
        acc = builder.extract_element(w, ir.Constant(_I32, 0))
        sums = builder.insert_element(ir.Constant(vt, None), acc, ir.Constant(_I32, 0))
        for j in range(1, 8):
            acc = builder.fadd(acc, builder.extract_element(w, ir.Constant(_I32, j)))
            sums = builder.insert_element(sums, acc, ir.Constant(_I32, j))
        above = builder.fcmp_ordered(">", sums, _splat(builder, builder.fmul(args[3], acc), vt))
        first = builder.or_(builder.zext(builder.bitcast(above, ir.IntType(8)), _I32), ir.Constant(_I32, 0x80))
        cttz = builder.module.declare_intrinsic("llvm.cttz", [_I32], fnty=ir.FunctionType(_I32, [_I32, ir.IntType(1)]))
        k = builder.zext(builder.call(cttz, [first, ir.Constant(ir.IntType(1), 1)]), ir.IntType(64))
        return context.make_tuple(builder, signature.return_type, [k, acc])

    return sig, codegen


# ---------------------------------------------------------------------------------------------
# Path statistics and deposits: per ant, over the valid steps only.

# Rows of the statistics output (`jaxplan.aco._rules.PathStats` fields, in order).
N_STATS = 7


@njit(cache=True, nogil=True, inline="always")
def _ant_stats(a, cells, moves, n, movef, cellf, K, stats):
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


@njit(cache=True, nogil=True)
def _stats_chunk(c, n_chunks, cells, moves, n, movef, cellf, K, stats):
    for a in range(c, n.shape[0], n_chunks):
        _ant_stats(a, cells, moves, n[a], movef, cellf, K, stats)


@njit(cache=True, nogil=True, parallel=True)
def _stats_chunks(n_chunks, cells, moves, n, movef, cellf, K, stats):
    for c in prange(n_chunks):
        _stats_chunk(c, n_chunks, cells, moves, n, movef, cellf, K, stats)


@njit(cache=True, nogil=True)
def _stats_all(cells, moves, n, movef, cellf, K, n_chunks, stats):
    """`_ant_stats` of every ant (for paths walked in JAX: the same numbers as the numba walk's)."""
    if n_chunks == 1:
        _stats_chunk(0, 1, cells, moves, n, movef, cellf, K, stats)
    else:
        _stats_chunks(n_chunks, cells, moves, n, movef, cellf, K, stats)


@njit(cache=True, nogil=True)
def _deposit_paths(tau, cells, moves, n, amount, colony, CK, K):
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


@njit(cache=True, nogil=True)
def _penalise(tau, counts, keep):
    """yu2020's dead-corner penalty: ``tau[e] *= keep ** counts[e]`` where an edge was retreated over.

    A pass over the counts, with a power only where one is non-zero (XLA's `jnp.power` over every
    edge cost praco ~1.7 ms per iteration on a 100x100 map with 5 colonies; libm's powf may differ
    from XLA's in the last bit).
    """
    for e in range(counts.shape[0]):
        c = counts[e]
        if c != _F(0.0):
            tau[e] = tau[e] * keep ** c


# ---------------------------------------------------------------------------------------------
# The walk.


@njit(cache=True, nogil=True)
def _finish_ant(a, n, t, status, cells, moves, n_out, status_out, steps_out, movef, cellf, K, stats):
    """Writes ant ``a``'s counters and, while its path is still in cache, its path statistics. Only an
    ant at the goal has a cost (the colony gives the others cost inf and never reads their
    statistics), so the others' stay zero: most ants of early iterations stop at the step limit,
    and summing their long paths cost a third of the walk."""
    n_out[a] = n
    status_out[a] = status
    steps_out[a] = t
    if status == GOAL:
        _ant_stats(a, cells, moves, n, movef, cellf, K, stats)
    else:
        for i in range(N_STATS):
            stats[i, a] = _F(0.0)


def _walk_ant_for(moves_per_cell: int):
    """`walk_ant` compiled for ``moves_per_cell`` moves per cell (0: any, read from ``nbr``). With K a
    compile-time constant the move loops unroll, which makes the 8-connected step ~1.2-1.4x faster."""

    @njit(cache=True, nogil=True)
    def walk_ant(a, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
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
        alerting = mode == _ALERT
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
                    acc = acc + (table[row, k] + _TINY) * _F(o)
                    p[k] = acc
            else:
                for k in range(K):
                    nb = nbr[pos, k]
                    safe = max(nb, 0)
                    o = (nb >= 0) & (seen[safe] != stamp)
                    if alerting:
                        o = o & (not alert[c0 + safe])
                    ok[k] = o
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
                for k in range(K):
                    v = hook_l[1 if k == prev else 0, row, k] if ok[k] else _NEG_INF
                    p[k] = v
                    mx = max(mx, v)
                shift = mx if np.isfinite(mx) else _F(0.0)
                acc = _F(0.0)
                for k in range(K):
                    # An allowed move whose logit is -inf gets exp(-inf) = 0, then the floor.
                    acc = acc + (_exp_xla(p[k] - shift) + _TINY if ok[k] else _F(0.0))
                    p[k] = acc
            # Inverse CDF with one uniform, as `draw`: k = number of the running sums of the first
            # K - 1 weights at or below u·Σp.
            total = p[K - 1]
            threshold = _uniform(sd, t, loc) * total
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
            if mode == _DIE or n == 0:
                status = DEAD_END
                break
            back = cells[a, n - 1]
            if penalise:
                penalty[(r0 + back) * K + _move_between(back, pos, width, lut)] += 1.0
            if has_hook:
                prev = _move_between(cells[a, n - 2], back, width, lut) if n >= 2 else -1
            pos = back
            n -= 1
        if status == WALKING:
            status = STEP_LIMIT
        _finish_ant(a, n, t, status, cells, moves, n_out, status_out, steps_out, movef, cellf, K, stats)

    return walk_ant


# 8-connected grids (every preset but opt_ant) get the unrolled copy; 4- and 16-connected ones the
# general walk (a third copy would add ~13 s to the one-off numba compile of a fresh install).
_walk_ant, _walk_ant_8 = _walk_ant_for(0), _walk_ant_for(8)


@njit(cache=True, nogil=True)
def _pair_tables(lut, width):
    """Flat offsets of the 8 moves on the map (``off``) and on the tabu grid padded by one cell on every
    side (``offp``), and ``lut9 [512]``: the moves (bit k) into the cells of a 3x3 block pattern
    (bit ``3 * (dy + 1) + dx + 1``, as `_visited3x3` reads it)."""
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def _walk_pair8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
                movef, cellf, cells, moves, n_out, status_out, steps_out, penalty, stats):
    """`walk_ant` for the common case (8 moves, no hook, ``die`` or ``retreat``), two ants at a time.

    Ants c, c + n_chunks, ... walk in two interleaved lanes: the step of one ant is a chain of
    dependent loads and float adds (~40 ns on this 2-core CPU whatever its instruction count), so a
    second, independent ant in the same loop body fills the waiting core (measured: 1.35-1.4x the
    single-ant walk). The step is also shorter than `walk_ant`'s: each lane's tabu is a grid padded
    by one cell, whose 3x3 block around the ant is read as three vector compares (`_visited3x3`);
    ``vbits`` holds each cell's allowed moves as bits; the weights, their running sums and the
    inverse-CDF draw are one vector sequence (`_draw8`). Same draws, same bits as `walk_ant`.

    Moves come from ``lut`` and ``width`` (``nbr`` is not read): the neighbour table must be the
    grid's own, where a valid move k from cell c leads to ``c + off[k]`` (`neighbour_table`'s).

    The two lanes' steps are written out twice on purpose: a shared step function inlined by numba
    keeps reference counting of its array arguments inside the loop (calls on every step, measured
    1.6x slower than the single-ant walk), and a non-inlined one costs a call per step.
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
            allowed = np.uint32(vbits[pos0]) & ~np.uint32(lut9[_visited3x3(seen0, pp0 - wp - 1, wp, st0)])
            k, total = _draw8(table, r0_0 + pos0, allowed, _uniform(sd0, t0, loc0))
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
            elif mode == _DIE or n0 == 0:
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
            allowed = np.uint32(vbits[pos1]) & ~np.uint32(lut9[_visited3x3(seen1, pp1 - wp - 1, wp, st1)])
            k, total = _draw8(table, r0_1 + pos1, allowed, _uniform(sd1, t1, loc1))
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
            elif mode == _DIE or n1 == 0:
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


@njit(cache=True, nogil=True)
def _walk_chunk(c, n_chunks, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                steps_out, part, marks, stats):
    """Walks ants c, c + n_chunks, ... one after another (a sequential function: called from a
    parallel loop, its array set-up must not become a parallel region of its own)."""
    A = start.shape[0]
    C, K = nbr.shape
    if K == 8 and not has_hook and mode != _ALERT and max_steps > 0:
        _walk_pair8(c, n_chunks, table, vbits, start, goal, row0, seed, local, max_steps, width, lut, mode, penalise,
                    movef, cellf, cells, moves, n_out, status_out, steps_out, part, stats)
        return
    seen = np.zeros(C, np.int32)
    p = np.empty(K, np.float32)
    ok = np.empty(K, np.bool_)
    is_goal = np.empty(K, np.bool_)
    for a in range(c, A, n_chunks):
        if K == 8:
            _walk_ant_8(a, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                        max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                        status_out, steps_out, part, marks, stats, seen, p, ok, is_goal)
        else:
            _walk_ant(a, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                      max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                      steps_out, part, marks, stats, seen, p, ok, is_goal)


@njit(cache=True, nogil=True, parallel=True)
def _walk_chunks(n_chunks, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                 vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                 steps_out, parts, marks, stats):
    """The chunks in parallel: this loop is the kernel's only parallel region (each region is a
    fork and a join of numba's threads, which costs a scheduler time slice on a busy machine)."""
    for c in prange(n_chunks):
        part = parts[c] if penalise else parts[0]
        _walk_chunk(c, n_chunks, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local,
                    alert, vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out,
                    status_out, steps_out, part, marks, stats)


@njit(cache=True, nogil=True)
def _walk_all(nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert, vbits,
              max_steps, width, lut, mode, has_hook, penalise, n_chunks, movef, cellf,
              cells, moves, n_out, status_out, steps_out, penalty, marks, stats):
    """Walks every ant; chunk c takes ants c, c + n_chunks, ... (interleaved: ants of every run
    and colony are spread over the chunks, which evens out their different walk lengths). One
    chunk runs without numba's thread pool."""
    marks[:] = 0
    parts = np.zeros((n_chunks if penalise else 1, penalty.shape[0]), np.float32)
    if n_chunks == 1:
        _walk_chunk(0, 1, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                    vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                    steps_out, parts[0], marks, stats)
    else:
        _walk_chunks(n_chunks, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                     vbits, max_steps, width, lut, mode, has_hook, penalise, movef, cellf, cells, moves, n_out, status_out,
                     steps_out, parts, marks, stats)
    # Counts of +1.0 are exact in float32 (below 2^24), so the chunk order does not matter.
    penalty[:] = 0.0
    if penalise:
        for c in range(n_chunks):
            penalty += parts[c]


@njit(cache=True, nogil=True)
def _loop_counters(steps, max_steps, out):
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


# ---------------------------------------------------------------------------------------------
# The XLA FFI handler: XLA calls it with its own buffers, so nothing is copied or allocated per
# call and no Python runs (`jax.pure_callback` costs 0.2–2 ms per call on this 2-core CPU, more
# than the whole walk of a small colony). The call frame is read with the offsets of XLA's FFI
# C API (``xla/ffi/api/c_api.h``, API version 0.x, x86-64/aarch64 layout).


def _pointer(nbtype):
    """An intrinsic turning an int64 address into a ``CPointer(nbtype)`` (for `numba.carray`)."""

    @intrinsic
    def ptr(typingctx, addr):
        sig = types.CPointer(nbtype)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(types.CPointer(nbtype)))

        return sig, codegen

    return ptr


_I64P, _I32P, _U32P, _F32P, _I8P, _U8P = (_pointer(t) for t in (types.int64, types.int32, types.uint32, types.float32,
                                                                  types.int8, types.uint8))


@intrinsic
def _address(typingctx, p):
    """int64 address of a void pointer."""
    sig = types.int64(types.voidptr)

    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _null(typingctx):
    """The null void pointer (an FFI handler's "no error")."""
    sig = types.voidptr()

    def codegen(context, builder, signature, args):
        return context.get_constant_null(types.voidptr)

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _i64(addr):
    return numba.carray(_I64P(addr), (1,))[0]


@njit(cache=True, nogil=True, inline="always")
def _i32(addr):
    return numba.carray(_I32P(addr), (1,))[0]


@njit(cache=True, nogil=True, inline="always")
def _buffer(lst, i):
    """``(data address, dims address)`` of the i-th `XLA_FFI_Buffer*` of an args/rets list."""
    b = _i64(lst + 8 * i)
    return _i64(b + 24), _i64(b + 40)


@njit(cache=True, nogil=True, inline="always")
def _dim(dims, i):
    return _i64(dims + 8 * i)


@njit(cache=True, nogil=True, inline="always")
def _not_execute(base):
    """Answers XLA's metadata query (FFI API version 0.1, no traits, stateless); True unless this
    call is the EXECUTE stage, the only one with work."""
    ext = _i64(base + 8)
    if ext != 0 and _i32(ext + 8) == 1:
        # XLA asks for the handler's metadata (XLA_FFI_Metadata_Extension). Older minor versions
        # are accepted by every newer XLA.
        meta = _i64(ext + 24)
        m64 = numba.carray(_I64P(meta), (6,))
        m32 = numba.carray(_I32P(meta), (12,))
        m64[1] = 24  # api_version.struct_size
        m64[2] = 0  # api_version.extension_start
        m32[6] = 0  # major
        m32[7] = 1  # minor
        m32[8] = 0  # traits
        m64[5] = 0  # state_type_id: XLA_FFI_UNKNOWN_TYPE_ID
        return True
    return _i32(base + 32) != 3


def _walk_handler(frame):
    """``XLA_FFI_Error* handler(XLA_FFI_CallFrame*)`` for `walk`'s call; see `walk` for the buffers."""
    base = _address(frame)
    if _not_execute(base):
        return _null()
    args = _i64(base + 40 + 32)
    rets = _i64(base + 80 + 32)
    d, s = _buffer(args, 0)
    C = _dim(s, 0)
    K = _dim(s, 1)
    nbr = numba.carray(_I32P(d), (C, K))
    d, s = _buffer(args, 1)
    table = numba.carray(_F32P(d), (_dim(s, 0), K))
    d, s = _buffer(args, 2)
    hook_l = numba.carray(_F32P(d), (2, _dim(s, 1), K))
    d, s = _buffer(args, 3)
    right_turn = numba.carray(_I32P(d), (K,))
    d, s = _buffer(args, 4)
    turn_rule = numba.carray(_U8P(d), (_dim(s, 0),))
    d, s = _buffer(args, 5)
    A = _dim(s, 1)
    ints = numba.carray(_I32P(d), (5, A))
    d, s = _buffer(args, 6)
    seed = numba.carray(_U32P(d), (A,))
    d, s = _buffer(args, 7)
    lut = numba.carray(_I32P(d), (25,))
    d, s = _buffer(args, 8)
    alert = numba.carray(_U8P(d), (_dim(s, 0),))
    d, s = _buffer(args, 9)
    cfg = numba.carray(_I32P(d), (6,))
    L = np.int64(cfg[0])
    d, s = _buffer(args, 10)
    movef = numba.carray(_F32P(d), (K + K * K,))
    d, s = _buffer(args, 11)
    cellf = numba.carray(_F32P(d), (3, _dim(s, 1)))
    d, s = _buffer(rets, 0)
    cells = numba.carray(_I32P(d), (A, L + 1))
    d, s = _buffer(rets, 1)
    moves = numba.carray(_I8P(d), (A, L))
    d, s = _buffer(rets, 2)
    per_ant = numba.carray(_I32P(d), (3, A))
    d, s = _buffer(rets, 3)
    counters = numba.carray(_I32P(d), (2,))
    d, s = _buffer(rets, 4)
    penalty = numba.carray(_F32P(d), (_dim(s, 0),))
    d, s = _buffer(rets, 5)
    marks = numba.carray(_U8P(d), (_dim(s, 0),))
    d, s = _buffer(rets, 6)
    stats = numba.carray(_F32P(d), (N_STATS, A))
    d, s = _buffer(args, 12)
    vbits = numba.carray(_U8P(d), (_dim(s, 0),))
    _walk_all(nbr, table, hook_l, right_turn, turn_rule, ints[0], ints[1], ints[2], ints[3], seed, ints[4], alert,
              vbits, L, np.int64(cfg[1]), lut, np.int64(cfg[2]), cfg[3] != 0, cfg[4] != 0, np.int64(cfg[5]), movef, cellf,
              cells, moves, per_ant[0], per_ant[1], per_ant[2], penalty, marks, stats)
    _loop_counters(per_ant[2], L, counters)
    return _null()


def _stats_handler(frame):
    """The handler of `path_stats`: cells ``i32[A, L + 1]``, moves ``i8[A, L]``, n ``i32[A]``, movef, cellf,
    ``i32[1]`` parallel chunks -> stats ``f32[N_STATS, A]``."""
    base = _address(frame)
    if _not_execute(base):
        return _null()
    args = _i64(base + 40 + 32)
    rets = _i64(base + 80 + 32)
    d, s = _buffer(args, 0)
    A = _dim(s, 0)
    L1 = _dim(s, 1)
    cells = numba.carray(_I32P(d), (A, L1))
    d, s = _buffer(args, 1)
    moves = numba.carray(_I8P(d), (A, L1 - 1))
    d, s = _buffer(args, 2)
    n = numba.carray(_I32P(d), (A,))
    d, s = _buffer(args, 3)
    nf = _dim(s, 0)
    K = np.int64(0)
    while K + K * K < nf:
        K += 1
    movef = numba.carray(_F32P(d), (nf,))
    d, s = _buffer(args, 4)
    cellf = numba.carray(_F32P(d), (3, _dim(s, 1)))
    d, s = _buffer(args, 5)
    n_chunks = np.int64(numba.carray(_I32P(d), (1,))[0])
    d, s = _buffer(rets, 0)
    stats = numba.carray(_F32P(d), (N_STATS, A))
    _stats_all(cells, moves, n, movef, cellf, K, n_chunks, stats)
    return _null()


def _deposit_handler(frame):
    """The handler of `deposit`: tau ``f32[T]`` (aliased to the result), then for the ants and for the
    best-so-far paths each: cells ``i32[P, L + 1]``, moves ``i8[P, L]``, n ``i32[P]``, amounts ``f32[2, P]``,
    colonies ``i32[2, P]``; then ``i32[2]`` (C·K, K), the retreat counts ``f32[T]`` (or ``[1]``: none) and
    ``f32[1]`` the factor an edge keeps per retreat."""
    base = _address(frame)
    if _not_execute(base):
        return _null()
    args = _i64(base + 40 + 32)
    rets = _i64(base + 80 + 32)
    d, s = _buffer(rets, 0)
    tau = numba.carray(_F32P(d), (_dim(s, 0),))
    d, s = _buffer(args, 11)
    sizes = numba.carray(_I32P(d), (2,))
    CK = np.int64(sizes[0])
    K = np.int64(sizes[1])
    # Own-colony deposits of the ants, their deposits into the next colony, then the best-so-far
    # paths' (own, next): the order `jaxplan.aco._colony._deposit_jax` adds them in.
    for group in range(2):
        d, s = _buffer(args, 1 + 5 * group)
        P = _dim(s, 0)
        L1 = _dim(s, 1)
        cells = numba.carray(_I32P(d), (P, L1))
        d, s = _buffer(args, 2 + 5 * group)
        moves = numba.carray(_I8P(d), (P, L1 - 1))
        d, s = _buffer(args, 3 + 5 * group)
        n = numba.carray(_I32P(d), (P,))
        d, s = _buffer(args, 4 + 5 * group)
        amounts = numba.carray(_F32P(d), (2, P))
        d, s = _buffer(args, 5 + 5 * group)
        colonies = numba.carray(_I32P(d), (2, P))
        for kind in range(2):
            _deposit_paths(tau, cells, moves, n, amounts[kind], colonies[kind], CK, K)
    d, s = _buffer(args, 12)
    penalty = numba.carray(_F32P(d), (_dim(s, 0),))
    d, s = _buffer(args, 13)
    keep = numba.carray(_F32P(d), (1,))
    if penalty.shape[0] == tau.shape[0]:
        _penalise(tau, penalty, keep[0])
    return _null()


_TARGETS = {"jaxplan_aco_walk": _walk_handler, "jaxplan_aco_path_stats": _stats_handler,
            "jaxplan_aco_deposit": _deposit_handler}
_HANDLERS: dict = {}  # the compiled cfuncs, kept alive while XLA may call them


def _register() -> None:
    """Compiles (or loads from numba's cache) the handlers and registers them with XLA, once."""
    if not _HANDLERS:
        # Start numba's thread pool first: loading a cached handler links the parallel kernels
        # against the pool's launch functions, which are null until then.
        numba.get_num_threads()
        for target, fn in _TARGETS.items():
            handler = numba.cfunc(types.voidptr(types.voidptr), cache=True, nopython=True)(fn)
            jax.ffi.register_ffi_target(target, jax.ffi.pycapsule(handler.ctypes), platform="cpu")
            _HANDLERS[target] = handler


_SHARERS = contextvars.ContextVar("jaxplan_walk_sharers", default=1)


@contextlib.contextmanager
def sharing_cores(devices: int):
    """While tracing a program that runs on ``devices`` host devices at once (a sharded batch),
    each device's walk takes only its share of the cores: measured on 2 cores, two devices
    whose walks each launched 2 threads were no faster than one device (4 threads on 2
    cores), with 1 thread each 1.2-1.3x faster. The chunk count is a trace-time constant and
    does not change any result (chunks walk independent ants)."""
    token = _SHARERS.set(max(1, int(devices)))
    try:
        yield
    finally:
        _SHARERS.reset(token)


def _thread_safe_layer() -> bool:
    """Whether numba's threading layer may launch parallel regions from several threads at once
    (``omp``, ``tbb``); ``workqueue`` aborts the process on concurrent access."""
    numba.get_num_threads()  # starts the pool, so that the layer is known
    try:
        return numba.threading_layer() in ("omp", "tbb")
    except ValueError:
        return False


def _n_chunks(A: int) -> int:
    """Parallel chunks: numba's threads, but no more than this device's share of the cores this
    process may use (`sharing_cores`). Sharded over several devices, whose walks run at the same
    time from XLA's threads, a layer that is not thread-safe gets 1 chunk (no parallel region)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    sharers = _SHARERS.get()
    if sharers > 1 and not _thread_safe_layer():
        return 1
    return max(1, min(numba.get_num_threads(), cores // sharers, A))


class StatTables(NamedTuple):
    """The per-map numbers `jaxplan.aco._rules.path_stats` reads, packed for the numba kernels.

    Attributes:
      movef: ``f32[K + K * K]`` move lengths (m), then |heading change| from move i to move j at ``K + i * K + j``.
      cellf: ``f32[3, C]`` clearance (m), risk, height (m) per cell.
    """

    movef: jnp.ndarray
    cellf: jnp.ndarray


def stat_tables(tables) -> StatTables:
    """`StatTables` of a `jaxplan.aco._context.MapTables`."""
    movef = jnp.concatenate([tables.step, tables.turn_angle.reshape(-1)]).astype(jnp.float32)
    cellf = jnp.stack([tables.clearance, tables.risk, tables.height]).astype(jnp.float32)
    return StatTables(movef, cellf)


def path_stats(st: StatTables, cells: jnp.ndarray, moves: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``f32[N_STATS, A]``: the statistics the numba walk returns, for paths walked elsewhere.

    Args:
      cells: ``i32[A, L + 1]``; moves: ``i8[A, L]``; n: ``i32[A]`` (slots past ``n`` are not read).
    """
    _register()
    A = n.shape[0]
    call = jax.ffi.ffi_call("jaxplan_aco_path_stats", jax.ShapeDtypeStruct((N_STATS, A), jnp.float32),
                            vmap_method="sequential")
    return call(jnp.asarray(cells, jnp.int32), jnp.asarray(moves, jnp.int8), jnp.asarray(n, jnp.int32), st.movef,
                st.cellf, jnp.asarray(np.array([_n_chunks(A)], np.int32)))


def deposit(tau: jnp.ndarray, paths: tuple, best: tuple, C: int, K: int, penalty: jnp.ndarray | None = None,
            keep: jnp.ndarray | None = None) -> jnp.ndarray:
    """Adds deposits along paths to the flat pheromone ``tau f32[T]`` (T = G·C·K), in one native call.

    Only the valid steps of paths with a non-zero amount are visited, so the cost is that of the
    successful ants' steps, not of the ``[P, L]`` buffers. The result equals XLA's scatter-add of
    the same amounts (`jaxplan.aco._colony._scatter_paths`) bit for bit: same additions, same order.

    Args:
      tau: ``f32[T]`` pheromone (already evaporated); its buffer is updated in place.
      paths, best: ``(cells i32[P, L + 1], moves i8[P, L], n i32[P], amounts f32[2, P], colonies i32[2, P])``
        for the ants and for the best-so-far paths: amounts ``[0]`` go to colony ``colonies[0]``
        (row ``colony * C * K`` of ``tau``), then amounts ``[1]`` to ``colonies[1]``.
      C, K: cells and moves per cell.
      penalty: optional ``f32[T]`` retreat counts per edge (yu2020): after the deposits, an edge
        keeps ``keep ** count`` of its pheromone; keep: ``f32`` scalar, 1 − λ_p.
    """
    _register()
    T = tau.shape[0]
    args = []
    for cells, moves, n, amounts, colonies in (paths, best):
        args += [jnp.asarray(cells, jnp.int32), jnp.asarray(moves, jnp.int8), jnp.asarray(n, jnp.int32),
                 jnp.asarray(amounts, jnp.float32), jnp.asarray(colonies, jnp.int32)]
    call = jax.ffi.ffi_call("jaxplan_aco_deposit", jax.ShapeDtypeStruct((T,), jnp.float32),
                            vmap_method="sequential", input_output_aliases={0: 0})
    if penalty is None:
        penalty, keep = jnp.zeros((1,), jnp.float32), jnp.float32(1.0)
    return call(tau, *args, jnp.asarray(np.array([C * K, K], np.int32)), jnp.asarray(penalty, jnp.float32).reshape(-1),
                jnp.asarray(keep, jnp.float32).reshape(1))


def move_bits(nbr: jnp.ndarray) -> jnp.ndarray:
    """``u8[C]``: bit k set where move k is allowed (``nbr [C, 8] >= 0``), for the 8-connected walk's fast
    path; ``u8[1]`` (unused) for other neighbourhoods."""
    C, K = nbr.shape
    if K != 8:
        return jnp.zeros((1,), jnp.uint8)
    return jnp.sum(jnp.where(nbr >= 0, jnp.left_shift(1, jnp.arange(8)), 0), axis=1).astype(jnp.uint8)


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
    hook: HookTables | None = None,
    stats: StatTables | None = None,
    bits: jnp.ndarray | None = None,
) -> Ants:
    """`jaxplan.aco._walk.walk` as one native call (XLA FFI, CPU): same arguments, same `Ants`, bit for bit
    on every path slot up to ``n`` (slots past it are unspecified in both), plus ``Ants.stats``.

    ``table`` is not used when ``hook`` is given (the hook's logits are in `HookTables.logits`,
    built by the colony's ``hook_logits`` rule). ``bits``: `move_bits` of ``nbr`` (computed here when None;
    a caller that walks many times passes it once). ``stats``: the map's `StatTables`; each ant's path
    statistics are summed as soon as it stops (``Ants.stats``, as `path_stats` computes them; zeros'
    worth of tables when None), for the ants that reached the goal only: the others' columns are zero
    (they have no cost). Works under `jit`, `lax.scan` and `vmap` (a vmapped batch is walked
    element by element, each in parallel over its ants).
    """
    _register()
    A = start.shape[0]
    C, K = nbr.shape
    L = max_steps
    mode = _MODES[dead_end]
    i32 = functools.partial(jnp.asarray, dtype=jnp.int32)
    if hook is None:
        hook_l, right_turn, turn_rule = jnp.zeros((2, 1, K), jnp.float32), jnp.zeros((K,), jnp.int32), jnp.zeros((1,), bool)
    else:
        hook_l, right_turn, turn_rule = hook.logits, hook.right_turn, hook.turn_rule
        table = jnp.zeros((1, K), jnp.float32)  # unused
    n_marks = alert.shape[0] if mode == _ALERT else 0
    if stats is None:
        stats = StatTables(jnp.ones((K + K * K,), jnp.float32), jnp.ones((3, C), jnp.float32))
    cfg = np.array([L, width, mode, hook is not None, penalty_size > 0, _n_chunks(A)], np.int32)
    bits = move_bits(nbr) if bits is None else jnp.asarray(bits, jnp.uint8)
    if bits.shape != ((C,) if K == 8 else (1,)):  # the native walk sizes its tabu grid from it
        raise ValueError(f"bits must be move_bits(nbr), of shape {(C,) if K == 8 else (1,)}, got {bits.shape}")
    shapes = [
        jax.ShapeDtypeStruct((A, L + 1), jnp.int32),  # cells
        # Move indices (< 16) as int8: a quarter of the bytes; the conversion fuses into their consumers.
        jax.ShapeDtypeStruct((A, L), jnp.int8),
        jax.ShapeDtypeStruct((3, A), jnp.int32),  # n, status, ant_steps
        jax.ShapeDtypeStruct((2,), jnp.int32),  # loop_steps, slots
        jax.ShapeDtypeStruct((max(penalty_size, 1),), jnp.float32),
        jax.ShapeDtypeStruct((max(n_marks, 1),), jnp.bool_),
        jax.ShapeDtypeStruct((N_STATS, A), jnp.float32),
    ]
    call = jax.ffi.ffi_call("jaxplan_aco_walk", shapes, vmap_method="sequential")
    cells, moves, per_ant, counters, penalty, marks, path_st = call(
        i32(nbr), jnp.asarray(table, jnp.float32), jnp.asarray(hook_l, jnp.float32), i32(right_turn),
        jnp.asarray(turn_rule, bool), jnp.stack([i32(start), i32(goal), i32(row0), i32(cell0), i32(local)]),
        jnp.asarray(seed, jnp.uint32), i32(lut), jnp.asarray(alert, bool) if n_marks else jnp.zeros((1,), bool),
        jnp.asarray(cfg), stats.movef, stats.cellf, bits,
    )
    return Ants(cells=cells, moves=moves, n=per_ant[0], status=per_ant[1],
                penalty=penalty if penalty_size else None, ant_steps=per_ant[2], loop_steps=counters[0],
                marks=marks if n_marks else None, slots=counters[1], stats=path_st)
