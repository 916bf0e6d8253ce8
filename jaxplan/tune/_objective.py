"""Objectives: a weight vector → a scalar cost over a training set of scenarios × seeds, in one compiled call.

An `Objective` evaluates a whole population ``pop f32[P, D]`` of weight vectors (rows in
the `Bounds` box, named dimensions) on a `Split` — scenarios × seeds — as ONE jitted call:
the planner's pure batch program (`jaxplan.aco.run_batch`, or the DWA episode program
below) is ``vmap``-ped over the population, scenarios and seeds are its own batch axes.
The weights are traced leaves, so a new population never recompiles.

A run's cost is a weighted sum of metrics (``weights``, lower is better), averaged over
scenarios per seed (``per_seed [P, R]``, whose spread over seeds is the seed-to-seed
noise) and then over seeds (``fitness [P]``). The training and held-out test splits use
different scenarios AND different seeds; tuning sees only the training split.

ACO metrics per run (`ACO_METRICS`): ``gap`` = length/optimal − 1 (a failed run counts
`FAIL_GAP`), ``failure`` = 1 − success, ``turns`` (count), ``roughness`` = 1 − smoothness
(docs/guide/smoothing-and-metrics.md), ``clearance`` = 1 / mean clearance (1/m); a failed run contributes only its
gap and failure terms. The tuned weights act on how the ants search; the objective's
metrics are fixed, so e.g. shrinking IACO's λ does not shrink the objective.

DWA metrics per episode (`DWA_METRICS`): ``time`` = time to the goal / time limit (1 if not
reached), ``failure`` = not (reached and collision-free), ``collision``, ``clearance`` =
max(0, 1 − min clearance / 1 m). Episodes are `dwa_episodes`: a fixed-length
`lax.scan` of `dwa_control` steps towards the goal among discs moving at constant
velocity (the seeds draw the discs and the start heading) — a reverse-differentiable
program (no early exit), which the relaxed-DWA gradient route reuses.

Non-finite costs (a failing configuration) are returned as they are, and a weight vector with a
non-finite entry costs inf whatever its runs gave; strategies map them to the worst value
(`jaxplan.tune.sanitize`) and the workflow counts them.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING, Any, Callable, Mapping, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import PartitionSpec as P

from jaxplan.scale import (
    BATCH_AXIS,
    MemoryEstimate,
    auto_mesh,
    check_memory,
    dwa_memory,
    pad_leading,
    padded_size,
)
from jaxplan.tune._bounds import Bounds, make_bounds

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from jaxplan.dwa import ClearanceTable, DWAConfig, DWAParams
    from jaxplan.grid import GridMap
    from jaxplan.mppi import MPPIConfig, MPPIParams

__all__ = ["Split", "Evaluation", "Objective", "aco_objective", "dwa_objective", "mppi_objective", "function_objective",
           "DWAEpisodes", "dwa_episodes", "mppi_episodes", "dwa_scenarios", "ACO_METRICS", "DWA_METRICS", "FAIL_GAP"]

ACO_METRICS = ("gap", "failure", "turns", "roughness", "clearance")
DWA_METRICS = ("time", "failure", "collision", "clearance")
FAIL_GAP = 1.0
"""Optimality gap charged to a run that found no path (as if its path were twice the optimum)."""


class Split(NamedTuple):
    """Scenarios × seeds. starts, goals ``int[N, 2]`` cells; optimal ``f[N]`` m; seeds ``R`` ints.

    An objective over several maps (`jaxplan.tune.nav_objective`) also gives each scenario its map,
    ``map_index int[N]`` (into the objective's maps), and its row of that map's scenario file, ``rows int[N]``;
    None for one map.
    """

    starts: np.ndarray
    goals: np.ndarray
    optimal: np.ndarray
    seeds: tuple[int, ...]
    map_index: np.ndarray | None = None
    rows: np.ndarray | None = None


class Evaluation(NamedTuple):
    """A population's evaluation (numpy): fitness ``[P]`` (raw, may hold NaN), per_seed ``[P, R]``,
    metrics ``{name: [P]}`` (means over runs), time_s (the compiled call, without compilation),
    compile_s."""

    fitness: np.ndarray
    per_seed: np.ndarray
    metrics: dict
    time_s: float
    compile_s: float


def _metric_weights(who: str, weights: Mapping[str, float] | None, allowed: Sequence[str],
                    default: Mapping[str, float]) -> dict:
    """The objective's metric weights (``default`` when None), each a known metric with a finite weight >= 0."""
    weights = dict(weights or default)
    for k, v in weights.items():
        if k not in allowed:
            raise ValueError(f"{who}: unknown metric {k!r}; choose from {tuple(allowed)}")
        if not math.isfinite(v) or v < 0:
            raise ValueError(f"{who}: metric weight {k!r} must be a finite number >= 0, got {v!r}")
    return weights


def _slots(bounds: Bounds) -> list[tuple[str, int | None]]:
    out = []
    for n in bounds.names:
        if n.endswith("]") and "[" in n:
            base, i = n[:-1].split("[")
            out.append((base, int(i)))
        else:
            out.append((n, None))
    return out


def _scatter(base: Mapping[str, jnp.ndarray], slots, x: jnp.ndarray) -> dict:
    """The params pytree with the tuned leaves taken from ``x [D]``."""
    p = dict(base)
    for d, (name, i) in enumerate(slots):
        p[name] = x[d] if i is None else jnp.asarray(p[name]).at[i].set(x[d])
    return p


@dataclasses.dataclass(frozen=True, eq=False)
class Objective:
    """A tuning objective (see the module docstring).

    Attributes:
      name: label.
      kind: ``"aco"`` or ``"dwa"``.
      planner: the planner (ACO) or evaluator (DWA) whose weights are tuned.
      bounds: the search box.
      defaults: ``f32[D]`` the paper's weights (the planner's defaults), clipped to the box.
      weights: metric weights of the cost.
      splits: ``{"train": Split, "test": Split}``.
      program: ``program(split_name) -> pure fn(pop [P, D]) -> (per_run cost [P, N, R], metrics {k: [P, N, R]})``.
      base: the planner's full parameter dict (for `params`).
      memory: ``memory(population, split) -> MemoryEstimate`` of one evaluation (None: not estimated);
        `evaluate` refuses a population that does not fit before compiling (`check_population`).
      mesh: where `evaluate` runs a population: ``"auto"`` (default: split over every local
        device when there are several and each gets at least 8 members — `jaxplan.scale.auto_mesh`),
        None (one device) or a 1-D `jax.sharding.Mesh`. Members are computed independently:
        success, gaps, failures and turns do not depend on it; float sums over path points
        (mean clearance, roughness) may differ in the last bit, as between population sizes on
        one device, and so may a fitness that weights them. Set with `with_mesh`.
    """

    name: str
    kind: str
    planner: str
    bounds: Bounds
    defaults: np.ndarray
    weights: Mapping[str, float]
    splits: Mapping[str, Split]
    program: Callable[[str], Callable]
    base: Mapping[str, Any]
    mesh: Any = "auto"
    memory: Callable[[int, str], MemoryEstimate] | None = None
    _compiled: dict = dataclasses.field(default_factory=dict, repr=False)

    def check_population(self, population: int, split: str = "train") -> None:
        """Refuses (`jaxplan.scale.MemoryLimitError`, naming the largest population that fits) a population
        whose evaluation on ``split`` would not fit in memory; before anything of it is allocated."""
        if self.memory is None:
            return
        n, R = len(self.splits[split].starts), len(self.splits[split].seeds)
        check_memory(self.memory(int(population), split),
                     f"objective {self.name!r} on {n} scenario{'s' * (n != 1)} x {R} seed{'s' * (R != 1)} ({split})",
                     unit="weight vectors (population)", advice="Use a smaller population, fewer scenarios or seeds",
                     single=f"Use fewer scenarios or seeds for {split!r} (each weight vector runs them all at once)")

    def with_mesh(self, mesh: Any) -> "Objective":
        """This objective evaluated on ``mesh`` (a `Mesh`, ``"auto"`` or None); compiled programs are not shared."""
        auto_mesh(mesh, 1)  # validates
        new = dataclasses.replace(self, mesh=mesh, _compiled={})
        for k, v in self.__dict__.items():  # extra attributes set after construction (e.g. the DWA episodes)
            if k not in new.__dict__:
                object.__setattr__(new, k, v)
        return new

    def batched(self, split: str = "train") -> Callable:
        """The pure batched objective ``pop f32[P, D] -> (fitness [P], per_seed [P, R], metrics {k: [P]})``
        (jittable; `evaluate` is its compiled, timed form)."""
        run = self.program(split)

        def fn(pop):
            cost, metrics = run(pop)
            # A weight vector with a NaN/inf entry is no configuration, yet a planner turns it into failed runs of
            # finite cost (2.0 for the default ACO weights), which a strategy could rank best: charge it inf.
            ok = jnp.all(jnp.isfinite(pop), axis=1)
            per_seed = jnp.where(ok[:, None], jnp.mean(cost, axis=1), jnp.inf)  # [P, R]
            return jnp.mean(per_seed, axis=1), per_seed, {k: jnp.mean(v, axis=(1, 2)) for k, v in metrics.items()}

        return fn

    def evaluate(self, pop: ArrayLike, split: str = "train") -> Evaluation:
        """Evaluates ``pop [P, D]`` (or one vector ``[D]``) on ``split`` as one compiled call."""
        pop = jnp.atleast_2d(jnp.asarray(pop, jnp.float32))
        if pop.shape[-1] != self.bounds.dim:
            raise ValueError(f"population has {pop.shape[-1]} columns, the space has {self.bounds.dim} "
                             f"({', '.join(self.bounds.names)})")
        n = pop.shape[0]
        self.check_population(n, split)
        mesh = auto_mesh(self.mesh, n)
        if mesh is not None:  # copies of the last member, sliced off below
            pop = pad_leading(pop, padded_size(n, mesh))
        key = (split, pop.shape, mesh)
        compile_s = 0.0
        if key not in self._compiled:
            t0 = time.perf_counter()
            fn = self.batched(split)
            if mesh is not None:
                # check_vma=False: the ACO walk is an FFI custom call without varying-axes types;
                # every output is per member, split along BATCH_AXIS.
                fn = jax.shard_map(fn, mesh=mesh, in_specs=P(BATCH_AXIS), out_specs=P(BATCH_AXIS), check_vma=False)
            from jaxplan.aco import sharing_cores  # late, as this module's other ACO imports

            with sharing_cores(1 if mesh is None else len(mesh.local_devices)):
                self._compiled[key] = jax.jit(fn).lower(pop).compile()
            compile_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        f, ps, m = jax.block_until_ready(self._compiled[key](pop))
        dt = time.perf_counter() - t0
        return Evaluation(np.asarray(f)[:n], np.asarray(ps)[:n], {k: np.asarray(v)[:n] for k, v in m.items()}, dt,
                          compile_s)

    def __call__(self, params: Mapping[str, Any], split: str = "train") -> float:
        """The scalar objective of one params pytree (``{name: value}``, vector weights as sequences)."""
        return float(self.evaluate(self.vector(params), split).fitness[0])

    def vector(self, params: Mapping[str, Any]) -> np.ndarray:
        """``f32[D]`` from ``{name: value}`` (missing names take the defaults)."""
        x = np.array(self.defaults, np.float32)
        for d, (name, i) in enumerate(_slots(self.bounds)):
            if name in params:
                v = params[name]
                x[d] = float(v if i is None else np.asarray(v)[i])
        return x

    def params(self, x: ArrayLike) -> dict[str, Any]:
        """``{name: value}`` of a vector ``x [D]`` (vector weights as lists, the rest of a vector
        weight from the planner's defaults): what `jaxplan run` takes as overrides / DWA params."""
        out: dict[str, Any] = {}
        for d, (name, i) in enumerate(_slots(self.bounds)):
            if i is None:
                out[name] = float(x[d])
            else:
                v = out.setdefault(name, [float(a) for a in np.asarray(self.base[name]).ravel()])
                v[i] = float(x[d])
        return out


def _check_names(bounds: Bounds, allowed: Mapping[str, Any], what: str, static: Sequence[str] = ()) -> None:
    for name, i in _slots(bounds):
        if name in static:
            raise ValueError(f"{what}: {name!r} cannot be tuned: it shapes the compiled program (set it in overrides)")
        if name not in allowed:
            raise ValueError(f"{what}: unknown parameter {name!r}; tunable: {', '.join(sorted(allowed))}")
        size = int(np.size(allowed[name]))
        if (i is None) != (np.ndim(allowed[name]) == 0) or (i is not None and not 0 <= i < size):
            shape = "a scalar" if np.ndim(allowed[name]) == 0 else f"a vector of {size}: give {size} (low, high) pairs"
            raise ValueError(f"{what}: parameter {name!r} is {shape}")


def _check_sign(bounds: Bounds, what: str, unit: Sequence[str] = ()) -> None:
    """Positivity (and [0, 1]) constraints of the planner, enforced through the box."""
    for (name, _), n, lo, hi in zip(_slots(bounds), bounds.names, bounds.low, bounds.high, strict=True):
        if lo < 0:
            raise ValueError(f"{what}: bounds of {n!r}: the parameter must be >= 0, but low = {lo:g}")
        if name in unit and hi > 1:
            raise ValueError(f"{what}: bounds of {n!r}: the parameter must lie in [0, 1], but high = {hi:g}")


# ---------------------------------------------------------------------------------------------
# ACO


class ACOSetup(NamedTuple):
    """What an ACO objective's population programs share (`aco_setup`): the colony and its static config, the
    planner's parameter dict, the tuned slots, the map's tables and collision map, the map's width (cells) and cell
    size (m)."""

    colony: Any
    cfg: Any
    base: Mapping[str, Any]
    slots: list
    tables: Any
    cmap: Any
    connectivity: int
    vh: Any
    width: int
    resolution: float


def aco_setup(grid: GridMap, planner: str, bounds: Bounds, overrides: Mapping[str, Any] | None) -> ACOSetup:
    """The `ACOSetup` of ``planner`` on ``grid`` with ``overrides``, its tuned slots those of ``bounds``."""
    from jaxplan.aco import COLONIES, cached_map_tables, split_params
    from jaxplan.grid import collision_map
    from jaxplan.registry import resolve

    _, p = resolve(planner, dict(overrides or {}))
    cfg, base, connectivity, vh = split_params(grid, p)
    return ACOSetup(COLONIES[planner], cfg, base, _slots(bounds), cached_map_tables(grid, connectivity, vh),
                    collision_map(grid), connectivity, vh, grid.width, float(grid.resolution))


def aco_runs(setup: ACOSetup, goal_tables: Any, keys: jax.Array, pop: jnp.ndarray) -> tuple[Any, dict]:
    """One population's colony runs on a split, and the metrics every ACO objective shares.

    Args:
      setup: the planner on its map (`aco_setup`).
      goal_tables: the split's goal tables (`jaxplan.aco.goal_tables`).
      keys: the split's seed keys (`jaxplan.aco.seed_keys`).
      pop: ``f32[P, D]`` weight vectors (traced).

    Returns:
      The runs (`jaxplan.aco.run_batch`'s, leading axes ``[P, N, R]``) and ``{"failure", "turns", "roughness",
      "clearance"}``, each ``f32[P, N, R]`` (a failed run counts failure 1 and nothing else).
    """
    from jaxplan.aco import run_batch
    from jaxplan.metrics import clearance_metrics, geometry_metrics

    W = setup.width
    # vmap over the population: the weights are traced leaves, scenarios × seeds are run_batch's axes.
    out = jax.vmap(lambda x: run_batch(setup.colony, setup.cfg, setup.tables, goal_tables,
                                       _scatter(setup.base, setup.slots, x), keys))(pop)
    ok = out.success
    path = jnp.stack([out.cells % W, out.cells // W], axis=-1)  # [P, N, R, L + 1, 2]
    npts = out.n + 1
    geo = geometry_metrics(path, npts, setup.resolution)
    _, mean_c = clearance_metrics(setup.cmap, path, npts)
    return out, {
        "failure": 1.0 - ok.astype(jnp.float32),
        "turns": jnp.where(ok, geo["turns"].astype(jnp.float32), 0.0),
        "roughness": jnp.where(ok, 1.0 - geo["smoothness"], 0.0),
        "clearance": jnp.where(ok, 1.0 / jnp.maximum(mean_c, 1e-3), 0.0),
    }


def aco_objective(grid: GridMap, train: Split, test: Split, planner: str = "iaco", space: Mapping | None = None,
                  weights: Mapping[str, float] | None = None, overrides: Mapping[str, Any] | None = None,
                  name: str | None = None) -> Objective:
    """The objective of an ACO planner's weights (see the module docstring).

    Args:
      grid: the map.
      train, test: `Split`s (scenarios with their exact optima, and seeds).
      planner: a colony planner (``aco``, ``iaco``, ``risk_aco``, ``opt_ant``, ``praco``).
      space: ``{name: (low, high)}`` or ``{name: [(low, high), …]}`` for vector weights; default
        α, β and (for iaco) λ.
      weights: metric weights (`ACO_METRICS`); default ``{"gap": 1, "failure": 1}``.
      overrides: the planner's settings (ants, iterations, …: static; weights not tuned).
      name: the objective's label (default ``PLANNER_weights``).

    Raises:
      ValueError: naming the parameter, for an unknown or static name, bad bounds, or bounds
        outside the parameter's valid range (negative; above 1 for ρ, δ, ρ_res, λ_p).
    """
    from jaxplan.aco import COLONIES, STATIC_PARAMS, UNIT_PARAMS, goal_tables, seed_keys

    if planner not in COLONIES:
        raise ValueError(f"aco_objective: planner must be one of {sorted(COLONIES)}, got {planner!r}")
    if space is None:
        space = {"alpha": (0.5, 3.0), "beta": (1.0, 10.0)}
        if planner == "iaco":
            space["lambdas"] = [(0.0, 1.0)] * 3
    weights = _metric_weights("aco_objective", weights, ACO_METRICS, {"gap": 1.0, "failure": 1.0})
    bounds = space if isinstance(space, Bounds) else make_bounds(space)
    setup = aco_setup(grid, planner, bounds, overrides)
    cfg, base, slots = setup.cfg, setup.base, setup.slots
    what = f"aco_objective({planner})"
    _check_names(bounds, base, what, STATIC_PARAMS)
    _check_sign(bounds, what, UNIT_PARAMS)
    defaults = np.array([float(np.asarray(base[n]) if i is None else np.asarray(base[n])[i]) for n, i in slots],
                        np.float32)
    defaults = np.clip(defaults, bounds.low, bounds.high)
    prepared = {}
    for split_name, sp in (("train", train), ("test", test)):
        gt = goal_tables(grid, np.asarray(sp.starts), np.asarray(sp.goals), setup.connectivity, setup.vh,
                         geodesic=cfg.heuristic == "geodesic")
        prepared[split_name] = (gt, seed_keys(sp.seeds), jnp.asarray(sp.optimal, jnp.float32))

    def program(split_name: str):
        gt, keys, optimal = prepared[split_name]

        def run(pop):
            out, shared = aco_runs(setup, gt, keys, pop)
            metrics = {"gap": jnp.where(out.success, out.length / optimal[None, :, None] - 1.0, FAIL_GAP), **shared}
            cost = sum(w * metrics[k] for k, w in weights.items())
            return cost, metrics

        return run

    def memory(population: int, split_name: str) -> MemoryEstimate:
        from jaxplan.aco import plan_memory

        sp = {"train": train, "test": test}[split_name]
        runs = population * len(sp.starts) * len(sp.seeds)
        est = plan_memory(grid, planner, runs, **dict(overrides or {}))
        # The metrics' [P, N, R, L + 1, 2] paths and their geometry and clearance temporaries (int32/f32).
        return _per_member(est, population, {"objective metrics": runs * (cfg.max_steps + 1) * 2 * 4 * 4})

    return Objective(name or f"{planner}_weights", "aco", planner, bounds, defaults, weights,
                     {"train": train, "test": test}, program, {k: np.asarray(v) for k, v in base.items()},
                     memory=memory)


def _per_member(est: MemoryEstimate, population: int, extra: Mapping[str, int]) -> MemoryEstimate:
    """``est`` (of all runs of a population) plus ``extra`` bytes, counted per population member."""
    fixed = est.total - est.per_run * est.runs
    total = int(est.total + sum(extra.values()))
    return MemoryEstimate(total, {**est.parts, **extra}, population, (total - fixed) / max(population, 1))


# ---------------------------------------------------------------------------------------------
# DWA episodes


class DWAEpisodes(NamedTuple):
    """Episodes for `dwa_episodes` (leading axis E). start ``f32[E, 5]``, goal ``f32[E, 2]`` (m),
    obstacles: `jaxplan.dwa.DiscObstacles` with ``[E, M, 2]`` positions at t = 0 and velocities,
    ``[E, M]`` radii."""

    start: jnp.ndarray
    goal: jnp.ndarray
    obstacles: Any


class EpisodeTrace(NamedTuple):
    """Per step ``[E, T]``: dist to the goal (m) after the step, clearance (m) of the robot's centre
    (static and discs, at the step's end), done (at the goal by then), moving (not done before the step)."""

    dist: jnp.ndarray
    clearance: jnp.ndarray
    done: jnp.ndarray
    moving: jnp.ndarray


def dwa_episodes(table: ClearanceTable, config: DWAConfig, params: DWAParams, episodes: DWAEpisodes, steps: int,
                 tolerance: float = 0.5) -> EpisodeTrace:
    """``steps`` DWA control steps (period ``config.period``) of E robots driving to their goals.

    Pure and reverse-differentiable (fixed-length `lax.scan`, a robot at its goal stays put
    through `jnp.where`); with ``config.selection == "softmax"`` the trace is a smooth
    function of the critic weights. The sub-goal is the goal itself (no global path).
    """
    from jaxplan.dwa import DiscObstacles, advance, disc_clearance, dwa_control, static_clearance

    period = config.period

    def one(start, goal, ob):
        def step(carry, k):
            state, done = carry
            t = k * period
            now = DiscObstacles(ob.positions + ob.velocities * t, ob.velocities, ob.radii)
            u, _ = dwa_control(table, config, params, state, goal, now)
            new = jnp.where(done, state, advance(state, u, period))
            c = jnp.minimum(static_clearance(table, new[0:1], new[1:2], config.clearance)[0],
                            disc_clearance(ob, new[0:1], new[1:2], t + period)[0])
            d = jnp.sqrt(jnp.sum((new[:2] - goal) ** 2) + 1e-12)
            done2 = done | (d < tolerance)
            return (new, done2), (d, c, done2, ~done)

        _, (d, c, dn, mv) = jax.lax.scan(step, (start, jnp.asarray(False)), jnp.arange(steps, dtype=start.dtype))
        return EpisodeTrace(d, c, dn, mv)

    return jax.vmap(one)(episodes.start, episodes.goal, episodes.obstacles)


def _episode_metrics(trace: EpisodeTrace, steps: int, period: float, radius: float) -> dict:
    reached = trace.done[..., -1]
    first = jnp.argmax(trace.done, axis=-1)
    t_goal = jnp.where(reached, (first + 1) * period, steps * period)
    hit = jnp.any(trace.moving & (trace.clearance < radius), axis=-1)
    min_c = jnp.min(jnp.where(trace.moving, trace.clearance, jnp.inf), axis=-1)
    return {
        "time": t_goal / (steps * period),
        "failure": 1.0 - (reached & ~hit).astype(jnp.float32),
        "collision": hit.astype(jnp.float32),
        "clearance": jnp.maximum(0.0, 1.0 - jnp.minimum(min_c, 1.0)),
    }


def dwa_scenarios(grid: GridMap, starts: np.ndarray, goals: np.ndarray, seeds: Sequence[int], n_discs: int = 2,
                  speed: tuple[float, float] = (0.4, 1.0), radius: float = 0.25,
                  heading_jitter: float = 0.5) -> DWAEpisodes:
    """Episodes ``[N·R]`` (scenario-major) from cells: start and goal at cell centres, start heading
    towards the goal ± ``heading_jitter`` rad, and ``n_discs`` discs that cross the start–goal line
    at 30–70 % of the way, at a random time a robot at 0.6 m/s would be there, at a speed drawn from
    ``speed`` (m/s) — drawn from ``numpy.random.default_rng((seed, scenario))`` for each seed."""
    from jaxplan.dwa import DiscObstacles

    res = float(grid.resolution)
    S, G, P, V, R = [], [], [], [], []
    for i, (a, b) in enumerate(zip(np.asarray(starts), np.asarray(goals), strict=True)):
        pa, pb = (np.asarray(a, float) + 0.5) * res, (np.asarray(b, float) + 0.5) * res
        d = pb - pa
        L = float(np.hypot(*d))
        for s in seeds:
            rng = np.random.default_rng((int(s), i))
            th = math.atan2(d[1], d[0]) + rng.uniform(-heading_jitter, heading_jitter)
            S.append([pa[0], pa[1], th, 0.0, 0.0])
            G.append(pb)
            pos, vel = [], []
            for _ in range(n_discs):
                f = rng.uniform(0.3, 0.7)
                cross = pa + f * d
                tc = f * L / 0.6 * rng.uniform(0.7, 1.3)
                ang = math.atan2(d[1], d[0]) + rng.choice([-1.0, 1.0]) * rng.uniform(math.pi / 3, 2 * math.pi / 3)
                v = rng.uniform(*speed) * np.array([math.cos(ang), math.sin(ang)])
                pos.append(cross - v * tc)
                vel.append(v)
            P.append(pos)
            V.append(vel)
            R.append([radius] * n_discs)
    f32 = lambda a: jnp.asarray(np.asarray(a, np.float32).reshape((len(S),) + np.shape(a)[1:]))  # noqa: E731
    obs = DiscObstacles(f32(P).reshape(len(S), n_discs, 2), f32(V).reshape(len(S), n_discs, 2),
                        f32(R).reshape(len(S), n_discs))
    return DWAEpisodes(f32(S), f32(G), obs)


DWA_TUNABLE = ("heading", "velocity", "clearance", "goal")


def _episode_programs(grid, train: Split, test: Split, config, base: Mapping[str, np.ndarray], slots, weights,
                      steps: int, tolerance: float, n_discs: int, params_type, episodes: Callable, points: int):
    """What `dwa_objective` and `mppi_objective` share: the batched episode program of each split, its memory
    estimate, and the parts a gradient route reuses.

    ``params_type`` builds the local planner's params from the scattered weights, ``episodes`` runs them
    (`dwa_episodes` or `mppi_episodes`), ``points`` is the rollout points per sample of the memory estimate.
    """
    from jaxplan.dwa import clearance_table
    from jaxplan.grid import collision_map

    splits = {"train": train, "test": test}
    table = clearance_table(collision_map(grid))
    radius = float(config.robot.footprint.radius) if hasattr(config.robot.footprint, "radius") else 0.25
    eps = {k: dwa_scenarios(grid, sp.starts, sp.goals, sp.seeds, n_discs) for k, sp in splits.items()}
    base_j = {k: jnp.asarray(v, jnp.float32) for k, v in base.items()}

    def program(split_name: str):
        ep = eps[split_name]
        N, R = len(splits[split_name].starts), len(splits[split_name].seeds)

        def run(pop):
            def one(x):
                tr = episodes(table, config, params_type(**_scatter(base_j, slots, x)), ep, steps, tolerance)
                return _episode_metrics(tr, steps, config.period, radius)

            metrics = {k: v.reshape(pop.shape[0], N, R) for k, v in jax.vmap(one)(pop).items()}
            cost = sum(w * metrics[k] for k, w in weights.items())
            return cost, metrics

        return run

    def memory(population: int, split_name: str) -> MemoryEstimate:
        sp = splits[split_name]
        robots = population * len(sp.starts) * len(sp.seeds)
        est = dwa_memory(robots, config.samples, points, obstacles=n_discs, chunk=None,
                         map_cells=int(np.asarray(grid.free).size))
        return _per_member(est, population, {"episode traces": robots * steps * 4 * 4})

    parts = dict(table=table, config=config, steps=steps, episodes=eps, slots=slots, base=base_j, tolerance=tolerance,
                 radius=radius)
    return program, memory, parts


def dwa_objective(grid: GridMap, train: Split, test: Split, evaluator: str = "weighted", space: Mapping | None = None,
                  weights: Mapping[str, float] | None = None, dwa: Mapping[str, Any] | None = None,
                  max_time: float = 20.0, n_discs: int = 2, tolerance: float = 0.5,
                  name: str | None = None) -> Objective:
    """The objective of the DWA critic weights (see the module docstring): argmax DWA episodes
    (as published) from each split's scenarios, discs drawn per seed (`dwa_scenarios`).

    Args:
      grid: the map (DWA clearance from its blocked squares).
      train, test: `Split`s (cells; ``optimal`` unused).
      evaluator: ``"weighted"`` (cui2025 Eq. 7) or ``"fuzzy"``.
      space: default heading, velocity, clearance in [0.01, 1].
      weights: metric weights (`DWA_METRICS`); default ``{"time": 1, "failure": 1}``.
      dwa: `DWAConfig` fields (static counts, distances); default a small, fast window.
      max_time: episode length (s).
    """
    from jaxplan.dwa import DWAConfig, DWAParams, default_params

    space = space or {"heading": (0.01, 1.0), "velocity": (0.01, 1.0), "clearance": (0.01, 1.0)}
    weights = _metric_weights("dwa_objective", weights, DWA_METRICS, {"time": 1.0, "failure": 1.0})
    bounds = space if isinstance(space, Bounds) else make_bounds(space)
    base_p = default_params(evaluator)
    base = {k: np.asarray(v) for k, v in base_p._asdict().items()}
    _check_names(bounds, {k: base[k] for k in DWA_TUNABLE}, f"dwa_objective({evaluator})", ("temperature", "path"))
    _check_sign(bounds, f"dwa_objective({evaluator})")
    config = DWAConfig(**{**dict(n_v=5, n_omega=9, horizon=1.5, dt=0.15, unroll=1, keep_rollouts=False,
                                 recovery="flee", d_clip=0.5), **dict(dwa or {}), "evaluator": evaluator})
    steps = int(math.ceil(max_time / config.period))
    slots = _slots(bounds)
    defaults = np.clip(np.array([float(base[n]) for n, _ in slots], np.float32), bounds.low, bounds.high)
    program, memory, parts = _episode_programs(grid, train, test, config, base, slots, weights, steps, tolerance,
                                               n_discs, DWAParams, dwa_episodes, config.steps)
    obj = Objective(name or f"dwa_{evaluator}_weights", "dwa", evaluator, bounds, defaults, weights,
                    {"train": train, "test": test}, program, base, memory=memory)
    object.__setattr__(obj, "_dwa", parts)
    return obj


def mppi_episodes(table: ClearanceTable, config: MPPIConfig, params: MPPIParams, episodes: DWAEpisodes, steps: int,
                  tolerance: float = 0.5,
                  key: jax.Array | None = None) -> EpisodeTrace:
    """``steps`` MPPI control steps (period ``config.period``) of E robots driving to their goals, as `dwa_episodes`.

    Each robot's sequence is warm-started from its last one; episode ``e`` draws the noise of step ``k`` from
    ``fold_in(fold_in(key, e), k)``, so the trace is a smooth function of the critic weights and λ (the softmax).
    """
    from jaxplan.dwa import DiscObstacles, advance, disc_clearance, static_clearance
    from jaxplan.mppi import initial_sequence, mppi_control, shift

    period = config.period
    key = jax.random.key(0) if key is None else key

    def one(start, goal, ob, e):
        k_e = jax.random.fold_in(key, e)

        def step(carry, k):
            state, mean, done = carry
            t = k * period
            now = DiscObstacles(ob.positions + ob.velocities * t, ob.velocities, ob.radii)
            u, info = mppi_control(table, config, params, state, mean, jax.random.fold_in(k_e, k.astype(jnp.int32)),
                                   goal, obstacles=now)
            new = jnp.where(done, state, advance(state, u, period))
            c = jnp.minimum(static_clearance(table, new[0:1], new[1:2], config.clearance)[0],
                            disc_clearance(ob, new[0:1], new[1:2], t + period)[0])
            d = jnp.sqrt(jnp.sum((new[:2] - goal) ** 2) + 1e-12)
            done2 = done | (d < tolerance)
            return (new, shift(info.sequence), done2), (d, c, done2, ~done)

        init = (start, initial_sequence(config, start), jnp.asarray(False))
        _, (d, c, dn, mv) = jax.lax.scan(step, init, jnp.arange(steps, dtype=start.dtype))
        return EpisodeTrace(d, c, dn, mv)

    E = episodes.start.shape[0]
    return jax.vmap(one)(episodes.start, episodes.goal, episodes.obstacles, jnp.arange(E))


def mppi_objective(grid: GridMap, train: Split, test: Split, space: Mapping | None = None,
                   weights: Mapping[str, float] | None = None, mppi: Mapping[str, Any] | None = None,
                   max_time: float = 20.0, n_discs: int = 2, tolerance: float = 0.5,
                   name: str | None = None) -> Objective:
    """The objective of the MPPI critic weights, temperature and noise: `mppi_episodes` from each split's scenarios,
    discs drawn per seed (`dwa_scenarios`), metrics and arguments as `dwa_objective`.

    Args:
      space: default the obstacle, dynamic, path-follow and goal-heading weights in [0.05, 5] and the temperature in
        [0.005, 0.2]; any `MPPIParams` field may be tuned.
      mppi: `MPPIConfig` fields (static counts, distances); default 128 samples.
    """
    from jaxplan.mppi import MPPIConfig, MPPIParams, default_params

    space = space or {"obstacle": (0.05, 5.0), "dynamic": (0.05, 5.0), "path_follow": (0.05, 5.0),
                      "goal_heading": (0.05, 5.0), "temperature": (0.005, 0.2)}
    weights = _metric_weights("mppi_objective", weights, DWA_METRICS, {"time": 1.0, "failure": 1.0})
    bounds = space if isinstance(space, Bounds) else make_bounds(space)
    base = {k: np.asarray(v) for k, v in default_params()._asdict().items()}
    _check_names(bounds, base, "mppi_objective")
    _check_sign(bounds, "mppi_objective")
    if bounds.names and any(n in ("temperature", "noise_v", "noise_omega") and lo <= 0
                            for n, lo in zip(bounds.names, bounds.low, strict=True)):
        raise ValueError("mppi_objective: temperature and noise must stay > 0 (their lower bounds)")
    config = MPPIConfig(**{**dict(samples=128), **dict(mppi or {})})
    steps = int(math.ceil(max_time / config.period))
    slots = _slots(bounds)
    defaults = np.clip(np.array([float(base[n]) for n, _ in slots], np.float32), bounds.low, bounds.high)
    program, memory, _ = _episode_programs(grid, train, test, config, base, slots, weights, steps, tolerance,
                                           n_discs, MPPIParams, mppi_episodes, config.points)
    return Objective(name or "mppi_weights", "mppi", "mppi", bounds, defaults, weights,
                     {"train": train, "test": test}, program, base, memory=memory)


# ---------------------------------------------------------------------------------------------
# Any function


def function_objective(fn: Callable, space: Mapping | Bounds, defaults: ArrayLike | None = None,
                       train_seeds: Sequence[int] = (0,), test_seeds: Sequence[int] = (1,),
                       name: str = "function") -> Objective:
    """An `Objective` from a pure function ``fn(x f32[D], seed i32[]) -> f32[]`` (one scenario):
    for tests, toy problems and custom pipelines. Evaluated as one ``vmap`` over population × seeds."""
    bounds = space if isinstance(space, Bounds) else make_bounds(space)
    defaults = np.asarray((bounds.low + bounds.high) / 2 if defaults is None else defaults, np.float32)
    seeds = {"train": jnp.asarray(train_seeds, jnp.int32), "test": jnp.asarray(test_seeds, jnp.int32)}

    def program(split_name):
        s = seeds[split_name]

        def run(pop):
            cost = jax.vmap(lambda x: jax.vmap(lambda k: fn(x, k))(s))(pop)[:, None, :]  # [P, 1, R]
            return cost, {"cost": cost}

        return run

    dummy = Split(np.zeros((1, 2), np.int64), np.zeros((1, 2), np.int64), np.ones(1), tuple(train_seeds))
    test = dummy._replace(seeds=tuple(test_seeds))
    return Objective(name, "function", name, bounds, np.clip(defaults, bounds.low, bounds.high), {"cost": 1.0},
                     {"train": dummy, "test": test}, program,
                     {n: np.asarray(v) for n, v in zip(bounds.names, defaults, strict=True)})
