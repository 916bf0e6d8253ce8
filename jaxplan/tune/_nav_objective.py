"""The local planner's weights tuned on full two-level navigation episodes among walkers, over several maps.

`nav_objective` scores a population ``pop f32[P, D]`` of DWA critic weights (or MPPI critic
weights, temperature and noise) on the episodes `jaxplan.navigate_batch` runs — the
pipeline's global path, its waypoints, then the compiled local-planner episode among
``n_walkers`` random walkers (`jaxplan.random_obstacles`, ``behavior="blind"`` or
``"social"`` for walkers that see) — as `benchmarks/bench_nav.py` sets them up: MovingAI maps
at 1.0 m per cell, scenario rows of optimal length ≤ 80 cells, walkers starting at least
`AVOID_RADIUS` from the robot's start and goal, seed ``10_000·seed + row index``.

Layout (the design, written down):

* **Global plans once.** The global path does not depend on the local planner's weights:
  `jaxplan.nav.prepare_episodes` plans every (map, row, seed) once on the host, at
  construction, and the objective keeps the `EpisodeInputs`.
* **A population is one batch per map.** A map's episodes — walker kinds × rows × seeds — are
  one batch of ``B`` episodes; the population is folded into the episode axis (``P·B``
  episodes, each with its own weights: ``per_episode=True``), so a population is one batch per
  map and split, with no Python loop over members, rows, seeds or walker kinds. Not ``vmap`` over
  the population: the episode's re-planning branch is a `lax.cond` taken only on steps where some
  robot needs it, and under ``vmap`` a batched predicate turns it into a select that computes the
  re-planning fields at every step. Maps run one after the other (their shapes differ); costs are
  concatenated along the scenario axis.
* **Same episodes as navigate.** Every episode is a re-planning group of its own
  (`NavConfig.replan_group` = 1, whatever the config says): it re-plans as `jaxplan.navigate` re-plans
  one scenario, never waiting for a slot another episode of the batch holds, so members never share
  anything — a member's episodes are the episodes `navigate_batch` runs with its weights and
  ``replan_group=1`` (step for step with DWA; with MPPI, weights given per episode rather than as
  broadcast scalars round differently in the last bits, which its softmax carries on, so an episode's
  time may differ slightly: docs/decisions.md).
* **Finished episodes are dropped.** `evaluate` steps each batch with `jaxplan.nav.run_outcomes`, which
  gathers the unfinished episodes into a batch half the size whenever they fit: among walkers most
  episodes end well before the one deadlock that would otherwise keep all ``P·B`` stepping to the time
  limit. Its outcomes equal `run_episodes`' (tested), so `map_program` — the same scores as one pure
  compiled program — agrees with `evaluate`.
* **Splits.** `Split` carries ``map_index`` (into `NavObjective.maps`) and ``rows`` (the
  scenario file's row numbers); train and held-out splits must be disjoint in (map, row) and in
  seeds (checked at construction: ``ValueError``).

Cost per episode (`NAV_METRICS`, weights default ``{"failure": 1, "time": 1}``: success first,
time to goal second): ``failure`` = not (at the goal without contact before the time limit);
``time`` = time to the goal / the episode's time limit (1 when not reached); ``collision`` = a
contact; ``active_contacts``, ``passive_contacts`` = counts (docs/guide/navigation.md). Metrics also report
``success``, ``time_s`` (seconds driven) and ``success_<kind>`` per walker kind. A scenario whose
robot does not run (infeasible for the footprint, or no global path) counts as a failure of time 1
for every member. Cost axis 1 is (map, row, walker kind), row-major: ``[P, Σ rows·kinds, R]``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import TYPE_CHECKING, Any, Callable, Mapping, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.scale import MemoryEstimate, episode_memory
from jaxplan.tune._bounds import Bounds, make_bounds
from jaxplan.tune._objective import (
    DWA_TUNABLE,
    Evaluation,
    Objective,
    Split,
    _check_names,
    _check_sign,
    _metric_weights,
    _scatter,
    _slots,
)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from jaxplan.nav import NavConfig

__all__ = ["NavMap", "NavObjective", "nav_map", "nav_objective", "spread_rows", "NAV_METRICS", "WALKER_KINDS",
           "AVOID_RADIUS"]

NAV_METRICS = ("time", "failure", "collision", "active_contacts", "passive_contacts")
WALKER_KINDS = {"blind": "blind", "seeing": "social"}
"""Walker kinds of the objective -> `random_obstacles` behaviour."""
AVOID_RADIUS = 3.0
"""m: no walker starts this close to the robot's start or goal (as `benchmarks/bench_nav.py`)."""


