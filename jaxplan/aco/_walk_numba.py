"""The ants' walk as one native call per iteration (numba), for the CPU backend.

`jaxplan.aco._walk.walk` advances all ants together, one `lax.while_loop` step per
move; on a CPU each step is ~15 small XLA kernels (gathers, scatters) of 1.5–20 µs,
so the loop costs far more than the arithmetic it does. Here the whole walk of one
iteration (every run, colony and ant, from the start until goal, dead end or step
limit) is one compiled call: each ant walks to the end on its own, the ants are shared
out over the cores with `prange`. It is invoked from the JAX program with
`jax.pure_callback`, so the iterations' `lax.scan`, the move tables, deposits and
everything else stay in JAX, and the JAX walk stays the one for GPUs.

The result equals `walk`'s bit for bit: the same counter-based uniforms (`hash_uniform`,
one per ant and step), the same float32 inverse-CDF sums in the same order, the same
dead-end rules, path buffers (including entries past ``n``), penalty counts, dead-end
marks and throughput counters (``loop_steps`` and ``slots`` are those the JAX loop,
with its compaction, would report). With a walk hook (seed 002's `opt_ant`) the hook's
state-dependent logits come from a table precomputed in JAX (`hook_logits`: one value
per cell and move for "keeps the previous heading" and one for "turns"); the step then
only needs the exponential of the logits relative to their maximum, computed with XLA's
own float32 exp algorithm (`_exp_xla`), so this case is bit-identical too.

Ants of one iteration never see each other's moves (the dead-end marks become
pseudo-obstacles only from the next iteration), so walking them one after another
gives the same paths as walking them in lockstep.
"""

from __future__ import annotations

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

__all__ = ["WALK_BACKENDS", "HookTables", "resolve_backend", "walk"]

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
    """What the numba walk needs for seed 002's hook (`jaxplan.aco._rules.hook_opt_ant`).

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
def _f2u(typingctx, x):
    """Bit pattern of a float32 as uint32."""
    sig = types.uint32(types.float32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(32))

    return sig, codegen


@intrinsic
def _u2f(typingctx, x):
    """float32 with the given uint32 bit pattern."""
    sig = types.float32(types.uint32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())

    return sig, codegen


# ---------------------------------------------------------------------------------------------
# The walk.


@njit(cache=True, nogil=True)
def _walk_ant(a, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
              max_steps, width, lut, mode, has_hook, penalise, cells, moves, n_out, status_out, steps_out,
              penalty, marks, seen, p, ok, is_goal):
    """Walks ant ``a`` to its end; ``seen`` is the chunk's tabu, stamped with ``a + 1`` (never cleared)."""
    K = nbr.shape[1]
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
    high = 0  # deepest path slot written: `cells` beyond it keep their zeros
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
            acc = _F(0.0)
            for k in range(K):
                nb = nbr[pos, k]
                safe = max(nb, 0)
                o = (nb >= 0) & (seen[safe] != stamp)
                if alerting:
                    o = o & (not alert[c0 + safe])
                w = table[row, k] + _TINY
                acc = acc + (w if o else _F(0.0))
                p[k] = acc
        else:
            for k in range(K):
                nb = nbr[pos, k]
                safe = max(nb, 0)
                o = (nb >= 0) & (seen[safe] != stamp)
                if alerting:
                    o = o & (not alert[c0 + safe])
                ok[k] = o
            # Seed 002's hook: an adjacent goal wins (judged on the moves allowed so far), else
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
            high = max(high, n)
            seen[new] = stamp
            prev = k
            pos = new
            if new == g:
                status = GOAL
                break
            continue
        # Stuck: no allowed move.
        if alerting:
            # Seed 002's dead-end alert: only one open move (the way back, ignoring this ant's tabu).
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
    n_out[a] = n
    status_out[a] = status
    steps_out[a] = t
    # `walk` derives every move from consecutive slots, stale ones included: slots up to n hold
    # the path (moves recorded above); past it, a retreat may have left an older branch behind.
    for j in range(n, min(high + 1, L)):
        m = _move_between(cells[a, j], cells[a, j + 1], width, lut)
        moves[a, j] = max(m, 0)


