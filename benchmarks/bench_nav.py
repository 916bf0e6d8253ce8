"""Two-level navigation: success, contacts and costs of the DWA and MPPI pipelines, multi-robot, speed.

Run:  python benchmarks/bench_nav.py [--data-dir ../shared/benchmarks] [--rows 50] [--seeds 5]
                                     [--sections maps,allrows,pipelines,multi,speed] [--local dwa,mppi] [--quick]

Robot: cui2025's (unicycle, 1.2 m/s, 2 rad/s, 0.5 m/s², radius 0.25 m, d_safe 0.3 m, control
period 0.2 s, DWA 20 x 40 samples over 2 s) on the MovingAI maps at 1.0 m per cell: at
cui2025's 0.5 m per cell their one-cell aisles and doors would be 0.5 m wide, which leaves
0.25 m on each side of the robot's centre — below its own 0.3 m safety distance.

Scenarios: rows of each map's scenario file with optimal length <= 80 cells, ``--rows`` of
them spread evenly over the file, each with ``--seeds`` seeds (the global planner's seed
and the obstacles'). A scenario whose start or goal the footprint inflated to d_safe cannot
use, or whose goal it cannot reach, is infeasible: not run, counted apart.

Sections:
  maps       `iaco_dwa` and `iaco_mppi` (``--local``) on every map: static, among 5 blind walkers
             (discs of 0.25 m at 1.0 m/s bouncing along random routes, starting at least 3 m from the
             robot's start and goal; they do not avoid the robot) and among 5 walkers that see (the
             same routes, avoiding robots, each other and walls with the social force model).
             Targets: static 100 %; among walkers that see >= 99 % with MPPI, >= 97 % with the DWA;
             among blind walkers with MPPI >= 97 % with active contacts in <= 0.5 % of episodes. With
             ``--oracle`` a row per map runs the blind walkers with ``NavConfig(prediction="oracle")``: the local
             planner knows their true routes (an upper bound for any walker predictor, not something a
             robot can have). With ``--admissible`` a row runs the blind walkers with the local
             planner's passive-safety admissibility on; with ``--passive-bounds 0.6,0.8`` a row per bound
             runs the walkers that see with passive safety against walkers no faster than that bound (the
             guarantee's bound is the walkers' true top speed; a lower one is an assumption, and the row
             shows what it buys); ``--cases`` picks among static, blind, seeing.
  allrows    static episodes of `iaco_dwa` and `iaco_mppi` on EVERY row (optimal <= 80 cells) of
             every scenario file, each failure printed with its scenario row and reason (target:
             every one arrives); per file: rows, infeasible, arrived, failed. ``--allrows-seeds``
             runs every row with each of these seeds (default 0).
  pipelines  every pipeline and ablation (`jaxplan.nav.pipelines()`) on the warehouse map
             (``--pipeline-maps`` for others), static and moving.
  multi      li2026's Table 3 set-up: teams of 5 robots on the warehouse map with 5
             random walkers at 1.0 and 1.5 m/s; contacts are counted, not stopped at.
  speed      1,000 static `iaco_dwa` episodes on the warehouse map in one batched call
             (global planning included), and one episode's control steps against real
             time (target >= 1,000x), with XLA's default threads and pinned to one core; for MPPI, one
             compiled control step for 1, 64 and 1,024 robots and one `iaco_mppi` episode against real
             time (targets <= 1 ms per step for one robot inside an episode, >= 500x real time).

Every figure is mean ± sd over seeds of the per-seed mean over episodes (success as a
rate; time over the successful episodes). Infeasible episodes are excluded and counted. The tables also go to a
JSON record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it): a table's name carries
the options that differ from the defaults, so a run of one map or with more seeds does not stand in for the full one.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

MAPS = ("warehouse-10-20-10-2-1", "random-32-32-20", "random-64-64-20", "room-64-64-8", "maze-32-32-2", "brc202d",
        "den520d", "ost003d")
"""Every scenario file in ../shared/benchmarks/movingai (the maps and allrows sections' default)."""
WAREHOUSE = "warehouse-10-20-10-2-1"
AVOID_RADIUS = 3.0
"""m: no walker starts this close to a robot's start or goal (one that starts within a metre of a robot
in a 1 m aisle, heading for it at 1 m/s, hits it before it can turn round)."""


def data_dir(arg: str | None) -> Path:
    d = Path(arg or os.environ.get("JAXPLAN_DATA", Path(__file__).resolve().parents[2] / "shared" / "benchmarks"))
    return d / "movingai" if (d / "movingai").is_dir() else d


def load(d: Path, name: str):
    import jaxplan as jp

    grid = jp.load_map(d / f"{name}.map", resolution=1.0)
    scen_file = d / f"{name}.map.scen"
    if not scen_file.exists():
        scen_file = d / f"{name}-random-1.scen"
    return grid, jp.load_scenarios(scen_file)


def rows(scen, n: int, max_len: float = 80.0) -> np.ndarray:
    ok = np.nonzero(scen.optimal <= max_len)[0]
    return ok[np.unique(np.linspace(0, len(ok) - 1, min(n, len(ok))).round().astype(int))]


def walkers(grid, starts, goals, n: int, speed: float, behavior: str = "blind"):
    """``f(scenario, seed)``: ``n`` random walkers keeping clear of that scenario's starts and goals (the same
    routes for either behavior)."""
    import jaxplan as jp

    def make(e: int, seed: int):
        avoid = (np.concatenate([np.atleast_2d(starts[e]), np.atleast_2d(goals[e])]) + 0.5) * grid.resolution
        return jp.random_obstacles(grid, n=n, speed=speed, radius=0.25, seed=10_000 * seed + e, avoid=avoid,
                                   avoid_radius=AVOID_RADIUS, behavior=behavior)

    return make


def fmt(mean: float, sd: float, digits: int = 2, pct: bool = False) -> str:
    if not np.isfinite(mean):
        return "—"
    if pct:
        return f"{100 * mean:.1f} ± {100 * sd:.1f}"
    return f"{mean:.{digits}f} ± {sd:.{digits}f}"


HEADER = (f"{'':<30}{'runs':>6}{'infeas':>7} | {'success %':>13}{'active/ep':>12}{'passive/ep':>12}"
          f"{'act. ep %':>10}{'time s':>14}{'rmse m':>13}{'max κ 1/m':>13}{'replans':>11}{'wall s':>8}")


COLUMNS = ["episodes", "infeasible", "success (%)", "active / ep.", "passive / ep.", "episodes with active contact (%)",
           "time (s)", "RMSE (m)", "max κ (1/m)", "re-plans", "wall (s)"]
"""The columns of `cells`: one batch of episodes, mean ± sd over seeds."""

RECORD = None
"""The run's `_timing.Record` (set by `main`)."""


def table(name: str, columns: list[str], title: str = "") -> list[list]:
    """A new table of the run's record (rows to append to)."""
    return RECORD.table(name, columns, title)


def variant(args, keys: tuple[str, ...]) -> str:
    """`` (…)`` naming the options among ``keys`` that differ from the defaults (for a table's name), or ``""``."""
    default = {"maps": list(MAPS), "rows": 50, "seeds": 5, "cases": ["static", "blind", "seeing"],
               "allrows_maps": list(MAPS), "allrows_seeds": [0], "pipeline_maps": [WAREHOUSE], "episodes": 1000,
               "teams": 10}
    parts = [f"{k.replace('_', ' ')} {','.join(map(str, v)) if isinstance(v, list) else v}"
             for k in keys if (v := getattr(args, k)) != default[k]]
    bounds = ",".join(f"{v:g}" for v in args.passive_bounds)
    parts += ["quick"] * args.quick + ["oracle"] * (args.oracle and "maps" in keys) + [
        "admissible"] * (args.admissible and "maps" in keys) + [
        f"passive bounds {bounds}"] * bool(args.passive_bounds and "maps" in keys)
    return f" ({'; '.join(parts)})" if parts else ""


def cells(b, wall: float) -> list:
    """`COLUMNS` of one batch (the ± figures as text, as printed)."""
    s = b.summary()
    run = b.feasible
    act_ep = 100 * float(np.mean(b.active_contacts[run] > 0)) if run.any() else None
    return [int(s["episodes"][0]), int(s["infeasible"][0]), fmt(*s["success"], pct=True), s["active_contacts"][0],
            s["passive_contacts"][0], act_ep, fmt(*s["time_s"], 1), fmt(*s["rmse"]), fmt(*s["max_curvature"]),
            fmt(*s["replans"], 1), wall]


def row(label: str, b, wall: float) -> str:
    s = b.summary()
    run = b.feasible
    act_ep = 100 * float(np.mean(b.active_contacts[run] > 0)) if run.any() else float("nan")
    return (f"{label:<30}{int(s['episodes'][0]):>6}{int(s['infeasible'][0]):>7} | {fmt(*s['success'], pct=True):>13}"
            f"{s['active_contacts'][0]:>12.3f}{s['passive_contacts'][0]:>12.3f}{act_ep:>10.1f}"
            f"{fmt(*s['time_s'], 1):>14}{fmt(*s['rmse']):>13}{fmt(*s['max_curvature']):>13}"
            f"{fmt(*s['replans'], 1):>11}{wall:>8.0f}")


def run(grid, starts, goals, pipeline: str, seeds, obstacles=None, config=None):
    import jaxplan as jp

    t0 = time.perf_counter()
    b = jp.navigate_batch(grid, starts, goals, pipeline=pipeline, seeds=seeds, obstacles=obstacles, config=config)
    return b, time.perf_counter() - t0


def section_maps(d: Path, args) -> None:
    from jaxplan.nav import NavConfig

    seeds = list(range(args.seeds))
    for local in args.local:
        pipe = f"iaco_{local}"
        print(f"\n== {pipe} on the MovingAI maps (1.0 m per cell) ==")
        print(HEADER)
        out = table(f"maps, {pipe}{variant(args, ('maps', 'rows', 'seeds', 'cases'))}", ["map", "case", *COLUMNS],
                    f"{pipe}, {args.rows} rows (optimal ≤ 80 cells) × {args.seeds} seeds per map; 5 walkers of "
                    "0.25 m at 1.0 m/s, blind or seeing")
        for name in args.maps:
            grid, scen = load(d, name)
            sel = rows(scen, args.rows)
            S, G = scen.starts[sel], scen.goals[sel]
            blind = walkers(grid, S, G, 5, 1.0)
            seeing = walkers(grid, S, G, 5, 1.0, "social")
            cases = [("static", None, None)] if "static" in args.cases else []
            if "blind" in args.cases:
                cases.append(("blind walkers", blind, None))
            if "seeing" in args.cases:
                cases.append(("seeing walkers", seeing, None))
            if args.oracle:
                cases.append(("blind, oracle", blind, NavConfig(prediction="oracle")))
            if args.admissible:
                cases.append(("blind, admissible", blind, NavConfig(safety="predicted")))
            for bound in args.passive_bounds:
                cases.append((f"seeing, pass. {bound:g}", seeing, NavConfig(safety="passive", walker_speed_max=bound)))
            for label, obs, cfg in cases:
                b, wall = run(grid, S, G, pipe, seeds, obs, cfg)
                print(row(f"{name[:12]} {label[:17]}", b, wall), flush=True)
                out.append([name, label, *cells(b, wall)])
                if args.verbose:
                    bad = ~b.success & b.feasible
                    print("   failures:", {r: int(np.sum(b.reason[bad] == r)) for r in np.unique(b.reason[bad])},
                          f"give-ways per episode {float(np.mean(b.give_ways[b.feasible])):.3f}")


ALLROWS_BATCH = 100
"""Scenario rows per batched call in the allrows section (a multiple of the re-planning group of 25)."""


def section_allrows(d: Path, args) -> None:
    """Static episodes on every row (optimal <= 80 cells) of every scenario file: every one must arrive."""
    print("\n== static episodes on every row (optimal <= 80 cells) of every scenario file ==")
    for local in args.local:
        pipe = f"iaco_{local}"
        total = failed = 0
        t0 = time.perf_counter()
        seeds = args.allrows_seeds
        out = table(f"allrows, {pipe}{variant(args, ('allrows_maps', 'allrows_seeds'))}",
                    ["map", "rows", "episodes", "infeasible", "arrived", "failed", "wall (s)"],
                    f"static {pipe} episodes on every row (optimal ≤ 80 cells) of every scenario file, "
                    f"seed{'s' * (len(seeds) > 1)} {', '.join(map(str, seeds))}")
        for name in args.allrows_maps:
            grid, scen = load(d, name)
            sel = np.nonzero(scen.optimal <= 80.0)[0][: 20 if args.quick else None]
            # In batches: brc202d's 200 rows of global planning at once need more memory than a shared
            # machine may have, and the memory guard refuses them.
            arrived = infeasible = 0
            wall = 0.0
            lines = []
            per = max(25, ALLROWS_BATCH // len(seeds) // 25 * 25)  # rows per call: about ALLROWS_BATCH episodes
            for part in (sel[i:i + per] for i in range(0, len(sel), per)):
                b, w = run(grid, scen.starts[part], scen.goals[part], pipe, seeds)
                wall += w
                ok, ran = b.success[..., 0], b.feasible[..., 0]  # [rows, seeds]
                arrived += int((ok & ran).sum())
                infeasible += int((~ran).sum())
                for i, r in zip(*np.nonzero(ran & ~ok), strict=True):
                    lines.append(f"    row {int(part[i])} {tuple(map(int, scen.starts[part[i]]))} -> "
                                 f"{tuple(map(int, scen.goals[part[i]]))}, seed {seeds[r]}: {b.reason[i, r, 0]} "
                                 f"after {float(b.steps[i, r, 0]) * b.period:.1f} s, contacts "
                                 f"{int(b.collisions[i, r, 0])}")
            n = len(sel) * len(seeds)
            total += n - infeasible
            failed += len(lines)
            print(f"{pipe:<12} {name:<24} rows {len(sel):>4}  episodes {n:>4}  infeasible {infeasible:>3}  arrived "
                  f"{arrived:>4}  failed {len(lines):>3}  ({wall:.0f} s)", flush=True)
            out.append([name, len(sel), n, infeasible, arrived, len(lines), wall])
            if lines:
                print("\n".join(lines), flush=True)
        print(f"{pipe}: {total - failed} of {total} feasible episodes arrived ({time.perf_counter() - t0:.0f} s)")
        RECORD.note(f"{total - failed} of {total} feasible episodes arrived (an episode: a row with a seed).")


def section_pipelines(d: Path, args) -> None:
    import jaxplan as jp

    for map_name in args.pipeline_maps:
        print(f"\n== every pipeline and ablation on {map_name} ==")
        grid, scen = load(d, map_name)
        sel = rows(scen, args.rows)
        S, G = scen.starts[sel], scen.goals[sel]
        seeds = list(range(args.seeds))
        out = table(f"pipelines, {map_name}{variant(args, ('rows', 'seeds'))}", ["pipeline", "case", *COLUMNS],
                    f"every pipeline and ablation on {map_name}, {args.rows} rows × {args.seeds} seeds")
        for label, obs in (("static", None), ("5 walkers at 1.0 m/s", walkers(grid, S, G, 5, 1.0))):
            print(f"-- {label}")
            print(HEADER)
            for name in args.pipelines or list(jp.pipelines()):
                b, wall = run(grid, S, G, name, seeds, obs)
                print(row(name, b, wall), flush=True)
                out.append([name, label, *cells(b, wall)])
                if args.verbose:
                    bad = ~b.success & b.feasible
                    print("   failures:", {r: int(np.sum(b.reason[bad] == r)) for r in np.unique(b.reason[bad])})


def section_multi(d: Path, args) -> None:
    import jaxplan as jp
    from jaxplan.nav import NavConfig

    print(f"\n== multi-robot (li2026 Table 3): teams of 5 robots on {WAREHOUSE}, 5 random walkers ==")
    grid, scen = load(d, WAREHOUSE)
    sel = rows(scen, 10_000)
    rng = np.random.default_rng(0)
    teams = []
    while len(teams) < args.teams:  # 5 rows with pairwise distinct starts and goals
        pick = scen.starts[rng.choice(sel, 5, replace=False)], scen.goals[rng.choice(sel, 5, replace=False)]
        cells = np.concatenate(pick)
        if len(np.unique(cells, axis=0)) == 10:
            teams.append(pick)
    S = np.stack([t[0] for t in teams])
    G = np.stack([t[1] for t in teams])
    seeds = list(range(args.seeds))
    cfg = NavConfig(replan=True, stop_on_collision=False)
    print(f"{'obstacle speed':<16}{'teams':>6} | {'robot contacts':>15}{'robot-robot':>13}{'max κ 1/m':>13}"
          f"{'time s':>13}{'energy J':>15}{'success %':>13}{'wall s':>8}")
    out = table(f"multi{variant(args, ('teams', 'seeds'))}",
                ["walker speed (m/s)", "teams", "robot contacts per team", "robot–robot", "max κ (1/m)", "time (s)",
                 "energy (J)", "success (%)", "wall (s)"],
                f"li2026 Table 3: {args.teams} teams of 5 iaco_dwa robots on {WAREHOUSE} among 5 random walkers, "
                f"{args.seeds} seeds")
    for speed in (1.0, 1.5):
        obs = walkers(grid, S.reshape(len(teams), -1, 2), G.reshape(len(teams), -1, 2), 5, speed)
        t0 = time.perf_counter()
        b = jp.navigate_multi(grid, S, G, pipeline="iaco_dwa", seeds=seeds, obstacles=obs, config=cfg)
        wall = time.perf_counter() - t0
        run_ = b.feasible.all(axis=2)  # [E, R] teams whose robots all ran

        def per_seed(x, run_=run_):
            return np.array([np.mean(x[:, r][run_[:, r]]) for r in range(len(seeds))])

        contacts = per_seed(b.collisions.sum(axis=2))
        pairs = per_seed(np.triu(b.pair_collisions, 1).sum(axis=(2, 3)))
        kappa = per_seed(np.nanmax(b.max_curvature, axis=2))
        t = per_seed(np.nanmean(np.where(b.success, b.time_s, np.nan), axis=2))
        en = per_seed(np.nansum(b.energy, axis=2))
        succ = per_seed(b.success.mean(axis=2))
        m = lambda x, k=2: fmt(float(np.nanmean(x)), float(np.nanstd(x)), k)  # noqa: E731
        print(f"{speed:<16.1f}{int(run_.sum()):>6} | {m(contacts):>15}{m(pairs):>13}{m(kappa):>13}{m(t, 1):>13}"
              f"{m(en, 0):>15}{fmt(float(np.mean(succ)), float(np.std(succ)), pct=True):>13}{wall:>8.0f}", flush=True)
        out.append([speed, int(run_.sum()), m(contacts), m(pairs), m(kappa), m(t, 1), m(en, 0),
                    fmt(float(np.mean(succ)), float(np.std(succ)), pct=True), wall])
    print("   robot contacts: per team, summed over its robots (a robot-robot contact counts for both);"
          " κ: the team's largest; time: mean over arrived robots; energy: team total (EnergyModel proxy, J).")
    RECORD.note("Robot contacts per team, summed over its robots (a robot–robot contact counts for both); κ the "
                "team's largest; time the mean over arrived robots; energy the team's total (EnergyModel proxy).")


def _one_episode(grid, scen, sel, pipeline: str) -> dict:
    """The compiled episode call of one static episode alone, median of repeats: seconds, steps, simulated time."""
    import jax
    from _timing import median_time

    import jaxplan as jp
    from jaxplan.nav import _front as F

    captured = {}
    real = F._compiled_episodes

    def spy(cfg, steps, mesh, args):  # keeps the compiled episode program and its arguments
        fn, c = real(cfg, steps, mesh, args)
        captured.update(fn=fn, a=args)
        return fn, c

    F._compiled_episodes = spy
    try:
        one = jp.navigate_batch(grid, scen.starts[sel[:1]], scen.goals[sel[:1]], pipeline=pipeline, seeds=[0])
    finally:
        F._compiled_episodes = real
    compiled, a = captured["fn"], captured["a"]

    def call():
        return jax.block_until_ready(compiled(*a))

    call()
    t = median_time(call, 9)
    steps = int(one.steps.sum())
    return dict(single_s=t, single_steps=steps, single_sim_s=steps * one.period, success=bool(one.success.all()))


def measure_mppi_speed(d: Path) -> dict:
    """One compiled MPPI control step for 1, 64 and 1,024 robots on the warehouse map (5 moving discs each), and one
    static `iaco_mppi` episode's compiled call against real time."""
    import jax
    import jax.numpy as jnp
    from _timing import median_time

    from jaxplan.dwa import DiscObstacles, table_of
    from jaxplan.mppi import MPPIConfig, default_params, initial_sequence, mppi_control

    grid, scen = load(d, WAREHOUSE)
    table = table_of(grid)
    cfg, params = MPPIConfig(), default_params()
    free = np.argwhere(np.asarray(grid.free))[:, ::-1] + 0.5
    rng = np.random.default_rng(0)
    out: dict = {"rows": []}
    for B in (1, 64, 1024):
        xy = free[rng.integers(0, len(free), B)]
        states = jnp.asarray(np.column_stack([xy, rng.uniform(-3, 3, B), rng.uniform(0, 1, B), np.zeros(B)]),
                             jnp.float32)
        goals = jnp.asarray(free[rng.integers(0, len(free), B)], jnp.float32)
        discs = DiscObstacles(jnp.asarray(free[rng.integers(0, len(free), (B, 5))], jnp.float32),
                              jnp.asarray(rng.uniform(-1, 1, (B, 5, 2)), jnp.float32), jnp.full((B, 5), 0.25))
        keys = jax.random.split(jax.random.key(0), B)

        def step(s, g, ob, k):
            return jax.vmap(lambda s1, g1, o1, k1: mppi_control(table, cfg, params, s1, initial_sequence(cfg, s1), k1,
                                                                g1, obstacles=o1)[0])(s, g, ob, k)

        t0 = time.perf_counter()
        fn = jax.jit(step).lower(states, goals, discs, keys).compile()
        compile_s = time.perf_counter() - t0

        def call(fn=fn, a=(states, goals, discs, keys)):
            return jax.block_until_ready(fn(*a))

        call()
        s = median_time(call, 15 if B < 1024 else 7)
        out["rows"].append(dict(robots=B, ms=1e3 * s, compile_s=compile_s,
                                points_per_s=B * cfg.samples * cfg.points / s))
    ok = np.nonzero(scen.optimal <= 80)[0]
    out.update(_one_episode(grid, scen, ok, "iaco_mppi"))
    return out


def measure_speed(d: Path, episodes: int) -> dict:

    import jaxplan as jp

    sys.path.insert(0, str(Path(__file__).parent))

    grid, scen = load(d, WAREHOUSE)
    ok = np.nonzero(scen.optimal <= 80)[0]
    sel = ok[np.arange(episodes) % len(ok)]
    out: dict = {}
    t0 = time.perf_counter()
    b = jp.navigate_batch(grid, scen.starts[sel], scen.goals[sel], pipeline="iaco_dwa", seeds=[0])
    out["batch_wall"] = time.perf_counter() - t0
    out.update(episodes=episodes, plan_s=b.plan_time_s * episodes, run_s=b.run_time_s, compile_s=b.compile_s,
               success=float(b.success.mean()), robot_steps=int(b.steps.sum()), loop_steps=int(b.steps.max()))
    out.update(_one_episode(grid, scen, sel, "iaco_dwa"))
    return out


def section_speed(d: Path, args) -> None:
    print(f"\n== speed: {args.episodes} static iaco_dwa episodes on {WAREHOUSE} in one call ==")
    out = table(f"speed, iaco_dwa{variant(args, ('episodes',))}",
                ["threads", "episodes", "success (%)", "ms per episode", "compile (s)", "one episode: ms per step",
                 "× real time"],
                f"{args.episodes} static iaco_dwa episodes on {WAREHOUSE} in one call (global planning included); "
                "one episode's compiled control loop against real time (target ≥ 1,000×)")
    for label, prefix in (("XLA default threads", []), ("pinned to 1 core", ["taskset", "-c", "0"])):
        cmd = prefix + [sys.executable, __file__, "--child-speed", str(args.episodes), "--data-dir", str(d)]
        res = subprocess.run(cmd, capture_output=True, text=True)
        if res.returncode != 0:
            print(f"{label}: failed\n{res.stderr[-2000:]}")
            continue
        r = json.loads(res.stdout.strip().splitlines()[-1])
        total = r["plan_s"] + r["run_s"]
        print(f"{label}: {r['episodes']} episodes, success {100 * r['success']:.1f} %: global planning "
              f"{r['plan_s']:.1f} s + episodes {r['run_s']:.1f} s = {1e3 * total / r['episodes']:.1f} ms per episode "
              f"(compile {r['compile_s']:.1f} s, call with compilation {r['batch_wall']:.0f} s; "
              f"{r['robot_steps']} robot-steps, loop ran {r['loop_steps']} steps)")
        print(f"   one episode: {r['single_steps']} control steps ({r['single_sim_s']:.1f} s simulated) in "
              f"{1e3 * r['single_s']:.1f} ms = {1e3 * r['single_s'] / r['single_steps']:.3f} ms per step, "
              f"{r['single_sim_s'] / r['single_s']:.0f}x real time (target >= 1000x)", flush=True)
        out.append([label, r["episodes"], 100 * r["success"], 1e3 * total / r["episodes"], r["compile_s"],
                    1e3 * r["single_s"] / r["single_steps"], r["single_sim_s"] / r["single_s"]])
    if "mppi" in args.local:
        print(f"\n== speed: MPPI ({WAREHOUSE}; 5 moving discs per robot) ==")
        steps = table("speed, MPPI step", ["threads", "robots", "ms per step", "M rollout points/s", "compile (s)"],
                      f"one compiled MPPI control step on {WAREHOUSE}, 5 moving discs per robot")
        episode = table("speed, iaco_mppi episode", ["threads", "control steps", "simulated (s)", "ms per step",
                                                     "× real time"],
                        "one static iaco_mppi episode's compiled call (targets ≤ 1 ms per step, ≥ 500× real time)")
        for label, prefix in (("XLA default threads", []), ("pinned to 1 core", ["taskset", "-c", "0"])):
            cmd = prefix + [sys.executable, __file__, "--child-mppi", "--data-dir", str(d)]
            res = subprocess.run(cmd, capture_output=True, text=True)
            if res.returncode != 0:
                print(f"{label}: failed\n{res.stderr[-2000:]}")
                continue
            r = json.loads(res.stdout.strip().splitlines()[-1])
            for x in r["rows"]:
                print(f"{label}: one compiled MPPI step, {x['robots']:>5} robots: {x['ms']:8.3f} ms "
                      f"({x['points_per_s'] / 1e6:.0f} M rollout points/s; compile {x['compile_s']:.2f} s)")
                steps.append([label, x["robots"], x["ms"], x["points_per_s"] / 1e6, x["compile_s"]])
            print(f"   one iaco_mppi episode: {r['single_steps']} control steps ({r['single_sim_s']:.1f} s simulated) "
                  f"in {1e3 * r['single_s']:.1f} ms = {1e3 * r['single_s'] / r['single_steps']:.3f} ms per step "
                  f"(target <= 1 ms), {r['single_sim_s'] / r['single_s']:.0f}x real time (target >= 500x)", flush=True)
            episode.append([label, r["single_steps"], r["single_sim_s"], 1e3 * r["single_s"] / r["single_steps"],
                            r["single_sim_s"] / r["single_s"]])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", default=None,
                    help="folder with movingai/ (default ../shared/benchmarks or $JAXPLAN_DATA)")
    ap.add_argument("--rows", type=int, default=50)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--teams", type=int, default=10)
    ap.add_argument("--episodes", type=int, default=1000)
    ap.add_argument("--maps", default=",".join(MAPS))
    ap.add_argument("--pipelines", default="", help="comma-separated (default: all)")
    ap.add_argument("--pipeline-maps", default=WAREHOUSE, help="maps of the pipelines section (comma-separated)")
    ap.add_argument("--sections", default="maps,pipelines,multi,speed")
    ap.add_argument("--quick", action="store_true", help="5 rows, 2 seeds, 2 teams, 100 episodes, two maps")
    ap.add_argument("--verbose", action="store_true", help="print failure reasons")
    ap.add_argument("--oracle", action="store_true",
                    help="maps: also run the walkers with the DWA knowing their true routes (prediction='oracle')")
    ap.add_argument("--admissible", action="store_true",
                    help="maps: also run the blind walkers with the local planner's passive-safety admissibility on")
    ap.add_argument("--passive-bounds", default="",
                    help="maps: also run the seeing walkers with passive safety at each of these walker speed bounds "
                         "(m/s, comma-separated; NavConfig(safety='passive', walker_speed_max=...))")
    ap.add_argument("--allrows-maps", default=",".join(MAPS), help="maps of the allrows section (comma-separated)")
    ap.add_argument("--allrows-seeds", default="0", help="seeds of the allrows section (comma-separated)")
    ap.add_argument("--cases", default="static,blind,seeing",
                    help="maps: which of static, blind, seeing to run (--oracle and --admissible add theirs)")
    ap.add_argument("--local", default="dwa,mppi", help="local planners of the maps, allrows and speed sections")
    ap.add_argument("--child-speed", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--child-mppi", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    d = data_dir(args.data_dir)
    sys.path.insert(0, str(Path(__file__).parent))
    if args.child_speed:
        print(json.dumps(measure_speed(d, args.child_speed)))
        return
    if args.child_mppi:
        print(json.dumps(measure_mppi_speed(d)))
        return
    args.local = [x for x in args.local.split(",") if x]
    args.cases = [x for x in args.cases.split(",") if x]
    args.allrows_maps = [m for m in args.allrows_maps.split(",") if m]
    args.allrows_seeds = [int(x) for x in args.allrows_seeds.split(",") if x]
    try:
        args.passive_bounds = [float(x) for x in args.passive_bounds.split(",") if x]
    except ValueError:
        ap.error(f"--passive-bounds must be comma-separated speeds in m/s, got {args.passive_bounds!r}")
    if any(not (math.isfinite(v) and v >= 0.0) for v in args.passive_bounds):
        ap.error(f"--passive-bounds must be finite speeds >= 0 m/s, got {args.passive_bounds}")
    bad = sorted(set(args.cases) - {"static", "blind", "seeing"})
    if bad:
        ap.error(f"unknown --cases {bad}; choose among static, blind, seeing")
    if args.quick:
        args.rows, args.seeds, args.teams, args.episodes = 5, 2, 2, 100
        args.maps = f"{WAREHOUSE},random-32-32-20"
    args.maps = [m for m in args.maps.split(",") if m]
    args.pipelines = [p for p in args.pipelines.split(",") if p]
    args.pipeline_maps = [m for m in args.pipeline_maps.split(",") if m]
    import jax

    sys.path.insert(0, str(Path(__file__).parent))
    from _timing import Record, Steal, machine_line

    global RECORD
    RECORD = Record("bench_nav", {k: v for k, v in vars(args).items() if not k.startswith("child")},
                    quick=args.quick)
    steal = Steal()
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {machine_line()}; maps from {d}")
    print(f"{args.rows} rows (optimal <= 80 cells) x {args.seeds} seeds per map")
    for s in args.sections.split(","):
        sections = {"maps": section_maps, "allrows": section_allrows, "pipelines": section_pipelines,
                    "multi": section_multi, "speed": section_speed}
        sections[s](d, args)
    print(steal.summary())
    RECORD.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
