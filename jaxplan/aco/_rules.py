"""The pieces a colony is made of (optax style: small pure functions, composed per planner).

Every rule reads its numbers from the ``params`` dict (a pytree of scalars), so a
planner's weights can be overridden per call, vmapped over and differentiated,
while the rule functions themselves are static. Equation numbers refer to the
seed papers in ``shared/seeds``.

Rule kinds:
  * initial pheromone ``init(tables, params) -> f32[C]`` per target cell;
  * path cost ``cost(stats, params) -> f32[A]``;
  * deposits ``deposit(costs [S, m], bs_cost [S], params) -> Deposit``;
  * bounds ``bound(tau, params) -> tau``;
  * walk hooks (see `jaxplan.aco._walk.walk`).
"""

from __future__ import annotations

from typing import Mapping, NamedTuple

import jax.numpy as jnp

from jaxplan.aco._context import GoalTables, MapTables
from jaxplan.aco._walk import Ants

TAU_FLOOR = 1e-30  # keeps log τ finite once evaporation has worn an edge down


# ---------------------------------------------------------------------------------------------
# Path statistics (everything the papers' costs are made of), from the ants' paths.


class PathStats(NamedTuple):
    """Per-ant path statistics, all ``f32[A]``.

    length: metres; turns: vertices where the move changes; heading: summed |heading
    change| (rad); inv_clearance: Σ 1/d over path cells (d floored at res/2, 1/m);
    risk: Σ risk over path cells; height_msd: mean square deviation of path-cell
    heights (m²); cells: number of cells on the path.
    """

    length: jnp.ndarray
    turns: jnp.ndarray
    heading: jnp.ndarray
    inv_clearance: jnp.ndarray
    risk: jnp.ndarray
    height_msd: jnp.ndarray
    cells: jnp.ndarray


def path_stats(tables: MapTables, ants: Ants) -> PathStats:
    """`PathStats` of ``ants`` (``[A, L]`` moves, ``[A, L + 1]`` cells) as array operations over whole buffers.

    On a CPU the colony takes them from the numba kernels instead (`jaxplan.aco._walk_numba.path_stats`:
    the same sums over the valid steps only, added left to right; XLA may add in another order, so the
    last bits can differ).
    """
    moves = ants.moves.astype(jnp.int32)
    ants = ants._replace(moves=moves)
    L = ants.moves.shape[1]
    t = jnp.arange(L)
    step_mask = t[None, :] < ants.n[:, None]  # [A, L]
    length = jnp.sum(jnp.where(step_mask, tables.step[ants.moves], 0.0), axis=1)
    turn_mask = step_mask[:, 1:]
    # |heading change| looked up per pair of moves (`MapTables.turn_angle`, the same arithmetic
    # as on the gathered angles). The lookup runs on whole rows (next move by `roll`, the wrapped
    # last column sliced off after it): indexed by odd-length slices, XLA's gather is ~3x slower.
    K = tables.angle.shape[0]
    d = tables.turn_angle.reshape(K * K)[ants.moves * K + jnp.roll(ants.moves, -1, axis=1)][:, :-1]
    changed = ants.moves[:, 1:] != ants.moves[:, :-1]
    turns = jnp.sum(turn_mask & changed, axis=1).astype(jnp.float32)
    heading = jnp.sum(jnp.where(turn_mask & changed, d, 0.0), axis=1)
    cell_mask = jnp.arange(L + 1)[None, :] <= ants.n[:, None]  # [A, L + 1]
    inv_clear = jnp.sum(jnp.where(cell_mask, 1.0 / tables.clearance[ants.cells], 0.0), axis=1)
    risk = jnp.sum(jnp.where(cell_mask, tables.risk[ants.cells], 0.0), axis=1)
    h = tables.height[ants.cells]
    count = jnp.sum(cell_mask, axis=1).astype(jnp.float32)
    mean_h = jnp.sum(jnp.where(cell_mask, h, 0.0), axis=1) / count
    msd = jnp.sum(jnp.where(cell_mask, (h - mean_h[:, None]) ** 2, 0.0), axis=1) / count
    return PathStats(length, turns, heading, inv_clear, risk, msd, count)


def stats_from_rows(rows: jnp.ndarray) -> PathStats:
    """`PathStats` from the rows of a ``f32[7, ...]`` array (the numba kernels' layout, fields in order)."""
    return PathStats(*(rows[i] for i in range(len(PathStats._fields))))


# ---------------------------------------------------------------------------------------------
# Initial pheromone τ0 of an edge = value of its target cell.


