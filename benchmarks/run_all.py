"""Every benchmark of jaxplan in one process, printed as one table and saved as JSON.

Run:  python benchmarks/run_all.py [--quick] [--json PATH] [--data-dir ../shared/benchmarks] [--only aco,dwa,...]
      python benchmarks/run_all.py --page     # docs/benchmarks.md from the JSON records (benchmarks/page.py)

Each row is ``quantity | jaxplan | reference (what it is) | speed-up | unit``. Every reference
is measured in the same run, on the same machine, right beside the jaxplan figure (the one
exception, the chen2023 row's MATLAB time, is labelled as the paper's figure). "speed-up" is
how many times faster jaxplan is than the reference (reference time / jaxplan time, or
jaxplan rate / reference rate): above 1 jaxplan is faster. Every timing excludes compilation
and warm-up (first calls are made before timing and reported separately as compile rows)
and is the median of the number of repeats printed in the row (``n=``). A row whose data
file is missing reads "skipped: FILE not found"; a section that fails reads "failed: …"
and the others still run.

Sections and rows (sizes: default / ``--quick``):

  aco      `iaco` with 1,024 ants, 5 iterations on ``jp.RandomMapGenerator(100, 100, 0.2)(0)``
           (its start and goal): M ant-steps/s — moves made by ants still walking
           (``o.ant_steps`` of `_run_colony`, as benchmarks/bench_aco_speed.py counts them) per
           second of run time — with the default numba walk against ``walk_backend="jax"``
           (the plain JAX `lax.while_loop` step loop); the compile time of each
           configuration (XLA lower + compile, and the first call minus the steady run, which
           adds numba's load/compile). Then a chen2023-sized run: `risk_aco` defaults on
           ``jp.warehouse_chen2023(0)`` with ``jp.poisson_risk`` (20x20, 100 ants x 50
           iterations), ms per run (`PlanResult.time_s`), beside the paper's 8,468 ms in MATLAB
           (a figure from the paper, not a measurement).
  dwa      one control step (20 x 40 samples x 20 steps = 16,000 trajectory points per robot,
           hybrid clearance, weighted evaluator) for 1 and 64 robots on bench_dwa.py's
           warehouse `scene`: ms per step and M trajectory points/s of the compiled
           `dwa_control` / `dwa_control_batch`, against bench_dwa.py's `numpy_step` (the same
           maths vectorised over robots and samples, a Python loop over the 20 steps); compile
           time (lower + compile) of each program.
  exact    brc202d (MovingAI): median time of one `jp.astar` query over sampled scenario rows
           against scipy's single-source `dijkstra` from the same start on the same graph
           (bench_exact.py's `csgraph_of`: 8-connected, no corner cutting); scenario rows through
           `jp.shortest_lengths` in one call against scipy's Dijkstra per row (timed on 50 rows,
           scaled); the first call (loading the compiled search loops).
  metrics  10,000 / 2,000 random walks x 256 points (bench_metrics.py's `random_walks`, valid
           counts in [128, 256]) through jaxplan.metrics' batched core (one compiled call:
           length, turns, sharp turns, smoothness, min/mean clearance, max curvature) against
           bench_metrics.py's numpy loop path by path on 500 / 100 paths, both as paths/s
           (the loop's time scaled per path); compile time.
  episodes static `iaco_dwa` episodes on warehouse-10-20-10-2-1 (scenario rows with optimal
           length <= 80 cells, 1.0 m per cell, as bench_nav.py's speed section): episodes/s of
           one `jp.navigate_batch` call over 64 / 16 episodes (global planning + episode call,
           compile excluded; 3 / 2 repeats) against the first 5 / 3 of the same episodes one per
           `navigate_batch` call; the simulated time / wall time of episode 0's compiled control
           loop alone (as bench_nav.py's speed section times it) against real time (1x); the
           episode call's compile time for both sizes, and the rest of the first call's one-off
           cost (compiling global planning and smoothing for the batch). `navigate_batch` lowers
           and compiles its episode program once per configuration and shapes (repeats reuse it);
           `_LastProgram` records the program and arguments of the last call.
  tune     population evaluations/s of a `jaxplan.tune.aco_objective` (iaco weights α, β, λ;
           random 32x32 map with 20 % obstacles, 8 / 4 training scenarios x 2 seeds, 64 / 32 ants
           x 10 / 5 iterations): a population of 16 / 8 members in one compiled call
           (`Objective.evaluate`) against the same members evaluated one at a time in a Python
           loop (the same objective compiled for one member); compile time. "not available"
           (with the reason) if jaxplan.tune has no such API.
  tsp      eil51 (TSPLIB): ms per iteration of `jp.solve_tsp(…, "aco", ants=500)` (Ant System,
           α = 1, β = 5, ρ = 0.5, Q = 100; 50 / 10 iterations per run) against a plain numpy Ant
           System iteration written here (`numpy_as_iteration`: vectorised over the 500 ants, a
           Python loop over the 51 construction steps, the same update); compile time.

  scale    `jp.plan_batch(…, planner="iaco")` on ``jp.RandomMapGenerator(100, 100, 0.2)(0)``, 16 / 8
           scenarios (free pairs, numpy seed 0) x 2 seeds, 256 ants x 10 / 5 iterations: runs/s
           split over this process's host devices (one per core: `jaxplan.use_host_devices`)
           against ``mesh=None`` (one device), the two timed in turn (bench_scale.py has the
           1-device-process and thread variants).

The machine header lists the CPU model, cores, this process's CPU affinity, RAM, the jax,
jaxlib, numba, numpy and scipy versions, XLA's devices and the git revision. The JSON
(machine, options, rows, wall time) goes to ``benchmarks/results/run_all-<UTC date>-<git
short rev>[-quick].json`` (written atomically) and, with ``--json PATH``, to PATH as well.
Other processes sharing the cores make every figure noisy; compare medians of quiet runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import functools
import json
import os
import statistics
import sys
import time
import traceback
from pathlib import Path
from typing import Any, Callable

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from _timing import Steal, blocking, median_time  # noqa: E402

PAPER_CHEN2023_MS = 8468.0
SECTIONS = ("aco", "dwa", "exact", "metrics", "episodes", "tune", "tsp", "scale")


# ---------------------------------------------------------------------------------------------
# Rows


@dataclasses.dataclass
class Row:
    """One line of the table. ``speedup`` > 1: jaxplan is faster than the reference."""

    section: str
    quantity: str
    unit: str
    value: float | None = None
    reference: float | None = None
    reference_what: str = ""
    speedup: float | None = None
    repeats: int | None = None
    status: str = "ok"  # "ok", or "skipped: …", "failed: …", "not available: …"


def rate_row(section: str, quantity: str, unit: str, value: float, reference: float | None, what: str,
             repeats: int) -> Row:
    """A throughput row (higher is better): speed-up = value / reference."""
    sp = value / reference if reference else None
    return Row(section, quantity, unit, value, reference, what, sp, repeats)


def time_row(section: str, quantity: str, unit: str, value: float, reference: float | None, what: str,
             repeats: int) -> Row:
    """A time row (lower is better): speed-up = reference / value."""
    sp = reference / value if reference and value else None
    return Row(section, quantity, unit, value, reference, what, sp, repeats)


def compile_row(section: str, quantity: str, seconds: float) -> Row:
    return Row(section, quantity, "s", seconds, None, "— (one-off)", None, 1)


def status_row(section: str, status: str) -> Row:
    return Row(section, f"{section} section", "", status=status)


# ---------------------------------------------------------------------------------------------
# Machine


def machine() -> dict[str, Any]:
    """The provenance record (`jaxplan.core.provenance`) under the keys this script's JSON has always used, plus
    the load average at the start."""
    from jaxplan.core.provenance import provenance

    rec = provenance()
    versions = {k: v or "not installed" for k, v in rec["versions"].items()}
    return {
        "cpu": rec["cpu"], "cpu_info": rec["cpu_info"], "cpu_line": rec["cpu_line"],
        "cores": rec["cores"], "affinity": rec["affinity"], "ram_gb": rec["ram_gb"],
        "load_avg": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "python": rec["python"], "platform": rec["platform"], "host": rec["host"],
        "jax": versions["jax"], "jaxlib": versions["jaxlib"], "numba": versions["numba"],
        "numpy": versions["numpy"], "scipy": versions["scipy"], "jaxplan": versions["jaxplan"],
        "devices": rec["devices"], "XLA_FLAGS": rec["xla_flags"],
        "git_rev": (rec["git_revision"] or "")[:7], "git_dirty": bool(rec["git_dirty"]),
    }


# ---------------------------------------------------------------------------------------------
# 1. ACO


def _colony_speed(scene, backend: str, ants: int, iterations: int, repeats: int) -> dict:
    """Median ant-steps/s and run time of iaco, plus its compile times (as bench_aco_speed.py)."""
    from jaxplan.aco._planners import _run_colony
    from jaxplan.registry import resolve

    starts, goals = np.asarray([scene.start]), np.asarray([scene.goal])
    _, p = resolve("iaco", dict(ants=ants, iterations=iterations, walk_backend=backend))
    t0 = time.perf_counter()
    _, _, compile_s, _ = _run_colony("iaco", scene.grid, starts, goals, [0], p)
    first = time.perf_counter() - t0
    rates, times = [], []
    for s in range(repeats):
        o, run_s, _, _ = _run_colony("iaco", scene.grid, starts, goals, [s + 1], p)
        times.append(run_s)
        rates.append(int(np.asarray(o.ant_steps).sum()) / run_s)
    run = statistics.median(times)
    return dict(rate=statistics.median(rates), run_s=run, xla_compile_s=compile_s, first_minus_run_s=first - run)


def section_aco(args) -> list[Row]:
    import jaxplan as jp

    n, ants, its = args.repeats, 1024, 5
    scene = jp.RandomMapGenerator(100, 100, 0.2)(0)
    res = {b: _colony_speed(scene, b, ants, its, n) for b in ("numba", "jax")}
    q = f"iaco {ants} ants x {its} it, 100x100 20 %"
    rows = [rate_row("aco", f"{q}: ant-steps/s", "M/s", res["numba"]["rate"] / 1e6, res["jax"]["rate"] / 1e6,
                     "walk_backend='jax' (plain JAX step loop)", n)]
    for b in ("numba", "jax"):
        rows.append(compile_row("aco", f"compile, iaco {ants} ants, {b} walk: XLA", res[b]["xla_compile_s"]))
        rows.append(compile_row("aco", f"compile, iaco {ants} ants, {b} walk: first call - run",
                                res[b]["first_minus_run_s"]))
    ware = jp.warehouse_chen2023(0)
    grid = jp.poisson_risk(ware.grid, 0, lam=1.0)
    jp.plan(grid, ware.start, ware.goal, planner="risk_aco", seed=0)
    m = max(n, 5)
    ms = 1e3 * statistics.median(jp.plan(grid, ware.start, ware.goal, planner="risk_aco", seed=s + 1).time_s
                                 for s in range(m))
    rows.append(time_row("aco", "chen2023-sized run: risk_aco 100 ants x 50 it, 20x20", "ms", ms, PAPER_CHEN2023_MS,
                         "paper's figure (MATLAB), not measured", m))
    return rows


# ---------------------------------------------------------------------------------------------
# 2. DWA


def _dwa_program(robots: int):
    """``(compiled, args, compile_s, grid, states, goals, cfg)`` for bench_dwa.py's scene with ``robots`` robots."""
    import jax
    from bench_dwa import scene

    from jaxplan.dwa import DWAConfig, default_params, dwa_control, dwa_control_batch
    from jaxplan.dwa._step import table_of

    cfg = DWAConfig(keep_rollouts=False, clearance="hybrid")
    grid, states, goals = scene(robots)
    table = table_of(grid)
    params, cfg_dev = jax.device_put(default_params()), jax.device_put(cfg)
    if robots == 1:
        fn = jax.jit(dwa_control)
        a = (table, cfg_dev, params, jax.device_put(states[0]), jax.device_put(goals[0]))
    else:
        fn = jax.jit(dwa_control_batch, static_argnames="chunk")
        a = (table, cfg_dev, params, jax.device_put(states), jax.device_put(goals))
    t0 = time.perf_counter()
    compiled = fn.lower(*a).compile()
    return compiled, a, time.perf_counter() - t0, grid, states, goals, cfg, table


