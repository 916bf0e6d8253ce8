"""Each colony's own optimum: the exact minimum of a planner's path cost, and that cost of any grid path.

The ACO planners minimise their papers' objectives, not the length, so their gap to the shortest path
says little about how well a colony searches. Each of these costs is a sum over moves, turns and
path cells (docs/guide/planners.md, `jaxplan.aco`'s ``cost_*`` rules on `PathStats`):

=============  ==========================================  ==========  ===============  ==========  ===============
planner        cost                                        per metre   per rad of turn  per turn    per path cell
=============  ==========================================  ==========  ===============  ==========  ===============
``aco``        L                                           1           0                0           0
``iaco``       λ1·L/L0 + λ2·Σ|θ|/π + λ3·Σ1/d (cui2025)     λ1/L0       λ2/π             0           λ3/d(c)
``risk_aco``   u·P + v·H + w·T (chen2023)                  u           0                w           v·risk(c)
``opt_ant``    a·L + b·R + c·H_msd (chu2024)               a           0                b           (refused if c·H)
``praco``      ω1·L + ω2·N (yu2020)                        ω1          0                ω2          0
``astar``,     L                                           1           0                0           0
``dijkstra``
=============  ==========================================  ==========  ===============  ==========  ===============

with the colonies' definitions: L in metres (steps 1, √2, √5 × resolution); a turn is a path vertex
where the move changes, θ its |heading change| in [0, π]; L0 the straight-line start–goal distance
(m); d(c) the clearance of cell c (m to the nearest blocked cell's boundary, floored at res/2, as
`jaxplan.aco.map_tables`); risk(c) the map's risk layer; path cells include the start and the goal.
Its exact minimum is therefore a shortest path over (cell, incoming move) states
(`jaxplan.search._objective_kernels`), with the planner's connectivity (4, 8, 16; no corner cutting;
16-direction moves need the crossed cells free), vehicle height and move rules (``opt_ant``: an
adjacent goal is always taken, the right-hand rule on ``turn_rule`` cells).

Not a sum over moves and turns, so refused with a ``ValueError``:
  * ``opt_ant``'s H_msd, the mean square deviation of the path cells' heights (a variance: it
    depends on the whole path at once). On flat terrain (one height on every passable cell) or with
    ``c=0`` it is 0 and the optimum is exact; with ``c=0`` on a height map it is a lower bound of the
    full cost (H_msd >= 0).
  * ``astar_kng``, ``rrt_star``, ``mrbs_rrt``: their paths are polylines (key nodes, continuous
    samples), not sums over grid moves.

Two limits, both documented where they apply:
  * the search minimises over walks; with every term >= 0 and without right-turn cells a loop never
    lowers a cost (it adds length and cells, and cannot lower the turns or heading change it
    replaces), so this is the minimum over the simple paths the colony's tabu list allows.
  * on ``turn_rule`` cells the rule is applied as chu2024 states it (forced whenever the map allows
    the right move); the walk lets an ant off when that cell is already on its path or a marked dead
    end, so on maps with right-turn cells an ``opt_ant`` path can, rarely, cost less.
"""

from __future__ import annotations

import time
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.grid import (
    H_EUCLID,
    H_MANHATTAN,
    H_OCTILE,
    GridMap,
    check_pair,
    check_pairs,
    neighbour_table,
    passable,
    state_cost_to_go,
)
from jaxplan.registry import resolve
from jaxplan.result import PlanResult
from jaxplan.search import _objective_kernels as OK

__all__ = ["NonAdditiveCost", "OBJECTIVE_PLANNERS", "ObjectiveTerms", "objective_terms", "exact_objective",
           "exact_objectives", "objective_cost_to_go", "path_objective", "path_objectives"]

OBJECTIVE_PLANNERS = ("aco", "iaco", "risk_aco", "opt_ant", "praco", "astar", "dijkstra")
"""Planners whose cost `exact_objective` minimises exactly (a sum over moves, turns and path cells)."""