def init_uniform(tables: MapTables, params: dict) -> jnp.ndarray:
    """Ant System: τ0 everywhere."""
    return jnp.full(tables.clearance.shape, 1.0, jnp.float32) * params["tau0"]


def init_obstacle_aware(tables: MapTables, params: dict) -> jnp.ndarray:
    """chen2023, Eqs. 5–6: τ0(i) = f0 + 1/(1 + n_blocked(i)): less pheromone beside obstacles."""
    return params["f0"] + 1.0 / (1.0 + tables.n_blocked)


def init_opt_ant(tables: MapTables, params: dict) -> jnp.ndarray:
    """chu2024, Eq. 2: C on boundary cells, else C + 1/(1 + n_blocked) − σ·H/H_max.

    The paper prints "+ σ·H/H_max" but says a larger σ makes high cells less likely;
    docs/guide/planners.md follows the text. H_max is the largest |H|, so that terrain below the datum
    (negative heights) keeps the term in [−σ, σ] instead of dividing by a floored maximum
    (the same for heights >= 0). Floored at TAU_FLOOR.
    """
    h_max = jnp.maximum(jnp.max(jnp.abs(tables.height)), 1e-6)
    inner = params["c_init"] + 1.0 / (1.0 + tables.n_blocked) - params["sigma"] * tables.height / h_max
    return jnp.maximum(jnp.where(tables.boundary, params["c_init"], inner), TAU_FLOOR)


# ---------------------------------------------------------------------------------------------
# Path costs (smaller is better). Lengths in metres.


def cost_length(stats: PathStats, params: dict, tables: MapTables, goal: GoalTables) -> jnp.ndarray:
    """Ant System: L."""
    return stats.length


def cost_iaco(stats: PathStats, params: dict, tables: MapTables, goal: GoalTables) -> jnp.ndarray:
    """cui2025, Eq. 4 (as docs/guide/planners.md reads it): F = λ1·L/L0 + λ2·Σ|θ|/π + λ3·Σ 1/d_j,
    L0 the straight-line start–goal distance."""
    l0 = jnp.linalg.norm(tables.xy[goal.start] - tables.xy[goal.goal])
    lam = params["lambdas"]
    return lam[0] * stats.length / l0 + lam[1] * stats.heading / jnp.pi + lam[2] * stats.inv_clearance


def cost_risk(stats: PathStats, params: dict, tables: MapTables, goal: GoalTables) -> jnp.ndarray:
    """chen2023, Eq. 8: B = u·P + v·H + w·T (length, summed risk, turns)."""
    return params["u"] * stats.length + params["v"] * stats.risk + params["w"] * stats.turns


def cost_opt_ant(stats: PathStats, params: dict, tables: MapTables, goal: GoalTables) -> jnp.ndarray:
    """chu2024, Eq. 6: S = a·L + b·R + c·H (length, turns, height mean square deviation)."""
    return params["a"] * stats.length + params["b"] * stats.turns + params["c"] * stats.height_msd


def cost_praco(stats: PathStats, params: dict, tables: MapTables, goal: GoalTables) -> jnp.ndarray:
    """yu2020, Eq. 7: Z = ω1·L + ω2·N (length, turns)."""
    return params["omega1"] * stats.length + params["omega2"] * stats.turns


# ---------------------------------------------------------------------------------------------
# Deposits. Each returns amounts for: the colony's own ants (own [S, m]), ants sent to the
# next colony on the ring (nbr [S, m]), and each colony's best-so-far path deposited into
# itself (bs_own [S]) and into the next colony (bs_nbr [S]). None = nothing of that kind.


class Deposit(NamedTuple):
    own: jnp.ndarray | None = None
    nbr: jnp.ndarray | None = None
    bs_own: jnp.ndarray | None = None
    bs_nbr: jnp.ndarray | None = None


def _inv(costs: jnp.ndarray) -> jnp.ndarray:
    return jnp.where(jnp.isfinite(costs), 1.0 / jnp.maximum(costs, 1e-12), 0.0)


def deposit_inverse(costs: jnp.ndarray, bs_cost: jnp.ndarray, params: Mapping[str, jnp.ndarray]) -> Deposit:
    """Ant System: every ant that reached the goal lays Q/cost on its edges."""
    return Deposit(own=params["q"] * _inv(costs))


def deposit_elite(costs: jnp.ndarray, bs_cost: jnp.ndarray, params: Mapping[str, jnp.ndarray]) -> Deposit:
    """cui2025, Eq. 3: the iteration-best path gets an extra δ·Q/cost_best."""
    best = jnp.argmin(costs, axis=1)
    onehot = jnp.arange(costs.shape[1])[None, :] == best[:, None]
    return Deposit(own=jnp.where(onehot, params["delta"] * params["q"] * _inv(costs), 0.0))


