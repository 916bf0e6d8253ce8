"""TSP mode: tour quality against TSPLIB optima, and time per iteration.

Run:  python benchmarks/bench_tsp.py [--seeds 10] [--data-dir ../shared/benchmarks]

Quality: for eil51 and berlin52 (optima 426 and 7542 from the MANIFEST), runs ``praco``
(yu2020's defaults: 5 colonies x 35 ants, 200 iterations) and ``aco`` (Ant System: 50 ants,
200 iterations), without local search, with ``--seeds`` seeds each, and prints mean / min /
max tour length, the mean gap to the optimum (target for praco: <= 5 %), median run time and
compile time.

Speed: median time per iteration with 500 ants on eil51 (``aco`` with ants=500, and a
single-colony ``praco`` with 500 ants), compilation excluded, over ``--speed-seeds`` runs of
``--speed-iterations`` iterations. Reference: scikit-opt's ``ACA_TSP`` takes about 0.7 s per
iteration for 500 ants on a problem this size; the target is >= 90x faster (<= 7.7 ms).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
from pathlib import Path

import jax
import numpy as np
from _timing import Steal, machine_line

from jaxplan.aco._tsp import solve_tsp
from jaxplan.aco._tsplib import load_tsplib

REFERENCE_S_PER_ITERATION = 0.7  # scikit-opt ACA_TSP, 500 ants (the figure)
TARGET_SPEEDUP = 90.0


def _manifest(folder: Path) -> dict[str, float]:
    lines = (folder / "MANIFEST.tsv").read_text().splitlines()
    head = lines[0].split("\t")
    rows = [dict(zip(head, line.split("\t"), strict=True)) for line in lines[1:] if line.strip()]
    return {r["file"][: -len(".tsp")]: float(r["optimum"]) for r in rows if r["file"].endswith(".tsp")}


def main() -> None:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", root.parent / "shared" / "benchmarks"))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--speed-iterations", type=int, default=50)
    ap.add_argument("--speed-seeds", type=int, default=5)
    ap.add_argument("--local-search", action="store_true", help="add praco with local_search='2opt' (slow)")
    args = ap.parse_args()
    folder = Path(args.data_dir) / "tsplib"
    optima = _manifest(folder)
    steal = Steal()
    print(f"machine: {machine_line()}; {jax.devices()}")
    print(f"\n{'instance':<10}{'planner':<12}{'runs':>5}{'mean':>9}{'min':>7}{'max':>7}{'mean gap':>10}"
          f"{'opt hits':>9}{'conv it':>8}{'run s':>7}{'ms/it':>7}{'compile s':>10}")
    for name in ("eil51", "berlin52"):
        prob = load_tsplib(folder / f"{name}.tsp")
        opt = optima[name]
        settings = [("praco", {}), ("aco", {})] + ([("praco", {"local_search": "2opt"})] if args.local_search else [])
        for planner, over in settings:
            res = [solve_tsp(prob, planner, seed=s, **over) for s in range(args.seeds)]
            lengths = np.array([r.length for r in res])
            run_s = statistics.median(r.time_s for r in res)
            its = len(res[0].history)
            label = planner + ("+2opt" if over else "")
            print(f"{name:<10}{label:<12}{len(res):>5}{lengths.mean():>9.1f}{lengths.min():>7.0f}{lengths.max():>7.0f}"
                  f"{100 * (lengths.mean() / opt - 1):>9.2f}%{int((lengths == opt).sum()):>9}"
                  f"{np.mean([r.info['converged_iteration'] for r in res]):>8.0f}{run_s:>7.2f}"
                  f"{1e3 * run_s / its:>7.2f}{res[0].info['compile_s']:>10.2f}")
    print(f"(optima: eil51 {optima['eil51']:.0f}, berlin52 {optima['berlin52']:.0f}; target: praco mean gap <= 5 %; "
          f"no local search unless marked +2opt)")

    prob = load_tsplib(folder / "eil51.tsp")
    its = args.speed_iterations
    print(f"\n500 ants on eil51, {its} iterations per run, median of {args.speed_seeds} runs (compilation excluded):")
    print(f"{'setting':<34}{'ms/iteration':>13}{'speed-up vs 0.7 s':>19}{'compile s':>11}")
    for label, planner, over in (("aco, ants=500", "aco", {"ants": 500}),
                                 ("praco, colonies=1, ants=500", "praco", {"colonies": 1, "ants": 500})):
        first = solve_tsp(prob, planner, seed=0, iterations=its, **over)
        per_it = statistics.median(solve_tsp(prob, planner, seed=s + 1, iterations=its, **over).time_s / its
                                   for s in range(args.speed_seeds))
        print(f"{label:<34}{1e3 * per_it:>13.2f}{REFERENCE_S_PER_ITERATION / per_it:>18.0f}x"
              f"{first.info['compile_s']:>11.2f}")
    target_ms = math.floor(1e4 * REFERENCE_S_PER_ITERATION / TARGET_SPEEDUP) / 10
    print(f"(target: >= {TARGET_SPEEDUP:.0f}x, i.e. <= {target_ms} ms per iteration)")
    print(steal.summary())


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