class NavMap(NamedTuple):
    """A map with its scenario file's rows and the rows each split uses.

    Attributes:
      name: label (unique within an objective).
      grid: the map (`GridMap`, 1.0 m per cell for the MovingAI maps).
      starts, goals: ``int[S, 2]`` the scenario file's cells; optimal: ``f[S]`` its optimal lengths (cells).
      train_rows, test_rows: row numbers into ``starts`` (disjoint).
    """

    name: str
    grid: Any
    starts: np.ndarray
    goals: np.ndarray
    optimal: np.ndarray
    train_rows: tuple[int, ...]
    test_rows: tuple[int, ...]


def spread_rows(optimal: np.ndarray, n_train: int, n_test: int, max_optimal: float = 80.0,
                skip: int = 0) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Disjoint train and held-out row numbers spread evenly over the rows with ``optimal <= max_optimal``:
    ``n_train + n_test`` rows evenly spaced (as `bench_nav.py` picks its rows), alternately train and held-out
    (after ``skip`` rows of the spread, e.g. to keep clear of another study's rows).

    Raises:
      ValueError: too few rows qualify.
    """
    ok = np.nonzero(np.asarray(optimal) <= max_optimal)[0]
    n = n_train + n_test + skip
    if n_train < 1 or n_test < 0 or len(ok) < n:
        raise ValueError(f"spread_rows: {len(ok)} rows have optimal <= {max_optimal:g}; need {n} "
                         f"(train {n_train}, held-out {n_test}, skip {skip})")
    pick = ok[np.unique(np.linspace(0, len(ok) - 1, n).round().astype(int))][skip:]
    train, test = [], []
    for i, r in enumerate(pick):
        (train if (i % 2 == 0 and len(train) < n_train) or len(test) >= n_test else test).append(int(r))
    return tuple(train), tuple(test)


def nav_map(map_path: str | os.PathLike, scen_path: str | os.PathLike | None = None,
            train_rows: Sequence[int] | int = 8, test_rows: Sequence[int] | int = 8, *, name: str | None = None,
            resolution: float = 1.0, max_optimal: float = 80.0) -> NavMap:
    """A `NavMap` from a MovingAI ``.map`` (and its ``.scen``: default ``MAP.scen``, else ``STEM-random-1.scen``).

    ``train_rows`` / ``test_rows``: row numbers, or counts (then `spread_rows` picks them among the rows with
    optimal length ≤ ``max_optimal`` cells)."""
    from pathlib import Path

    from jaxplan.grid import load_map, load_scenarios

    mp = Path(map_path)
    if scen_path is None:
        scen_path = mp.with_name(mp.name + ".scen")
        if not scen_path.exists():
            scen_path = mp.with_name(mp.stem + "-random-1.scen")
    grid = load_map(mp, resolution=resolution)
    scen = load_scenarios(scen_path, grid)
    if isinstance(train_rows, int) and isinstance(test_rows, int):
        train_rows, test_rows = spread_rows(scen.optimal, train_rows, test_rows, max_optimal)
    elif isinstance(train_rows, int) or isinstance(test_rows, int):
        raise ValueError("nav_map: give train_rows and test_rows both as counts or both as row numbers")
    return NavMap(name or mp.stem, grid, np.asarray(scen.starts), np.asarray(scen.goals), np.asarray(scen.optimal),
                  tuple(int(r) for r in train_rows), tuple(int(r) for r in test_rows))


def _check_splits(maps: Sequence[NavMap], train_seeds: Sequence[int], test_seeds: Sequence[int]) -> None:
    names = [m.name for m in maps]
    if not maps:
        raise ValueError("nav_objective: give at least one map")
    if len(set(names)) != len(names):
        raise ValueError(f"nav_objective: map names must be unique, got {names}")
    for m in maps:
        n = len(m.starts)
        for what, rows in (("train_rows", m.train_rows), ("test_rows", m.test_rows)):
            bad = [r for r in rows if not 0 <= r < n]
            if bad:
                raise ValueError(f"nav_objective: map {m.name!r}: {what} {bad} outside the scenario file's {n} rows")
            if len(set(rows)) != len(rows):
                raise ValueError(f"nav_objective: map {m.name!r}: {what} repeat a row: {list(rows)}")
        if not m.train_rows or not m.test_rows:
            raise ValueError(f"nav_objective: map {m.name!r} needs train and held-out rows")
        shared = sorted(set(m.train_rows) & set(m.test_rows))
        if shared:
            raise ValueError(f"nav_objective: map {m.name!r}: rows {shared} are in both the train and the held-out "
                             f"split; the held-out split must be unseen")
    for what, s in (("train_seeds", train_seeds), ("test_seeds", test_seeds)):
        if not s or any(int(x) < 0 for x in s) or len(set(s)) != len(s):
            raise ValueError(f"nav_objective: {what} must be distinct integers >= 0, got {list(s)}")
    shared = sorted(set(map(int, train_seeds)) & set(map(int, test_seeds)))
    if shared:
        raise ValueError(f"nav_objective: seeds {shared} are in both train_seeds and test_seeds; the held-out seeds "
                         f"must be unseen")


def _walkers(grid, starts: np.ndarray, goals: np.ndarray, n: int, speed: float, radius: float, behavior: str):
    """``f(e, seed)``: bench_nav's walkers for scenario ``e`` of ``starts, goals [E, 2]``."""
    from jaxplan.nav import random_obstacles

    def make(e: int, seed: int):
        avoid = (np.stack([starts[e], goals[e]]).astype(np.float64) + 0.5) * float(grid.resolution)
        return random_obstacles(grid, n=n, speed=speed, radius=radius, seed=10_000 * seed + e, avoid=avoid,
                                avoid_radius=AVOID_RADIUS, behavior=behavior)

    return make


def _concat_blocks(blocks):
    """Episode blocks (`EpisodeInputs`) concatenated along the episode axis, waypoint and route axes padded."""
    from jaxplan.nav import pad_obstacles, with_reactive

    K = max(b.waypoints.shape[2] for b in blocks)
    M = max(b.obstacles.count for b in blocks)
    Kr = max(b.obstacles.waypoints.shape[-2] for b in blocks)
    out = []
    for b in blocks:
        wp = b.waypoints
        if wp.shape[2] < K:  # slots after the last waypoint repeat it
            wp = jnp.concatenate([wp, jnp.repeat(wp[:, :, -1:], K - wp.shape[2], axis=2)], axis=2)
        obs = pad_obstacles(b.obstacles, M, Kr)
        if any(c.obstacles.reactive is not None for c in blocks):  # blind walkers beside seeing ones: explicit
            obs = with_reactive(obs)
        out.append(b._replace(waypoints=wp, obstacles=obs))
    return jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs, axis=0), *out)