@njit(cache=True, nogil=True, parallel=True)
def _walk_all(nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
              max_steps, width, lut, mode, has_hook, penalise, n_chunks,
              cells, moves, n_out, status_out, steps_out, penalty, marks):
    """Walks every ant; chunk c takes ants c, c + n_chunks, ... (interleaved: ants of every run
    and colony are spread over the chunks, which evens out their different walk lengths)."""
    A = start.shape[0]
    C, K = nbr.shape
    parts = np.zeros((n_chunks if penalise else 1, penalty.shape[0]), np.float32)
    for c in prange(n_chunks):
        seen = np.zeros(C, np.int32)
        p = np.empty(K, np.float32)
        ok = np.empty(K, np.bool_)
        is_goal = np.empty(K, np.bool_)
        part = parts[c] if penalise else parts[0]
        for a in range(c, A, n_chunks):
            _walk_ant(a, nbr, table, hook_l, right_turn, turn_rule, start, goal, row0, cell0, seed, local, alert,
                      max_steps, width, lut, mode, has_hook, penalise, cells, moves, n_out, status_out, steps_out,
                      part, marks, seen, p, ok, is_goal)
    if penalise:
        # Counts of +1.0 are exact in float32 (below 2^24), so the chunk order does not matter.
        for c in range(n_chunks):
            penalty += parts[c]


