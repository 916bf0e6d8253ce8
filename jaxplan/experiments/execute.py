"""Running one chunk: one compiled batch call per chunk, and its trials as CSV text.

A plan chunk is one `jaxplan.plan_batch` call, a navigate chunk one `jaxplan.navigate_batch`
call (seeds on the second batch axis — never a Python loop over seeds), a TSP chunk
`jaxplan.aco.run_tsp` vmapped over the seeds' keys (the program `jaxplan.solve_tsp` runs for one
seed). The last chunk of a (map, planner) is padded to the full chunk size with copies of its
last scenario (rows dropped after the call): every chunk then has the same shapes and the
program compiles once.

Reproducibility. Floats are written with Python's ``repr`` (shortest round-trip text),
integers as integers, and undefined values (a failed plan's length, an infeasible
episode's metrics) as ``nan``; wall-clock times never enter the trials (they go to timings).
"""

from __future__ import annotations

import csv
import io
import math
import time
from typing import Any, Callable, Sequence

import numpy as np

from jaxplan.core.cache import Built, memoize
from jaxplan.experiments.config import PlannerConfig, nav_config
from jaxplan.experiments.prepare import ID_COLUMNS, MapWork, Prepared, Unit, trial_columns
from jaxplan.experiments.team import team_cells, team_values
from jaxplan.experiments.trial_metrics import (
    INT_METRICS,
    LOS_KEYS,
    PATH_KEYS,
    accuracy,
    convergence_metrics,
    executed_optimum,
    executed_shape,
    grid_path_lengths,
    hausdorff,
    los_metrics,
    objective_gaps,
    optimality_gaps,
    reductions,
)

__all__ = ["run_unit", "chunk_rows", "obstacle_fn", "NAV_KEYS"]

def _fmt(v: Any) -> str:
    """The fixed text of a value: ``repr`` of a float (nan for undefined), an integer as an integer."""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return "nan" if math.isnan(f) else repr(f)
    return str(v)


def _pad(idx: np.ndarray, size: int) -> np.ndarray:
    return np.concatenate([idx, np.full(size - len(idx), idx[-1])]) if len(idx) < size else idx


