"""The papers' ACO planners as presets of the colony engine, registered with their batch (every scenario × seed
in one compiled call, what `jaxplan.plan_batch` runs for them).

Defaults are the papers' values. Where a paper is silent jaxplan chooses,
and says so here:
  * ``dead_end``: ``"retreat"`` for ``aco`` (Ant System), ``iaco`` and ``risk_aco`` (the papers
    do not say; with dying ants half of room-64-64-8's runs fail, docs/decisions.md, so a
    baseline that dies would lose comparisons for a reason that is not its rule; ``"die"`` is
    still there to ask for), ``"alert"`` for ``opt_ant`` (chu2024; the ant steps
    back and the dead end becomes a pseudo-obstacle of the run),
    ``"retreat"`` with the edge penalty for ``praco`` (yu2020).
  * τ0 = 1 where a paper gives no initial pheromone (``aco``, ``iaco``, ``praco``);
    chen2023's constant f(0) is ``f0 = 1``.
  * ``praco`` on grids uses α = 1, β = 7 like the other grid presets (yu2020 gives
    no values); its TSP mode uses β = 5.
  * ``max_steps`` defaults to ``min(free cells, 4·(H + W))``.
  * ``keep_pheromone=True`` (every ACO planner; not a paper parameter) also returns the
    final pheromone: ``BatchResult.tau`` and ``PlanResult.info["tau"]`` (for plots).
  * ``walk_backend`` (every ACO planner; not a paper parameter): ``"auto"`` (default) walks
    the ants in one numba call per iteration when JAX runs on the CPU and in the JAX step
    loop elsewhere; ``"jax"`` / ``"numba"`` force one. Both give identical results.
  * ``update_backend`` (every ACO planner; not a paper parameter): where each iteration's path
    statistics and deposits are computed, ``"auto"`` (numba on the CPU), ``"jax"`` or
    ``"numba"``; the two may differ in the last bits of summed statistics (summation order).
    ``walk_backend="jax", update_backend="jax"`` needs no numba compilation at all (once per
    install, for the walk, statistics and deposit kernels), which pays for small colonies run
    once (the demo does this).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any, Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh
from jax.sharding import PartitionSpec as P
from numpy.typing import ArrayLike

from jaxplan.aco import _rules as R
from jaxplan.aco._colony import HEURISTICS, Colony, RunConfig, RunOutput, run_batch, walk_backend
from jaxplan.aco._context import GoalTables, MapTables, check_one, goal_tables, map_tables
from jaxplan.aco._objective import objective_variants
from jaxplan.aco._walk_numba import WALK_BACKENDS, sharing_cores
from jaxplan.core.cache import Built, digest, memoize
from jaxplan.core.progress import ProgressBar
from jaxplan.grid import GridMap, passable
from jaxplan.registry import BatchFn, MemoryFn, Seeds, check_seeds, register_planner, seed_count
from jaxplan.result import BatchResult, PlanResult
from jaxplan.scale import (
    BATCH_AXIS,
    Knob,
    MemoryEstimate,
    aco_memory,
    auto_mesh,
    check_memory,
    check_mesh,
    pad_leading,
    padded_size,
)

__all__ = ["COLONIES", "aco_defaults", "STATIC_PARAMS", "UNIT_PARAMS", "seed_keys", "split_params",
           "cached_map_tables"]

COLONIES: dict[str, Colony] = {
    "aco": Colony("aco", R.init_uniform, R.cost_length, (R.deposit_inverse,)),
    "iaco": Colony("iaco", R.init_uniform, R.cost_iaco, (R.deposit_inverse, R.deposit_elite)),
    "risk_aco": Colony("risk_aco", R.init_obstacle_aware, R.cost_risk, (R.deposit_inverse,)),
    "opt_ant": Colony(
        "opt_ant", R.init_opt_ant, R.cost_opt_ant, (R.deposit_inverse,), bound=R.bound_min_max,
        evaporation="residual", hook=R.hook_opt_ant, heuristic_in_hook=True, hook_logits=R.hook_opt_ant_logits,
    ),
    "praco": Colony("praco", R.init_uniform, R.cost_praco, (R.deposit_ranked, R.deposit_neighbour)),
}

_COMMON = {"ants": 50, "iterations": 50, "alpha": 1.0, "beta": 7.0, "connectivity": 8, "max_steps": None,
           "heuristic": "euclidean", "dead_end": "retreat", "vehicle_height": None, "keep_pheromone": False,
           "walk_backend": "auto", "update_backend": "auto"}

_DEFAULTS: dict[str, dict[str, Any]] = {
    "aco": {**_COMMON, "rho": 0.3, "q": 100.0, "tau0": 1.0},  # dead_end "retreat" since issue 43 (was "die")
    "iaco": {**_COMMON, "rho": 0.3, "q": 100.0, "tau0": 1.0, "lambdas": (0.5, 0.3, 0.2), "delta": 0.7},
    "risk_aco": {**_COMMON, "ants": 100, "beta": 8.0, "rho": 0.3, "q": 110.0, "u": 100.0, "v": 1.0, "w": 100.0,
                 "f0": 1.0},
    "opt_ant": {**_COMMON, "connectivity": 16, "iterations": 30, "dead_end": "alert", "c_init": 20.0, "q": 100.0,
                "rho_res": 0.3, "sigma": 0.125, "tau_min": 10.0, "tau_max": 40.0, "a": 1.0, "b": 100.0, "c": 1.0,
                "mu": 0.5, "vehicle_height": 0.5},
    "praco": {**_COMMON, "ants": 35, "iterations": 100, "colonies": 5, "w_rank": 6.0, "n_exchange": 3.0,
              "rho": 0.3, "lambda_p": 0.3, "omega1": 1.0, "omega2": 1.0, "tau0": 1.0},
}

STATIC_PARAMS = ("ants", "iterations", "connectivity", "max_steps", "heuristic", "dead_end", "vehicle_height",
                 "colonies", "keep_pheromone", "walk_backend", "update_backend")
"""ACO parameters that shape the compiled program (every other parameter is a traced leaf of ``params``)."""
UNIT_PARAMS = ("rho", "rho_res", "lambda_p", "delta")
"""ACO parameters that must lie in [0, 1]."""
_DESCRIPTIONS = {
    "aco": "Ant System (Dorigo): uniform τ0, η = 1/distance to goal, deposit Q/L",
    "iaco": "cui2025 IACO: multi-objective fitness λ·(L/L0, Σ|θ|/π, Σ1/d), elite reinforcement δ",
    "risk_aco": "chen2023: obstacle-aware τ0, cost B = u·P + v·H(risk) + w·T",
    "opt_ant": "chu2024 Opt Ant: 16 directions, height-aware τ0 and η, S = a·L + b·R + c·H, MMAS, dead-end alert, "
               "right-hand rule",
    "praco": "yu2020 P-RACO: ranked sub-colonies on a ring, dead-corner step-back with penalty, Z = ω1·L + ω2·N",
}


def aco_defaults(name: str) -> dict[str, Any]:
    """A copy of the defaults of ACO planner ``name``."""
    return dict(_DEFAULTS[name])


def _real(name: str, key: str, value: Any, default: Any) -> np.ndarray:
    """``value`` as float64, checked to be real numbers of ``default``'s shape: NumPy would read ``True`` or
    ``"1.0"`` as 1.0, and a list where a scalar belongs passes until it breaks a broadcast mid-run."""
    items = value if isinstance(value, (list, tuple)) else [value]
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf" or any(isinstance(x, (bool, np.bool_, str)) for x in items):
        raise ValueError(f"planner {name!r}: parameter {key!r} must be a real number (not a bool or a string)"
                         f"{'' if np.ndim(default) == 0 else ' per component'}, got {value!r}")
    if arr.shape != np.shape(default):
        want = "a single number" if np.ndim(default) == 0 else f"{np.size(default)} numbers"
        raise ValueError(f"planner {name!r}: parameter {key!r} must be {want}, got {value!r}")
    return arr.astype(np.float64)


def _validate(name: str) -> Callable[[Mapping[str, Any]], None]:
    def check(p: Mapping[str, Any]) -> None:
        for k in ("ants", "iterations", "colonies"):
            if k in p and (not isinstance(p[k], (int, np.integer)) or isinstance(p[k], bool) or p[k] < 1):
                raise ValueError(f"planner {name!r}: {k} must be a positive integer, got {p[k]!r}")
        if p["max_steps"] is not None and (not isinstance(p["max_steps"], (int, np.integer))
                                           or isinstance(p["max_steps"], bool) or p["max_steps"] < 1):
            raise ValueError(f"planner {name!r}: max_steps must be a positive integer or None, got {p['max_steps']!r}")
        if p["connectivity"] not in (4, 8, 16):
            raise ValueError(f"planner {name!r}: connectivity must be one of (4, 8, 16), got {p['connectivity']!r}")
        if p["heuristic"] not in HEURISTICS:
            raise ValueError(f"planner {name!r}: heuristic must be one of {HEURISTICS}, got {p['heuristic']!r}")
        if p.get("walk_backend", "auto") not in WALK_BACKENDS:
            raise ValueError(f"planner {name!r}: walk_backend must be one of {WALK_BACKENDS}, "
                             f"got {p['walk_backend']!r}")
        if p.get("update_backend", "auto") not in WALK_BACKENDS:
            raise ValueError(
                f"planner {name!r}: update_backend must be one of {WALK_BACKENDS}, got {p['update_backend']!r}")
        if not isinstance(p.get("keep_pheromone", False), (bool, np.bool_)):
            raise ValueError(f"planner {name!r}: keep_pheromone must be True or False, got {p['keep_pheromone']!r}")
        vh = p["vehicle_height"]
        if vh is not None and (not math.isfinite(vh) or vh < 0):
            raise ValueError(f"planner {name!r}: vehicle_height must be a finite height >= 0, got {vh!r}")
        if "lambdas" in p and np.shape(p["lambdas"]) != (3,):
            raise ValueError(f"planner {name!r}: lambdas must be three weights (λ1, λ2, λ3), got {p['lambdas']!r}")
        for k, v in p.items():
            if k in STATIC_PARAMS:
                continue
            arr = _real(name, k, v, _DEFAULTS[name][k])
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"planner {name!r}: parameter {k!r} must be finite, got {v!r}")
            if np.any(arr < 0):
                raise ValueError(f"planner {name!r}: parameter {k!r} must be >= 0, got {v!r}")
            if k in UNIT_PARAMS and np.any(arr > 1):
                raise ValueError(f"planner {name!r}: parameter {k!r} must lie in [0, 1], got {v!r}")
        if "lambdas" in p and not np.sum(p["lambdas"]) > 0:
            raise ValueError(f"planner {name!r}: lambdas must have a weight > 0 (all zero, every path costs 0), "
                             f"got {p['lambdas']!r}")
        for k in ("w_rank", "n_exchange"):  # counts of ranked ants (yu2020, Eq. 10)
            if k in p and not (float(p[k]).is_integer() and p[k] >= 1):
                raise ValueError(f"planner {name!r}: parameter {k!r} must be a whole number >= 1, got {p[k]!r}")
        if "tau_min" in p and not (0 < p["tau_min"] <= p["tau_max"]):
            raise ValueError(f"planner {name!r}: need 0 < tau_min <= tau_max, got {p['tau_min']}, {p['tau_max']}")
        for k in ("q", "tau0", "u", "a", "omega1", "f0", "c_init"):
            if k in p and not p[k] > 0:
                raise ValueError(f"planner {name!r}: parameter {k!r} must be > 0, got {p[k]!r}")

    return check


def split_params(grid: GridMap, p: Mapping[str, Any]) -> tuple[RunConfig, dict, int, float | None]:
    """Splits resolved parameters into the static `RunConfig` and the traced params pytree."""
    H, W = grid.shape
    free = int(passable(grid, p["vehicle_height"]).sum())
    max_steps = p["max_steps"] or max(1, min(free, 4 * (H + W)))
    cfg = RunConfig(
        colonies=int(p.get("colonies", 1)),
        ants=int(p["ants"]),
        iterations=int(p["iterations"]),
        max_steps=int(max_steps),
        width=W,
        heuristic=p["heuristic"],
        dead_end=p["dead_end"],
        # yu2020's dead-corner penalty falls on the edges an ant retreats over: none without retreat.
        penalise="lambda_p" in p and p["dead_end"] == "retreat",
        keep_pheromone=bool(p.get("keep_pheromone", False)),
        walk_backend=p.get("walk_backend", "auto"),
        update_backend=p.get("update_backend", "auto"),
    )
    params = {k: jnp.asarray(v, jnp.float32) for k, v in p.items() if k not in STATIC_PARAMS}
    return cfg, params, int(p["connectivity"]), p["vehicle_height"]


def _tables_key(grid: GridMap, connectivity: int, vehicle_height: float | None) -> tuple:
    layers = (grid.free, grid.height, grid.clearance_height, grid.risk, grid.turn_rule)
    return digest(*layers), float(grid.resolution), connectivity, vehicle_height


@memoize(maxsize=8, key=_tables_key)
def cached_map_tables(grid: GridMap, connectivity: int, vehicle_height: float | None) -> MapTables:
    """`map_tables`, memoised on the map's layers and the move rules."""
    return map_tables(grid, connectivity, vehicle_height)