def _n_chunks(A: int) -> int:
    """Parallel chunks: numba's threads, but no more than the cores this process may use."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(numba.get_num_threads(), cores, A))


def _loop_counters(steps: np.ndarray, max_steps: int) -> tuple[np.int32, np.int32]:
    """``(loop_steps, slots)`` the JAX step loop reports for ants that walked ``steps [A]`` steps.

    The loop runs until every ant has stopped; from `COMPACT_MIN_ANTS` ants on it continues with
    A / `COMPACT_FACTOR` slots once no more than that many are walking. int32 like the JAX counters.
    """
    A = steps.shape[0]
    loop = int(steps.max()) if A else 0
    if A >= COMPACT_MIN_ANTS:
        small = A // COMPACT_FACTOR
        walking = A - np.cumsum(np.bincount(steps, minlength=max_steps + 1))  # walking[t]: ants with > t steps
        below = np.nonzero(walking[:max_steps] <= small)[0]
        t_full = int(below[0]) if below.size else max_steps
        loop = max(loop, t_full)
        slots = t_full * A + (loop - t_full) * small
    else:
        slots = loop * A
    return np.int64(loop).astype(np.int32), np.int64(slots).astype(np.int32)


# Number of axes of each argument of one walk (more leading axes = a vmapped batch).
_CORE_NDIM = {"nbr": 2, "table": 2, "start": 1, "goal": 1, "row0": 1, "cell0": 1, "seed": 1, "local": 1, "lut": 1,
              "alert": 1, "hook_logits": 3, "right_turn": 1, "turn_rule": 1}


def _host_walk(args: dict, *, max_steps: int, width: int, mode: int, penalty_size: int, n_marks: int) -> dict:
    """The callback: runs `_walk_all` once per element of the (vmapped) batch, on numpy views."""
    args = {k: np.asarray(v) for k, v in args.items()}
    batch = np.broadcast_shapes(*(v.shape[: v.ndim - _CORE_NDIM[k]] for k, v in args.items()))
    A = args["start"].shape[-1]
    L = max_steps
    K = args["nbr"].shape[-1]
    out = {
        "cells": np.zeros(batch + (A, L + 1), np.int32),
        "moves": np.zeros(batch + (A, L), np.int8),
        "n": np.empty(batch + (A,), np.int32),
        "status": np.empty(batch + (A,), np.int32),
        "ant_steps": np.empty(batch + (A,), np.int32),
        "loop_steps": np.empty(batch, np.int32),
        "slots": np.empty(batch, np.int32),
        "penalty": np.zeros(batch + (max(penalty_size, 1),), np.float32),
        "marks": np.zeros(batch + (max(n_marks, 1),), np.bool_),
    }
    dummy_f3 = np.zeros((2, 1, K), np.float32)
    dummy_i = np.zeros(1, np.int32)
    dummy_b = np.zeros(1, np.bool_)
    n_chunks = _n_chunks(A)
    for idx in np.ndindex(*batch):
        def arg(k, dummy=None):
            if k not in args:
                return dummy
            v = args[k]
            lead = v.ndim - _CORE_NDIM[k]
            # Size-1 leading axes (unbatched arguments under vmap) broadcast to every element.
            sub = tuple(i if v.shape[j] > 1 else 0 for j, i in enumerate(idx[len(idx) - lead:])) if lead else ()
            return np.ascontiguousarray(v[sub])

        o = {k: v[idx] for k, v in out.items()}
        _walk_all(
            arg("nbr"), arg("table"), arg("hook_logits", dummy_f3), arg("right_turn", dummy_i),
            arg("turn_rule", dummy_b), arg("start"), arg("goal"), arg("row0"), arg("cell0"), arg("seed"),
            arg("local"), arg("alert", dummy_b), L, width, arg("lut"), mode, "hook_logits" in args,
            penalty_size > 0, n_chunks,
            o["cells"], o["moves"], o["n"], o["status"], o["ant_steps"], o["penalty"], o["marks"],
        )
        out["loop_steps"][idx], out["slots"][idx] = _loop_counters(o["ant_steps"], L)
    if not penalty_size:
        del out["penalty"]
    if not n_marks:
        del out["marks"]
    return out


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
) -> Ants:
    """`jaxplan.aco._walk.walk` as one host call: same arguments, same `Ants`, bit for bit.

    Differences in the arguments: ``table`` is not used when ``hook`` is given (the hook's
    logits are in `HookTables.logits`, built by the colony's ``hook_logits`` rule). Works
    under `jit`, `lax.scan` and `vmap` (a vmapped batch is walked element by element, each
    element in parallel over its ants).
    """
    A = start.shape[0]
    L = max_steps
    mode = _MODES[dead_end]
    args = {"nbr": nbr, "start": start, "goal": goal, "row0": row0, "cell0": cell0, "seed": seed, "local": local,
            "lut": lut}
    args = {k: jnp.asarray(v, jnp.uint32 if k == "seed" else jnp.int32) for k, v in args.items()}
    if hook is None:
        args["table"] = jnp.asarray(table, jnp.float32)
    else:
        args["table"] = jnp.zeros((1, nbr.shape[1]), jnp.float32)  # unused: keeps the kernel's signature
        args["hook_logits"] = jnp.asarray(hook.logits, jnp.float32)
        args["right_turn"] = jnp.asarray(hook.right_turn, jnp.int32)
        args["turn_rule"] = jnp.asarray(hook.turn_rule, bool)
    n_marks = 0
    if mode == _ALERT:
        args["alert"] = jnp.asarray(alert, bool)
        n_marks = alert.shape[0]
    shapes = {
        "cells": jax.ShapeDtypeStruct((A, L + 1), jnp.int32),
        # Move indices (< 16) travel as int8: a quarter of the bytes to allocate and copy
        # back; the conversion fuses into the consumers of `Ants.moves`.
        "moves": jax.ShapeDtypeStruct((A, L), jnp.int8),
        "n": jax.ShapeDtypeStruct((A,), jnp.int32),
        "status": jax.ShapeDtypeStruct((A,), jnp.int32),
        "ant_steps": jax.ShapeDtypeStruct((A,), jnp.int32),
        "loop_steps": jax.ShapeDtypeStruct((), jnp.int32),
        "slots": jax.ShapeDtypeStruct((), jnp.int32),
    }
    if penalty_size:
        shapes["penalty"] = jax.ShapeDtypeStruct((penalty_size,), jnp.float32)
    if n_marks:
        shapes["marks"] = jax.ShapeDtypeStruct((n_marks,), jnp.bool_)
    host = functools.partial(_host_walk, max_steps=L, width=width, mode=mode, penalty_size=penalty_size,
                             n_marks=n_marks)
    out = jax.pure_callback(host, shapes, args, vmap_method="expand_dims")
    return Ants(cells=out["cells"], moves=out["moves"].astype(jnp.int32), n=out["n"], status=out["status"],
                penalty=out.get("penalty"), ant_steps=out["ant_steps"], loop_steps=out["loop_steps"],
                marks=out.get("marks"), slots=out["slots"])