def _run_plan(mw: MapWork, pc: PlannerConfig, idx: np.ndarray, seeds: tuple[int, ...], chunk: int,
              metrics: Sequence[str]) -> tuple[dict, dict, dict]:
    """Metric arrays ``[n, R]``, arrays to keep, and timings of one plan chunk (one `plan_batch` call)."""
    from jaxplan.aco import COLONIES
    from jaxplan.metrics import path_metrics
    from jaxplan.planning import plan_batch

    batched = pc.name in COLONIES
    run_idx = _pad(idx, chunk) if batched else idx  # equal shapes: one compilation per (map, planner)
    overrides = {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()}
    br = plan_batch(mw.grid, mw.starts[run_idx], mw.goals[run_idx], planner=pc.name, seeds=seeds, **overrides)
    n, R = len(idx), len(seeds)
    ok = br.success[:n]
    out: dict[str, np.ndarray] = {"success": ok.astype(np.int64)}
    los = any(m in LOS_KEYS for m in metrics)
    if any(m in PATH_KEYS for m in metrics) or los or "accuracy" in metrics:
        P = br.paths.shape[2]
        pm = path_metrics(br.paths[:n].reshape(n * R, P, 2), mw.grid, optimal=np.repeat(mw.optimal[idx], R),
                          n=br.n_cells[:n].reshape(-1))
        raw = {k: np.where(ok, np.asarray(getattr(pm, k), np.float64).reshape(n, R), np.nan) for k in PATH_KEYS}
        # The device's float32 sums depend on the batch's layout, so a --chunk change moved the last bits of a
        # stored path's length; the same seed gives the same result: recompute from the integer cells.
        length = grid_path_lengths(br.paths[:n].reshape(n * R, P, 2), br.n_cells[:n].reshape(-1),
                                   float(mw.grid.resolution)).reshape(n, R)
        raw["length"] = np.where(ok, length, np.nan)
        raw["optimality_gap"] = np.where(ok, optimality_gaps(length, mw.optimal[idx][:, None]), np.nan)
        out.update({k: v for k, v in raw.items() if k in metrics})
        if "accuracy" in metrics:  # the raw grid path against the exact octile optimum
            out["accuracy"] = accuracy(ok, raw["optimality_gap"])
        if los:
            sm = los_metrics(mw.grid, br.paths[:n].reshape(n * R, P, 2), br.n_cells[:n].reshape(-1), ok.reshape(-1),
                              np.repeat(mw.starts[idx], R, axis=0))
            sm = {k: v.reshape(n, R) for k, v in sm.items()}
            sm["los_length_reduction"] = reductions(raw["length"], sm["los_length"])
            sm["los_turns_reduction"] = reductions(raw["turns"], sm["los_turns"])
            out.update({k: v for k, v in sm.items() if k in metrics})
    if "hausdorff" in metrics:
        out["hausdorff"] = np.where(ok, hausdorff(mw, idx, br.paths[:n], br.n_cells[:n]), np.nan)
    if "cost" in metrics:
        out["cost"] = np.where(ok, br.cost[:n], np.nan)
    if "objective_gap" in metrics:
        out["objective_gap"] = objective_gaps(mw.grid, mw.starts[idx], mw.goals[idx], pc.name, overrides,
                                              br.paths[:n], br.n_cells[:n], ok)
    if "converged_iteration" in metrics:  # the colony kernel's (`jaxplan.metrics.converged_iteration`)
        out["converged_iteration"] = np.where(ok, br.converged[:n].astype(np.float64), np.nan)
    # The other definitions (strict, chu2024's, yu2020's) from the same history, on the host.
    out.update(convergence_metrics(br.history[:n], ok, [m for m in metrics if m != "converged_iteration"]))
    keep = {"history": br.history[:n].astype(np.float32), "diversity": br.diversity[:n].astype(np.float32),
            "successes": br.successes[:n].astype(np.int32), "paths": br.paths[:n].astype(np.int32),
            "n_cells": br.n_cells[:n].astype(np.int32), "success": ok}
    trials = len(run_idx) * R
    timing = {"compile_s": float(br.compile_s), "time_s": float(br.time_s), "plan_time_s": float(br.time_s) / trials}
    return out, keep, timing


def obstacle_fn(mw: MapWork, m: int, pc: PlannerConfig, run_idx: np.ndarray) -> Callable | None:
    """``f(e, seed) -> MovingObstacles``: every (scenario, seed) trial draws its own discs, reproducibly."""
    o = pc.obstacles
    if o is None or o.n == 0:
        return None
    from jaxplan.nav import random_obstacles

    def fn(e: int, seed: int):
        sc = int(run_idx[e])
        key = (o, pc.team, sc, int(seed))
        if key in mw.draws:  # another planner of the config met these discs already
            return mw.draws[key]
        s = int(np.random.SeedSequence([o.seed, m, sc, int(seed)]).generate_state(1)[0])
        # world metres, as random_obstacles takes them; a team's discs keep clear of every robot of the team
        cells = (np.stack([mw.starts[sc], mw.goals[sc]]) if pc.team is None
                 else np.concatenate(team_cells(mw, m, pc.team, sc)))
        avoid = mw.grid.centre(cells)
        mw.draws[key] = random_obstacles(mw.grid, n=o.n, speed=o.speed, radius=o.radius, seed=s,
                                         waypoints=o.waypoints, avoid=avoid, avoid_radius=o.avoid_radius,
                                         loop=o.loop, behavior=o.behavior)
        return mw.draws[key]

    return fn


NAV_KEYS = ("success", "collisions", "active_contacts", "passive_contacts", "time_s", "rmse", "max_curvature", "energy",
            "path_length", "recoveries", "replans", "arrived", "robot_contacts")
