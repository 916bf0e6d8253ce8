"""`navigate`, `navigate_batch`, `navigate_multi`: two-level navigation from the host.

The steps of every episode (docs/guide/navigation.md):

1. **Planning map.** The map inflated for the robot: a free cell whose centre is closer
   than d_safe to a blocked square is closed for planning, so the global path fits the
   footprint. A scenario whose start or goal is closed, or whose goal the inflated map
   does not connect to the start, is *infeasible* for this robot: it is not run, and is
   reported with that reason (benchmarks count it apart). At 1.0 m per cell every free
   cell centre keeps 0.5 m, so nothing is closed for the cui2025 robot (0.3 m); at
   cui2025's 0.5 m per cell a one-cell aisle keeps only 0.25 m, narrower than the
   robot's own radius plus nothing — which is why the MovingAI maps run at 1.0 m.
2. **Global plan** with the pipeline's planner on the planning map (`plan_batch`: every
   scenario × seed in one compiled call for the ACO planners).
3. **Waypoints**: the pipeline's smoothers (`jaxplan.smoothing`, clearance d_safe) reduce
   the path; the start is dropped, the goal is the last waypoint.
4. **Episode**: `jaxplan.nav._episode.run_episodes`, one compiled call for the batch.
5. **Metrics** (docs/guide/smoothing-and-metrics.md) from the trajectories: success (goal within tolerance, no
   collision, within the time limit), collisions (contacts), time, RMSE to the polyline
   being tracked (after a re-plan, the new one), max curvature of the executed motion (|ω|/v over steps moving at least
   `CURVATURE_MIN_SPEED`; turning on the spot has no finite curvature), energy proxy
   (`jaxplan.metrics.EnergyModel`), planning and per-step times.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import Any, Mapping, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh
from jax.sharding import PartitionSpec as P
from numpy.typing import ArrayLike

from jaxplan.core.cache import Built, memoize
from jaxplan.core.deprecation import keyword_only
from jaxplan.core.progress import ProgressBar
from jaxplan.dwa import DWAParams, table_of
from jaxplan.grid import GridMap, clearance_field, shortest_lengths
from jaxplan.metrics import EnergyModel, energy
from jaxplan.mppi import MPPIParams
from jaxplan.nav._checks import check_obstacle_starts, checked_run, obstacle_sets
from jaxplan.nav._config import NavConfig
from jaxplan.nav._episode import run_episodes
from jaxplan.nav._moving import MovingObstacles, obstacle_state, stack_obstacles
from jaxplan.nav._pipelines import Pipeline
from jaxplan.nav._results import Episode, EpisodeBatch
from jaxplan.nav._state import GOAL, REASONS, EpisodeInputs
from jaxplan.scale import BATCH_AXIS, Knob, auto_mesh, check_memory, episode_memory, pad_leading

__all__ = ["navigate", "navigate_batch", "navigate_multi", "planning_grid", "prepare_episodes", "PreparedEpisodes",
           "CURVATURE_MIN_SPEED", "INFEASIBLE_START",
           "INFEASIBLE_GOAL", "UNREACHABLE", "PLAN_FAILED"]

CURVATURE_MIN_SPEED = 0.1
"""m/s: steps slower than this do not enter the executed max curvature (|ω|/v blows up at v → 0)."""

INFEASIBLE_START = "infeasible: start closer than d_safe to an obstacle"
INFEASIBLE_GOAL = "infeasible: goal closer than d_safe to an obstacle"
UNREACHABLE = "infeasible: goal not reachable for the inflated footprint"
PLAN_FAILED = "global planner found no path"
_NOT_RUN = (INFEASIBLE_START, INFEASIBLE_GOAL, UNREACHABLE, PLAN_FAILED)


def _compiled_episodes(cfg: NavConfig, steps: int, mesh: Mesh | None, args: tuple) -> tuple[Any, float]:
    """The compiled episode program for ``args = (table, free, params, inputs)``'s shapes, and the
    seconds spent compiling it now (0 if cached): one compilation per configuration and shape
    (the last 16 programs are kept).

    With a ``mesh`` the episode axis of ``inputs`` (a multiple of the devices and of
    `NavConfig.replan_group`) is split over its devices with `jax.shard_map`; the map and
    the DWA params are replicated.
    """
    return _episode_program(cfg, steps, mesh, args).take()


def _program_key(cfg: NavConfig, steps: int, mesh: Mesh | None, args: tuple) -> tuple:
    sig = jax.tree_util.tree_map(lambda a: (np.shape(a), str(jnp.result_type(a))), args)
    return cfg, steps, mesh, str(jax.tree_util.tree_structure(sig)), str(jax.tree_util.tree_leaves(sig))


@memoize(maxsize=16, key=_program_key)  # thread-safe: navigate_batch may be called from several threads
def _episode_program(cfg: NavConfig, steps: int, mesh: Mesh | None, args: tuple) -> Built:
    t0 = time.perf_counter()
    body = functools.partial(run_episodes, cfg, steps)
    if mesh is not None:
        # check_vma=False: the loop carries shard-local scalars (step counter, chunk index) beside
        # per-episode arrays; every output is per episode and split along BATCH_AXIS.
        body = jax.shard_map(body, mesh=mesh, in_specs=(P(), P(), P(), P(BATCH_AXIS)), out_specs=P(BATCH_AXIS),
                             check_vma=False)
    fn = jax.jit(body).lower(*args).compile()
    return Built(fn, time.perf_counter() - t0)


def planning_grid(grid: GridMap, d_safe: float) -> GridMap:
    """``grid`` with every free cell whose centre is closer than ``d_safe`` (m) to a blocked square closed."""
    field = clearance_field(grid)
    free = np.asarray(grid.free) & (field >= d_safe - 1e-9)
    return dataclasses.replace(grid, free=free) if dataclasses.is_dataclass(grid) else grid._replace(free=free)


# One compiled call per shape, not an op-by-op dispatch (each eager op compiles on its first shape).
_STATE = jax.jit(obstacle_state)
_ENERGY = jax.jit(lambda v, w, dt, n: energy(v, w, dt, EnergyModel(), n))


# ---------------------------------------------------------------------------------------------
# The run

def _global_plans(plan_grid: GridMap, starts: np.ndarray, goals: np.ndarray, ok: np.ndarray, pipe: Pipeline,
                  seeds: list[int], overrides: Mapping[str, Any], mesh: Mesh | str | None = "auto",
                  bar: ProgressBar | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Plans ``f64[S, R, P, 2]`` (cell coordinates, −1 padded), valid points ``[S, R]`` (0: failed) and the
    planning wall time (s, compilation excluded) for the ``ok`` rows of ``starts``/``goals [S, 2]``.

    A planner with its own batch (the ACO planners) runs every scenario × seed in one compiled call
    (`plan_batch`); the others are called per scenario (and per seed unless deterministic), and an any-angle
    planner's exact polyline (``info["points"]``) is used rather than its rasterised cells.
    """
    from jaxplan.planning import plan, plan_batch, planners

    S, R = len(starts), len(seeds)
    params = {**pipe.planner_overrides, **overrides}
    idx = np.nonzero(ok)[0]
    if idx.size == 0:
        return np.full((S, R, 2, 2), -1.0), np.zeros((S, R), np.int64), 0.0
    if bar is not None:
        bar.stage(f"{pipe.name}: global plans ({pipe.global_planner}, compiled on first use)")
    spec = planners().get(pipe.global_planner)  # None: plan() below names the unknown planner
    if spec is not None and spec.batch is not None:
        br = plan_batch(plan_grid, starts[idx], goals[idx], planner=pipe.global_planner, seeds=seeds, mesh=mesh,
                        **params)
        plans = np.full((S, R) + br.paths.shape[2:], -1.0)
        plans[idx] = br.paths
        n = np.zeros((S, R), np.int64)
        n[idx] = np.where(br.success, br.n_cells, 0)
        return plans, n, float(br.time_s)
    results: dict[tuple[int, int], Any] = {}
    t0 = time.perf_counter()
    for i in idx.tolist():  # per-scenario host planners (A*, RRT*): nothing to batch
        for r, seed in enumerate(seeds):
            if spec is not None and spec.deterministic and r > 0:
                results[i, r] = results[i, 0]
                continue
            res = plan(plan_grid, starts[i], goals[i], planner=pipe.global_planner, seed=seed, **params)
            pts = res.info.get("points", res.path) if res.success else np.zeros((0, 2))
            results[i, r] = np.asarray(pts, np.float64)
            if bar is not None:
                bar.stage(f"{pipe.name}: global plans ({pipe.global_planner}) {len(results)}/{idx.size * len(seeds)}")
    elapsed = time.perf_counter() - t0
    P = max(2, max(len(p) for p in results.values()))
    plans = np.full((S, R, P, 2), -1.0)
    n = np.zeros((S, R), np.int64)
    for (i, r), pts in results.items():
        plans[i, r, : len(pts)] = pts
        n[i, r] = len(pts)
    return plans, n, elapsed