def _program_key(colony: Colony, cfg: RunConfig, tables: MapTables, goals: GoalTables, params: dict, keys: jax.Array,
                 mesh: Mesh | None) -> tuple:
    sig = jax.tree_util.tree_map(lambda a: (a.shape, a.dtype), (tables, goals, params, keys))
    return colony, cfg, str(jax.tree_util.tree_structure(sig)), str(jax.tree_util.tree_leaves(sig)), mesh


def compiled(colony: Colony, cfg: RunConfig, tables: MapTables, goals: GoalTables, params: dict, keys: jax.Array,
             mesh: Mesh | None = None) -> tuple[Any, float]:
    """The compiled batch program for these shapes, and the seconds spent compiling it now (0 if cached).

    With a ``mesh`` (`jaxplan.scale.batch_mesh`), the scenario axis of ``goals`` (a multiple of
    the mesh's devices) is split over its devices with `jax.shard_map`; the map tables, params
    and keys are replicated. Every run depends only on its own scenario and key, so the result
    equals the single-device one. Programs are kept by (colony, config, argument shapes, mesh), so
    a call's time can be reported without its one-off compilation.
    """
    return _program(colony, cfg, tables, goals, params, keys, mesh).take()


@memoize(maxsize=32, key=_program_key)
def _program(colony: Colony, cfg: RunConfig, tables: MapTables, goals: GoalTables, params: dict, keys: jax.Array,
             mesh: Mesh | None) -> Built:
    t0 = time.perf_counter()
    body = lambda t, g, p, k: run_batch(colony, cfg, t, g, p, k)  # noqa: E731
    if mesh is not None:
        # check_vma=False: the numba walk is an FFI custom call, whose outputs carry no
        # varying-axes annotation; every output really is per shard (split along BATCH_AXIS).
        body = jax.shard_map(body, mesh=mesh, in_specs=(P(), P(BATCH_AXIS), P(), P()), out_specs=P(BATCH_AXIS),
                             check_vma=False)
    with sharing_cores(1 if mesh is None else len(mesh.local_devices)):
        fn = jax.jit(body).lower(tables, goals, params, keys).compile()
    return Built(fn, time.perf_counter() - t0)