class _MapEpisodes(NamedTuple):
    """One map's episodes of one split: the prepared program's pieces and the layout of its ``B`` episodes."""

    config: Any
    steps: int
    table: Any
    free: Any
    inputs: Any
    index: np.ndarray  # int[E, K, R]: the episode of (row, walker kind, seed)
    B: int


def _prepare_map(m: NavMap, rows: Sequence[int], seeds: Sequence[int], pipeline: str, walkers: Sequence[str],
                 n_walkers: int, speed: float, radius: float, config, time_limit) -> tuple[_MapEpisodes, Any]:
    from jaxplan.nav import prepare_episodes

    rows = np.asarray(rows, np.int64)
    S, G = m.starts[rows], m.goals[rows]
    E, R = len(rows), len(seeds)
    blocks, index, offset, params = [], np.zeros((E, len(walkers), R), np.int64), 0, None
    for k, kind in enumerate(walkers):
        p = prepare_episodes(m.grid, S, G, pipeline=pipeline, seeds=list(seeds),
                             obstacles=_walkers(m.grid, S, G, n_walkers, speed, radius, WALKER_KINDS[kind]),
                             config=config, time_limit=time_limit, mesh=None)
        blocks.append(p.inputs)
        index[:, k, :] = offset + np.arange(E * R).reshape(E, R)
        offset += E * R
        params = p.params
    # Every episode re-plans on its own (module docstring): no group couples two episodes, members or not.
    cfg = dataclasses.replace(p.config, replan_group=1)
    inputs = _concat_blocks(blocks)
    return _MapEpisodes(cfg, p.steps, p.table, jnp.asarray(p.free), inputs, index, offset), params