def section_dwa(args) -> list[Row]:
    from bench_dwa import numpy_step

    from jaxplan.dwa._clearance import PAD

    rows: list[Row] = []
    n, n_np = args.repeats + 4, args.repeats
    for B in (1, 64):
        compiled, a, compile_s, grid, states, goals, cfg, table = _dwa_program(B)
        call = blocking(compiled, a)
        call()
        t_jax = median_time(call, n)
        quads = np.asarray(table.quads)
        nst = functools.partial(numpy_step, quads, float(grid.resolution), grid.shape, states, goals, cfg, PAD)
        nst()
        t_np = median_time(nst, n_np)
        points = B * cfg.samples * cfg.steps
        what = f"numpy_step (bench_dwa.py), n={n_np}"
        rows.append(time_row("dwa", f"DWA control step, {B} robot{'s' * (B > 1)}", "ms", 1e3 * t_jax, 1e3 * t_np,
                             what, n))
        rows.append(rate_row("dwa", f"DWA trajectory points, {B} robot{'s' * (B > 1)}", "M pts/s",
                             points / t_jax / 1e6, points / t_np / 1e6, what, n))
        rows.append(compile_row("dwa", f"compile, DWA {'dwa_control' if B == 1 else 'dwa_control_batch'} ({B})",
                                compile_s))
    return rows