def seed_keys(seeds: Seeds) -> jax.Array:
    """``key[R]`` PRNG keys of integer seeds (``jax.random.key(seed)`` each); bad seeds raise ``ValueError``."""
    s = check_seeds(seeds)
    if jax.random.key_impl(jax.random.key(0)) == jax.random.key_impl(jax.random.key(0, impl="threefry2x32")):
        # jax.random.key(s) is threefry's (0, s): building the data on the host avoids tracing
        # a vmap of jax.random.key on every call (~4 ms).
        return jax.random.wrap_key_data(jnp.asarray(np.stack([np.zeros_like(s), s], axis=1).astype(np.uint32)))
    return jax.vmap(jax.random.key)(jnp.asarray(s, jnp.uint32))


def _colony_memory(name: str, grid: GridMap, cfg: RunConfig, connectivity: int, runs: int) -> MemoryEstimate:
    colony = COLONIES[name]
    variants = objective_variants(name, connectivity) if cfg.heuristic == "objective" else 0
    return aco_memory(grid.n_cells, connectivity, runs, cfg.colonies, cfg.ants, cfg.max_steps, cfg.iterations,
                      keep_pheromone=cfg.keep_pheromone, hook=colony.hook is not None, penalty=cfg.penalise,
                      alert=cfg.dead_end == "alert", jax_walk=walk_backend(colony, cfg) == "jax",
                      objective_variants=variants)


