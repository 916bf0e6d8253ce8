"""``heuristic="objective"``: η of a move = 1 / (the move's own cost + the exact cost of the rest), per colony.

The papers' η is 1 / (straight-line distance to the goal), and ``"geodesic"`` makes it the exact goal
distance; both speak of length, while the colonies minimise their own costs (IACO's fitness, the risk cost,
Opt Ant's a·L + b·R, P-RACO's ω1·L + ω2·N). Each of these is a sum over moves, turns and path cells
(`jaxplan.search.exact_objective`), so the exact cost of the rest of a path depends only on the
(cell, incoming move) state: for an ant on cell c that entered it by move m, taking move k to cell v costs

    q(c, m, k) = w_len·step[k] + cell[v] + turn(m, k) + h[v, k]

in total to the goal, with ``turn(m, k) = w_angle·|θ(m, k)| + w_turn`` when k ≠ m (0 when k = m or c is
the start) and ``h`` the exact cost-to-go (`jaxplan.grid.state_cost_to_go`, backward Dijkstra from the
goal over (cell, incoming move) states, with the colony's neighbourhood and move rules). η = 1/q; with a
large β the ants follow the exact optimum of their own cost.

The ant's incoming move enters only through ``turn(m, k)``, which takes few values: 1 for ``aco`` (no
turn term), 2 for ``risk_aco``, ``praco``, ``opt_ant`` (turn or not), one per distinct heading change for
``iaco`` (5 at 8-connectivity). The walk reads one logit table per value (``variant[m + 1, k]`` picks it),
so the turn at the ant's own cell is exact, not averaged over incoming moves.

Opt Ant's c·H (the mean square deviation of the path's heights) is no sum over moves: its cost-to-go
covers a·L + b·R only (exact on flat maps or with c = 0; on a height map the heuristic ignores the
height term, which the ants' cost and pheromone still carry). The η replaces chu2024's η = l + r + h
(its straightness and flatness terms); the colony keeps its move rules (an adjacent goal first, the
right-hand rule), which the cost-to-go also obeys.

Each colony's cost as these weights (`cost_weights`) is defined here, once: the exact search
`jaxplan.search.objective_terms` reads the same function.
"""

from __future__ import annotations

from typing import Any, Mapping, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.grid import GridMap, clearance_field, neighbour_table, passable, state_cost_to_go

__all__ = ["ETA_COST_FLOOR", "CostWeights", "ObjectiveTables", "cost_weights", "objective_tables",
           "objective_variants"]

ETA_COST_FLOOR = 1e-30
"""The smallest q the heuristic's log(1/q) reads (a move that is free under a colony's weights stays finite)."""


class ObjectiveTables(NamedTuple):
    """What ``heuristic="objective"`` adds to `jaxplan.aco.GoalTables` (leading axis N scenarios).

    Attributes:
      move_cost: ``f32[N, C, K]`` ``w_len·step[k] + cell[v] + h[v, k]`` for move k from cell c to v (inf
        where the goal is out of reach or the move not allowed): q without the turn at c.
      turn_cost: ``f32[N, V]`` the V distinct values of ``turn(m, k)``, ``[:, 0] = 0``.
      variant: ``i32[N, (K + 1) · K]`` index into ``turn_cost`` of ``turn(m, k)`` at ``(m + 1)·K + k``
        (row 0: the start, no incoming move).
    """

    move_cost: np.ndarray
    turn_cost: np.ndarray
    variant: np.ndarray


class CostWeights(NamedTuple):
    """A colony's path cost as a sum over moves, turns and cells (docs/guide/planners.md).

    Attributes:
      w_len: ``f64[N]`` weight per metre, per scenario (iaco's 1/L0 depends on the scenario).
      w_angle: weight per radian of heading change; w_turn: weight per turn.
      cell: ``f64[C]`` cost of entering each cell (0 on cells the vehicle cannot pass).
      goal_first: an adjacent goal must be taken (chu2024); turn_rule: ``bool[C]`` cells with chu2024's forced
        right turn.
    """

    w_len: np.ndarray
    w_angle: float
    w_turn: float
    cell: np.ndarray
    goal_first: bool
    turn_rule: np.ndarray


