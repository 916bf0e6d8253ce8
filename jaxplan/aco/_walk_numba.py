"""The ants' walk as one native call per iteration (numba), for the CPU backend.

`jaxplan.aco._walk.walk` advances all ants together, one `lax.while_loop` step per
move; on a CPU each step is about fifteen small XLA kernels (gathers, scatters), so the
loop costs far more than the arithmetic it does. Here the whole walk of one
iteration (every run, colony and ant, from the start until goal, dead end or step
limit) is one compiled call: each ant walks to the end on its own (on 8-connected grids
without a hook, 16 ants step at once in SIMD lanes), the ants are shared out over the cores
with `prange`. The JAX program calls it as an XLA FFI custom call (a numba `cfunc`
registered with `jax.ffi`; CPU only), so the iterations' `lax.scan`, the move tables and
the rules stay in JAX, and the JAX walk stays the one for GPUs. Two more native kernels
serve the colony's update on the CPU (for either walk): `path_stats` and
`deposit` visit only the valid steps of the paths instead of whole ``[A, L]`` buffers.

The result equals `walk`'s bit for bit: the same counter-based uniforms (`hash_uniform`,
one per ant and step), the same float32 inverse-CDF sums in the same order, the same
dead-end rules, paths (up to ``n``; slots past it are left unwritten), penalty counts, dead-end
marks and throughput counters (``loop_steps`` and ``slots`` are those the JAX loop,
with its compaction, would report). With a walk hook (chu2024's `opt_ant`) the hook's
state-dependent logits come from a table precomputed in JAX (`hook_logits`: one value
per cell and move for "keeps the previous heading" and one for "turns"); the step then
only needs the exponential of the logits relative to their maximum, computed with XLA's
own float32 exp algorithm (`exp_xla`), so this case is bit-identical too.

Ants of one iteration never see each other's moves (the dead-end marks become
pseudo-obstacles only from the next iteration), so walking them one after another
gives the same paths as walking them in lockstep.

This module is the JAX side (the custom calls' shapes, the tables they read, the core share); the native
side is in `jaxplan.aco._walk_numba_intrinsics` (scalar pieces), `jaxplan.aco._walk_numba_update` (path
statistics, deposits), `jaxplan.aco._walk_numba_kernels` (the walk) and `jaxplan.aco._walk_ffi` (the
handlers XLA calls, and their registration).
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import os
from typing import Iterator, NamedTuple

import jax
import jax.numpy as jnp
import numba
import numpy as np

from jaxplan.aco._context import MapTables
from jaxplan.aco._walk import Ants
from jaxplan.aco._walk_ffi import register
from jaxplan.aco._walk_numba_kernels import ALERT, HOOK_RULES, HOOK_TABLE, MODES, NO_HOOK
from jaxplan.aco._walk_numba_update import N_STATS

__all__ = ["WALK_BACKENDS", "N_STATS", "HookTables", "StatTables", "resolve_backend", "stat_tables", "walk",
           "move_bits", "path_stats", "deposit", "sharing_cores"]

WALK_BACKENDS = ("jax", "numba", "auto")


class HookTables(NamedTuple):
    """What the numba walk needs for chu2024's hook (`jaxplan.aco._rules.hook_opt_ant`).

    Attributes:
      logits: ``f32[V, G * C, K]`` the hook's logits of each colony's cell and move, one table per variant:
        chu2024's ``[0]`` when the move changes the ant's heading, ``[1]`` when it keeps it.
      right_turn: ``i32[K]`` the move a quarter turn to the right of each move.
      turn_rule: ``bool[C]`` right-hand-rule cells.
      variant: ``i32[(K + 1) · K]`` the table of move k for an ant whose previous move is m, at
        ``(m + 1)·K + k`` (m = −1: no move yet); None: chu2024's two (``k == m``).
      rules: apply chu2024's move rules (an adjacent goal first, the right-hand rule); False for
        ``heuristic="objective"`` of the other colonies, whose tables only depend on the previous move.
    """

    logits: jnp.ndarray
    right_turn: jnp.ndarray
    turn_rule: jnp.ndarray
    variant: jnp.ndarray | None = None
    rules: bool = True


def resolve_backend(name: str) -> str:
    """``"jax"`` or ``"numba"``: ``"auto"`` picks numba when JAX computes on the CPU."""
    if name not in WALK_BACKENDS:
        raise ValueError(f"walk_backend must be one of {WALK_BACKENDS}, got {name!r}")
    if name == "auto":
        return "numba" if jax.default_backend() == "cpu" else "jax"
    return name


_SHARERS = contextvars.ContextVar("jaxplan_walk_sharers", default=1)


@contextlib.contextmanager
def sharing_cores(devices: int) -> Iterator[None]:
    """While tracing a program that runs on ``devices`` host devices at once (a sharded batch),
    each device's walk takes only its share of the cores: walks that each launch a thread
    per core oversubscribe the cores and are no faster than one device. The chunk count is a
    trace-time constant and does not change any result (chunks walk independent ants)."""
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


def stat_tables(tables: MapTables) -> StatTables:
    """`StatTables` of a `jaxplan.aco._context.MapTables`."""
    movef = jnp.concatenate([tables.step, tables.turn_angle.reshape(-1)]).astype(jnp.float32)
    cellf = jnp.stack([tables.clearance, tables.risk, tables.height]).astype(jnp.float32)
    return StatTables(movef, cellf)


def path_stats(st: StatTables, cells: jnp.ndarray, moves: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``f32[N_STATS, A]``: the statistics the numba walk returns, for paths walked elsewhere.

    Args:
      cells: ``i32[A, L + 1]``; moves: ``i8[A, L]``; n: ``i32[A]`` (slots past ``n`` are not read).
    """
    register()
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
    register()
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
    register()
    A = start.shape[0]
    C, K = nbr.shape
    L = max_steps
    mode = MODES[dead_end]
    i32 = functools.partial(jnp.asarray, dtype=jnp.int32)
    straight = np.concatenate([np.zeros(K, np.int32), np.eye(K, dtype=np.int32).ravel()])  # chu2024's k == prev
    if hook is None:
        hook_l, hook_v = jnp.zeros((2, 1, K), jnp.float32), jnp.asarray(straight)
        right_turn, turn_rule = jnp.zeros((K,), jnp.int32), jnp.zeros((1,), bool)
    else:
        hook_l, right_turn, turn_rule = hook.logits, hook.right_turn, hook.turn_rule
        hook_v = jnp.asarray(straight) if hook.variant is None else i32(hook.variant)
        table = jnp.zeros((1, K), jnp.float32)  # unused
    n_marks = 0
    if mode == ALERT:
        assert alert is not None, "dead_end='alert' needs the alert table"
        n_marks = alert.shape[0]
    if stats is None:
        stats = StatTables(jnp.ones((K + K * K,), jnp.float32), jnp.ones((3, C), jnp.float32))
    hook_mode = NO_HOOK if hook is None else HOOK_RULES if hook.rules else HOOK_TABLE
    cfg = np.array([L, width, mode, hook_mode, penalty_size > 0, _n_chunks(A)], np.int32)
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
        jnp.asarray(cfg), stats.movef, stats.cellf, bits, hook_v,
    )
    return Ants(cells=cells, moves=moves, n=per_ant[0], status=per_ant[1],
                penalty=penalty if penalty_size else None, ant_steps=per_ant[2], loop_steps=counters[0],
                marks=marks if n_marks else None, slots=counters[1], stats=path_st)