_INT_NAV = ("success", "collisions", "active_contacts", "passive_contacts", "recoveries", "replans", "robot_contacts")


def _run_navigate(mw: MapWork, m: int, pc: PlannerConfig, idx: np.ndarray, seeds: tuple[int, ...], chunk: int,
                  metrics: Sequence[str]) -> tuple[dict, dict, dict]:
    """Metric arrays ``[n, R]`` (and ``reason``), arrays to keep, and timings of one `navigate_batch` call."""
    from jaxplan.nav import navigate_batch

    run_idx = _pad(idx, chunk)
    cfg, weights = nav_config(pc)
    overrides = {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()}
    if pc.team is not None:
        return _run_team(mw, m, pc, idx, run_idx, seeds, metrics, cfg, weights, overrides)
    eb = navigate_batch(mw.grid, mw.starts[run_idx], mw.goals[run_idx], pipeline=pc.name, seeds=list(seeds),
                        obstacles=obstacle_fn(mw, m, pc, run_idx), config=cfg, params=weights or None,
                        **overrides)
    n = len(idx)
    out: dict[str, np.ndarray] = {}
    for k in NAV_KEYS:
        if k in metrics:
            v = (eb.success if k == "arrived" else np.zeros_like(eb.collisions) if k == "robot_contacts"
                 else getattr(eb, k))[:n, :, 0]
            out[k] = v.astype(np.int64) if k in _INT_NAV else \
                np.asarray(v, np.float64)
    if "hausdorff" in metrics:
        out["hausdorff"] = hausdorff(mw, idx, eb.plans[:n, :, 0], eb.n_plan[:n, :, 0])
    if "accuracy" in metrics:  # the executed path against the smoothed exact path the robot fits
        gap = np.asarray(eb.path_length[:n, :, 0], np.float64) / executed_optimum(mw, pc, idx)[:, None] - 1.0
        out["accuracy"] = accuracy(eb.success[:n, :, 0], gap)
    out["reason"] = eb.reason[:n, :, 0]
    T = int(eb.steps[:n].max()) + 1
    shape = [k for k in ("smoothness", "mean_clearance") if k in metrics]
    if shape:
        got = executed_shape(mw.grid, eb.states[:n, :, 0, :T, :2], eb.steps[:n, :, 0])
        out.update({k: got[k] for k in shape})
    # states (x, y, theta, v, omega) feed the velocity traces and the DWA fans of `jaxplan figures`.
    keep = {"positions": eb.states[:n, :, 0, :T, :2].astype(np.float32),
            "states": eb.states[:n, :, 0, :T].astype(np.float32), "steps": eb.steps[:n, :, 0].astype(np.int32),
            "plans": eb.plans[:n, :, 0].astype(np.float32), "n_plan": eb.n_plan[:n, :, 0].astype(np.int32),
            "success": eb.success[:n, :, 0]}
    timing = {"compile_s": float(eb.compile_s), "time_s": float(eb.run_time_s), "plan_time_s": float(eb.plan_time_s),
              "step_time_s": float(eb.step_time_s)}
    return out, keep, timing