def _bucket(n: int, lo: int = 8) -> int:
    return max(lo, 1 << max(0, int(n - 1).bit_length()))


def _feasibility(plan_free: np.ndarray, plan_grid: GridMap, s_flat: np.ndarray, g_flat: np.ndarray) -> np.ndarray:
    """Step 1: ``object[S]`` why each start/goal pair (``[S, 2]`` cells) is infeasible on the planning map, ``""``
    where it is feasible."""
    reason0 = np.full(len(s_flat), "", object)
    reason0[~plan_free[s_flat[:, 1], s_flat[:, 0]]] = INFEASIBLE_START
    reason0[(reason0 == "") & ~plan_free[g_flat[:, 1], g_flat[:, 0]]] = INFEASIBLE_GOAL
    ok = reason0 == ""
    if ok.any():
        lens = shortest_lengths(plan_grid, s_flat[ok], g_flat[ok])
        r = reason0[ok]
        r[~np.isfinite(lens)] = UNREACHABLE
        reason0[ok] = r
    return reason0


def _waypoints(grid: GridMap, pipe: Pipeline, plans: np.ndarray, n_plan: np.ndarray, run: np.ndarray,
               start_xy: np.ndarray, d_safe: float) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: waypoints ``f32[S, R, K, 2]`` (m) and their counts ``[S, R]``, the start dropped; a robot that
    does not run (``run [S, R]`` False) has its start (``start_xy [S, 2]``) as its only waypoint."""
    from jaxplan.smoothing import smooth

    res = float(grid.resolution)
    S, R = run.shape
    K = 1
    wp_m = np.broadcast_to(start_xy[:, None, None, :], (S, R, K, 2)).copy()
    n_wp = np.ones((S, R), np.int64)
    if run.any():
        sm = smooth(plans[run].astype(np.float32), grid, pipe.waypoints, n=n_plan[run], radius=d_safe)
        pts, n = np.asarray(sm.points, np.float64), np.asarray(sm.n)
        K = _bucket(int(n.max()) - 1)
        idx = np.minimum(np.arange(K)[None, :] + 1, (n - 1)[:, None])  # slots after the goal repeat it
        wp = np.take_along_axis(pts, idx[..., None], axis=1)
        wp_m = np.broadcast_to(start_xy[:, None, None, :], (S, R, K, 2)).copy()
        wp_m[run] = ((wp + 0.5) * res).astype(np.float32)
        n_wp[run] = n - 1
    return wp_m, n_wp


def _initial_states(cfg: NavConfig, start_xy: np.ndarray, wp_m: np.ndarray,
                    time_limit: float | None) -> tuple[np.ndarray, np.ndarray]:
    """``(f32[S, R, 5] states at rest facing the first waypoint, time limits [S, R] in s)``: the default limit is
    60 s + 3 × the waypoint polyline's length at v_max, capped at `NavConfig.max_time`."""
    R = wp_m.shape[1]
    first = wp_m[:, :, 0]  # [S, R, 2]
    heading = np.arctan2(first[..., 1] - start_xy[:, None, 1], first[..., 0] - start_xy[:, None, 0])
    state0 = np.zeros(first.shape[:2] + (5,), np.float32)
    state0[..., 0:2] = start_xy[:, None]
    state0[..., 2] = heading
    poly_len = np.sum(np.hypot(*np.diff(np.concatenate([start_xy[:, None, None, :].repeat(R, 1), wp_m], axis=2),
                                        axis=2).transpose(3, 0, 1, 2)), axis=-1)
    limit = np.minimum(cfg.max_time, 60.0 + 3.0 * poly_len / float(cfg.dwa.robot.v_max)) if time_limit is None else \
        np.full(first.shape[:2], time_limit)
    return state0, limit