# ---------------------------------------------------------------------------------------------
# 3. Exact search


def section_exact(args) -> list[Row]:
    from bench_exact import csgraph_of
    from scipy.sparse.csgraph import dijkstra

    import jaxplan as jp

    d = Path(args.data_dir) / "movingai"
    for f in (d / "brc202d.map", d / "brc202d.map.scen"):
        if not f.exists():
            return [status_row("exact", f"skipped: {f} not found")]
    grid = jp.load_map(d / "brc202d.map")
    scen = jp.load_scenarios(d / "brc202d.map.scen", grid=grid)
    graph = csgraph_of(grid)
    W = grid.width
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    jp.astar(grid, scen.starts[0], scen.goals[0])
    first = time.perf_counter() - t0
    q = rng.choice(len(scen.starts), size=min(args.queries, len(scen.starts)), replace=False)
    t_ours, t_ref = [], []
    for i in q:
        s = scen.starts[i]
        t0 = time.perf_counter()
        jp.astar(grid, s, scen.goals[i])
        t_ours.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        dijkstra(graph, indices=int(s[1] * W + s[0]))
        t_ref.append(time.perf_counter() - t0)
    rows = [time_row("exact", "brc202d: one A* query (jp.astar)", "ms", 1e3 * statistics.median(t_ours),
                     1e3 * statistics.median(t_ref), "scipy csgraph dijkstra, same start, same graph", len(q))]
    sel = rng.choice(len(scen.starts), size=min(args.rows, len(scen.starts)), replace=False)
    S, G = scen.starts[sel], scen.goals[sel]
    jp.shortest_lengths(grid, S, G)
    reps = max(1, min(args.repeats, 3))
    batch = median_time(lambda: jp.shortest_lengths(grid, S, G), reps)
    sub = sel[:50]
    t0 = time.perf_counter()
    for i in sub:
        dijkstra(graph, indices=int(scen.starts[i][1] * W + scen.starts[i][0]))
    scipy_rows = (time.perf_counter() - t0) / len(sub) * len(sel)
    rows.append(time_row("exact", f"brc202d: {len(sel)} rows via shortest_lengths", "s", batch, scipy_rows,
                         f"scipy dijkstra per row (timed on {len(sub)}, scaled)", reps))
    rows.append(compile_row("exact", "first A* call (loads the compiled search loops)", first))
    return rows