def _run_team(mw: MapWork, m: int, pc: PlannerConfig, idx: np.ndarray, run_idx: np.ndarray, seeds: tuple[int, ...],
              metrics: Sequence[str], cfg, weights: dict, overrides: dict) -> tuple[dict, dict, dict]:
    """`_run_navigate` for a team planner: one `navigate_multi` call for the chunk's ``E`` teams × seeds, team
    metrics ``[n, R]`` (`jaxplan.experiments.team`); robot 0's arrays are kept as a single robot's, and every
    robot's positions as ``team_positions [n, R, N, T, 2]``."""
    from jaxplan.nav import navigate_multi

    cells = [team_cells(mw, m, pc.team, int(sc)) for sc in run_idx]  # N cells per team: host work, not a hot path
    starts, goals = np.stack([c[0] for c in cells]), np.stack([c[1] for c in cells])  # [E, N, 2]
    eb = navigate_multi(mw.grid, starts, goals, pipeline=pc.name, seeds=list(seeds),
                        obstacles=obstacle_fn(mw, m, pc, run_idx), config=cfg, params=weights or None, **overrides)
    n = len(idx)
    out = team_values(eb, n, metrics)
    # The team's first failure reason in robot order ("goal" when every robot arrived).
    reason = np.asarray(eb.reason[:n], object)  # [n, R, N]
    first_bad = np.argmax(~np.asarray(eb.success[:n], bool), axis=-1)
    out["reason"] = np.where(out["success"] == 1, "goal",
                             np.take_along_axis(reason, first_bad[..., None], axis=-1)[..., 0])
    T = int(eb.steps[:n].max()) + 1
    keep = {"positions": eb.states[:n, :, 0, :T, :2].astype(np.float32),
            "states": eb.states[:n, :, 0, :T].astype(np.float32), "steps": eb.steps[:n, :, 0].astype(np.int32),
            "plans": eb.plans[:n, :, 0].astype(np.float32), "n_plan": eb.n_plan[:n, :, 0].astype(np.int32),
            "success": out["success"].astype(bool), "team_positions": eb.states[:n, :, :, :T, :2].astype(np.float32),
            "team_steps": eb.steps[:n].astype(np.int32), "team_starts": starts[:n].astype(np.int32),
            "team_goals": goals[:n].astype(np.int32)}
    # plan_time_s per trial, as for the other kinds: a team trial plans for its N robots.
    timing = {"compile_s": float(eb.compile_s), "time_s": float(eb.run_time_s),
              "plan_time_s": float(eb.plan_time_s) * starts.shape[1], "step_time_s": float(eb.step_time_s)}
    return out, keep, timing


def _tsp_program(cfg, dist, params: dict, keys) -> tuple[Callable, float]:
    """`run_tsp` vmapped over ``keys [R]``, compiled for these shapes, and the seconds spent compiling now (0 if
    cached): one compile per (config, instance size, seeds, parameter names); a sweep over many sizes keeps only
    the last 8 executables alive."""
    return _compiled_tsp(cfg, dist, params, keys).take()


@memoize(maxsize=8, key=lambda cfg, dist, params, keys: (cfg, dist.shape, keys.shape, tuple(sorted(params))))
def _compiled_tsp(cfg, dist, params: dict, keys) -> Built:
    import jax

    from jaxplan.aco import run_tsp

    program = jax.jit(jax.vmap(lambda d, p, k: run_tsp(cfg, d, p, k), in_axes=(None, None, 0)))
    return Built.timed(lambda: program.lower(dist, params, keys).compile())


