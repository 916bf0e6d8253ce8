"""The colony engine: one ACO run as one compiled program (`lax.scan` over iterations).

A planner is a `Colony` (static rules) plus `RunConfig` (static sizes and switches)
plus a params dict (numbers, a pytree). `run` plays all iterations; `run_batch`
vmaps it over scenarios and seeds, so a whole experiment grid is one call.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.aco import _rules as R
from jaxplan.aco import _walk_numba
from jaxplan.aco._context import GoalTables, MapTables
from jaxplan.aco._objective import ETA_COST_FLOOR
from jaxplan.aco._walk import DEAD_END_RULES, GOAL, Ants, move_lut, walk
from jaxplan.aco._walk_numba import WALK_BACKENDS, HookTables
from jaxplan.metrics import converged_iteration
from jaxplan.metrics import diversity as run_diversity

__all__ = ["Colony", "RunConfig", "ColonyState", "RunOutput", "run", "run_batch", "HEURISTICS"]

HEURISTICS = ("euclidean", "geodesic", "objective")


@dataclass(frozen=True)
class Colony:
    """The rules of one ACO variant (all static: module-level functions).

    Attributes:
      name: planner name.
      init: initial pheromone per target cell, ``init(tables, params) -> f32[C]``.
      cost: path cost, ``cost(stats, params, tables, goal) -> f32[A]``.
      deposits: deposit rules, summed (`jaxplan.aco._rules.combine`).
      bound: ``bound(tau, params) -> tau`` after each update.
      evaporation: ``"rate"`` (τ ← (1−ρ)·τ, param ``rho``) or ``"residual"`` (τ ← ρ_res·τ,
        param ``rho_res``, chu2024's Eq. 4).
      hook: optional walk hook (state-dependent logits / move restrictions).
      heuristic_in_hook: the hook adds β·log η itself (the static η table is not used).
      hook_logits: the hook's logits as a table for the numba walk,
        ``hook_logits(tables, params, h_cell [B, C], logits [B, S, C, K]) -> f32[2, B * S * C, K]``
        (``[1]``: the move keeps the previous heading); None: a hooked colony walks in JAX.
    """

    name: str
    init: Callable
    cost: Callable
    deposits: tuple
    bound: Callable = R.bound_floor
    evaporation: str = "rate"
    hook: Callable | None = None
    heuristic_in_hook: bool = False
    hook_logits: Callable | None = None


@dataclass(frozen=True)
class RunConfig:
    """Static sizes and switches (changing one recompiles).

    Attributes:
      colonies: number of sub-colonies S (1 except praco).
      ants: ants per colony m.
      iterations: iterations of the scan.
      max_steps: moves an ant may make before it is stopped.
      width: map columns (to turn flat cell indices back into moves).
      heuristic: ``"euclidean"`` (the papers'), ``"geodesic"`` (exact goal distance) or ``"objective"``
        (η = 1 / (the move's own cost + the exact cost of the rest), `jaxplan.aco._objective`; the goal
        tables must carry its tables).
      dead_end: ``"die"`` (stuck ants stop), ``"retreat"`` (step back one cell) or
        ``"alert"`` (step back, and true dead ends become pseudo-obstacles for the rest of the run).
      penalise: yu2020's dead-corner penalty on retreat edges (param ``lambda_p``).
      keep_pheromone: return the final pheromone (``[S, C, K]`` per run) for plots.
      walk_backend: ``"jax"`` (the `lax.while_loop` walk, for any device), ``"numba"`` (one
        native call per iteration, `jaxplan.aco._walk_numba`; same results) or ``"auto"``
        (numba when JAX computes on the CPU).
      update_backend: where the path statistics and deposits are computed after the walk:
        ``"numba"`` (CPU; visits only the valid steps), ``"jax"`` (array operations over the whole
        ``[ants, max_steps]`` buffers, any device) or ``"auto"`` (numba on the CPU). Independent of
        ``walk_backend``, so both walks give the same results; the two updates may differ in the
        last bits of the summed path statistics (another summation order).
    """

    colonies: int
    ants: int
    iterations: int
    max_steps: int
    width: int
    heuristic: str = "euclidean"
    dead_end: str = "retreat"
    penalise: bool = False
    keep_pheromone: bool = False
    walk_backend: str = "auto"
    update_backend: str = "auto"

    def __post_init__(self) -> None:
        for name in ("colonies", "ants", "iterations", "max_steps", "width"):
            v = getattr(self, name)
            if not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        if self.heuristic not in HEURISTICS:
            raise ValueError(f"heuristic must be one of {HEURISTICS}, got {self.heuristic!r}")
        if self.dead_end not in DEAD_END_RULES:
            raise ValueError(f"dead_end must be one of {DEAD_END_RULES}, got {self.dead_end!r}")
        if self.penalise and self.dead_end != "retreat":
            raise ValueError("the dead-corner penalty needs dead_end='retreat'")
        if self.walk_backend not in WALK_BACKENDS:
            raise ValueError(f"walk_backend must be one of {WALK_BACKENDS}, got {self.walk_backend!r}")
        if self.update_backend not in WALK_BACKENDS:
            raise ValueError(f"update_backend must be one of {WALK_BACKENDS}, got {self.update_backend!r}")


class ColonyState(NamedTuple):
    """What evolves between iterations.

    tau: ``f32[S, C, K]`` pheromone per colony and directed edge; alert: ``bool[C]``
    pseudo-obstacles; bs_*: each colony's best-so-far path (cells ``i32[S, L + 1]``, moves
    ``i8[S, L]``, both zero past the path; n ``[S]``, cost ``[S]``, length ``[S]``, turns ``[S]``).
    """

    tau: jnp.ndarray
    alert: jnp.ndarray
    bs_cells: jnp.ndarray
    bs_moves: jnp.ndarray
    bs_n: jnp.ndarray
    bs_cost: jnp.ndarray
    bs_length: jnp.ndarray
    bs_turns: jnp.ndarray


class RunOutput(NamedTuple):
    """One run's result (add leading axes for batches).

    cells ``i32[L + 1]`` best path (valid up to ``n``), n ``i32`` moves, cost, length (m), turns,
    success, history ``f32[I]`` best cost after each iteration (inf before the first
    success), diversity ``f32[I]`` std of successful ants' costs per iteration,
    successes ``i32[I]`` ants reaching the goal per iteration, converged ``i32`` first
    iteration within 1 % of the final best (−1 without success), tau ``f32[S, C, K]``
    final pheromone (None unless ``keep_pheromone``); ant_steps ``i32[I]`` moves made by
    the run's walking ants, loop_steps ``i32[I]`` iterations of the (batch-wide) step
    loop and slots ``i32[I]`` ant slots it processed (all runs of the batch), per iteration.
    """

    cells: jnp.ndarray
    n: jnp.ndarray
    cost: jnp.ndarray
    length: jnp.ndarray
    turns: jnp.ndarray
    success: jnp.ndarray
    history: jnp.ndarray
    diversity: jnp.ndarray
    successes: jnp.ndarray
    converged: jnp.ndarray
    ant_steps: jnp.ndarray
    loop_steps: jnp.ndarray
    slots: jnp.ndarray
    tau: jnp.ndarray | None


def goal_distances(tables: MapTables, goal: GoalTables, heuristic: str) -> jnp.ndarray:
    """``f32[C]`` distance of each cell to the goal (m): straight line or exact (inf unreachable)."""
    if heuristic in ("geodesic", "objective"):  # "objective": only opt_ant's hook could read it, and it does not
        return goal.goal_dist
    return jnp.linalg.norm(tables.xy - tables.xy[goal.goal], axis=1)


def _scatter_paths(flat_tau: jnp.ndarray, colony_idx: jnp.ndarray, cells: jnp.ndarray, moves: jnp.ndarray,
                   n: jnp.ndarray, amount: jnp.ndarray, K: int, CK: int) -> jnp.ndarray:
    """Adds ``amount [P]`` on every edge of paths ``cells [P, L + 1]``/``moves [P, L]`` of colony ``colony_idx [P]``."""
    L = moves.shape[1]
    mask = jnp.arange(L)[None, :] < n[:, None]
    idx = colony_idx[:, None] * CK + cells[:, :L] * K + moves
    add = jnp.where(mask, amount[:, None], 0.0)
    return flat_tau.at[idx.ravel()].add(add.ravel())


def _init_state(colony: Colony, cfg: RunConfig, tables: MapTables, params: dict) -> ColonyState:
    S, L = cfg.colonies, cfg.max_steps
    C, K = tables.index.shape
    tau0 = colony.init(tables, params)[tables.index]  # [C, K]
    return ColonyState(
        tau=jnp.broadcast_to(tau0, (S, C, K)).astype(jnp.float32),
        alert=jnp.zeros((C,), bool),
        bs_cells=jnp.zeros((S, L + 1), jnp.int32),
        bs_moves=jnp.zeros((S, L), jnp.int8),
        bs_n=jnp.zeros((S,), jnp.int32),
        bs_cost=jnp.full((S,), jnp.inf, jnp.float32),
        bs_length=jnp.full((S,), jnp.inf, jnp.float32),
        bs_turns=jnp.zeros((S,), jnp.float32),
    )


def _move_table(colony: Colony, tables: MapTables, params: dict, tau: jnp.ndarray, log_eta: jnp.ndarray, *,
                hooked: bool) -> jnp.ndarray:
    """``f32[S, C, K]``: normalised move weights, or logits when the walk has a hook (``hooked``)."""
    logits = params["alpha"] * jnp.log(jnp.maximum(tau, R.TAU_FLOOR))
    if not colony.heuristic_in_hook:
        logits = logits + params["beta"] * log_eta
    logits = jnp.where(tables.valid, logits, -jnp.inf)
    if hooked:
        return logits
    # Per-cell normalised weights: the step loop then needs no exp or log.
    mx = jnp.max(logits, axis=2, keepdims=True)
    return jnp.where(tables.valid, jnp.exp(logits - jnp.where(jnp.isfinite(mx), mx, 0.0)), 0.0)


def _choose(colony: Colony, cfg: RunConfig, tables: MapTables, params: dict, state: ColonyState, ants: Ants,
            stats: R.PathStats, goal: GoalTables) -> tuple:
    """One run's costs, deposit amounts and best-so-far update from its ants (``[S * m]`` of them).

    Returns:
      ``(state, deposit, outputs)``: the state with the new best-so-far paths (pheromone not yet
      updated), the `R.Deposit` amounts, and (best cost, diversity, successes, ant steps).
    """
    S, m = cfg.colonies, cfg.ants
    L = cfg.max_steps
    ok = ants.status == GOAL
    cost = jnp.where(ok, colony.cost(stats, params, tables, goal), jnp.inf)
    cost = jnp.where(jnp.isnan(cost), jnp.inf, cost).reshape(S, m)
    length = stats.length.reshape(S, m)
    it_best = jnp.argmin(cost, axis=1)
    ant_idx = jnp.arange(S) * m + it_best
    it_cost = cost[jnp.arange(S), it_best]
    better = it_cost < state.bs_cost
    # Path slots past n are unspecified in `Ants`: keep zeros there, so a run's outputs are its own.
    new_n = ants.n[ant_idx]
    new_cells = jnp.where(jnp.arange(L + 1)[None, :] <= new_n[:, None], ants.cells[ant_idx], 0)
    new_moves = jnp.where(jnp.arange(L)[None, :] < new_n[:, None], ants.moves[ant_idx], 0).astype(jnp.int8)
    bs_cells = jnp.where(better[:, None], new_cells, state.bs_cells)
    bs_moves = jnp.where(better[:, None], new_moves, state.bs_moves)
    bs_n = jnp.where(better, new_n, state.bs_n)
    bs_cost = jnp.where(better, it_cost, state.bs_cost)
    bs_length = jnp.where(better, length[jnp.arange(S), it_best], state.bs_length)
    bs_turns = jnp.where(better, stats.turns.reshape(S, m)[jnp.arange(S), it_best], state.bs_turns)
    dep = R.without_exchange(R.combine(colony.deposits, cost, bs_cost, params), S)
    alert = state.alert
    if ants.marks is not None:
        alert = alert | ants.marks
    n_ok = jnp.sum(ok)
    # Failed ants carry cost inf, so the finite costs are the successful ants (all colonies').
    diversity = run_diversity(cost, jnp.isfinite(cost), axis=None)
    new = ColonyState(state.tau, alert, bs_cells, bs_moves, bs_n, bs_cost, bs_length, bs_turns)
    return new, dep, (jnp.min(bs_cost), diversity, n_ok.astype(jnp.int32), jnp.sum(ants.ant_steps))


def _evaporate(colony: Colony, params: dict, tau: jnp.ndarray) -> jnp.ndarray:
    """τ ← (1−ρ)·τ (``"rate"``) or ρ_res·τ (``"residual"``)."""
    evap = (1.0 - params["rho"]) if colony.evaporation == "rate" else params["rho_res"]
    return evap * tau


def _deposit_jax(cfg: RunConfig, tau: jnp.ndarray, ants: Ants, state: ColonyState, dep: R.Deposit) -> jnp.ndarray:
    """One run's deposits as XLA scatter-adds over the whole ``[S * m, L]`` path buffers (any device)."""
    S, m = cfg.colonies, cfg.ants
    _, C, K = tau.shape
    CK = C * K
    flat = tau.reshape(S * CK)
    colony_of_ant = jnp.repeat(jnp.arange(S), m)
    nxt = (jnp.arange(S) + 1) % S
    moves, bs_moves = ants.moves.astype(jnp.int32), state.bs_moves.astype(jnp.int32)
    if dep.own is not None:
        flat = _scatter_paths(flat, colony_of_ant, ants.cells, moves, ants.n, dep.own.ravel(), K, CK)
    if dep.nbr is not None:
        flat = _scatter_paths(flat, nxt[colony_of_ant], ants.cells, moves, ants.n, dep.nbr.ravel(), K, CK)
    if dep.bs_own is not None:
        flat = _scatter_paths(flat, jnp.arange(S), state.bs_cells, bs_moves, state.bs_n, dep.bs_own, K, CK)
    if dep.bs_nbr is not None:
        flat = _scatter_paths(flat, nxt, state.bs_cells, bs_moves, state.bs_n, dep.bs_nbr, K, CK)
    return flat.reshape(S, C, K)


def _deposit_numba(cfg: RunConfig, params: dict, tau: jnp.ndarray, ants: Ants, state: ColonyState,
                   dep: R.Deposit) -> jnp.ndarray:
    """Every run's deposits in one native call over the successful ants' valid steps only, then
    yu2020's dead-corner penalty on the edges retreated over.

    Args:
      tau: ``f32[B, S, C, K]`` evaporated pheromone; ants: all runs' ants (flat ``[B * S * m]``);
      state: the runs' states with the new best-so-far paths (``[B, S, ...]``); dep: ``[B, S, m]`` /
      ``[B, S]`` amounts.
    """
    B, S, C, K = tau.shape
    m = cfg.ants
    zeros = lambda shape: jnp.zeros(shape, jnp.float32)  # noqa: E731
    pick = lambda a, shape: zeros(shape) if a is None else a.reshape(shape)  # noqa: E731
    own_colony = jnp.repeat(jnp.arange(B * S), m)  # [B * S * m]: row b * S + s of tau
    run_first = (own_colony // S) * S
    nbr_colony = run_first + (own_colony - run_first + 1) % S
    best_colony = jnp.arange(B * S)
    best_nbr = (best_colony // S) * S + (best_colony % S + 1) % S
    paths = (ants.cells, ants.moves, ants.n,
             jnp.stack([pick(dep.own, (B * S * m,)), pick(dep.nbr, (B * S * m,))]),
             jnp.stack([own_colony, nbr_colony]))
    L = cfg.max_steps
    best = (state.bs_cells.reshape(B * S, L + 1), state.bs_moves.reshape(B * S, L), state.bs_n.reshape(B * S),
            jnp.stack([pick(dep.bs_own, (B * S,)), pick(dep.bs_nbr, (B * S,))]), jnp.stack([best_colony, best_nbr]))
    keep = 1.0 - params["lambda_p"] if ants.penalty is not None else None
    return _walk_numba.deposit(tau.reshape(-1), paths, best, C, K, ants.penalty, keep).reshape(B, S, C, K)


def _finish(colony: Colony, params: dict, tau: jnp.ndarray, penalty: jnp.ndarray | None) -> jnp.ndarray:
    """One run's pheromone after its deposits: yu2020's dead-corner penalty, then the bounds."""
    if penalty is not None:
        tau = tau * jnp.power(1.0 - params["lambda_p"], penalty.reshape(tau.shape))
    return colony.bound(tau, params)


def walk_backend(colony: Colony, cfg: RunConfig) -> str:
    """The walk this run uses, ``"jax"`` or ``"numba"`` (``"auto"`` resolved for the default device)."""
    backend = _walk_numba.resolve_backend(cfg.walk_backend)
    if backend == "numba" and colony.hook is not None and colony.hook_logits is None and cfg.heuristic != "objective":
        if cfg.walk_backend == "numba":
            raise ValueError(f"colony {colony.name!r}: its walk hook has no table form for walk_backend='numba'")
        return "jax"
    return backend


def update_backend(cfg: RunConfig) -> str:
    """Where path statistics and deposits are computed: ``"numba"`` (one native call each, over the
    valid steps only) when JAX computes on the CPU, whatever walk the ants take, else ``"jax"``."""
    if cfg.update_backend == "auto":
        return "numba" if jax.default_backend() == "cpu" else "jax"
    return cfg.update_backend


def run_batch(colony: Colony, cfg: RunConfig, tables: MapTables, goals: GoalTables, params: dict,
              keys: jax.Array) -> RunOutput:
    """Plays ``cfg.iterations`` iterations on every scenario of ``goals`` (leading axis N) with
    every key of ``keys [R]``. Outputs have leading axes ``[N, R]``.

    The B = N·R runs keep separate pheromone and best paths; their ants walk together
    in one step loop. Each run's result depends only on its own scenario and key.
    Pure and jittable with ``colony`` and ``cfg`` static.
    """
    N, R_ = goals.start.shape[0], keys.shape[0]
    B = N * R_
    S, m, L, I = cfg.colonies, cfg.ants, cfg.max_steps, cfg.iterations
    M = S * m
    C, K = tables.index.shape
    goal_b = jax.tree_util.tree_map(lambda a: jnp.repeat(a, R_, axis=0), goals)
    key_b = keys[jnp.tile(jnp.arange(R_), N)]
    objective = cfg.heuristic == "objective"
    if objective:
        if goals.move_cost is None:
            raise ValueError("heuristic='objective' needs the goal tables' move_cost (goal_tables(..., objective=...))")
        # β·log η per turn-cost variant: [V, B * C, K] (see `jaxplan.aco._objective`).
        q = goal_b.move_cost[:, None] + goal_b.turn_cost[:, :, None, None]  # [B, V, C, K]
        eta_v = params["beta"] * -jnp.log(jnp.maximum(q, ETA_COST_FLOOR))
        eta_v = jnp.swapaxes(eta_v, 0, 1)  # [V, B, C, K]
        variant = goal_b.variant[0]
        colony = dataclasses.replace(colony, heuristic_in_hook=True)
        h_cell: jnp.ndarray | None = None
        log_eta = jnp.zeros((B, 1, 1), jnp.float32)  # unused: the hook adds β·log η
    else:
        h_cell = jax.vmap(lambda g: goal_distances(tables, g, cfg.heuristic))(goal_b)  # [B, C]
        log_eta = -jnp.log(jnp.maximum(h_cell, 0.5 * tables.resolution))[:, tables.index]  # [B, C, K]
    state0 = _init_state(colony, cfg, tables, params)
    state = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (B,) + a.shape), state0)
    nbr = jnp.where(tables.valid, tables.index, -1)
    bits = _walk_numba.move_bits(nbr)
    lut = move_lut(tables.offsets)
    run_of = jnp.repeat(jnp.arange(B), M)
    colony_of = jnp.tile(jnp.repeat(jnp.arange(S), m), B)
    row0 = (run_of * S + colony_of) * C
    cell0 = run_of * C
    local = jnp.tile(jnp.arange(M), B)
    start, goal = goal_b.start[run_of], goal_b.goal[run_of]
    hook = None
    backend = walk_backend(colony, cfg)
    rules = colony.hook is not None  # opt_ant keeps chu2024's move rules under any heuristic
    hooked = rules or objective
    if objective and backend == "jax":
        hook = functools.partial(R.hook_objective, tables, eta_v.reshape(-1, B * C, K), variant, rules)
    elif colony.hook is not None and backend == "jax":
        assert h_cell is not None
        hook = functools.partial(colony.hook, tables, params, h_cell.reshape(B * C))
    # One seed per run and iteration, all drawn before the loop in one threefry call per run: the
    # walk's uniforms are hashed from it (`hash_uniform`). Keeping key splits and draws out of the
    # loop body keeps the compiled program small (XLA's CPU compile time grows with its kernels).
    iter_seeds = jax.vmap(lambda k: jax.random.bits(k, (I,), jnp.uint32))(key_b).T  # [I, B]
    choose = jax.vmap(functools.partial(_choose, colony, cfg, tables, params))
    evaporate = jax.vmap(functools.partial(_evaporate, colony, params))
    finish = jax.vmap(functools.partial(_finish, colony, params))
    native_update = update_backend(cfg) == "numba"
    stat_tables = _walk_numba.stat_tables(tables) if native_update else None

    def iteration(state: ColonyState, seeds: jnp.ndarray) -> tuple[ColonyState, tuple]:
        table = jax.vmap(functools.partial(_move_table, colony, tables, params, hooked=hooked))(state.tau, log_eta)
        walk_args = (nbr, table.reshape(B * S * C, K), start, goal, row0, cell0, seeds[run_of], local,
                     state.alert.reshape(B * C) if cfg.dead_end == "alert" else None)
        sizes: dict[str, Any] = dict(max_steps=L, width=cfg.width, lut=lut, dead_end=cfg.dead_end,
                     penalty_size=B * S * C * K if cfg.penalise else 0)
        if backend == "numba":
            hook_tables = None
            if objective:
                logits = (table[None] + eta_v[:, :, None]).reshape(-1, B * S * C, K)  # [V, B * S * C, K]
                hook_tables = HookTables(logits, tables.right_turn, tables.turn_rule, variant, rules)
            elif colony.hook is not None:
                assert colony.hook_logits is not None and h_cell is not None, "the numba walk needs hook_logits"
                logits = colony.hook_logits(tables, params, h_cell, table)
                hook_tables = HookTables(logits, tables.right_turn, tables.turn_rule)
            ants = _walk_numba.walk(*walk_args, **sizes, hook=hook_tables, stats=stat_tables, bits=bits)
        else:
            ants = walk(*walk_args, **sizes, hook=hook)
        per_run = Ants(
            cells=ants.cells.reshape(B, M, L + 1), moves=ants.moves.reshape(B, M, L), n=ants.n.reshape(B, M),
            status=ants.status.reshape(B, M),
            penalty=None if ants.penalty is None else ants.penalty.reshape(B, S, C * K),
            ant_steps=ants.ant_steps.reshape(B, M), loop_steps=jnp.broadcast_to(ants.loop_steps, (B,)),
            marks=None if ants.marks is None else ants.marks.reshape(B, C),
            slots=jnp.broadcast_to(jnp.asarray(ants.slots), (B,)),
        )
        if native_update:
            # Sums over the valid steps only; the numba walk has them already, a JAX walk's paths get
            # the same kernel (so both walks give the same bits).
            assert stat_tables is not None
            rows = ants.stats if ants.stats is not None else _walk_numba.path_stats(
                stat_tables, ants.cells, ants.moves, ants.n)
            stats = R.stats_from_rows(rows.reshape(-1, B, M))
        else:
            stats = jax.vmap(functools.partial(R.path_stats, tables))(per_run)
        state, dep, (best, diversity, successes, ant_steps) = choose(state, per_run, stats, goal_b)
        tau = evaporate(state.tau)
        if native_update:
            tau = finish(_deposit_numba(cfg, params, tau, ants, state, dep), None)  # penalty included
        else:
            tau = finish(jax.vmap(functools.partial(_deposit_jax, cfg))(tau, per_run, state, dep), per_run.penalty)
        state = state._replace(tau=tau)
        return state, (best, diversity, successes, ant_steps, per_run.loop_steps, per_run.slots)

    state, outs = jax.lax.scan(iteration, state, iter_seeds)
    history, diversity, successes, ant_steps, loop_steps, slots = (jnp.swapaxes(o, 0, 1) for o in outs)  # [B, I]
    best = jnp.argmin(state.bs_cost, axis=1)
    pick = lambda a: a[jnp.arange(B), best]  # noqa: E731
    final = pick(state.bs_cost)
    success = jnp.isfinite(final)
    converged = converged_iteration(history)  # history[:, -1] is the final best
    out = RunOutput(
        cells=pick(state.bs_cells), n=pick(state.bs_n), cost=final, length=pick(state.bs_length),
        turns=pick(state.bs_turns), success=success, history=history, diversity=diversity, successes=successes,
        converged=converged, ant_steps=ant_steps, loop_steps=loop_steps, slots=slots,
        tau=state.tau if cfg.keep_pheromone else None,
    )
    return jax.tree_util.tree_map(lambda a: a.reshape((N, R_) + a.shape[1:]), out)


def run(colony: Colony, cfg: RunConfig, tables: MapTables, goal: GoalTables, params: dict, key: jax.Array) -> RunOutput:
    """One scenario (scalar fields in ``goal``) with one key: `run_batch` with N = R = 1."""
    goals = jax.tree_util.tree_map(lambda a: a[None], goal)
    out = run_batch(colony, cfg, tables, goals, params, key[None])
    return jax.tree_util.tree_map(lambda a: a[0, 0], out)