def _shift_obstacles(obs: MovingObstacles, delta: np.ndarray) -> MovingObstacles:
    """``obs`` with its routes moved by ``delta [2]`` metres (between the world and the map's frame)."""
    return obs._replace(waypoints=jnp.asarray(np.asarray(obs.waypoints) + delta.astype(np.float32)))


def _episode_obstacles(obstacles: Any, E: int, N: int, seeds: list[int], start_xy: np.ndarray,
                       radius: float, origin: np.ndarray | None = None) -> MovingObstacles:
    """Step 4: the obstacle sets of the ``E × R`` episodes stacked (``[E*R, M, ...]``); none may start inside a
    robot (``start_xy [E*N, 2]``). Routes come in world coordinates; with a map ``origin`` they are moved into the
    map's frame, where the episodes run."""
    R = len(seeds)
    sets = obstacle_sets(obstacles, E, R, seeds)
    for e in range(E):
        for r in range(R):
            if not isinstance(sets[e][r], MovingObstacles):
                raise ValueError(f"obstacles for scenario {e}, seed {seeds[r]} must be MovingObstacles")
    obs = stack_obstacles([sets[e][r] for e in range(E) for r in range(R)])  # [E*R, M, ...]
    if origin is not None:
        obs = _shift_obstacles(obs, -origin)
    if obs.count:
        # Positions at t = 0 of every set in one compiled call (padding slots are parked far away).
        pos0, rad0 = np.asarray(_STATE(obs, 0.0)[0]), np.asarray(obs.radii)
        for e in range(E):
            for r in range(R):
                check_obstacle_starts(pos0[e * R + r], rad0[e * R + r], start_xy.reshape(E, N, 2)[e], radius,
                                       f"scenario {e}, seed {seeds[r]}")
    return obs


def _to_episodes(x: ArrayLike, E: int, N: int, R: int) -> np.ndarray:
    """``[E*N, R, ...]`` -> episodes ``[E*R, N, ...]`` (B = E*R episodes of N robots)."""
    x = np.asarray(x)
    return x.reshape((E, N, R) + x.shape[2:]).swapaxes(1, 2).reshape((E * R, N) + x.shape[2:])