@dataclasses.dataclass(frozen=True, eq=False)
class NavObjective(Objective):
    """An `Objective` over navigation episodes on several maps (see the module docstring).

    Attributes (beyond `Objective`'s):
      maps: the `NavMap`s; walkers: the walker kinds; pipeline: the navigate pipeline; local: ``"dwa"`` or
      ``"mppi"``; episodes: ``{split: [per-map episodes]}`` (internal); base_params: the pipeline's default
      `DWAParams` or `MPPIParams`, into which a weight vector is scattered.
    """

    maps: tuple = ()
    walkers: tuple = ()
    pipeline: str = ""
    local: str = ""
    episodes: Mapping[str, Any] = dataclasses.field(default_factory=dict, repr=False)
    base_params: Any = dataclasses.field(default=None, repr=False)  # DWAParams | MPPIParams: the pipeline's defaults

    def _population(self, ep: _MapEpisodes, pop):
        """``pop [P, D]`` as per-episode params and the map's inputs repeated per member (``[P·B]`` leaves)."""
        params_type = type(self.base_params)
        base_j = {k: jnp.asarray(v, jnp.float32) for k, v in self.base.items()}
        slots = _slots(self.bounds)
        P = pop.shape[0]
        params = jax.vmap(lambda x: params_type(**_scatter(base_j, slots, x)))(pop)  # leaves [P]
        params = jax.tree_util.tree_map(lambda a: jnp.repeat(a, ep.B, axis=0), params)  # [P·B]
        inputs = jax.tree_util.tree_map(lambda a: jnp.tile(a, (P,) + (1,) * (a.ndim - 1)), ep.inputs)
        return params, inputs

    def _score(self, ep: _MapEpisodes, P: int, inputs, steps, reason, collisions, active_contacts):
        """Cost ``[P, E·K, R]`` and metrics of a population's episodes (``inputs``: `_population`'s) from how
        they ended (``[P·B, 1]`` each)."""
        from jaxplan.nav import REASONS

        E, K, R = ep.index.shape
        idx = jnp.asarray(ep.index.reshape(-1))

        def pick(a):  # [P·B, 1] -> [P, E, K, R]
            return jnp.asarray(a)[:, 0].reshape(P, ep.B)[:, idx].reshape(P, E, K, R)

        active, coll = pick(inputs.active), pick(collisions)
        success = active & (pick(reason) == REASONS.index("goal")) & (coll == 0)
        t = pick(steps).astype(jnp.float32) * float(ep.config.dwa.period)
        limit = pick(inputs.time_limit)
        act = pick(active_contacts).astype(jnp.float32)
        m = {
            "time": jnp.where(success, t / limit, 1.0),
            "failure": 1.0 - success.astype(jnp.float32),
            "collision": (coll > 0).astype(jnp.float32),
            "active_contacts": act,
            "passive_contacts": coll.astype(jnp.float32) - act,
            "success": success.astype(jnp.float32),
            "time_s": t,
        }
        cost = sum(w * m[k] for k, w in self.weights.items())
        flat = lambda a: a.reshape(P, E * K, R)  # noqa: E731
        metrics = {k: flat(v) for k, v in m.items()}
        for j, kind in enumerate(self.walkers):
            metrics[f"success_{kind}"] = success[:, :, j].astype(jnp.float32)
        return flat(cost), metrics

    def map_program(self, split: str, i: int) -> Callable:
        """Map ``i``'s pure program ``pop [P, D] -> (cost [P, E·K, R], metrics {k: [P, ·, R]})`` on ``split``: one
        compiled `run_episodes` call, every episode stepped until the batch's last ends (`evaluate` drops
        finished ones instead, with the same scores)."""
        from jaxplan.nav import run_episodes

        ep: _MapEpisodes = self.episodes[split][i]

        def run(pop):
            params, inputs = self._population(ep, pop)
            out = run_episodes(ep.config, ep.steps, ep.table, ep.free, params, inputs, per_episode=True)
            return self._score(ep, pop.shape[0], inputs, out.steps, out.reason, out.collisions, out.active_contacts)

        return run

    def evaluate(self, pop: ArrayLike, split: str = "train") -> Evaluation:
        """Evaluates ``pop [P, D]`` (or one vector) on ``split``: one batch per map, stepped by
        `jaxplan.nav.run_outcomes` (finished episodes dropped; its programs compiled once per batch size)."""
        from jaxplan.nav import run_outcomes

        pop = jnp.atleast_2d(jnp.asarray(pop, jnp.float32))
        if pop.shape[-1] != self.bounds.dim:
            raise ValueError(f"population has {pop.shape[-1]} columns, the space has {self.bounds.dim} "
                             f"({', '.join(self.bounds.names)})")
        self.check_population(pop.shape[0], split)
        compile_s = run_s = 0.0
        costs, metrics = [], {}
        # A member equal to an earlier one (a held-out chunk padded with copies, a strategy proposing a vector
        # twice) does not run: its episodes end at step 0, are dropped with the first finished ones, and it
        # takes the earlier member's scores.
        P = pop.shape[0]
        _, first, back = np.unique(np.asarray(pop), axis=0, return_index=True, return_inverse=True)
        source = first[back.reshape(-1)]  # [P]: the member whose episodes stand for this one
        for i, ep in enumerate(self.episodes[split]):
            t0 = time.perf_counter()
            params, inputs = self._population(ep, pop)
            runs = jnp.asarray(np.repeat(source == np.arange(P), ep.B))[:, None]
            out = run_outcomes(ep.config, ep.steps, ep.table, ep.free, params,
                               inputs._replace(active=inputs.active & runs), per_episode=True,
                               programs=self._compiled.setdefault(("outcomes", split, i), {}))
            rows = (source[:, None] * ep.B + np.arange(ep.B)).reshape(-1)
            c, m = self._score(ep, P, inputs, *(getattr(out, f)[rows] for f in
                                                ("steps", "reason", "collisions", "active_contacts")))
            run_s += time.perf_counter() - t0 - out.compile_s
            compile_s += out.compile_s
            costs.append(np.asarray(c))
            for k, v in m.items():
                metrics.setdefault(k, []).append(np.asarray(v))
        cost = np.concatenate(costs, axis=1)  # [P, N, R]
        ok = np.all(np.isfinite(np.asarray(pop)), axis=1)
        per_seed = np.where(ok[:, None], cost.mean(axis=1), np.inf)
        means = {k: np.concatenate(v, axis=1).mean(axis=(1, 2)) for k, v in metrics.items()}
        return Evaluation(per_seed.mean(axis=1), per_seed, means, run_s, compile_s)


