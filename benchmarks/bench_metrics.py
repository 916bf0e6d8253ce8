"""Path-metric throughput: a batch of padded paths in one compiled call, beside a numpy loop.

Run:  python benchmarks/bench_metrics.py [--paths 10000] [--length 256] [--repeat 5] [--subset 500]

Paths: random 8-connected walks (no corner cutting, a 70 % chance of keeping the previous
direction, so they turn like planner output rather than like noise) on a 100x100
random map with 20 % obstacles; each walk has ``--length`` points and a valid count drawn
in [length/2, length] so that padding is exercised.

Prints one table:
  * ``core``: the section-6 metrics that need no reference (length, turns, sharp turns,
    smoothness, min/mean clearance, max curvature) of the whole batch in ONE compiled
    call (`jaxplan.metrics._front._core`); target < 1 s for 10,000 x 256;
  * ``core, float paths``: the same walks jittered by up to 0.3 cell (as smoothed paths are
    float): their clearance goes through `point_clearance` (a 5x5 window per vertex)
    instead of the exact cell-centre field;
  * ``path_metrics``: the public front on the same batch (validation on the host,
    padding, transfers, and the automatic optimality gap through `jp.shortest_lengths`);
  * ``hausdorff``: `hausdorff` of ``--hausdorff-paths`` paths against references
    of the same size (O(k·L²) per pair, so timed on fewer paths);
  * ``numpy loop``: the same metrics path by path with the numpy host functions (and
    the clearance field at the vertices), timed on ``--subset`` paths (median of 3) and
    extrapolated.
Each JAX figure is the median of ``--repeat`` runs after one compiling call. The table also goes to a JSON record
in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import os
import time

import jax
import jax.numpy as jnp
import numpy as np
from _timing import Record, median_time

import jaxplan as jp
from jaxplan.grid._collision import cached_collision_map
from jaxplan.metrics import _host as H
from jaxplan.metrics._front import _core, _hausdorff_core, _pad, bucket


def random_walks(grid: jp.GridMap, count: int, length: int, seed: int) -> np.ndarray:
    """``int64[count, length, 2]`` 8-connected walks over free cells, without corner cutting."""
    rng = np.random.default_rng(seed)
    table = jp.neighbour_table(grid, 8)
    W = grid.width
    free = np.flatnonzero(np.asarray(grid.free).ravel() & table.valid.any(axis=1))
    cell = rng.choice(free, size=count)
    move = rng.integers(0, table.valid.shape[1], size=count)
    out = np.empty((count, length), np.int64)
    out[:, 0] = cell
    rows = np.arange(count)
    for t in range(1, length):
        valid = table.valid[cell]  # [count, K]
        keep = valid[rows, move] & (rng.random(count) < 0.7)
        # Otherwise a uniformly random valid move (every cell kept has at least one).
        score = np.where(valid, rng.random(valid.shape), -1.0)
        move = np.where(keep, move, np.argmax(score, axis=1))
        cell = table.index[cell, move]
        out[:, t] = cell
    return np.stack([out % W, out // W], axis=-1)



def numpy_metrics(path: np.ndarray, field: np.ndarray, res: float) -> tuple:
    """The same metrics for one unpadded integer path, with numpy."""
    c = field[path[:, 1], path[:, 0]]
    return (H.path_length(path, res), H.count_turns(path), H.count_sharp_turns(path), H.smoothness(path),
            c.min(), c.mean(), H.max_curvature(path, res))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--paths", type=int, default=10_000)
    ap.add_argument("--length", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--subset", type=int, default=500, help="paths timed in the numpy loop")
    ap.add_argument("--hausdorff-paths", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    record = Record("bench_metrics", vars(args))
    print(f"machine: {os.cpu_count()} cores; {jax.devices()}; jax {jax.__version__}")

    scene = jp.RandomMapGenerator(100, 100, 0.2)(args.seed)
    grid = scene.grid
    B, L = args.paths, args.length
    paths = random_walks(grid, B, L, args.seed)
    rng = np.random.default_rng(args.seed + 1)
    n = rng.integers(L // 2, L + 1, size=B)
    cmap = cached_collision_map(grid)
    padded = jnp.asarray(_pad(paths, bucket(L)))  # as the front pads (256 is its own bucket)
    n_dev = jnp.asarray(n, jnp.int32)
    rows = []

    def core():
        jax.block_until_ready(_core(cmap, padded, n_dev))

    t0 = time.perf_counter()
    core()
    compile_core = time.perf_counter() - t0
    t_core = median_time(core, args.repeat)
    rows.append(("core (one compiled call)", B, compile_core, t_core))

    # Smoothed paths are float: their clearance goes through point_clearance's exact window.
    jitter = np.random.default_rng(args.seed + 2).uniform(-0.3, 0.3, paths.shape)
    floats = jnp.asarray(_pad(paths + jitter, bucket(L)), jnp.float32)

    def core_float():
        jax.block_until_ready(_core(cmap, floats, n_dev))

    t0 = time.perf_counter()
    core_float()
    rows.append(("core, float paths", B, time.perf_counter() - t0, median_time(core_float, args.repeat)))

    t0 = time.perf_counter()
    jp.metrics.path_metrics(paths, grid, n=n)
    first_front = time.perf_counter() - t0
    t_front = median_time(lambda: jp.metrics.path_metrics(paths, grid, n=n), args.repeat)
    rows.append(("path_metrics (front, with gap)", B, first_front, t_front))

    Bh = min(args.hausdorff_paths, B)
    refs = jnp.asarray(paths[::-1][:Bh])
    n_ref = jnp.asarray(n[::-1][:Bh], jnp.int32)

    def haus():
        jax.block_until_ready(_hausdorff_core(padded[:Bh], n_dev[:Bh], refs, n_ref, cmap.resolution, samples=8))

    t0 = time.perf_counter()
    haus()
    compile_h = time.perf_counter() - t0
    rows.append(("hausdorff (k=8, vs a reference)", Bh, compile_h, median_time(haus, args.repeat), False))

    field = jp.clearance_field(grid)  # metres; exact at the (integer) vertices
    sub = min(args.subset, B)
    loop = lambda: [numpy_metrics(paths[b, : n[b]], field, float(grid.resolution)) for b in range(sub)]  # noqa: E731
    ref = loop()
    t_np = median_time(loop, 3) / sub * B
    rows.append((f"numpy loop (extrapolated from {sub})", B, 0.0, t_np))

    # The two must agree (float32 against float64) on the subset.
    got = jax.tree_util.tree_map(np.asarray, _core(cmap, padded[:sub], n_dev[:sub]))
    ref = np.array(ref, dtype=np.float64)
    keys = ("length", "turns", "sharp_turns", "smoothness", "min_clearance", "mean_clearance", "max_curvature")
    worst = max(float(np.max(np.abs(got[k] - ref[:, i]) / np.maximum(1.0, np.abs(ref[:, i]))))
                for i, k in enumerate(keys))

    print(f"\n{B} paths x {L} points (valid {L // 2}..{L}) on a 100x100 map with 20 % obstacles; "
          f"median of {args.repeat} runs\n")
    print(f"{'what':<36}{'paths':>8}{'compile/first s':>17}{'run s':>9}{'paths/s':>12}{'vs numpy':>10}")
    table = record.table("path metrics", ["what", "paths", "compile / first call (s)", "run (s)", "paths/s",
                                          "× numpy loop"],
                         f"{B} paths × {L} points on a 100×100 map with 20 % obstacles, median of {args.repeat} runs")
    for name, count, comp, t, *same in rows:
        rate = count / t
        ratio = f"{rate / (B / t_np):>9.1f}x" if not same or same[0] else f"{'-':>10}"
        print(f"{name:<36}{count:>8}{comp:>17.2f}{t:>9.3f}{rate:>12,.0f}{ratio}")
        table.append([name, count, comp, t, rate, rate / (B / t_np) if not same or same[0] else None])
    print("(vs numpy: paths/s against the numpy loop; the Hausdorff row has no numpy counterpart)")
    print(f"\ntarget: core < 1 s for 10,000 x 256 -> {'met' if t_core < 1.0 else 'MISSED'} ({t_core:.3f} s); "
          f"largest relative difference JAX vs numpy on the subset: {worst:.1e}")
    record.note(f"Target: the core under 1 s for 10,000 × 256 ({'met' if t_core < 1.0 else 'missed'}); largest "
                f"relative difference JAX against numpy on the subset {worst:.1e}.")
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
