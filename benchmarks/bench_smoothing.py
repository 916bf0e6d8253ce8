"""How much each smoother cuts length and turns of the exact grid path on the MovingAI maps.

Run:  python benchmarks/bench_smoothing.py [--data-dir ../shared/benchmarks] [--rows 100] [--maps ...]

For each map, ``--rows`` scenario rows (evenly spread over the file) are solved exactly
with A* (8-connected, no corner cutting: the raw grid path of the scenario's optimal
length), and the whole batch goes through each smoother in one compiled call. Printed
per map and smoother, relative to the raw path (sums over the rows):
  * length cut (%), turn cut (%) — turns are vertices with a heading change > 1e-6 —
    and sharp-turn cut (%, >= 45°);
  * corners/vertices changed and fallbacks (places kept unsmoothed to stay clear);
  * seconds per path (after compilation) and the compile + first call time.
yu2020 reports 5.9 % / 7.2 % length and 15–39 % turns for its line-of-sight pruning.
Turn counts of sampled curves (fillet, Bezier, B-spline) count every sample, so for them
read the sharp-turn column. The table also goes to a JSON record in benchmarks/results/ (`_timing.Record`;
docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _timing import Record

import jaxplan as jp
from jaxplan.metrics import count_sharp_turns, count_turns, path_length

METHODS = {
    "los": ("los",),
    "key_nodes": ("key_nodes",),
    "los+fillet": ("los", "fillet"),
    "los+bezier": ("los", "bezier"),
    "bspline": ("bspline",),
}
MAPS = ["warehouse-10-20-10-2-1", "random-32-32-20", "random-64-64-20", "room-64-64-8", "maze-32-32-2", "brc202d"]


def scen_file(folder: Path, name: str) -> Path:
    for cand in (folder / f"{name}.map.scen", folder / f"{name}-random-1.scen"):
        if cand.exists():
            return cand
    raise FileNotFoundError(f"no scenario file for {name} in {folder}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-dir", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "benchmarks")
    ap.add_argument("--rows", type=int, default=100)
    ap.add_argument("--maps", nargs="*", default=MAPS)
    ap.add_argument("--radius", type=float, default=0.0, help="robot inflation radius (m)")
    args = ap.parse_args()
    record = Record("bench_smoothing", vars(args))
    table = record.table("smoothers", ["map", "smoother", "rows", "length cut (%)", "turn cut (%)",
                                       "sharp-turn cut (%)", "changed", "fallbacks", "ms per path", "compile (s)"],
                         "each smoother against the exact A* grid path, sums over the rows")
    folder = args.data_dir / "movingai"
    print(f"{'map':24s} {'smoother':11s} {'rows':>4s} {'len cut%':>8s} {'turn cut%':>9s} {'sharp cut%':>10s} "
          f"{'changed':>7s} {'fallback':>8s} {'ms/path':>8s} {'compile s':>9s}")
    for name in args.maps:
        grid = jp.load_map(folder / f"{name}.map")
        sc = jp.load_scenarios(scen_file(folder, name))
        rows = np.unique(np.linspace(0, len(sc.starts) - 1, args.rows).astype(int))
        raw = [jp.astar(grid, sc.starts[i], sc.goals[i]).path for i in rows]
        L = max(len(p) for p in raw)
        pts = np.stack([np.concatenate([p, np.repeat(p[-1:], L - len(p), 0)]) for p in raw])
        n = np.array([len(p) for p in raw])
        l0 = sum(path_length(p) for p in raw)
        t0 = sum(count_turns(p) for p in raw)
        s0 = sum(count_sharp_turns(p) for p in raw)
        for label, method in METHODS.items():
            t = time.perf_counter()
            jp.smooth(pts, grid, method, n=n, radius=args.radius)
            first = time.perf_counter() - t
            t = time.perf_counter()
            out = jp.smooth(pts, grid, method, n=n, radius=args.radius)
            run = time.perf_counter() - t
            paths = [out.points[i, : out.n[i]] for i in range(len(raw))]
            l1 = sum(path_length(p) for p in paths)
            t1 = sum(count_turns(p) for p in paths)
            s1 = sum(count_sharp_turns(p) for p in paths)
            print(f"{name:24s} {label:11s} {len(raw):4d} {100 * (1 - l1 / l0):8.2f} {100 * (1 - t1 / t0):9.1f} "
                  f"{100 * (1 - s1 / s0):10.1f} {int(np.sum(out.removed)):7d} {int(np.sum(out.fallbacks)):8d} "
                  f"{1e3 * run / len(raw):8.2f} {first - run:9.1f}", flush=True)
            table.append([name, label, len(raw), 100 * (1 - l1 / l0), 100 * (1 - t1 / t0), 100 * (1 - s1 / s0),
                          int(np.sum(out.removed)), int(np.sum(out.fallbacks)), 1e3 * run / len(raw), first - run])
    record.note("yu2020 reports 5.9 % and 7.2 % length and 15–39 % turns for its line-of-sight pruning. Sampled "
                "curves (fillet, Bezier, B-spline) count every sample as a turn: read the sharp-turn column.")
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