def nav_objective(maps: Sequence[NavMap], train_seeds: Sequence[int], test_seeds: Sequence[int], local: str = "dwa",
                  *, pipeline: str | None = None, walkers: Sequence[str] = ("blind", "seeing"), n_walkers: int = 5,
                  speed: float = 1.0, walker_radius: float = 0.25, space: Mapping | Bounds | None = None,
                  weights: Mapping[str, float] | None = None, config: NavConfig | None = None,
                  time_limit: float | None = None, name: str | None = None) -> NavObjective:
    """The objective of the local planner's weights on navigation episodes among walkers (module docstring).

    Args:
      maps: `NavMap`s (`nav_map`), each with disjoint train and held-out rows.
      train_seeds, test_seeds: disjoint seeds (the global planner's, and the walkers' ``10_000·seed + row index``).
      local: ``"dwa"`` or ``"mppi"``.
      pipeline: the navigate pipeline (default ``"astar_kng_dwa"`` / ``"astar_kng_mppi"``); its local planner must
        be ``local``; a DWA pipeline's evaluator decides the DWA weights' meaning.
      walkers: walker kinds, ``"blind"`` and/or ``"seeing"`` (`WALKER_KINDS`); every tuned vector is scored on each.
      n_walkers, speed, walker_radius: the walkers (m/s, m).
      space: the search box; default DWA heading, velocity, clearance in [0.01, 1], MPPI obstacle, dynamic,
        path_follow, goal_heading in [0.05, 5] and temperature in [0.005, 0.2].
      weights: metric weights (`NAV_METRICS`); default ``{"failure": 1, "time": 1}``.
      config: `jaxplan.nav.NavConfig` (default `NavConfig()`: bench_nav's).
      time_limit: seconds for every episode (default: navigate_batch's per-episode limit).

    Raises:
      ValueError: overlapping splits (rows of a map, or seeds), unknown names, bad bounds or kinds.
    """
    from jaxplan.nav import get_pipeline

    if local not in ("dwa", "mppi"):
        raise ValueError(f"nav_objective: local must be 'dwa' or 'mppi', got {local!r}")
    pipeline = pipeline or f"astar_kng_{local}"
    pipe = get_pipeline(pipeline)
    if pipe.local != local:
        raise ValueError(f"nav_objective: pipeline {pipeline!r} runs the {pipe.local!r} local planner, not {local!r}")
    walkers = tuple(walkers)
    bad = [w for w in walkers if w not in WALKER_KINDS]
    if not walkers or bad or len(set(walkers)) != len(walkers):
        raise ValueError(f"nav_objective: walkers must be distinct kinds among {tuple(WALKER_KINDS)}, got {walkers}")
    if not (isinstance(n_walkers, int) and n_walkers >= 1):
        raise ValueError(f"nav_objective: n_walkers must be an integer >= 1, got {n_walkers!r}")
    for what, v in (("speed", speed), ("walker_radius", walker_radius)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"nav_objective: {what} must be a finite number > 0, got {v!r}")
    maps = tuple(maps)
    _check_splits(maps, train_seeds, test_seeds)
    if local == "dwa":
        space = space or {"heading": (0.01, 1.0), "velocity": (0.01, 1.0), "clearance": (0.01, 1.0)}
    else:
        space = space or {"obstacle": (0.05, 5.0), "dynamic": (0.05, 5.0), "path_follow": (0.05, 5.0),
                          "goal_heading": (0.05, 5.0), "temperature": (0.005, 0.2)}
    weights = _metric_weights("nav_objective", weights, NAV_METRICS, {"failure": 1.0, "time": 1.0})
    bounds = space if isinstance(space, Bounds) else make_bounds(space)
    what = f"nav_objective({pipeline})"

    seeds = {"train": tuple(int(s) for s in train_seeds), "test": tuple(int(s) for s in test_seeds)}
    episodes: dict[str, list] = {"train": [], "test": []}
    params0 = None
    for sp in ("train", "test"):
        for m in maps:
            rows = m.train_rows if sp == "train" else m.test_rows
            ep, params0 = _prepare_map(m, rows, seeds[sp], pipeline, walkers, n_walkers, float(speed),
                                       float(walker_radius), config, time_limit)
            episodes[sp].append(ep)
    base = {k: np.asarray(v) for k, v in params0._asdict().items()}
    tunable = {k: base[k] for k in DWA_TUNABLE} if local == "dwa" else base
    _check_names(bounds, tunable, what, ("temperature", "path") if local == "dwa" else ())
    _check_sign(bounds, what)
    if local == "mppi" and any(n in ("temperature", "noise_v", "noise_omega") and lo <= 0
                               for n, lo in zip(bounds.names, bounds.low, strict=True)):
        raise ValueError(f"{what}: temperature and noise must stay > 0 (their lower bounds)")
    slots = _slots(bounds)
    defaults = np.clip(np.array([float(base[n]) for n, _ in slots], np.float32), bounds.low, bounds.high)

    splits = {}
    for sp in ("train", "test"):
        rows = [np.asarray(m.train_rows if sp == "train" else m.test_rows, np.int64) for m in maps]
        cat = np.concatenate(rows)
        mi = np.concatenate([np.full(len(r), i, np.int64) for i, r in enumerate(rows)])
        splits[sp] = Split(np.concatenate([m.starts[r] for m, r in zip(maps, rows, strict=True)]),
                           np.concatenate([m.goals[r] for m, r in zip(maps, rows, strict=True)]),
                           np.concatenate([m.optimal[r] for m, r in zip(maps, rows, strict=True)]).astype(float),
                           seeds[sp], map_index=mi, rows=cat)

    def memory(population: int, split_name: str) -> MemoryEstimate:
        """The largest map's call (maps run one after the other): ``population × B`` robot episodes."""
        best = None
        for ep in episodes[split_name]:
            cfg = ep.config
            if local == "mppi":
                mc = cfg.local_mppi()
                samples, points = mc.samples, mc.points
            else:
                samples, points = cfg.dwa.samples, cfg.dwa.steps
            est = episode_memory(population * ep.B, ep.steps, samples, rollout_steps=points,
                                 discs=int(ep.inputs.obstacles.count), waypoints=int(ep.inputs.waypoints.shape[2]),
                                 map_cells=int(np.asarray(ep.free).size))
            best = est if best is None or est.total > best.total else best
        return best

    def program(split_name: str):  # all maps in one pure function (`Objective.batched`); `evaluate` splits them
        def run(pop):
            outs = [obj.map_program(split_name, i)(pop) for i in range(len(maps))]
            cost = jnp.concatenate([c for c, _ in outs], axis=1)
            return cost, {k: jnp.concatenate([m[k] for _, m in outs], axis=1) for k in outs[0][1]}

        return run

    obj = NavObjective(name or f"nav_{local}_weights", "nav", local if local == "mppi" else pipe.evaluator, bounds,
                       defaults, weights, splits, program, base, mesh=None, memory=memory, maps=maps,
                       walkers=walkers, pipeline=pipeline, local=local, episodes=episodes, base_params=params0)
    return obj