def _ranks(costs: jnp.ndarray) -> jnp.ndarray:
    """0-based rank of each ant within its colony (failures rank last)."""
    order = jnp.argsort(costs, axis=1)
    return jnp.argsort(order, axis=1)


def deposit_ranked(costs: jnp.ndarray, bs_cost: jnp.ndarray, params: Mapping[str, jnp.ndarray]) -> Deposit:
    """yu2020, Eq. 10 (own colony): the w−1 best ants lay (w−r)/Z_r, the best-so-far w/Z_bs."""
    w = params["w_rank"]
    r = _ranks(costs) + 1.0
    own = jnp.where(r <= w - 1, (w - r) * _inv(costs), 0.0)
    return Deposit(own=own, bs_own=w * _inv(bs_cost))


def deposit_neighbour(costs: jnp.ndarray, bs_cost: jnp.ndarray, params: Mapping[str, jnp.ndarray]) -> Deposit:
    """yu2020, Eq. 10 (exchange): each colony passes its n−1 best ants ((n−q)/Z_q) and its
    best-so-far (n/Z_nbs) to the next colony on a ring."""
    n = params["n_exchange"]
    q = _ranks(costs) + 1.0
    nbr = jnp.where(q <= n - 1, (n - q) * _inv(costs), 0.0)
    return Deposit(nbr=nbr, bs_nbr=n * _inv(bs_cost))


def without_exchange(dep: Deposit, colonies: int) -> Deposit:
    """``dep`` without the ring exchange when there is one colony (static): it has no neighbour, and
    the ring ``(s + 1) % S`` would hand its exchange deposits back to itself."""
    return dep._replace(nbr=None, bs_nbr=None) if colonies == 1 else dep


def combine(deposits: tuple, costs: jnp.ndarray, bs_cost: jnp.ndarray, params: Mapping[str, jnp.ndarray]) -> Deposit:
    """Sums the amounts of several deposit rules field by field."""
    out: dict = {}
    for rule in deposits:
        for name, value in rule(costs, bs_cost, params)._asdict().items():
            if value is not None:
                out[name] = value if name not in out else out[name] + value
    return Deposit(**out)


# ---------------------------------------------------------------------------------------------
# Bounds.


def bound_floor(tau: jnp.ndarray, params: dict) -> jnp.ndarray:
    """Keeps τ positive and finite (no upper bound)."""
    return jnp.maximum(tau, TAU_FLOOR)


def bound_min_max(tau: jnp.ndarray, params: dict) -> jnp.ndarray:
    """chu2024, Eq. 7 (MAX–MIN): τ clamped to [τ_min, τ_max]."""
    return jnp.clip(tau, params["tau_min"], params["tau_max"])


# ---------------------------------------------------------------------------------------------
# Walk hook: chu2024's state-dependent heuristic and right-hand rule.