_REFUSED = {
    "astar_kng": "its path is a polyline of key nodes (li2026), not a sum over grid moves; its grid optimum is "
                 "astar's",
    "rrt_star": "it plans in continuous space (a polyline of samples), not over grid moves and turns",
    "mrbs_rrt": "it plans in continuous space (a polyline of samples), not over grid moves and turns",
}
_HEURISTIC = {4: H_MANHATTAN, 8: H_OCTILE, 16: H_EUCLID}


class NonAdditiveCost(ValueError):
    """A planner's cost (on this map) is not a sum over moves, turns and cells, so it has no exact optimum here."""


class ObjectiveTerms(NamedTuple):
    """A planner's cost as weights of its terms, on one map (see the module's table).

    Attributes:
      planner: the planner's registry name.
      connectivity, vehicle_height: its move rules.
      w_len: ``f64[N]`` weight per metre for each of N scenarios (``iaco``'s λ1/L0 depends on the scenario).
      w_angle: weight per radian of heading change; w_turn: weight per turn.
      cell: ``f64[C]`` cost of each cell on a path (start and goal included).
      goal_first: an adjacent goal must be taken; turn_rule: ``bool[C]`` cells with a forced right turn.
    """

    planner: str
    connectivity: int
    vehicle_height: float | None
    w_len: np.ndarray
    w_angle: float
    w_turn: float
    cell: np.ndarray
    goal_first: bool
    turn_rule: np.ndarray


def _check_planner(planner: str) -> None:
    # The colonies register themselves on import; imported here, not at module level, so that importing
    # jaxplan.search (which the config parser does) stays as light as it was.
    import jaxplan.aco  # noqa: F401
    if planner in _REFUSED:
        raise NonAdditiveCost(f"exact_objective: planner {planner!r} has no cost that is a sum over moves and turns: "
                         f"{_REFUSED[planner]}")
    if planner not in OBJECTIVE_PLANNERS:
        raise ValueError(f"exact_objective: no exact objective for planner {planner!r}; it handles "
                         f"{', '.join(OBJECTIVE_PLANNERS)}")


def objective_terms(grid: GridMap, starts: ArrayLike, goals: ArrayLike, planner: str,
                    **weights: Any) -> ObjectiveTerms:
    """The weights of ``planner``'s cost (its defaults with ``weights`` applied, checked by the registry).

    Args:
      grid: the map; starts, goals: ``int[N, 2]`` cells (only ``iaco``'s L0 reads them).
      planner: one of `OBJECTIVE_PLANNERS`.
      **weights: any of the planner's parameters (those that do not enter the cost, such as ``ants``, are
        accepted and ignored, so a run's overrides can be passed as they are).

    Raises:
      NonAdditiveCost: (a ``ValueError``) a planner whose cost is no sum over moves and turns (the message
        says why), or ``opt_ant`` with ``c > 0`` on a map whose passable cells differ in height.
      ValueError: a planner jaxplan does not know, an unknown or bad parameter.
    """
    from jaxplan.aco import cost_weights  # imported here, as in _check_planner

    _check_planner(planner)
    _, p = resolve(planner, weights)
    conn, vh = int(p["connectivity"]), p.get("vehicle_height")
    if planner == "opt_ant":
        h = np.asarray(grid.height, np.float32)[passable(grid, vh)]
        if float(p["c"]) > 0 and h.size and not np.all(h == h[0]):
            raise NonAdditiveCost(
                "exact_objective: opt_ant's cost a·L + b·R + c·H has H = the mean square deviation of the path "
                "cells' heights, which is not a sum over moves and turns (it depends on the whole path); this map's "
                "passable cells differ in height, so its exact minimum is not computed. Pass c=0 for the exact "
                "minimum of a·L + b·R, a lower bound of the full cost (H >= 0)")
    # A* and Dijkstra minimise length: the Ant System's cost.
    w = cost_weights("aco" if planner in ("astar", "dijkstra") else planner, grid, starts, goals, p,
                     what="exact_objective")
    return ObjectiveTerms(planner, conn, vh, w.w_len, w.w_angle, w.w_turn, w.cell, w.goal_first, w.turn_rule)