def cost_weights(name: str, grid: GridMap, starts: ArrayLike, goals: ArrayLike, p: Mapping[str, Any],
                 what: str = "heuristic='objective'") -> CostWeights:
    """`CostWeights` of colony ``name``'s own cost (resolved parameters ``p``) for ``starts``/``goals int[N, 2]``:
    ``aco`` length; ``iaco`` λ1·L/L0 + λ2·Σ|θ|/π + λ3·Σ 1/clearance; ``risk_aco`` u·L + v·risk + w·turns;
    ``opt_ant`` a·L + b·turns (its c·H is no sum over moves: left out here); ``praco`` ω1·L + ω2·turns.

    Raises:
      ValueError: an unknown colony, or a cell whose cost is negative or not finite (``what`` starts the message).
    """
    s = np.asarray(starts, np.float64).reshape(-1, 2)
    g = np.asarray(goals, np.float64).reshape(-1, 2)
    N = len(s)
    res = float(grid.resolution)
    ok = passable(grid, p.get("vehicle_height"))
    cell = np.zeros(grid.n_cells)
    w_angle = w_turn = 0.0
    goal_first = False
    turn_rule = np.zeros(grid.n_cells, bool)
    if name == "aco":
        w_len = np.ones(N)
    elif name == "iaco":
        lam = np.asarray(p["lambdas"], np.float64)
        l0 = np.hypot(*(s - g).T) * res
        with np.errstate(divide="ignore"):  # L0 = 0 only for start = goal, which a search may be asked
            w_len = np.where(l0 > 0, lam[0] / l0, np.inf)
        w_angle = float(lam[1] / np.pi)
        clear = np.maximum(clearance_field(grid), 0.5 * res).astype(np.float32).astype(np.float64).ravel()
        cell = lam[2] / clear
    elif name == "risk_aco":
        w_len = np.full(N, float(p["u"]))
        w_turn = float(p["w"])
        cell = float(p["v"]) * np.asarray(grid.risk, np.float32).astype(np.float64).ravel()
    elif name == "opt_ant":
        w_len = np.full(N, float(p["a"]))
        w_turn = float(p["b"])
        goal_first = True
        turn_rule = np.asarray(grid.turn_rule).ravel() == 1
    elif name == "praco":
        w_len = np.full(N, float(p["omega1"]))
        w_turn = float(p["omega2"])
    else:
        raise ValueError(f"{what}: no objective for colony {name!r}")
    cell = np.where(ok.ravel(), cell, 0.0)
    if (cell < 0).any() or not np.isfinite(cell).all():
        bad = int(np.argmax((cell < 0) | ~np.isfinite(cell)))
        raise ValueError(f"{what}: planner {name!r} gives cell {(bad % grid.width, bad // grid.width)} the path cost "
                         f"{cell[bad]}; the cost must be finite and >= 0 on every cell (check the risk layer)")
    return CostWeights(np.asarray(w_len, np.float64), w_angle, w_turn, cell, goal_first, turn_rule)


def _turn_classes(offsets: np.ndarray, w_angle: float, w_turn: float) -> tuple[np.ndarray, np.ndarray]:
    """``(turn_cost f64[V], variant i32[(K + 1)·K])``: the distinct turn costs, value 0 first."""
    offs = offsets.astype(np.float64)
    K = len(offs)
    heading = np.arctan2(offs[:, 1], offs[:, 0])
    angle = np.abs((heading[None, :] - heading[:, None] + np.pi) % (2 * np.pi) - np.pi)
    cost = np.where(np.eye(K, dtype=bool), 0.0, w_angle * angle + w_turn)
    cost = np.concatenate([np.zeros((1, K)), cost])  # row 0: the start
    key = np.round(cost, 12)
    values, variant = np.unique(key, return_inverse=True)  # sorted: 0 first
    return values, variant.reshape(-1).astype(np.int32)


def objective_variants(name: str, connectivity: int) -> int:
    """How many logit tables the walk needs for colony ``name`` (its distinct turn costs, at most, for any weights)."""
    if name == "aco":
        return 1
    if name != "iaco":
        return 2
    from jaxplan.grid import offsets

    return len(_turn_classes(np.asarray(offsets(connectivity)), 1.0, 0.0)[0])


def objective_tables(name: str, grid: GridMap, starts: np.ndarray, goals: np.ndarray,
                     p: Mapping[str, Any]) -> ObjectiveTables:
    """`ObjectiveTables` of colony ``name`` (resolved parameters ``p``) for ``starts``/``goals`` ``int[N, 2]``
    (checked cells). The cost-to-go is computed once per distinct (goal, w_len) pair."""
    conn, vh = int(p["connectivity"]), p["vehicle_height"]
    s = np.asarray(starts, np.int64).reshape(-1, 2)
    g = np.asarray(goals, np.int64).reshape(-1, 2)
    w_len, w_angle, w_turn, cell, goal_first, turn_rule = cost_weights(name, grid, s, g, p)
    nb = neighbour_table(grid, conn, vh)
    keys = np.concatenate([g.astype(np.float64), w_len[:, None]], axis=1)
    uniq, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    h = state_cost_to_go(grid, uniq[:, :2].astype(np.int64), conn, vh, w_len=uniq[:, 2], w_angle=w_angle,
                         w_turn=w_turn, cell=cell, goal_first=goal_first, turn_rule=turn_rule)  # [U, C, K]
    K = nb.index.shape[1]
    step = np.hypot(*nb.offsets.astype(np.float64).T) * float(grid.resolution)
    target = nb.index  # [C, K]
    rest = h[:, target, np.arange(K)[None, :]]  # [U, C, K]: h[v, k] for the move's target v
    q = uniq[:, 2][:, None, None] * step[None, None, :] + cell[target][None] + rest
    q = np.where(nb.valid[None], q, np.inf).astype(np.float32)
    values, variant = _turn_classes(nb.offsets, w_angle, w_turn)
    N = len(g)
    return ObjectiveTables(move_cost=q[inv], turn_cost=np.broadcast_to(values.astype(np.float32), (N, len(values))),
                           variant=np.broadcast_to(variant, (N, variant.size)))
