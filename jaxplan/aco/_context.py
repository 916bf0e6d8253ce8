"""What a colony needs to know about a map, as device arrays (built once per map and goal).

`MapTables` is per map (moves, layers); `GoalTables` per scenario (start, goal,
goal distance). Both are pytrees, so a batch of scenarios is just a stacked
`GoalTables` with the same `MapTables`.
"""

from __future__ import annotations

from typing import Any, Mapping, NamedTuple

import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.aco._objective import objective_tables
from jaxplan.grid import GridMap, check_pair, check_pairs, clearance_field, distance_from, neighbour_table, passable

__all__ = ["MapTables", "GoalTables", "map_tables", "goal_tables"]


class MapTables(NamedTuple):
    """Per-map arrays. ``C = H * W`` cells, ``K`` moves.

    Attributes:
      index: ``i32[C, K]`` target cell of each move (the cell itself where not allowed).
      valid: ``bool[C, K]`` allowed moves (passable, no corner cutting, vehicle height).
      step: ``f32[K]`` move lengths (m).
      offsets: ``i32[K, 2]`` the moves (dx, dy).
      angle: ``f32[K]`` move headings (rad).
      right_turn: ``i32[K]`` the move a quarter turn to the right of each move.
      xy: ``f32[C, 2]`` cell centres (m).
      clearance: ``f32[C]`` distance to the nearest obstacle boundary (m), floored at res/2.
      risk: ``f32[C]`` unknown-factor intensity.
      height: ``f32[C]`` terrain height (m).
      turn_rule: ``bool[C]`` right-turn cells.
      n_blocked: ``f32[C]`` blocked (or outside) cells among the 8 neighbours.
      boundary: ``bool[C]`` cells on the map's edge.
      resolution: metres per cell (f32 scalar).
      turn_angle: ``f32[K, K]`` |heading change| from move i to move j (rad, in [0, π]).
    """

    index: jnp.ndarray  # type: ignore[assignment]  # a field named as tuple.index
    valid: jnp.ndarray
    step: jnp.ndarray
    offsets: jnp.ndarray
    angle: jnp.ndarray
    right_turn: jnp.ndarray
    xy: jnp.ndarray
    clearance: jnp.ndarray
    risk: jnp.ndarray
    height: jnp.ndarray
    turn_rule: jnp.ndarray
    n_blocked: jnp.ndarray
    boundary: jnp.ndarray
    resolution: jnp.ndarray
    turn_angle: jnp.ndarray


class GoalTables(NamedTuple):
    """Per-scenario arrays: ``start``, ``goal`` (flat cell indices, i32) and
    ``goal_dist`` (``f32[C]`` exact distance to the goal in metres, inf where unreachable;
    zeros when the heuristic does not need it); for ``heuristic="objective"`` only (else None),
    ``move_cost`` ``f32[C, K]``, ``turn_cost`` ``f32[V]`` and ``variant`` ``i32[(K + 1)·K]``
    (`jaxplan.aco._objective.ObjectiveTables`)."""

    start: jnp.ndarray
    goal: jnp.ndarray
    goal_dist: jnp.ndarray
    move_cost: jnp.ndarray | None = None
    turn_cost: jnp.ndarray | None = None
    variant: jnp.ndarray | None = None


