"""Exact search speed: jaxplan's A* and batched `shortest_lengths` beside scipy's Dijkstra.

Run:  python benchmarks/bench_exact.py [--data-dir ../shared/benchmarks] [--queries 50] [--rows 1000]

For brc202d (MovingAI, 530x481) and a 512x512 random map with 20 % obstacles it prints
  * one exact query: median time of `jp.astar` (map prepared once, as scipy's graph is)
    beside scipy.sparse.csgraph.dijkstra from the same start on the same graph
    (same move table: 8-connected, no corner cutting), and their ratio (target <= 1.0);
  * 1,000 scenario rows through `jp.shortest_lengths` (median of 3 runs; target < 10 s
    on brc202d), beside scipy's single-source Dijkstra per row (timed on a subset and
    scaled, as a full scipy run takes minutes);
  * the first-call time (loading the compiled search loops) and the machine.
The figures also go to a JSON record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import scipy
import scipy.sparse as sp
from _timing import Record, median_time
from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

import jaxplan as jp
from jaxplan.grid import _kernels


def csgraph_of(grid: jp.GridMap) -> sp.csr_array:
    t = jp.neighbour_table(grid, 8)
    rows = np.repeat(np.arange(grid.n_cells), t.valid.shape[1])[t.valid.ravel()]
    cols = t.index.ravel()[t.valid.ravel()]
    step = np.hypot(t.offsets[:, 0], t.offsets[:, 1]) * float(grid.resolution)  # f64, as the search uses
    w = np.tile(step, grid.n_cells)[t.valid.ravel()]
    return sp.csr_array((w, (rows, cols)), shape=(grid.n_cells, grid.n_cells))



def bench_map(name: str, grid: jp.GridMap, starts: np.ndarray, goals: np.ndarray, optimal, n_queries: int, n_rows: int,
              table: list[list] | None = None):
    rng = np.random.default_rng(0)
    graph = csgraph_of(grid)
    W = grid.width
    t0 = time.perf_counter()
    jp.astar(grid, starts[0], goals[0])
    first = time.perf_counter() - t0

    q = rng.choice(len(starts), size=min(n_queries, len(starts)), replace=False)
    t_ours, t_scipy, expanded = [], [], []
    for i in q:
        s, g = starts[i], goals[i]
        t0 = time.perf_counter()
        r = jp.astar(grid, s, g)
        t_ours.append(time.perf_counter() - t0)
        expanded.append(r.info["expanded"])
        t0 = time.perf_counter()
        d = scipy_dijkstra(graph, indices=int(s[1] * W + s[0]))
        t_scipy.append(time.perf_counter() - t0)
        assert abs(d[g[1] * W + g[0]] - r.length) <= 1e-9 * max(1.0, r.length)
        if optimal is not None:
            assert abs(r.length - optimal[i]) <= 1e-4 * max(1.0, optimal[i])
    one_ours, one_scipy = statistics.median(t_ours), statistics.median(t_scipy)

    rows = rng.choice(len(starts), size=min(n_rows, len(starts)), replace=False)
    S, G = starts[rows], goals[rows]
    out = jp.shortest_lengths(grid, S, G)
    if optimal is not None:
        np.testing.assert_allclose(out, optimal[rows], rtol=1e-4)
    batch = median_time(lambda: jp.shortest_lengths(grid, S, G), 3)
    sub = rows[:50]
    t0 = time.perf_counter()
    for i in sub:
        scipy_dijkstra(graph, indices=int(starts[i][1] * W + starts[i][0]))
    scipy_rows = (time.perf_counter() - t0) / len(sub) * len(rows)

    free = int(np.asarray(grid.free).sum())
    print(f"\n{name}: {grid.shape[1]}x{grid.shape[0]}, {free} free cells, {graph.nnz} directed moves")
    print(f"  {'measure':<44}{'jaxplan':>12}{'scipy':>12}{'ratio':>8}")
    print(f"  {'one query, median of ' + str(len(q)) + ' (ms)':<44}{one_ours * 1e3:>12.2f}{one_scipy * 1e3:>12.2f}"
          f"{one_ours / one_scipy:>8.2f}")
    print(f"  {'  A* nodes expanded, median':<44}{statistics.median(expanded):>12.0f}{free:>12d}")
    print(f"  {str(len(rows)) + ' rows via shortest_lengths, median of 3 (s)':<44}{batch:>12.3f}{scipy_rows:>12.3f}"
          f"{batch / scipy_rows:>8.3f}")
    print(f"  {'first call incl. loading compiled loops (s)':<44}{first:>12.3f}")
    if table is not None:
        short = name.split(" (")[0]
        table += [[short, f"one query, median of {len(q)}", "ms", one_ours * 1e3, one_scipy * 1e3,
                   one_ours / one_scipy],
                  [short, "A* nodes expanded, median (scipy: every free cell)", "", statistics.median(expanded), free,
                   None],
                  [short, f"{len(rows)} rows via shortest_lengths, median of 3 (scipy: per row, scaled)", "s", batch,
                   scipy_rows, batch / scipy_rows],
                  [short, "first call, loading the compiled search loops", "s", first, None, None]]
    return dict(one=one_ours, one_scipy=one_scipy, batch=batch)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = Path(__file__).resolve().parents[1]
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", root.parent / "shared" / "benchmarks"))
    ap.add_argument("--queries", type=int, default=50)
    ap.add_argument("--rows", type=int, default=1000)
    args = ap.parse_args()
    record = Record("bench_exact", vars(args))
    table = record.table("exact search", ["map", "measure", "unit", "jaxplan", "scipy", "jaxplan ÷ scipy"],
                         "jp.astar and jp.shortest_lengths beside scipy's Dijkstra on the same graph")
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}, scipy {scipy.__version__}, jaxplan {jp.__version__}, "
          f"search threads {_kernels.n_threads()}")

    d = Path(args.data_dir) / "movingai"
    grid = jp.load_map(d / "brc202d.map")
    scen = jp.load_scenarios(d / "brc202d.map.scen", grid=grid)
    r1 = bench_map("brc202d (scenario rows, sampled across all buckets)", grid, scen.starts, scen.goals,
                   scen.optimal, args.queries, args.rows, table)

    scene = jp.RandomMapGenerator(512, 512, 0.2)(0)
    grid = scene.grid
    rng = np.random.default_rng(1)
    cells = np.argwhere(grid.free)[:, ::-1]
    pairs = cells[rng.choice(len(cells), size=(args.rows, 2))]
    ok = np.isfinite(jp.shortest_lengths(grid, pairs[:, 0], pairs[:, 1]))
    r2 = bench_map("random 512x512, 20 % obstacles (random connected pairs)", grid, pairs[ok, 0], pairs[ok, 1],
                   None, args.queries, args.rows, table)

    print("\ntargets: one query ratio <= 1.0 ->",
          "brc202d %.2f, random512 %.2f" % (r1["one"] / r1["one_scipy"], r2["one"] / r2["one_scipy"]),
          "| 1000 brc202d rows < 10 s -> %.2f s" % r1["batch"])
    record.note("Targets: one query at most scipy's time (ratio <= 1); 1,000 brc202d rows in under 10 s.")
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
