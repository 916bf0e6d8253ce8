"""Sampling planners beside exact ones: RRT*, MRBS-RRT* (li2026), KNG-A* (li2026) and A*.

Run:  python benchmarks/bench_sampling.py [--data-dir ../shared/benchmarks] [--rows 20] [--seeds 1]

On the MovingAI maps warehouse-10-20-10-2-1 and random-32-32-20 it takes ``--rows``
scenario rows with optimal length <= 80 (evenly spread over the eligible rows) and prints,
per planner with its registry defaults: success rate, mean ratio of the planned length to
the scenario's optimal octile length (any-angle paths can go below 1), mean turns, and the
median wall and CPU milliseconds per plan (CPU time is the steadier figure on a shared
machine). One-off costs (loading compiled numba loops, memoised map preparation) are
excluded by a warm-up pass over the same rows. The table also goes to a JSON record in benchmarks/results/
(`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from _timing import Record

import jaxplan as jp

MAPS = ("warehouse-10-20-10-2-1", "random-32-32-20")
PLANNERS = ("rrt_star", "mrbs_rrt", "astar_kng", "astar")


def rows_of(scen: jp.Scenarios, n: int, max_optimal: float) -> np.ndarray:
    ok = np.flatnonzero(scen.optimal <= max_optimal)
    return ok[np.linspace(0, len(ok) - 1, min(n, len(ok))).astype(int)]


def bench(grid: jp.GridMap, scen: jp.Scenarios, rows: np.ndarray, planner: str, seeds: int) -> dict[str, float]:
    for i in rows:  # warm-up: compilation and memoised map preparation
        jp.plan(grid, scen.starts[i], scen.goals[i], planner=planner, seed=0)
    ok, ratio, turns, ms, cpu = [], [], [], [], []
    for i in rows:
        for seed in range(seeds):
            t0, c0 = time.perf_counter(), time.process_time()
            r = jp.plan(grid, scen.starts[i], scen.goals[i], planner=planner, seed=seed)
            ms.append((time.perf_counter() - t0) * 1e3)
            cpu.append((time.process_time() - c0) * 1e3)
            ok.append(r.success)
            if r.success:
                ratio.append(r.length / scen.optimal[i])
                turns.append(r.turns)
    return {
        "success": float(np.mean(ok)),
        "ratio": float(np.mean(ratio)) if ratio else float("nan"),
        "turns": float(np.mean(turns)) if turns else float("nan"),
        "ms": statistics.median(ms),
        "cpu": statistics.median(cpu),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-dir", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "benchmarks")
    ap.add_argument("--rows", type=int, default=20)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--max-optimal", type=float, default=80.0)
    args = ap.parse_args()
    record = Record("bench_sampling", vars(args))
    table = record.table("sampling planners", ["map", "planner", "success", "length ÷ optimal", "turns", "ms per plan",
                                               "CPU ms per plan"],
                         f"{args.rows} rows × {args.seeds} seed(s) per map, optimal ≤ {args.max_optimal:g} cells")
    folder = args.data_dir / "movingai"
    if not folder.is_dir():
        raise SystemExit(f"MovingAI benchmarks not found at {folder} (pass --data-dir)")
    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"{args.rows} rows x {args.seeds} seed(s), optimal <= {args.max_optimal:g}")
    print(f"{'map':<24} {'planner':<10} {'success':>8} {'len/opt':>8} {'turns':>6} {'ms/plan':>8} {'cpu ms':>8}")
    for name in MAPS:
        grid = jp.load_map(folder / f"{name}.map")
        scen = jp.load_scenarios(folder / f"{name}-random-1.scen", grid=grid)
        rows = rows_of(scen, args.rows, args.max_optimal)
        for planner in PLANNERS:
            m = bench(grid, scen, rows, planner, args.seeds)
            print(f"{name:<24} {planner:<10} {m['success']:>8.2f} {m['ratio']:>8.3f} {m['turns']:>6.1f} "
                  f"{m['ms']:>8.2f} {m['cpu']:>8.2f}")
            table.append([name, planner, m["success"], m["ratio"], m["turns"], m["ms"], m["cpu"]])
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