def _run_tsp(mw: MapWork, pc: PlannerConfig, seeds: tuple[int, ...], metrics: Sequence[str]
             ) -> tuple[dict, dict, dict]:
    """Metric arrays ``[1, R]``, arrays to keep and timings of one TSP chunk: every seed in one compiled call.

    Each seed's run is `jaxplan.solve_tsp`'s (same parameter resolution, program and PRNG key
    ``jax.random.key(seed)``), vmapped over the seeds; lengths are recomputed in float64 on the host from the tours,
    as `solve_tsp` does.
    """
    import jax
    import jax.numpy as jnp

    from jaxplan.aco import TSP_STATIC_PARAMS, resolve_tsp, tour_length, tsp_config

    problem = mw.problem
    p = resolve_tsp(pc.name, {k: tuple(v) if isinstance(v, tuple) else v for k, v in pc.overrides.items()})
    cfg = tsp_config(pc.name, p, problem.n)
    params = {k: jnp.asarray(v, jnp.float32) for k, v in p.items() if k not in TSP_STATIC_PARAMS}
    dist = jnp.asarray(np.asarray(problem.dist, np.float64), jnp.float32)
    keys = jax.random.wrap_key_data(jnp.stack([jax.random.key_data(jax.random.key(int(s))) for s in seeds]))
    fn, compile_s = _tsp_program(cfg, dist, params, keys)
    t0 = time.perf_counter()
    res = jax.block_until_ready(fn(dist, params, keys))
    time_s = time.perf_counter() - t0
    tours = np.asarray(res.tour, np.int64)  # [R, n], any rotation
    tours = np.stack([np.roll(t, -int(np.flatnonzero(t == 0)[0])) for t in tours])
    lengths = np.asarray([tour_length(problem, t) for t in tours], np.float64)
    history = np.asarray(res.history, np.float64)  # [R, I] best length so far
    R = len(seeds)
    values = {"success": np.ones((1, R), np.int64), "tour_length": lengths[None],
              "optimality_gap": (lengths / mw.optimal[0] - 1.0)[None],
              # yu2020 Table 1's "number of iterations" is optimum_iteration; converged_iteration the general one.
              **convergence_metrics(history[None], np.ones((1, R), bool), metrics)}
    keep = {"history": history[None].astype(np.float32), "tours": tours[None].astype(np.int32),
            "success": np.ones((1, R), bool)}
    timing = {"compile_s": float(compile_s), "time_s": float(time_s), "plan_time_s": float(time_s) / R}
    return {k: v for k, v in values.items() if k in metrics}, keep, timing


def chunk_rows(prep: Prepared, u: Unit, values: dict) -> str:
    """The CSV text (no header) of a chunk's trials, scenario-major then seed."""
    cfg = prep.config
    mw, pc = prep.maps[u.m], cfg.planners[u.p]
    cols = trial_columns(cfg)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    for i, sc in enumerate(range(u.lo, u.hi)):
        for r, seed in enumerate(cfg.seeds):
            row = {"map": mw.spec.name, "planner": pc.label, "kind": pc.kind, "scenario": sc,
                   "scen_row": int(mw.rows[sc]), "start_x": int(mw.starts[sc, 0]), "start_y": int(mw.starts[sc, 1]),
                   "goal_x": int(mw.goals[sc, 0]), "goal_y": int(mw.goals[sc, 1]),
                   "optimal": float(mw.optimal[sc]), "seed": seed}
            if mw.problem is not None:  # a TSP has no start or goal cell
                row.update(start_x="", start_y="", goal_x="", goal_y="")
            for c in cols[len(ID_COLUMNS):]:
                if c == "reason":
                    row[c] = str(values["reason"][i, r]) if "reason" in values else (
                        "goal" if values["success"][i, r] else "no path")
                elif c in values:
                    v = values[c][i, r]
                    row[c] = int(v) if (c in INT_METRICS and np.isfinite(v)) else v
                else:
                    row[c] = ""  # the metric does not apply to this planner kind
            w.writerow([_fmt(row[c]) for c in cols])
    return buf.getvalue()


def run_unit(prep: Prepared, u: Unit) -> tuple[str, dict, dict]:
    """(CSV rows, arrays to keep, timings) of chunk ``u``: one compiled batch call."""
    cfg = prep.config
    mw, pc = prep.maps[u.m], cfg.planners[u.p]
    idx = np.arange(u.lo, u.hi)
    metrics = ("success",) + cfg.metrics  # success is always a column: other metrics are read given it
    if pc.kind == "tsp":
        values, keep, timing = _run_tsp(mw, pc, cfg.seeds, metrics)
    elif pc.kind == "plan":
        values, keep, timing = _run_plan(mw, pc, idx, cfg.seeds, cfg.chunk, metrics)
    else:
        values, keep, timing = _run_navigate(mw, u.m, pc, idx, cfg.seeds, cfg.chunk, metrics)
    return chunk_rows(prep, u, values), keep, timing