# ---------------------------------------------------------------------------------------------
# 4. Metrics


def section_metrics(args) -> list[Row]:
    import jax
    import jax.numpy as jnp
    from bench_metrics import numpy_metrics, random_walks

    import jaxplan as jp
    from jaxplan.grid._collision import cached_collision_map
    from jaxplan.metrics._front import _core, _pad, bucket

    B, L = args.paths, 256
    grid = jp.RandomMapGenerator(100, 100, 0.2)(0).grid
    paths = random_walks(grid, B, L, 0)
    n = np.random.default_rng(1).integers(L // 2, L + 1, size=B)
    cmap = cached_collision_map(grid)
    padded, n_dev = jnp.asarray(_pad(paths, bucket(L))), jnp.asarray(n, jnp.int32)
    core = lambda: jax.block_until_ready(_core(cmap, padded, n_dev))  # noqa: E731
    t0 = time.perf_counter()
    core()
    compile_s = time.perf_counter() - t0
    t_core = median_time(core, args.repeats)
    field = jp.clearance_field(grid)
    sub = min(args.subset, B)
    res = float(grid.resolution)
    loop = lambda: [numpy_metrics(paths[b, : n[b]], field, res) for b in range(sub)]  # noqa: E731
    loop()
    t_np = median_time(loop, 3)
    return [rate_row("metrics", f"path metrics, {B} paths x {L} (one compiled call)", "paths/s", B / t_core,
                     sub / t_np, f"numpy loop path by path ({sub} paths, n=3, per path)", args.repeats),
            compile_row("metrics", "compile, metrics core (first call)", compile_s)]


# ---------------------------------------------------------------------------------------------
# 5. Episodes


class _LastProgram:
    """Wraps `jaxplan.nav._front._compiled_episodes` (which keeps one compiled episode program per
    configuration and shapes) to remember the last call's program and arguments, so that the
    episode call alone can be timed, as bench_nav.py's speed section does."""

    def __init__(self, real) -> None:
        self.real, self.last = real, None

    def __call__(self, cfg, steps, mesh, args):
        fn, compile_s = self.real(cfg, steps, mesh, args)
        self.last = (fn, args)
        return fn, compile_s


def section_episodes(args) -> list[Row]:
    from bench_nav import WAREHOUSE, load

    import jaxplan as jp
    from jaxplan.nav import _front as F

    d = Path(args.data_dir) / "movingai"
    if not (d / f"{WAREHOUSE}.map").exists():
        return [status_row("episodes", f"skipped: {d / WAREHOUSE}.map not found")]
    if not any((d / f"{WAREHOUSE}{x}").exists() for x in (".map.scen", "-random-1.scen")):  # as bench_nav.load
        return [status_row("episodes", f"skipped: {d / WAREHOUSE}.map.scen not found")]
    grid, scen = load(d, WAREHOUSE)
    ok = np.nonzero(scen.optimal <= 80)[0]
    sel = ok[np.arange(args.episodes) % len(ok)]
    S, G = scen.starts[sel], scen.goals[sel]
    E = len(sel)
    memo = _LastProgram(F._compiled_episodes)
    F._compiled_episodes = memo
    try:
        def batch(s, g):
            b = jp.navigate_batch(grid, s, g, pipeline="iaco_dwa", seeds=[0])
            return b.plan_time_s * len(s) + b.run_time_s, b  # global planning + episode call, compile excluded

        t0 = time.perf_counter()
        t_first, b = batch(S, G)  # compiles
        first_extra = time.perf_counter() - t0 - t_first - b.compile_s
        reps = args.nav_repeats
        t_batch = statistics.median(batch(S, G)[0] for _ in range(reps))
        # Reference: the same episodes one per call (the one-episode program compiled first).
        k = min(E, args.nav_singles)
        _, one = batch(S[:1], G[:1])
        single_compile = one.compile_s
        t_one = statistics.median(batch(S[i:i + 1], G[i:i + 1])[0] for i in range(k))
        # One episode's compiled control loop alone (episode 0), against real time.
        one = batch(S[:1], G[:1])[1]
        compiled, a = memo.last
        call = blocking(compiled, a)
        call()
        n_loop = args.repeats + 4
        t_loop = median_time(call, n_loop)
    finally:
        F._compiled_episodes = memo.real
    sim = int(one.steps.sum()) * one.period
    return [rate_row("episodes", f"iaco_dwa static episodes, {E} in one call ({100 * b.success.mean():.0f} % ok)",
                     "episodes/s", E / t_batch, 1 / t_one,
                     f"first {k} of them one per navigate_batch call (median)", reps),
            rate_row("episodes", f"one episode's control loop ({sim:.1f} s simulated)", "x real time", sim / t_loop,
                     1.0, "real time (1 s simulated per s)", n_loop),
            compile_row("episodes", f"compile, episode call ({E} episodes)", b.compile_s),
            compile_row("episodes", "compile, episode call (1 episode, reference)", single_compile),
            compile_row("episodes", f"first call - run - episode compile ({E} episodes: planning, smoothing)",
                        first_extra)]


# ---------------------------------------------------------------------------------------------
# 6. Tuning


def _tune_objective(args):
    """A small iaco-weights objective (or raises ImportError/AttributeError if jaxplan.tune lacks the API)."""
    import jaxplan as jp
    from jaxplan.tune import Split, aco_objective

    grid = jp.RandomMapGenerator(32, 32, 0.2)(0).grid
    rng = np.random.default_rng(0)
    cells = np.argwhere(np.asarray(grid.free))[:, ::-1]
    pairs = cells[rng.choice(len(cells), size=(4 * args.tune_scenarios, 2))]
    opt = jp.shortest_lengths(grid, pairs[:, 0], pairs[:, 1])
    good = np.nonzero(np.isfinite(opt) & (opt >= 8))[0][: args.tune_scenarios + 2]
    s, g, o = pairs[good, 0], pairs[good, 1], opt[good]
    N = args.tune_scenarios
    train, test = Split(s[:N], g[:N], o[:N], (0, 1)), Split(s[N:], g[N:], o[N:], (9,))
    obj = aco_objective(grid, train, test, "iaco", overrides=dict(ants=args.tune_ants, iterations=args.tune_iterations))
    if not callable(getattr(obj, "evaluate", None)):
        raise AttributeError("Objective has no evaluate(pop)")
    return obj, N


def section_tune(args) -> list[Row]:
    try:
        obj, N = _tune_objective(args)
    except (ImportError, AttributeError, TypeError) as e:
        return [status_row("tune", f"not available: jaxplan.tune ({type(e).__name__}: {e})")]
    P = args.population
    rng = np.random.default_rng(0)
    pop = (obj.bounds.low + rng.random((P, obj.bounds.dim)) * (obj.bounds.high - obj.bounds.low)).astype(np.float32)
    first = obj.evaluate(pop)
    n = args.repeats
    t_batch = statistics.median(obj.evaluate(pop).time_s for _ in range(n))
    compile_one = obj.evaluate(pop[:1]).compile_s

    def loop() -> None:
        for i in range(P):
            obj.evaluate(pop[i:i + 1])

    reps = max(2, n - 1)
    t_loop = median_time(loop, reps)
    return [rate_row("tune", f"tune: iaco objective, {P} members x {N} scenarios x 2 seeds", "members/s", P / t_batch,
                     P / t_loop, f"same members one at a time in a Python loop (n={reps})", n),
            compile_row("tune", f"compile, objective for {P} members", first.compile_s),
            compile_row("tune", "compile, objective for 1 member (reference)", compile_one)]


# ---------------------------------------------------------------------------------------------
# 7. TSP


def numpy_as_iteration(dist: np.ndarray, tau: np.ndarray, rng: np.random.Generator, ants: int, alpha: float = 1.0,
                       beta: float = 5.0, rho: float = 0.5, q: float = 100.0) -> tuple[np.ndarray, np.ndarray]:
    """One Ant System iteration in plain numpy: ``(new pheromone, tour lengths)``.

    All ants build their tours together (vectorised over ants, a Python loop over the n − 1
    construction steps, random start cities, next city by inverse CDF of τ^α·η^β over the
    unvisited cities), then τ ← (1 − ρ)·τ + Σ_ants Q/L on both directions of every tour edge.
    """
    n = len(dist)
    eta = 1.0 / np.where(dist > 0, dist, np.inf)
    weights = tau ** alpha * eta ** beta
    rows = np.arange(ants)
    pos = rng.integers(0, n, ants)
    visited = np.zeros((ants, n), bool)
    visited[rows, pos] = True
    tours = np.empty((ants, n), np.int64)
    tours[:, 0] = pos
    for t in range(1, n):
        p = np.where(visited, 0.0, weights[pos] + 1e-300)
        cum = np.cumsum(p, axis=1)
        u = rng.random(ants)[:, None] * cum[:, -1:]
        pos = np.minimum((cum <= u).sum(axis=1), n - 1)
        visited[rows, pos] = True
        tours[:, t] = pos
    nxt = np.roll(tours, -1, axis=1)
    lengths = dist[tours, nxt].sum(axis=1)
    dep = np.zeros_like(tau)
    amount = np.broadcast_to((q / lengths)[:, None], tours.shape)
    np.add.at(dep, (tours, nxt), amount)
    np.add.at(dep, (nxt, tours), amount)
    return (1 - rho) * tau + dep, lengths


def section_tsp(args) -> list[Row]:
    import jaxplan as jp

    f = Path(args.data_dir) / "tsplib" / "eil51.tsp"
    if not f.exists():
        return [status_row("tsp", f"skipped: {f} not found")]
    prob = jp.load_tsplib(f)
    its, ants = args.tsp_iterations, 500
    first = jp.solve_tsp(prob, "aco", seed=0, iterations=its, ants=ants)
    n = args.repeats
    per_it = statistics.median(jp.solve_tsp(prob, "aco", seed=s + 1, iterations=its, ants=ants).time_s / its
                               for s in range(n))
    dist = np.asarray(prob.dist, np.float64)
    tau = np.ones_like(dist)
    rng = np.random.default_rng(0)
    tau, _ = numpy_as_iteration(dist, tau, rng, ants)  # warm-up
    ts = []
    for _ in range(n):
        t0 = time.perf_counter()
        tau, _ = numpy_as_iteration(dist, tau, rng, ants)
        ts.append(time.perf_counter() - t0)
    return [time_row("tsp", f"TSP eil51: aco, {ants} ants, ms per iteration ({its} it per run)", "ms", 1e3 * per_it,
                     1e3 * statistics.median(ts), f"numpy Ant System iteration (run_all.py), n={n}", n),
            compile_row("tsp", f"compile, solve_tsp aco {ants} ants", float(first.info.get("compile_s", 0.0)))]


# ---------------------------------------------------------------------------------------------
# 8. Scale


def section_scale(args) -> list[Row]:
    import jax

    import jaxplan as jp
    from jaxplan.scale import batch_mesh

    devices = jax.local_devices()
    if len(devices) < 2:
        return [status_row("scale", f"skipped: {len(devices)} local device (JAXPLAN_HOST_DEVICES / XLA_FLAGS)")]
    scene = jp.RandomMapGenerator(100, 100, 0.2)(0)
    free = np.argwhere(np.asarray(scene.grid.free))[:, ::-1]
    n, its = args.scale_scenarios, args.scale_iterations
    idx = np.random.default_rng(0).choice(len(free), (n, 2), replace=False)
    s, g = free[idx[:, 0]], free[idx[:, 1]]
    mesh = batch_mesh(devices)

    def run(m):
        return lambda: jp.plan_batch(scene.grid, s, g, planner="iaco", seeds=[0, 1], ants=256, iterations=its, mesh=m)

    sharded, single = run(mesh), run(None)
    sharded(), single()  # compile both
    ts: dict[str, list[float]] = {"mesh": [], "one": []}
    for _ in range(args.repeats):  # in turn, so that the machine's drift hits both alike
        for k, f in (("mesh", sharded), ("one", single)):
            t0 = time.perf_counter()
            f()
            ts[k].append(time.perf_counter() - t0)
    runs = 2 * n
    return [rate_row("scale", f"iaco plan_batch {n} scenarios x 2 seeds, 256 ants x {its} it, over {len(devices)} "
                     "host devices", "runs/s", runs / statistics.median(ts["mesh"]),
                     runs / statistics.median(ts["one"]), "mesh=None (one device), timed in turn", args.repeats)]


# ---------------------------------------------------------------------------------------------
# Table, JSON, main

SECTION_FNS: dict[str, Callable] = {"aco": section_aco, "dwa": section_dwa, "exact": section_exact,
                                    "metrics": section_metrics, "episodes": section_episodes, "tune": section_tune,
                                    "tsp": section_tsp, "scale": section_scale}


def _num(x: float | None) -> str:
    if x is None:
        return "—"
    if x == 0:
        return "0"
    a = abs(x)
    if a >= 1e4:
        return f"{x:,.0f}"
    if a >= 100:
        return f"{x:.0f}"
    if a >= 10:
        return f"{x:.1f}"
    if a >= 0.1:
        return f"{x:.2f}"
    return f"{x:.3g}"


def table(rows: list[Row]) -> str:
    """The rows as a fixed-width text table (status rows as ``quantity | status``)."""
    head = ("quantity", "jaxplan", "reference", "reference is", "speed-up", "unit", "n")
    cells = {id(r): (r.quantity, _num(r.value), _num(r.reference), r.reference_what,
                     f"{r.speedup:.1f}x" if r.speedup is not None else "—", r.unit, str(r.repeats or ""))
             for r in rows if r.status == "ok"}
    widths = [max([len(h)] + [len(c[i]) for c in cells.values()]) for i, h in enumerate(head)]
    widths[0] = max([widths[0]] + [len(r.quantity) for r in rows])
    right = {1, 2, 4, 6}

    def line(c) -> str:
        cells = zip(c, widths, strict=True)
        return " | ".join(x.rjust(w) if i in right else x.ljust(w) for i, (x, w) in enumerate(cells))

    out = [line(head), "-+-".join("-" * w for w in widths)]
    for k, r in enumerate(rows):
        if k and r.section != rows[k - 1].section:
            out.append("")
        out.append(line(cells[id(r)]) if r.status == "ok" else f"{r.quantity:<{widths[0]}} | {r.status}")
    return "\n".join(out)


COLUMNS = ["section", "quantity", "jaxplan", "reference", "reference is", "speed-up", "unit", "n"]
"""The columns of the recorded table (docs/benchmarks.md shows it)."""


def rows_table(rows: list[dict]) -> dict:
    """The JSON record's table of ``rows`` (`Row` as dicts): a row that did not run holds its status as quantity."""
    out = [[r["section"], r["quantity"], r["value"], r["reference"], r["reference_what"], r["speedup"], r["unit"],
            r["repeats"]] if r["status"] == "ok" else [r["section"], r["status"], None, None, "", None, "", None]
            for r in rows]
    return {"name": "all sections",
            "title": "every section in one table: jaxplan beside the reference measured (or quoted) in the same run",
            "columns": COLUMNS, "rows": out,
            "notes": ["speed-up: how many times faster jaxplan is than the reference (above 1: faster); n: repeats "
                      "of the median; compilation excluded (its own rows). Every reference is measured in the same "
                      "run, except the chen2023 row's MATLAB time, the paper's figure."]}


def write_json_atomic(path: Path, data: dict) -> None:
    from jaxplan.core.io import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, json.dumps(data, indent=1) + "\n")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="small sizes (about 3 min on 2 cores)")
    ap.add_argument("--json", type=Path, default=None, help="also write the JSON here")
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", str(ROOT.parent / "shared" / "benchmarks")))
    ap.add_argument("--only", default=",".join(SECTIONS), help=f"comma-separated sections of {','.join(SECTIONS)}")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar on stderr (drawn only on a terminal)")
    ap.add_argument("--page", action="store_true",
                    help="only write docs/benchmarks.md from the JSON records in benchmarks/results/ (runs nothing)")
    args = ap.parse_args(argv)
    sizes = dict(repeats=5, queries=50, rows=1000, paths=10_000, subset=500, episodes=64, nav_repeats=3,
                 nav_singles=5, population=16,
                 tune_scenarios=8, tune_ants=64, tune_iterations=10, tsp_iterations=50, scale_scenarios=16,
                 scale_iterations=10)
    if args.quick:
        sizes = dict(repeats=3, queries=10, rows=250, paths=2_000, subset=100, episodes=16, nav_repeats=2,
                     nav_singles=3, population=8,
                     tune_scenarios=4, tune_ants=32, tune_iterations=5, tsp_iterations=10, scale_scenarios=8,
                 scale_iterations=5)
    for k, v in sizes.items():
        setattr(args, k, v)
    args.only = [s for s in args.only.split(",") if s]
    bad = [s for s in args.only if s not in SECTIONS]
    if bad:
        ap.error(f"unknown section(s) {bad}; choose from {SECTIONS}")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    if args.page:
        from page import write_page

        print(f"wrote {write_page()}")
        return
    import jaxplan

    jaxplan.use_host_devices()  # first, before JAX's backend starts: one host device per core (the scale rows)
    started = dt.datetime.now(dt.timezone.utc)
    t_start = time.perf_counter()
    mach = machine()
    steal = Steal()
    print(f"jaxplan benchmarks ({'quick' if args.quick else 'default'} sizes), {started:%Y-%m-%d %H:%M} UTC")
    print(f"machine: {mach['cpu_line']} (affinity {mach['affinity']}), "
          f"{mach['ram_gb']:.1f} GB RAM, load {mach['load_avg'][0]:.1f}" if mach["ram_gb"] and mach["load_avg"]
          else f"machine: {mach['cpu_line']}")
    print(f"  jax {mach['jax']}, jaxlib {mach['jaxlib']}, numba {mach['numba']}, numpy {mach['numpy']}, "
          f"scipy {mach['scipy']}; devices {mach['devices']}; git {mach['git_rev']}"
          f"{' (uncommitted changes)' if mach['git_dirty'] else ''}", flush=True)
    rows: list[Row] = []
    timings: dict[str, float] = {}
    from jaxplan.core.progress import ProgressBar

    with ProgressBar("bench", len(args.only), unit="sections", enabled=not args.no_progress) as bar:
        for k, name in enumerate(args.only):
            bar.update(k, description=f"bench: {name}")
            t0 = time.perf_counter()
            try:
                rows.extend(SECTION_FNS[name](args))
            except FileNotFoundError as e:
                rows.append(status_row(name, f"skipped: {e.filename or e} not found"))
            except Exception as e:  # noqa: BLE001 - one failing section must not hide the others
                traceback.print_exc()
                rows.append(status_row(name, f"failed: {type(e).__name__}: {e}"))
            timings[name] = time.perf_counter() - t0
            print(f"  [{name}: {timings[name]:.0f} s]", file=sys.stderr, flush=True)
        bar.update(len(args.only), description="bench")
    wall = time.perf_counter() - t_start
    print("\nspeed-up: times faster than the reference (>1: jaxplan faster); n: repeats of the median; "
          "compilation excluded\n")
    print(table(rows))
    mach["steal_fraction"] = steal.fraction()
    print(steal.summary(mach["steal_fraction"]))
    print(f"\nwall time {wall:.0f} s ({', '.join(f'{k} {v:.0f} s' for k, v in timings.items())})")
    data = {"bench": "run_all", "command": " ".join(["python", "benchmarks/run_all.py", *sys.argv[1:]]),
            "started_utc": started.isoformat(timespec="seconds"), "quick": args.quick,
            "machine_line": mach["cpu_line"], "machine": mach, "load_avg": mach["load_avg"],
            "steal": mach["steal_fraction"],
            "options": {k: v for k, v in vars(args).items() if k not in ("json", "no_progress", "page")},
            "wall_s": wall, "section_wall_s": timings, "rows": [dataclasses.asdict(r) for r in rows]}
    data["tables"] = [rows_table(data["rows"])]
    name = f"run_all-{started:%Y-%m-%d}-{mach['git_rev'] or 'norev'}{'-quick' if args.quick else ''}.json"
    out = HERE / "results" / name
    write_json_atomic(out, data)
    print(f"JSON: {out}")
    if args.json:
        write_json_atomic(args.json, data)
        print(f"JSON: {args.json}")


if __name__ == "__main__":
    main()