class _Moves(NamedTuple):
    index: np.ndarray  # type: ignore[assignment]  # a field named as tuple.index
    valid: np.ndarray
    step: np.ndarray  # f64[K] metres
    angle: np.ndarray  # f64[K, K] |heading change|
    right: np.ndarray  # i64[K]
    offsets: np.ndarray


def _moves(grid: GridMap, connectivity: int, vehicle_height: float | None) -> _Moves:
    nb = neighbour_table(grid, connectivity, vehicle_height)
    offs = nb.offsets.astype(np.float64)
    K = len(offs)
    heading = np.arctan2(offs[:, 1], offs[:, 0])
    angle = np.abs((heading[None, :] - heading[:, None] + np.pi) % (2 * np.pi) - np.pi)
    return _Moves(nb.index, nb.valid, np.hypot(offs[:, 0], offs[:, 1]) * float(grid.resolution), angle,
                  (np.arange(K) + K // 4) % K, nb.offsets)


def _pairs(grid: GridMap, starts: ArrayLike, goals: ArrayLike,
           vehicle_height: float | None) -> tuple[np.ndarray, np.ndarray]:
    s, g = check_pairs(grid, starts, goals, passable(grid, vehicle_height))
    W = grid.width
    return s[:, 1] * W + s[:, 0], g[:, 1] * W + g[:, 0]


def exact_objective(grid: GridMap, start: ArrayLike, goal: ArrayLike, planner: str = "aco",
                    **weights: Any) -> PlanResult:
    """The exact minimum of ``planner``'s own path cost between ``start`` and ``goal``, and a path attaining it.

    A* over (cell, incoming move) states with the planner's neighbourhood, corner-cutting and turn
    rules (module docstring). A colony's best cost can never be below it (up to the colony's float32
    sums, ~1e-6 relative), so ``colony cost / optimum − 1`` is how far the colony is from its own
    objective's optimum (``objective_gap``).

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells (passable, different).
      planner: one of `OBJECTIVE_PLANNERS`.
      **weights: the planner's parameters (e.g. ``lambdas=(0.5, 0.3, 0.2)``, ``connectivity=16``); others
        of its parameters are accepted and ignored.

    Returns:
      `PlanResult` with ``cost`` the optimum (float64), ``path`` a cell path attaining it, its ``length`` (m)
      and ``turns``; ``planner`` is ``"exact_objective[<planner>]"``; ``info``: ``expanded`` states,
      ``objective`` the planner. ``success=False`` (cost inf) when the goal cannot be reached.

    Raises:
      ValueError: see `objective_terms`; a bad start or goal.

    Example:
      >>> import numpy as np, jaxplan as jp
      >>> grid = jp.grid_from_array(np.ones((5, 5), bool))
      >>> r = jp.search.exact_objective(grid, (0, 0), (4, 2), planner="praco", omega2=10.0)
      >>> r.turns, round(r.cost, 4)  # a shortest path with one turn
      (1, 14.8284)
    """
    t0 = time.perf_counter()
    _check_planner(planner)
    s, g = check_pair(grid, start, goal, passable(grid, resolve(planner, weights)[1].get("vehicle_height")))
    terms = objective_terms(grid, np.asarray([s]), np.asarray([g]), planner, **weights)
    mv = _moves(grid, terms.connectivity, terms.vehicle_height)
    W = grid.width
    w_len = float(terms.w_len[0])
    cost, cells, expanded = OK.one_search(
        mv.index, mv.valid, mv.step, mv.angle, mv.right.astype(np.int64), terms.cell, terms.turn_rule, w_len,
        terms.w_angle, terms.w_turn, terms.goal_first, W, _HEURISTIC[terms.connectivity],
        w_len * float(grid.resolution), s[1] * W + s[0], g[1] * W + g[0])
    name = f"exact_objective[{planner}]"
    dt = time.perf_counter() - t0
    if not np.isfinite(cost):
        return PlanResult.failure(name, dt, expanded=int(expanded), objective=planner)
    path = np.stack([cells % W, cells // W], axis=1).astype(np.int64)
    moves = _move_indices(path[None], np.array([len(path)]), mv.offsets)[0]
    return PlanResult.found(name, path, float(mv.step[moves].sum()), int((moves[1:] != moves[:-1]).sum()), dt,
                            cost=float(cost), expanded=int(expanded), objective=planner)


def exact_objectives(grid: GridMap, starts: ArrayLike, goals: ArrayLike, planner: str = "aco",
                     **weights: Any) -> np.ndarray:
    """`exact_objective`'s optimum for many scenarios at once: ``f64[N]`` (inf where unreachable).

    Searches run in compiled code on `numba.get_num_threads` threads (each holds ``C·(K + 1)``
    states: about 40 MB for a 512×512 map at 8-connectivity).
    """
    s = np.asarray(starts)
    g = np.asarray(goals)
    terms = objective_terms(grid, s, g, planner, **weights)
    if len(np.atleast_2d(s)) == 0:
        return np.zeros(0)
    src, dst = _pairs(grid, s, g, terms.vehicle_height)
    mv = _moves(grid, terms.connectivity, terms.vehicle_height)
    return OK.many_searches(
        mv.index, mv.valid, mv.step, mv.angle, mv.right.astype(np.int64), terms.cell, terms.turn_rule, terms.w_len,
        terms.w_angle, terms.w_turn, terms.goal_first, grid.width, _HEURISTIC[terms.connectivity],
        terms.w_len * float(grid.resolution), src.astype(np.int64), dst.astype(np.int64))


def objective_cost_to_go(grid: GridMap, starts: ArrayLike, goals: ArrayLike, planner: str = "aco",
                         **weights: Any) -> np.ndarray:
    """``planner``'s exact cost-to-go ``f64[N, C, K]`` from every (cell, incoming move) state to each scenario's goal.

    ``h[i, v, k]``: the least cost of the rest of a path to ``goals[i]`` for an ant on cell v that entered it
    by move k (slot k of `jaxplan.neighbour_table` at the planner's connectivity): its later moves, turns and
    cells under ``planner``'s cost and move rules, as `exact_objective` minimises them
    (`jaxplan.grid.state_cost_to_go`); 0 on the goal, inf where it cannot be reached. So
    ``exact_objective(start, goal).cost`` is ``cell[start] + min_k (w_len·step[k] + cell[v_k] + h[v_k, k])``
    over the moves allowed from the start.
    The starts matter only for ``iaco`` (its L0). It is the table behind the colonies' ``heuristic="objective"``.

    Args and raises: as `exact_objectives`.
    """
    s = np.asarray(starts)
    g = np.asarray(goals)
    terms = objective_terms(grid, s, g, planner, **weights)
    if len(np.atleast_2d(s)) == 0:
        return np.zeros((0, grid.n_cells, terms.connectivity), np.float64)
    _pairs(grid, s, g, terms.vehicle_height)  # the same checks as the forward search
    return state_cost_to_go(grid, np.atleast_2d(g), terms.connectivity, terms.vehicle_height, w_len=terms.w_len,
                            w_angle=terms.w_angle, w_turn=terms.w_turn, cell=terms.cell,
                            goal_first=terms.goal_first, turn_rule=terms.turn_rule)


def _move_indices(paths: np.ndarray, n: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``i64[B, P − 1]`` move index of each step (−1 past ``n``); ``ValueError`` for a step that is no move."""
    B, P = paths.shape[:2]
    lut = np.full(25, -1, np.int64)
    lut[(offsets[:, 1] + 2) * 5 + offsets[:, 0] + 2] = np.arange(len(offsets))
    d = np.diff(paths.astype(np.int64), axis=1)
    inside = (np.abs(d) <= 2).all(axis=-1)
    k = np.where(inside, lut[np.clip((d[..., 1] + 2) * 5 + d[..., 0] + 2, 0, 24)], -1)
    steps = np.arange(P - 1)[None, :] < (n[:, None] - 1)
    bad = steps & (k < 0)
    if bad.any():
        b, i = map(int, np.argwhere(bad)[0])
        raise ValueError(f"path {b} step {i}, {paths[b, i].tolist()} -> {paths[b, i + 1].tolist()}, is not a "
                         f"{len(offsets)}-connected move")
    return np.where(steps, k, -1)


def path_objectives(paths: ArrayLike, n: ArrayLike, grid: GridMap, planner: str = "aco",
                    **weights: Any) -> np.ndarray:
    """``planner``'s cost of each grid path, in float64 with the terms `exact_objective` minimises.

    Args:
      paths: ``int[B, P, 2]`` cell paths ``(x, y)``, each from its start (first point) to its goal (point
        ``n − 1``); n: ``int[B]`` valid points (paths with fewer than 2 get nan).
      grid, planner, **weights: as `exact_objective`.

    Returns:
      ``f64[B]`` costs. A colony's own float32 cost of the same path agrees to ~1e-6 relative.

    Raises:
      ValueError: a step that is not a move of the planner's connectivity or not allowed on the map
        (blocked cell, cut corner, too low for the vehicle), or as `objective_terms`.
    """
    p = np.asarray(paths)
    if p.ndim != 3 or p.shape[-1] != 2 or not np.issubdtype(p.dtype, np.integer):
        raise ValueError(f"paths must be integer cells [B, P, 2], got {p.dtype} {p.shape}")
    counts = np.asarray(n, np.int64).reshape(-1)
    if counts.shape != (p.shape[0],) or (counts < 0).any() or (counts > p.shape[1]).any():
        raise ValueError(f"n must hold {p.shape[0]} counts in [0, {p.shape[1]}], got {counts.tolist()}")
    B, P = p.shape[:2]
    has = counts >= 2
    last = np.maximum(counts - 1, 0)
    ends_s = np.where(has[:, None], p[:, 0], 0)
    ends_g = np.where(has[:, None], p[np.arange(B), last], 0)
    terms = objective_terms(grid, ends_s, ends_g, planner, **weights)
    mv = _moves(grid, terms.connectivity, terms.vehicle_height)
    W = grid.width
    k = _move_indices(p, counts, mv.offsets)
    pts = np.arange(P)[None, :] < counts[:, None]
    flat = np.where(pts, p[..., 1] * W + p[..., 0], 0)
    H_, W_ = grid.shape
    inside = (p[..., 0] >= 0) & (p[..., 0] < W_) & (p[..., 1] >= 0) & (p[..., 1] < H_)
    if (pts & ~inside).any():
        b, i = map(int, np.argwhere(pts & ~inside)[0])
        raise ValueError(f"path {b} point {i}, {p[b, i].tolist()}, lies outside the {W_}x{H_} map")
    step = k >= 0
    allowed = mv.valid[flat[:, :-1], np.maximum(k, 0)]
    if (step & ~allowed).any():
        b, i = map(int, np.argwhere(step & ~allowed)[0])
        raise ValueError(f"path {b} step {i}, {p[b, i].tolist()} -> {p[b, i + 1].tolist()}, is not allowed on the map "
                         f"(blocked cell, cut corner or too low for the vehicle)")
    length = np.where(step, mv.step[np.maximum(k, 0)], 0.0).sum(axis=1)
    pair = step[:, 1:] & step[:, :-1]
    changed = pair & (k[:, 1:] != k[:, :-1])
    turns = changed.sum(axis=1)
    heading = np.where(changed, mv.angle[np.maximum(k[:, :-1], 0), np.maximum(k[:, 1:], 0)], 0.0).sum(axis=1)
    cells = np.where(pts, terms.cell[flat], 0.0).sum(axis=1)
    with np.errstate(invalid="ignore"):
        cost = terms.w_len * length + terms.w_angle * heading + terms.w_turn * turns + cells
    return np.where(has, cost, np.nan)


def path_objective(path: ArrayLike, grid: GridMap, planner: str = "aco", **weights: Any) -> float:
    """``planner``'s cost of one grid path ``int[L, 2]`` from its start to its goal (see `path_objectives`)."""
    p = np.asarray(path)
    if p.ndim != 2:
        raise ValueError(f"path must be cells [L, 2], got shape {p.shape}")
    return float(path_objectives(p[None], [len(p)], grid, planner, **weights)[0])