def map_tables(grid: GridMap, connectivity: int = 8, vehicle_height: float | None = None) -> MapTables:
    """Builds the per-map tables on the host and moves them to the device."""
    moves = neighbour_table(grid, connectivity, vehicle_height)
    ok = passable(grid, vehicle_height)
    H, W = ok.shape
    res = float(grid.resolution)
    offs = moves.offsets
    K = len(offs)
    angle = np.arctan2(offs[:, 1], offs[:, 0])
    # offsets are sorted by angle, so a quarter turn to the right (clockwise on screen,
    # y down) is K/4 indices further on.
    right = (np.arange(K) + K // 4) % K
    ys, xs = np.mgrid[0:H, 0:W]
    xy = (np.stack([xs.ravel(), ys.ravel()], axis=1) + 0.5) * res
    pad = np.pad(ok, 1, constant_values=False)
    n_blocked = sum(
        (~pad[1 + dy : 1 + dy + H, 1 + dx : 1 + dx + W]).astype(np.float32)
        for dy in (-1, 0, 1)
        for dx in (-1, 0, 1)
        if (dx, dy) != (0, 0)
    )
    boundary = np.zeros((H, W), bool)
    boundary[0, :] = boundary[-1, :] = boundary[:, 0] = boundary[:, -1] = True
    clear = np.maximum(clearance_field(grid), 0.5 * res)
    return MapTables(
        index=jnp.asarray(moves.index),
        valid=jnp.asarray(moves.valid),
        step=jnp.asarray(moves.step, jnp.float32),
        offsets=jnp.asarray(offs, jnp.int32),
        angle=jnp.asarray(angle, jnp.float32),
        right_turn=jnp.asarray(right, jnp.int32),
        xy=jnp.asarray(xy, jnp.float32),
        clearance=jnp.asarray(clear.ravel(), jnp.float32),
        risk=jnp.asarray(np.asarray(grid.risk).ravel(), jnp.float32),
        height=jnp.asarray(np.asarray(grid.height).ravel(), jnp.float32),
        turn_rule=jnp.asarray(np.asarray(grid.turn_rule).ravel() == 1),
        n_blocked=jnp.asarray(np.ravel(n_blocked), jnp.float32),
        boundary=jnp.asarray(boundary.ravel()),
        resolution=jnp.asarray(res, jnp.float32),
        turn_angle=_turn_angle(jnp.asarray(angle, jnp.float32)),
    )


def _turn_angle(angle: jnp.ndarray) -> jnp.ndarray:
    """``f32[K, K]``: |heading change| |(θ_j − θ_i + π) mod 2π − π| between moves i and j.

    Path statistics look it up instead of computing it per path step: over ``[A, L]`` steps
    the float remainder is the costliest operation of an iteration's update on a CPU, and XLA
    fuses a table computed inside the program back into the lookup (recomputing it per step).
    """
    return jnp.abs((angle[None, :] - angle[:, None] + jnp.pi) % (2 * jnp.pi) - jnp.pi)


def goal_tables(
    grid: GridMap,
    starts: ArrayLike,
    goals: ArrayLike,
    connectivity: int = 8,
    vehicle_height: float | None = None,
    geodesic: bool = False,
    objective: tuple[str, Mapping[str, Any]] | None = None,
) -> GoalTables:
    """Per-scenario tables for ``starts``/``goals`` ``int[N, 2]``, stacked on a leading axis.

    ``objective``: ``(colony name, its resolved parameters)`` adds the tables of ``heuristic="objective"``
    (`jaxplan.aco._objective.objective_tables`: the colony's exact cost-to-go, ``[N, C, K]`` floats).

    Raises:
      ValueError: a start or goal outside the map or blocked, or a start equal to its goal.
    """
    s, g = check_pairs(grid, starts, goals, passable(grid, vehicle_height))
    W = grid.width
    if geodesic:
        fields = {}
        for cell in map(tuple, g.tolist()):
            if cell not in fields:
                fields[cell] = distance_from(grid, cell, connectivity, vehicle_height).ravel()
        gd = np.stack([fields[tuple(c)] for c in g.tolist()]).astype(np.float32)
    else:
        gd = np.zeros((len(g), grid.n_cells), np.float32)
    extra = {}
    if objective is not None:
        ot = objective_tables(objective[0], grid, s, g, objective[1])
        extra = dict(move_cost=jnp.asarray(ot.move_cost), turn_cost=jnp.asarray(ot.turn_cost),
                     variant=jnp.asarray(ot.variant, jnp.int32))
    return GoalTables(
        start=jnp.asarray(s[:, 1] * W + s[:, 0], jnp.int32),
        goal=jnp.asarray(g[:, 1] * W + g[:, 0], jnp.int32),
        goal_dist=jnp.asarray(gd),
        **extra,
    )


def check_one(grid: GridMap, start: ArrayLike, goal: ArrayLike, vehicle_height: float | None) -> None:
    """Validates a single start/goal pair with the single-cell messages."""
    check_pair(grid, start, goal, passable(grid, vehicle_height))
