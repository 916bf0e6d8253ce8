"""Objectives built from objectives: a colony's own-objective gap, and one objective over several maps.

`aco_own_objective` is `aco_objective` with its ``gap`` metric measured against the planner's OWN cost
instead of the path length: each run's best path is costed with the planner's cost at its DEFAULT weights
(IACO: λ1·L/L0 + λ2·Σ|θ|/π + λ3·Σ1/d, cui2025; the terms of `jaxplan.search.objective_terms`), divided by
that cost's exact minimum (`jaxplan.search.exact_objectives`) minus 1. The cost is fixed while the tuned
weights (α, β, λ, δ, …) only steer the ants: tuning λ cannot shrink the yardstick, which it would if the
objective used the tuned λ (a λ of zeros costs every path 0). The length gap is kept as the extra metric
``length_gap`` (reported, never weighted).

`concat_objectives` joins objectives of the same planner and search box on different maps into one: a
population is evaluated on every map in ONE compiled call, the runs of all maps side by side along the scenario
axis (``cost [P, N1 + N2 + …, R]``), so the fitness is the mean over all scenarios of all maps (maps weigh by their
scenario counts). Every map must use the same seeds.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import jax.numpy as jnp
import numpy as np

from jaxplan.scale import MemoryEstimate
from jaxplan.tune._objective import FAIL_GAP, Objective, Split, aco_objective, aco_runs, aco_setup

if TYPE_CHECKING:
    from jaxplan.grid import GridMap

__all__ = ["aco_own_objective", "concat_objectives", "path_costs", "check_disjoint"]


def path_costs(cells: jnp.ndarray, n: jnp.ndarray, width: int, resolution: float, w_len: jnp.ndarray,
               w_angle: float, w_turn: float, cell_cost: jnp.ndarray) -> jnp.ndarray:
    """A planner's additive cost of grid paths (`jaxplan.search.path_objectives`' terms, float32, jittable).

    Args:
      cells: ``int[..., L + 1]`` flat cell indices (``y·width + x``) of each path, valid up to point ``n``.
      n: ``int[...]`` moves of each path (``n + 1`` valid points).
      width, resolution: the map's width (cells) and cell size (m).
      w_len: weight per metre, broadcastable to ``n``'s shape (IACO's λ1/L0 depends on the scenario).
      w_angle: weight per radian of heading change; w_turn: weight per turn (a change of move).
      cell_cost: ``f32[C]`` cost of each cell on a path (start and goal included).

    Returns:
      ``f32[...]`` costs.
    """
    x, y = cells % width, cells // width
    dx = jnp.diff(x, axis=-1).astype(jnp.float32)
    dy = jnp.diff(y, axis=-1).astype(jnp.float32)
    L = dx.shape[-1]
    step_ok = jnp.arange(L) < n[..., None]
    length = jnp.sum(jnp.where(step_ok, jnp.sqrt(dx * dx + dy * dy), 0.0), axis=-1) * resolution
    th = jnp.arctan2(dy, dx)
    dth = jnp.abs(jnp.mod(th[..., 1:] - th[..., :-1] + math.pi, 2 * math.pi) - math.pi)
    change = (dx[..., 1:] != dx[..., :-1]) | (dy[..., 1:] != dy[..., :-1])
    turn_ok = (jnp.arange(1, L) < n[..., None]) & change
    angle = jnp.sum(jnp.where(turn_ok, dth, 0.0), axis=-1)
    turns = jnp.sum(turn_ok, axis=-1).astype(jnp.float32)
    pts_ok = jnp.arange(L + 1) < (n[..., None] + 1)
    cell = jnp.sum(jnp.where(pts_ok, cell_cost[jnp.clip(cells, 0, cell_cost.shape[0] - 1)], 0.0), axis=-1)
    return w_len * length + w_angle * angle + w_turn * turns + cell


def aco_own_objective(grid: GridMap, train: Split, test: Split, planner: str = "iaco", space: Mapping | None = None,
                      weights: Mapping[str, float] | None = None, overrides: Mapping[str, Any] | None = None,
                      name: str | None = None) -> Objective:
    """`aco_objective` with ``gap`` = the gap to the planner's own optimum at its default weights (module docstring).

    Arguments as `aco_objective`; ``planner`` must be one of `jaxplan.search.OBJECTIVE_PLANNERS` whose cost is
    additive on this map (else `jaxplan.search.NonAdditiveCost`).

    Raises:
      ValueError: as `aco_objective`; a scenario whose own optimum is not finite and positive.
    """
    from jaxplan.aco import goal_tables, seed_keys
    from jaxplan.search import exact_objectives, objective_terms

    base_obj = aco_objective(grid, train, test, planner, space, weights, overrides, name=name)
    setup = aco_setup(grid, planner, base_obj.bounds, overrides)
    W, res = setup.width, setup.resolution
    prepared = {}
    for split_name, sp in (("train", train), ("test", test)):
        s, g = np.asarray(sp.starts), np.asarray(sp.goals)
        gt = goal_tables(grid, s, g, setup.connectivity, setup.vh, geodesic=setup.cfg.heuristic == "geodesic")
        terms = objective_terms(grid, s, g, planner, **dict(overrides or {}))
        own = exact_objectives(grid, s, g, planner, **dict(overrides or {}))
        if not np.all(np.isfinite(own) & (own > 0)):
            bad = int(np.argmin(np.isfinite(own) & (own > 0)))
            raise ValueError(f"aco_own_objective: {split_name} scenario {bad} has no finite positive own optimum "
                             f"({own[bad]!r})")
        prepared[split_name] = (gt, seed_keys(sp.seeds), jnp.asarray(sp.optimal, jnp.float32),
                                jnp.asarray(own, jnp.float32), jnp.asarray(terms.w_len, jnp.float32),
                                float(terms.w_angle), float(terms.w_turn), jnp.asarray(terms.cell, jnp.float32))
    mw = dict(base_obj.weights)

    def program(split_name: str):
        gt, keys, optimal, own, w_len, w_angle, w_turn, cell_cost = prepared[split_name]

        def run(pop):
            out, shared = aco_runs(setup, gt, keys, pop)
            ok = out.success
            cost = path_costs(out.cells, out.n, W, res, w_len[None, :, None], w_angle, w_turn, cell_cost)
            metrics = {"gap": jnp.where(ok, cost / own[None, :, None] - 1.0, FAIL_GAP), **shared}
            total = sum(w * metrics[k] for k, w in mw.items())
            metrics["length_gap"] = jnp.where(ok, out.length / optimal[None, :, None] - 1.0, FAIL_GAP)
            return total, metrics

        return run

    return dataclasses.replace(base_obj, program=program, name=name or f"{planner}_own_weights", _compiled={})


def concat_objectives(objectives: Sequence[Objective], name: str | None = None) -> Objective:
    """One objective over the maps of ``objectives`` (module docstring); a single objective is returned as is.

    Raises:
      ValueError: objectives of different kinds, planners, search boxes, defaults, metric weights or seeds.
    """
    objs = list(objectives)
    if not objs:
        raise ValueError("concat_objectives: no objectives")
    if len(objs) == 1:
        return objs[0] if name is None else dataclasses.replace(objs[0], name=name, _compiled={})
    a = objs[0]
    for o in objs[1:]:
        same = (o.kind == a.kind and o.planner == a.planner and o.bounds.names == a.bounds.names
                and np.array_equal(o.bounds.low, a.bounds.low) and np.array_equal(o.bounds.high, a.bounds.high)
                and np.array_equal(o.defaults, a.defaults) and dict(o.weights) == dict(a.weights))
        if not same:
            raise ValueError(f"concat_objectives: {o.name!r} differs from {a.name!r} in kind, planner, search box, "
                             "defaults or metric weights")
        for s in ("train", "test"):
            if tuple(o.splits[s].seeds) != tuple(a.splits[s].seeds):
                raise ValueError(f"concat_objectives: the {s} seeds of {o.name!r} and {a.name!r} differ")

    def program(split_name: str):
        runs = [o.program(split_name) for o in objs]

        def run(pop):
            outs = [r(pop) for r in runs]
            cost = jnp.concatenate([c for c, _ in outs], axis=1)
            keys = set.intersection(*(set(m) for _, m in outs))
            metrics = {k: jnp.concatenate([m[k] for _, m in outs], axis=1) for k in sorted(keys)}
            return cost, metrics

        return run

    def join(s: str) -> Split:
        sp = [o.splits[s] for o in objs]
        return Split(np.concatenate([x.starts for x in sp]), np.concatenate([x.goals for x in sp]),
                     np.concatenate([x.optimal for x in sp]), tuple(sp[0].seeds))

    def memory(population: int, split: str) -> MemoryEstimate:
        ests = [o.memory(population, split) for o in objs if o.memory is not None]
        total = sum(e.total for e in ests)
        parts: dict = {}
        for o, e in zip(objs, ests, strict=False):
            parts.update({f"{o.name}: {k}": v for k, v in e.parts.items()})
        return MemoryEstimate(total, parts, population, sum(e.per_run for e in ests))

    return dataclasses.replace(a, name=name or "+".join(o.name for o in objs),
                               splits={"train": join("train"), "test": join("test")}, program=program,
                               memory=memory if all(o.memory is not None for o in objs) else None, _compiled={})


def check_disjoint(train: Split, test: Split, where: str = "") -> None:
    """Refuses a held-out split that is not held out: shared seeds, or a (start, goal) row in both splits.

    Raises:
      ValueError: naming the shared seeds or the first shared row.
    """
    at = f" ({where})" if where else ""
    shared = sorted(set(train.seeds) & set(test.seeds))
    if shared:
        raise ValueError(f"train and held-out splits share seeds{at}: {shared}")
    tr = {(tuple(map(int, s)), tuple(map(int, g))) for s, g in zip(train.starts, train.goals, strict=True)}
    for i, (s, g) in enumerate(zip(test.starts, test.goals, strict=True)):
        row = (tuple(map(int, s)), tuple(map(int, g)))
        if row in tr:
            raise ValueError(f"train and held-out splits share a scenario row{at}: held-out row {i}, start {row[0]}, "
                             f"goal {row[1]}")