def _ants_knob(name: str, grid: GridMap, cfg: RunConfig, connectivity: int, runs: int) -> Knob:
    """The ant count as a refusal's knob: the largest ``ants`` that fits is the advice when one run does not."""
    return Knob("ants" if cfg.colonies == 1 else "ants per colony", cfg.ants,
                lambda n: _colony_memory(name, grid, dataclasses.replace(cfg, ants=n), connectivity, runs))


def _colony_what(name: str, grid: GridMap, cfg: RunConfig) -> str:
    return f"planner {name!r} with {cfg.colonies * cfg.ants} ants on a {grid.shape[0]}x{grid.shape[1]} map"


def _memory(name: str) -> MemoryFn:
    def memory(grid: GridMap, p: Mapping[str, Any], runs: int) -> MemoryEstimate:
        cfg, _, connectivity, _ = split_params(grid, p)
        return _colony_memory(name, grid, cfg, connectivity, runs)

    return memory


def _run_colony(name: str, grid: GridMap, starts: np.ndarray, goals: np.ndarray, seeds: Seeds, p: Mapping[str, Any],
                keep_pheromone: bool = False, mesh: Mesh | None = None,
                bar: ProgressBar | None = None) -> tuple[RunOutput, float, float, int]:
    cfg, params, connectivity, vh = split_params(grid, p)
    if keep_pheromone:
        cfg = RunConfig(**{**cfg.__dict__, "keep_pheromone": True})
    N = len(starts)
    colony = COLONIES[name]
    runs = (N if mesh is None else padded_size(N, check_mesh(mesh))) * seed_count(seeds)
    # Refuse a batch that cannot fit before anything of it is allocated (on a mesh, per device).
    devices = 1 if mesh is None else mesh.devices.size
    check_memory(_colony_memory(name, grid, cfg, connectivity, runs // devices), _colony_what(name, grid, cfg),
                 unit="runs (scenarios x seeds)" + (" per device" if devices > 1 else ""),
                 advice="Plan fewer scenarios or seeds per call",
                 knob=_ants_knob(name, grid, cfg, connectivity, runs // devices))
    tables = cached_map_tables(grid, connectivity, vh)
    keys = seed_keys(seeds)
    gt = goal_tables(grid, starts, goals, connectivity, vh, geodesic=cfg.heuristic == "geodesic",
                     objective=(name, p) if cfg.heuristic == "objective" else None)
    if mesh is not None:
        gt = pad_leading(gt, padded_size(N, mesh))  # copies of the last scenario, sliced off below
    if bar is not None:
        bar.stage(f"{name}: compiling the batch program")
    fn, compile_s = compiled(colony, cfg, tables, gt, params, keys, mesh)
    if bar is not None:
        bar.stage(f"{name}: {N} scenarios x {len(keys)} seeds, {cfg.iterations} iterations (one compiled call)")
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(tables, gt, params, keys))
    if mesh is not None:
        out = jax.tree_util.tree_map(lambda a: a[:N], out)
    return out, time.perf_counter() - t0, compile_s, grid.width


def _to_batch(name: str, out: RunOutput, time_s: float, compile_s: float, width: int) -> BatchResult:
    cells = np.asarray(out.cells, np.int64)
    n_cells = np.asarray(out.n, np.int64) + 1
    success = np.asarray(out.success)
    n_cells = np.where(success, n_cells, 0)
    P = cells.shape[-1]
    valid = np.arange(P)[None, None, :] < n_cells[..., None]
    paths = np.where(valid[..., None], np.stack([cells % width, cells // width], axis=-1), -1)
    return BatchResult(
        paths=paths, n_cells=n_cells, length=np.where(success, np.asarray(out.length, np.float64), np.inf),
        cost=np.asarray(out.cost, np.float64), turns=np.where(success, np.asarray(out.turns), 0).astype(np.int64),
        success=success, converged=np.asarray(out.converged), history=np.asarray(out.history, np.float64),
        diversity=np.asarray(out.diversity, np.float64), successes=np.asarray(out.successes), time_s=time_s,
        compile_s=compile_s, planner=name, tau=None if out.tau is None else np.asarray(out.tau),
    )


def _empty_batch(name: str, R: int, iterations: int) -> BatchResult:
    """The `BatchResult` of zero scenarios: every array ``[0, R, …]``, nothing compiled."""
    z = lambda *shape, dtype=np.float64: np.zeros((0, R) + shape, dtype)  # noqa: E731
    return BatchResult(paths=z(1, 2, dtype=np.int64), n_cells=z(dtype=np.int64), length=z(), cost=z(),
                       turns=z(dtype=np.int64), success=z(dtype=bool), converged=z(dtype=np.int64),
                       history=z(iterations), diversity=z(iterations), successes=z(iterations, dtype=np.int64),
                       time_s=0.0, compile_s=0.0, planner=name, tau=None)


def _plan_one(name: str) -> Callable[..., PlanResult]:
    def fn(grid: GridMap, start: ArrayLike, goal: ArrayLike, seed: int, **p: Any) -> PlanResult:
        check_one(grid, start, goal, p["vehicle_height"])
        out, dt, compile_s, width = _run_colony(name, grid, np.asarray([start]), np.asarray([goal]), [seed], p)
        return _to_batch(name, out, dt, compile_s, width).result(0, 0)

    return fn


def _batch(name: str) -> BatchFn:
    def batch(grid: GridMap, starts: np.ndarray, goals: np.ndarray, seeds: Seeds, p: Mapping[str, Any], *,
              mesh: Mesh | str | None = "auto", progress: bool = False) -> BatchResult:
        """Every scenario × seed of colony ``name`` in one compiled call (`jaxplan.plan_batch`)."""
        if len(starts) == 0:  # e.g. a host past the end of a multi-host sweep's scenarios
            if len(goals) != 0:
                raise ValueError(f"starts and goals differ in shape: {starts.shape} vs {goals.shape}")
            one = seeds if isinstance(seeds, (int, np.integer)) else [int(x) for x in seeds]
            return _empty_batch(name, len(seed_keys(one)), int(p["iterations"]))
        mesh_ = auto_mesh(mesh, len(starts))
        with ProgressBar(f"{name}: preparing", None, enabled=progress) as bar:
            out, dt, compile_s, width = _run_colony(name, grid, starts, goals, seeds, p, mesh=mesh_, bar=bar)
        return _to_batch(name, out, dt, compile_s, width)

    return batch


def _register() -> None:
    for name in COLONIES:
        register_planner(name, _plan_one(name), _DEFAULTS[name], _DESCRIPTIONS[name], _validate(name),
                         batch=_batch(name), memory=_memory(name))


_register()