def hook_opt_ant(tables: MapTables, params: Mapping[str, jnp.ndarray], h_flat: jnp.ndarray, pos: jnp.ndarray,
                 prev: jnp.ndarray, nb: jnp.ndarray, ok: jnp.ndarray, logits: jnp.ndarray, goal: jnp.ndarray,
                 cell0: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """chu2024, Eq. 3: η = l + r + h, and the right-hand rule of its Section 2.3.

    ``l`` distance factor ("modified Euclidean distance"): the normalised progress of the
    move towards the goal, (1 + (d_i − d_j)/|move|)/2 in [0, 1] (1 when heading straight
    at it). jaxplan's reading: a literal 1/d_j barely differs between neighbours far from
    the goal, so once summed with r and h it stops steering the ants (paths far longer than the
    optimum on room maps). ``r`` straightness: μ when the move keeps the previous heading;
    ``h`` flatness: 1/(1 + |Δheight|). Adds β·log η to the logits.
    On a right-turn cell the ant must take the move a quarter turn to the right of its
    heading when that move is allowed. An adjacent goal has absolute priority (on every
    cell, not only right-turn cells: taking it can never make a path worse).
    """
    safe = jnp.maximum(nb, 0)
    d_to = h_flat[cell0[:, None] + safe]  # [A, K] distance of each target to the goal (inf: unreachable)
    d_from = h_flat[cell0 + pos][:, None]
    progress = (d_from - d_to) / tables.step[None, :]  # in [-1, 1]: 1 = straight at the goal
    dist_term = jnp.where(jnp.isfinite(d_to) & jnp.isfinite(d_from), jnp.clip(0.5 + 0.5 * progress, 0.0, 1.0), 0.0)
    straight = jnp.where(jnp.arange(nb.shape[1])[None, :] == prev[:, None], params["mu"], 0.0)
    flat = 1.0 / (1.0 + jnp.abs(tables.height[safe] - tables.height[pos][:, None]))
    eta = dist_term + straight + flat
    logits = logits + params["beta"] * jnp.log(eta)
    return logits, _opt_ant_rules(tables, pos, prev, nb, ok, goal)


def _opt_ant_rules(tables: MapTables, pos: jnp.ndarray, prev: jnp.ndarray, nb: jnp.ndarray, ok: jnp.ndarray,
                   goal: jnp.ndarray) -> jnp.ndarray:
    """chu2024's move rules: the right-hand rule on right-turn cells; an adjacent goal before anything."""
    is_goal = (nb == goal[:, None]) & ok
    # Right-hand rule.
    right = tables.right_turn[jnp.maximum(prev, 0)]
    right_ok = jnp.take_along_axis(ok, right[:, None], axis=1)[:, 0]
    on_rule = tables.turn_rule[pos] & (prev >= 0) & right_ok
    only_right = jnp.arange(nb.shape[1])[None, :] == right[:, None]
    ok = jnp.where(on_rule[:, None], ok & only_right, ok)
    return jnp.where(jnp.any(is_goal, axis=1, keepdims=True), is_goal, ok)


def hook_objective(tables: MapTables, eta: jnp.ndarray, variant: jnp.ndarray, rules: bool, pos: jnp.ndarray,
                   prev: jnp.ndarray, nb: jnp.ndarray, ok: jnp.ndarray, logits: jnp.ndarray, goal: jnp.ndarray,
                   cell0: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``heuristic="objective"`` (`jaxplan.aco._objective`) as a walk hook: adds β·log η of the ant's move
    given its previous move, and, for ``opt_ant`` (``rules``), chu2024's move rules.

    Args:
      eta: ``f32[V, B * C, K]`` β·log η per turn-cost variant, run (``cell0``) and cell, move.
      variant: ``i32[(K + 1) · K]`` the variant of move k after move m at ``(m + 1)·K + k``.
    """
    K = nb.shape[1]
    ks = jnp.arange(K)[None, :]
    v = variant[(prev[:, None] + 1) * K + ks]  # [A, K]
    logits = logits + eta[v, (cell0 + pos)[:, None], ks]
    if rules:
        ok = _opt_ant_rules(tables, pos, prev, nb, ok, goal)
    return logits, ok


def hook_opt_ant_logits(tables: MapTables, params: Mapping[str, jnp.ndarray], h_cell: jnp.ndarray,
                        logits: jnp.ndarray) -> jnp.ndarray:
    """`hook_opt_ant`'s logits for every colony, cell and move, as a table (for the numba walk).

    The hook's η depends on the ant's state only through "does the move keep the previous
    heading" (the straightness term μ), so two values per move cover every case. The
    arithmetic is the hook's, operation for operation, so the walk draws the same moves.

    Args:
      h_cell: ``f32[B, C]`` each run's distance to the goal (inf: unreachable).
      logits: ``f32[B, S, C, K]`` α·log τ (−inf where a move is not allowed).

    Returns:
      ``f32[2, B * S * C, K]``: ``[0]`` for a move that turns, ``[1]`` for one that keeps the heading.
    """
    K = logits.shape[-1]
    safe = jnp.maximum(jnp.where(tables.valid, tables.index, -1), 0)  # [C, K], as the walk's max(nb, 0)
    d_to = h_cell[:, safe]  # [B, C, K]
    d_from = h_cell[:, :, None]
    progress = (d_from - d_to) / tables.step[None, None, :]
    dist_term = jnp.where(jnp.isfinite(d_to) & jnp.isfinite(d_from), jnp.clip(0.5 + 0.5 * progress, 0.0, 1.0), 0.0)
    flat = 1.0 / (1.0 + jnp.abs(tables.height[safe] - tables.height[:, None]))
    # Stacked before adding the logits, not after: a concatenate of two fused log-and-add loops
    # made XLA's CPU backend emit ~1.3 MB of LLVM IR, about 2 s of this planner's compile time.
    eta = jnp.stack([params["beta"] * jnp.log(dist_term + straight + flat)
                     for straight in (jnp.zeros_like(params["mu"]), params["mu"])])  # [2, B, C, K]
    return (logits[None] + eta[:, :, None]).reshape(2, -1, K)