def _execute(cfg: NavConfig, grid: GridMap, plan_free: np.ndarray, params: DWAParams | MPPIParams,
             inputs: EpisodeInputs, mesh: Mesh | str | None,
             bar: ProgressBar | None = None) -> tuple[Any, float, float]:
    """Step 4: the episode program on the ``B`` episodes of ``inputs``, split over a mesh when results do not
    depend on it; returns its outputs (numpy, ``[B, ...]``), compile and run seconds."""
    steps = cfg.steps
    table = table_of(grid)
    free_j = jnp.asarray(plan_free)
    B = inputs.start.shape[0]
    # Results are independent of the device count only when the re-planning budget is per group
    # of episodes (or there is no re-planning): only then does "auto" split the episodes.
    G = cfg.replan_group if cfg.replan else 1  # episodes per re-planning group (0: the whole batch)
    mesh_ = auto_mesh(mesh, B) if (G > 0 or not isinstance(mesh, str)) else None
    if mesh_ is not None and isinstance(mesh, str) and -(-B // max(G, 1)) < mesh_.devices.size:
        mesh_ = None  # "auto": fewer groups than devices would leave a device only padding
    if mesh_ is not None:  # every device a whole number of groups: copies that do not run, sliced off below
        unit = max(G, 1) * mesh_.devices.size
        B_pad = -(-B // unit) * unit
        if B_pad != B:
            inputs = pad_leading(inputs, B_pad)
            inputs = inputs._replace(active=inputs.active.at[B:].set(False))
    if bar is not None:
        bar.stage(f"compiling the episode program ({cfg.local})")
    compiled, compile_s = _compiled_episodes(cfg, steps, mesh_, (table, free_j, params, inputs))
    if bar is not None:
        bar.stage(f"{B} episodes of up to {steps} steps (one compiled call)")
    t0 = time.perf_counter()
    out = jax.block_until_ready(compiled(table, free_j, params, inputs))
    run_s = time.perf_counter() - t0
    out = jax.tree_util.tree_map(lambda a: np.asarray(a)[:B], out)
    return out, compile_s, run_s


def _episode_batch(out: Any, E: int, R: int, N: int, active: np.ndarray, reason: np.ndarray, plans: np.ndarray,
                   n_plan: np.ndarray, wp_m: np.ndarray, n_wp: np.ndarray, obs: MovingObstacles, period: float,
                   timing: tuple[float, float, float], pipeline: str, res: float) -> EpisodeBatch:
    """Step 5: the metrics of the episodes (``out``, ``[E*R, N, ...]``) and the `EpisodeBatch`, axes ``[E, R, N]``.
    ``reason``, ``plans``, ``n_plan``, ``wp_m``, ``n_wp`` are per robot and seed (``[E*N, R, ...]``);
    ``timing``: the seconds spent planning, compiling and running the episodes."""
    plan_time, compile_s, run_s = timing

    def back(x):
        x = np.asarray(x)
        return x.reshape((E, R, N) + x.shape[2:])

    to_b = functools.partial(_to_episodes, E=E, N=N, R=R)
    states = back(out.states.swapaxes(1, 2))  # [B, N, S+1, 5] -> [E, R, N, S+1, 5]
    controls = back(out.controls.swapaxes(1, 2))
    recovery = back(out.recovery.swapaxes(1, 2))
    n_steps = back(out.steps)
    code = back(out.reason)
    active_e = back(active)
    reason_txt = np.where(active_e, np.asarray(REASONS, object)[code], back(to_b(reason)))
    coll = back(out.collisions)
    success = active_e & (code == GOAL) & (coll == 0)
    t_s = n_steps * period
    pos = states[..., :2]
    valid_n = n_steps + 1
    rm = back(out.rmse)
    v, w = controls[..., 0], controls[..., 1]
    live = np.arange(controls.shape[-2]) < n_steps[..., None]
    fast = live & (np.abs(v) >= CURVATURE_MIN_SPEED)
    kappa = np.max(np.where(fast, np.abs(w) / np.maximum(np.abs(v), CURVATURE_MIN_SPEED), 0.0), axis=-1)
    vs = np.concatenate([states[..., :1, 3], v], axis=-1)  # velocity samples at 0, P, 2P, ...
    ws = np.concatenate([states[..., :1, 4], w], axis=-1)
    en = np.asarray(_ENERGY(jnp.asarray(vs), jnp.asarray(ws), period, jnp.asarray(valid_n)))
    seg = np.hypot(*np.diff(pos, axis=-2).transpose(4, 0, 1, 2, 3))
    length = np.sum(np.where(live, seg, 0.0), axis=-1)
    robot_steps = max(int(np.sum(n_steps)), 1)
    nan = np.where(active_e, 1.0, np.nan)
    return EpisodeBatch(  # type: ignore[call-arg]  # mypy reads EpisodeBatch.METRICS as a field
        states=states, steps=n_steps, controls=controls, recovery=recovery, reason=reason_txt,
        feasible=back(to_b(~np.isin(reason, (INFEASIBLE_START, INFEASIBLE_GOAL, UNREACHABLE)))),
        success=success, collisions=coll, active_contacts=back(out.active_contacts),
        passive_contacts=coll - back(out.active_contacts), pair_collisions=back(out.pair_collisions), time_s=t_s * nan,
        rmse=rm * nan, max_curvature=kappa * nan, energy=en * nan, path_length=length * nan,
        recoveries=np.sum(recovery & live, axis=-1), replans=back(out.replans),
        plans=back(to_b(plans)), n_plan=back(to_b(n_plan)), waypoints=back(to_b(wp_m)),
        n_waypoints=back(to_b(n_wp)), final_waypoints=back(out.waypoints), n_final_waypoints=back(out.n_waypoints),
        obstacles=jax.tree_util.tree_map(lambda x: np.asarray(x).reshape((E, R) + x.shape[1:]), obs),
        plan_time_s=plan_time / max(E * R * N, 1), step_time_s=run_s / robot_steps, run_time_s=run_s,
        compile_s=compile_s, period=period, pipeline=pipeline, resolution=res,
        obstacle_positions=None if out.walkers is None else np.asarray(out.walkers).reshape(
            (E, R) + out.walkers.shape[1:]),
        give_ways=np.zeros_like(n_steps) if out.give_ways is None else back(out.give_ways),
    )


def _check_episode_memory(cfg: NavConfig, grid: GridMap, robots: int, obstacles: Any) -> None:
    """Refuses, before any planning, a batch of episodes whose working memory exceeds the limit
    (`jaxplan.scale.episode_memory`: the local planner's samples and rollout points per robot dominate; discs of an
    obstacle set given as a callable are not known yet and counted as none: they add little)."""
    if cfg.local == "mppi":
        mc = cfg.local_mppi()
        samples, points = mc.samples, mc.points
    else:
        samples, points = cfg.dwa.samples, cfg.dwa.steps
    discs = obstacles.count if isinstance(obstacles, MovingObstacles) else 0
    est = lambda n: episode_memory(robots, cfg.steps, n, rollout_steps=points, discs=discs,  # noqa: E731
                                   map_cells=int(np.asarray(grid.free).size))
    check_memory(est(samples), f"navigation ({cfg.local}, {robots} robot episodes of up to {cfg.steps} steps)",
                 unit="robot episodes (scenarios x seeds x robots)", advice="Use fewer scenarios, seeds or robots",
                 knob=Knob(f"{cfg.local} samples", samples, est))


def _run(grid: GridMap, starts: np.ndarray, goals: np.ndarray, pipeline: str | None, global_planner: str | None,
         local_planner: str | None, seeds: Sequence[int], obstacles: Any, config: NavConfig | None,
         params: DWAParams | MPPIParams | Mapping[str, float] | None, time_limit: float | None,
         overrides: Mapping[str, Any], mesh: Mesh | str | None = "auto", progress: bool = False) -> EpisodeBatch:
    """The steps of the module docstring for ``starts, goals [E, N, 2]`` (cells) × seeds: an `EpisodeBatch`
    ``[E, R, N]``; ``progress``: the stages on stderr (`jaxplan.core.progress`, only on a terminal)."""
    with ProgressBar("navigation: checking", None, enabled=progress) as bar:
        return _run_steps(grid, starts, goals, pipeline, global_planner, local_planner, seeds, obstacles, config,
                          params, time_limit, overrides, mesh, bar if bar.active else None)


class PreparedEpisodes(NamedTuple):
    """Steps 1-4 of a navigation call (the module docstring) before the episode program runs: what
    `run_episodes` takes, and how the episodes were laid out. Built by `prepare_episodes`.

    Attributes:
      config: the resolved `NavConfig`; steps: the buffer length (`NavConfig.steps`).
      table: the map's `ClearanceTable`; free: ``bool[H, W]`` the planning map (inflated to d_safe).
      params: the checked default local-planner params (`DWAParams` / `MPPIParams`).
      inputs: `EpisodeInputs` of the ``B = E·R`` episodes (scenario-major, then seed) of ``N`` robots.
      reason: ``object[E·N, R]`` why a robot does not run (``""``: it runs).
      E, R, N: scenarios, seeds, robots per episode.
    """

    config: NavConfig
    steps: int
    table: Any
    free: np.ndarray
    params: Any
    inputs: EpisodeInputs
    reason: np.ndarray
    E: int
    R: int
    N: int


def _prepare(grid: GridMap, starts: np.ndarray, goals: np.ndarray, pipeline: str | None,
             global_planner: str | None, local_planner: str | None, seeds: Sequence[int], obstacles: Any,
             config: NavConfig | None, params: DWAParams | MPPIParams | Mapping[str, float] | None,
             time_limit: float | None, overrides: Mapping[str, Any], mesh: Mesh | str | None,
             bar: ProgressBar | None) -> tuple:
    """Steps 1-4 of `_run_steps` (checks, planning map, global plans, waypoints, obstacles, inputs)."""
    run_args = checked_run(grid, starts, goals, pipeline, global_planner, local_planner, seeds, config, params,
                            time_limit, mesh)
    pipe, cfg, seeds, starts, goals = run_args.pipe, run_args.cfg, run_args.seeds, run_args.starts, run_args.goals
    E, N = starts.shape[:2]
    R = len(seeds)
    _check_episode_memory(cfg, grid, E * N * R, obstacles)
    res = float(grid.resolution)
    d_safe = float(cfg.dwa.d_safe)

    # 1. Planning map and feasibility.
    plan_grid = planning_grid(grid, d_safe)
    pf = np.asarray(plan_grid.free)
    s_flat, g_flat = starts.reshape(-1, 2), goals.reshape(-1, 2)
    reason0 = _feasibility(pf, plan_grid, s_flat, g_flat)
    ok = reason0 == ""

    # 2. Global plans on the planning map, in cell coordinates.
    plans, n_plan, plan_time = _global_plans(plan_grid, s_flat, g_flat, ok, pipe, seeds, overrides, mesh, bar)
    reason = np.repeat(reason0[:, None], R, axis=1)  # [E*N, R]
    reason[(reason == "") & (n_plan < 2)] = PLAN_FAILED
    run = reason == ""

    # 3. Waypoints (m) and the robots' initial states.
    start_xy = ((s_flat + 0.5) * res).astype(np.float32)
    goal_xy = ((g_flat + 0.5) * res).astype(np.float32)
    wp_m, n_wp = _waypoints(grid, pipe, plans, n_plan, run, start_xy, d_safe)
    state0, limit = _initial_states(cfg, start_xy, wp_m, time_limit)

    # 4. Obstacles per episode [E][R] (none may start inside a robot), and the episodes.
    origin = np.asarray(grid.origin, np.float64) if grid.has_origin else None
    obs = _episode_obstacles(obstacles, E, N, seeds, start_xy, run_args.radius, origin)
    to_b = functools.partial(_to_episodes, E=E, N=N, R=R)
    active = to_b(run)
    inputs = EpisodeInputs(
        start=jnp.asarray(to_b(state0)), goal=jnp.asarray(to_b(np.broadcast_to(goal_xy[:, None], (E * N, R, 2)))),
        goal_cell=jnp.asarray(to_b(np.broadcast_to(g_flat[:, None], (E * N, R, 2))).astype(np.int32)),
        waypoints=jnp.asarray(to_b(wp_m)), n_waypoints=jnp.asarray(to_b(n_wp).astype(np.int32)),
        time_limit=jnp.asarray(to_b(limit).astype(np.float32)), obstacles=obs, active=jnp.asarray(active),
        # Episode (scenario e, seed s) draws its MPPI noise from the key data (s, e).
        key=jnp.asarray(np.array([[s, e] for e in range(E) for s in seeds], np.uint32).reshape(E * R, 2)),
    )
    return run_args, pf, inputs, active, reason, plans, n_plan, wp_m, n_wp, obs, plan_time, origin


@keyword_only("pipeline", "seeds", "obstacles")
def prepare_episodes(grid: GridMap, starts: ArrayLike, goals: ArrayLike, *, pipeline: str | None = "iaco_dwa",
                     global_planner: str | None = None, local_planner: str | None = None,
                     seeds: Sequence[int] = range(1), obstacles: Any = None, config: NavConfig | None = None,
                     params: DWAParams | MPPIParams | Mapping[str, float] | None = None,
                     time_limit: float | None = None, mesh: Mesh | str | None = "auto",
                     safety: str | None = None, walker_speed_max: float | None = None,
                     **overrides: Any) -> PreparedEpisodes:
    """What `navigate_batch` runs, before it runs it: the checked arguments, the global plans, waypoints,
    obstacles and `EpisodeInputs` of ``starts, goals int[E, 2]`` × ``seeds`` (arguments as `navigate_batch`).

    ``run_episodes(p.config, p.steps, p.table, p.free, p.params, p.inputs)`` then gives exactly the
    episodes `navigate_batch` runs (on one device). Tuning reuses the global plans — they do not depend on the
    local planner's weights — for every weight vector (`jaxplan.tune.nav_objective`). The previous release's
    positional ``pipeline, seeds, obstacles`` still work for one release, with a `DeprecationWarning`.
    """
    s, g = np.asarray(starts), np.asarray(goals)
    if s.ndim != 2 or s.shape[-1] != 2 or g.shape != s.shape:
        raise ValueError(f"starts and goals must both be [E, 2] cells, got {s.shape} and {g.shape}")
    if pipeline is not None and global_planner is not None:
        pipeline = None
    config = _with_safety(config, safety, walker_speed_max)
    run_args, pf, inputs, _, reason, *_ = _prepare(grid, s[:, None], g[:, None], pipeline, global_planner,
                                                   local_planner, list(seeds), obstacles, config, params,
                                                   time_limit, overrides, mesh, None)
    cfg = run_args.cfg
    return PreparedEpisodes(cfg, cfg.steps, table_of(grid), pf, run_args.params, inputs, reason, len(s),
                            len(run_args.seeds), 1)


def _run_steps(grid: GridMap, starts: np.ndarray, goals: np.ndarray, pipeline: str | None,
               global_planner: str | None, local_planner: str | None, seeds: Sequence[int], obstacles: Any,
               config: NavConfig | None, params: DWAParams | MPPIParams | Mapping[str, float] | None,
               time_limit: float | None, overrides: Mapping[str, Any], mesh: Mesh | str | None,
               bar: ProgressBar | None) -> EpisodeBatch:
    """`_run` with its stages shown on ``bar`` (or None)."""
    run_args, pf, inputs, active, reason, plans, n_plan, wp_m, n_wp, obs, plan_time, origin = _prepare(
        grid, starts, goals, pipeline, global_planner, local_planner, seeds, obstacles, config, params, time_limit,
        overrides, mesh, bar)
    cfg = run_args.cfg
    E, N = run_args.starts.shape[:2]
    R = len(run_args.seeds)
    out, compile_s, run_s = _execute(cfg, grid, pf, run_args.params, inputs, mesh, bar)

    # 5. Metrics, back to [E, R, N, ...]; metres in world coordinates (the map's origin added).
    batch = _episode_batch(out, E, R, N, active, reason, plans, n_plan, wp_m, n_wp, obs, float(cfg.dwa.period),
                           (plan_time, compile_s, run_s), run_args.pipe.name, float(grid.resolution))
    return batch if origin is None else _batch_to_world(batch, origin)


def _batch_to_world(batch: EpisodeBatch, origin: np.ndarray) -> EpisodeBatch:
    """``batch`` with every position (states, waypoints, obstacle routes and positions) moved from the map's
    frame to the world by adding ``origin [2]`` (m); metrics are distances and stay as they are."""
    o = origin.astype(np.float32)

    def shift(a, cols=2):
        if a is None:
            return None
        a = np.array(a, copy=True)
        a[..., :cols] = a[..., :cols] + o.astype(a.dtype)
        return a

    return batch._replace(
        states=shift(batch.states), waypoints=shift(batch.waypoints), final_waypoints=shift(batch.final_waypoints),
        obstacles=_shift_obstacles(batch.obstacles, origin), obstacle_positions=shift(batch.obstacle_positions))


def _with_safety(config: NavConfig | None, safety: str | None, walker_speed_max: float | None) -> NavConfig | None:
    """``config`` with the fronts' ``safety`` and ``walker_speed_max`` keywords set (None: the config's own)."""
    if safety is None and walker_speed_max is None:
        return config
    changes = {k: v for k, v in (("safety", safety), ("walker_speed_max", walker_speed_max)) if v is not None}
    return (config or NavConfig()).replace(**changes)


# ---------------------------------------------------------------------------------------------
# Fronts


@keyword_only("global_planner", "local_planner", "seed", "obstacles")
def navigate(grid: GridMap, start: ArrayLike, goal: ArrayLike, *, pipeline: str | None = None,
             global_planner: str | None = None, local_planner: str | None = None, seed: int = 0,
             obstacles: MovingObstacles | None = None, config: NavConfig | None = None,
             params: DWAParams | MPPIParams | Mapping[str, float] | None = None, time_limit: float | None = None,
             progress: bool = False, safety: str | None = None, walker_speed_max: float | None = None,
             **overrides: Any) -> Episode:
    """One two-level navigation episode (docs/guide/navigation.md).

    Args:
      grid: the map.
      start, goal: cells ``(x, y)``.
      pipeline: a named pipeline (`jaxplan.nav.pipelines()`, e.g. ``"iaco_dwa"``) for a paper's system; giving it
        and ``global_planner`` both is an error.
      global_planner: without a pipeline, a registry planner (default ``"iaco"``), tracked through key nodes by a
        weighted DWA.
      local_planner: ``"dwa"`` (default), ``"mppi"`` or ``"follow"``.
      seed: the global planner's seed.
      obstacles: `MovingObstacles` (e.g. `jaxplan.random_obstacles`).
      config: `NavConfig` (robot, DWA settings, tolerances, re-planning).
      params: the local planner's weights: `DWAParams`, `MPPIParams` (``local_planner="mppi"``) or a dict of
        overrides.
      time_limit: seconds (default: 60 s + 3 × the waypoint polyline's length at v_max, capped
        at ``config.max_time``).
      progress: the stages on stderr (as `navigate_batch`).
      safety: what the local planner checks before it commits to a control: ``"none"``, ``"predicted"`` or
        ``"passive"`` (`NavConfig.safety`; None: the config's own). ``"passive"``: the robot is touched only at
        rest, whatever walkers no faster than ``walker_speed_max`` do (docs/guide/navigation.md).
      walker_speed_max: the walkers' speed bound of ``"passive"`` in m/s (None: each episode's fastest walker).
      **overrides: the global planner's parameters (as for `jaxplan.plan`).

    Returns:
      The `Episode`.

    Raises:
      ValueError: start/goal outside the map or blocked, start == goal, a moving obstacle
        starting inside the robot, unknown names, bad numbers. An infeasible or
        unreachable goal is an `Episode` with ``success=False`` and the reason.

    The previous release's positional form ``navigate(grid, start, goal, global_planner, local_planner, seed,
    obstacles)`` still works for one release, with a `DeprecationWarning`.
    """
    cfg = _with_safety(config, safety, walker_speed_max)
    b = _run(grid, np.asarray(start)[None, None], np.asarray(goal)[None, None], pipeline, global_planner,
             local_planner, [seed], obstacles, cfg, params, time_limit, overrides, progress=progress)
    return b.episode(0, 0, 0)


@keyword_only("pipeline", "seeds", "obstacles")
def navigate_batch(grid: GridMap, starts: ArrayLike, goals: ArrayLike, *, pipeline: str | None = "iaco_dwa",
                   global_planner: str | None = None, local_planner: str | None = None,
                   seeds: Sequence[int] = range(1), obstacles: Any = None, config: NavConfig | None = None,
                   params: DWAParams | MPPIParams | Mapping[str, float] | None = None, time_limit: float | None = None,
                   mesh: Mesh | str | None = "auto", progress: bool = False, safety: str | None = None,
                   walker_speed_max: float | None = None, **overrides: Any) -> EpisodeBatch:
    """Scenarios × seeds single-robot episodes in one compiled global-planning call and one episode call.

    Args:
      grid: the map.
      starts, goals: ``int[E, 2]`` cells.
      pipeline: a named pipeline (`jaxplan.nav.pipelines()`; default ``"iaco_dwa"``); a ``global_planner``
        replaces it (as in `navigate`).
      global_planner, local_planner: as in `navigate`.
      seeds: R seeds (global planner's seed; obstacle callables receive it too).
      obstacles: None, one `MovingObstacles` for all, an ``[E][R]`` nested list, or a callable
        ``f(scenario_index, seed) -> MovingObstacles``.
      mesh: a 1-D device mesh (`jaxplan.scale.batch_mesh`), ``"auto"`` (default) or None. The
        ACO global planning always follows it (`jaxplan.plan_batch`). The episodes (``E × R``,
        padded to whole groups per device) are split over the mesh when
        `NavConfig.replan_group` is set or re-planning is off — then every result equals the
        single-device run's; ``"auto"`` leaves them on one device otherwise. An explicit mesh
        with ``replan_group = 0`` gives each device its own re-planning budget (results then
        depend on the device count).
      progress: show the stages on stderr (global plans, compiling, the episodes; `jaxplan.core.progress`, only
        on a terminal): the episodes are one compiled call, so the bar names the stage with the elapsed time and
        gives no time left for it. The results are the same either way.
      config, params, time_limit, safety, walker_speed_max, **overrides: as in `navigate`.

    Returns:
      `EpisodeBatch` with axes ``[E, R, 1]``.

    The previous release's positional form ``navigate_batch(grid, starts, goals, pipeline, seeds, obstacles)``
    still works for one release, with a `DeprecationWarning`.
    """
    s, g = np.asarray(starts), np.asarray(goals)
    if s.ndim != 2 or s.shape[-1] != 2 or g.shape != s.shape:
        raise ValueError(f"starts and goals must both be [E, 2] cells, got {s.shape} and {g.shape}")
    if pipeline is not None and global_planner is not None:
        pipeline = None
    cfg = _with_safety(config, safety, walker_speed_max)
    return _run(grid, s[:, None], g[:, None], pipeline, global_planner, local_planner, list(seeds), obstacles, cfg,
                params, time_limit, overrides, mesh, progress)


@keyword_only("pipeline", "seeds", "obstacles")
def navigate_multi(grid: GridMap, starts: ArrayLike, goals: ArrayLike, *, pipeline: str | None = "iaco_dwa",
                   global_planner: str | None = None, local_planner: str | None = None,
                   seeds: Sequence[int] = range(1), obstacles: Any = None, config: NavConfig | None = None,
                   params: DWAParams | MPPIParams | Mapping[str, float] | None = None, time_limit: float | None = None,
                   mesh: Mesh | str | None = "auto", progress: bool = False, safety: str | None = None,
                   walker_speed_max: float | None = None, **overrides: Any) -> EpisodeBatch:
    """Multi-robot episodes: ``starts, goals int[N, 2]`` (one team) or ``[E, N, 2]`` (E teams).

    Each robot plans its own global path and runs its own DWA, treating the other robots
    (at their current positions and velocities) and the moving obstacles as moving discs;
    robots that arrive stay where they are. Collisions are counted per robot and per pair
    (``pair_collisions``).

    Arguments other than ``starts, goals`` are as in `navigate_batch` (the same keywords, the same defaults).

    Args:
      grid: the map.
      starts, goals: ``int[N, 2]`` or ``int[E, N, 2]`` cells.

    Returns:
      `EpisodeBatch` with axes ``[E, R, N]``.

    The previous release's positional form ``navigate_multi(grid, starts, goals, pipeline, seeds, obstacles)``
    still works for one release, with a `DeprecationWarning`.
    """
    s, g = np.asarray(starts), np.asarray(goals)
    if s.ndim == 2:
        s, g = s[None], g[None]
    if s.ndim != 3 or s.shape[-1] != 2 or g.shape != s.shape:
        raise ValueError(f"starts and goals must both be [N, 2] or [E, N, 2] cells, got {s.shape} and {g.shape}")
    if pipeline is not None and global_planner is not None:
        pipeline = None
    cfg = _with_safety(config, safety, walker_speed_max)
    return _run(grid, s, g, pipeline, global_planner, local_planner, list(seeds), obstacles, cfg, params,
                time_limit, overrides, mesh, progress)
