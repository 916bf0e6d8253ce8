"""Tuning benchmark: every optimiser with the same evaluation budget on (i) IACO weights and (ii) DWA critic weights.

Run:  python benchmarks/bench_tune.py [--quick] [--parts aco,dwa,call] [--out runs/bench_tune]

(i)  IACO (cui2025) on a random 24 x 24 map (20 % obstacles, 1 m cells): α, β and the fitness
     weights λ1..λ3; cost = optimality gap of the best path + 1 per failed run; 16 ants x 8
     iterations. 32 training scenarios x 4 seeds; held-out test: 16 other scenarios x 4 other seeds.
(ii) Weighted DWA (cui2025 Eq. 7) on a 12 m x 12 m hall with pillars (0.5 m cells), two moving
     discs per episode drawn from the seed, the goal as the sub-goal: heading, velocity and
     clearance weights; cost = time to goal / 20 s + 1 per failed episode (collision or not there).
     16 training scenarios x 4 seeds; test 16 others x 4 other seeds.

Budget: P weight vectors x G generations for every gradient-free method (grid, random, CMA-ES
and SNES from evosax, ISSA, SSA) and for the score-function (REINFORCE) and surrogate routes;
the relaxed-DWA gradient route gets P·G/3 gradient steps (one step — loss and gradient over
the training set — costs about three forward evaluations of one weight vector). Every method
starts from (or, for the sampling ones, regardless of) the paper's defaults.

Printed per method: the best training objective found, the held-out test objective of that
weight vector (mean over test seeds of the per-seed mean cost, ± its sd over seeds), and the
wall time (compilations included). Then the paper defaults' test objective ± sd and, for the
best method, the margin over the defaults against the seed-to-seed spread.

"call": one population of 64 weight vectors x 32 scenarios x 4 seeds (IACO) evaluated as ONE
compiled call; its compile and run times are printed. The tables also go to a JSON record in benchmarks/results/
(`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from _timing import Record

import jaxplan as jp
from jaxplan.experiments import random_pairs
from jaxplan.tune import (
    Split,
    aco_objective,
    compare,
    dwa_objective,
    make_strategy,
    plot_tuning,
    relaxed_dwa,
    tune_loop,
)

METHODS = ("grid", "random", "cma_es", "snes", "issa", "ssa", "reinforce", "surrogate")


def aco_setup(quick: bool):
    grid = jp.RandomMapGenerator(width=24, height=24, obstacle_ratio=0.2)(3).grid
    n_train, n_test = (12, 8) if quick else (32, 16)
    s, g, opt = random_pairs(grid, n_train + n_test, 0, 8.0)
    seeds = (0, 1) if quick else (0, 1, 2, 3)
    tseeds = (1000, 1001) if quick else (1000, 1001, 1002, 1003)
    train = Split(s[:n_train], g[:n_train], opt[:n_train], seeds)
    test = Split(s[n_train:], g[n_train:], opt[n_train:], tseeds)
    ov = dict(ants=8, iterations=4) if quick else dict(ants=16, iterations=8)
    space = {"alpha": (0.5, 3.0), "beta": (1.0, 12.0), "lambdas": [(0.0, 1.0)] * 3}
    return grid, aco_objective(grid, train, test, "iaco", space, {"gap": 1.0, "failure": 1.0}, ov, name="iaco")


def dwa_setup(quick: bool):
    grid = jp.RandomMapGenerator(width=24, height=24, obstacle_ratio=0.04, resolution=0.5)(1).grid
    n_train, n_test = (6, 6) if quick else (16, 16)
    s, g, opt = random_pairs(grid, n_train + n_test, 0, 6.0)
    seeds = (0, 1) if quick else (0, 1, 2, 3)
    tseeds = (1000, 1001) if quick else (1000, 1001, 1002, 1003)
    train = Split(s[:n_train], g[:n_train], opt[:n_train], seeds)
    test = Split(s[n_train:], g[n_train:], opt[n_train:], tseeds)
    return grid, dwa_objective(grid, train, test, "weighted", None, {"time": 1.0, "failure": 1.0},
                               dict(n_v=5, n_omega=9), max_time=20.0, n_discs=2, name="dwa")


def run_part(label: str, obj, P: int, G: int, out: Path, gradient: bool, record: Record) -> None:
    print(f"\n== ({label}) {obj.name}: {obj.bounds.dim} weights {obj.bounds.names}; budget {P} x {G} = {P * G} "
          f"evaluations; train {len(obj.splits['train'].starts)} scenarios x {len(obj.splits['train'].seeds)} seeds, "
          f"test {len(obj.splits['test'].starts)} x {len(obj.splits['test'].seeds)} ==", flush=True)
    base = compare(obj, obj.defaults, "test")["defaults"]
    base_train = compare(obj, obj.defaults, "train", P)["defaults"]
    rows_by, results = {}, []
    table = record.table(f"methods, {obj.name}", ["method", "train", "held-out", "held-out sd over seeds",
                                                  "wall (s)", "NaN/inf"],
                         f"{obj.name}: {obj.bounds.dim} weights, budget {P} × {G} = {P * G} evaluations; best "
                         "training objective and the held-out objective of its weights")
    with tempfile.TemporaryDirectory() as tmp:
        for m in METHODS:
            t0 = time.perf_counter()
            res = tune_loop(obj, make_strategy(m, P, G), G, Path(tmp) / m, seed=0, checkpoint_every=G, progress=False)
            wall = time.perf_counter() - t0
            te = compare(obj, res.best_x, "test")["tuned"]
            rows_by[m] = res.rows
            results.append((m, res.best_f, te, wall, res.n_bad, res.best_x))
            print(f"  {m:10s} train {res.best_f:.4f}  test {te['objective']:.4f} ± {te['seed_sd']:.4f}  "
                  f"wall {wall:6.1f} s  NaN/inf {res.n_bad}  x = {np.round(res.best_x, 3).tolist()}", flush=True)
    if gradient:
        steps = max(1, P * G // 3)
        t0 = time.perf_counter()
        r = relaxed_dwa(obj, steps, learning_rate=0.1, t0=0.5, t1=0.02)
        wall = time.perf_counter() - t0
        x = r.x[-1]
        tr = compare(obj, x, "train", P)["tuned"]
        te = compare(obj, x, "test")["tuned"]
        results.append(("relaxed", tr["objective"], te, wall, 0, x))
        print(f"  {'relaxed':10s} train {tr['objective']:.4f}  test {te['objective']:.4f} ± {te['seed_sd']:.4f}  "
              f"wall {wall:6.1f} s  ({steps} optax steps; relaxed loss {r.loss[0]:.4f} -> {r.loss[-1]:.4f}, "
              f"T {r.temperature[0]:.3g} -> {r.temperature[-1]:.3g})  x = {np.round(x, 3).tolist()}", flush=True)
    table += [[m, f, te["objective"], te["seed_sd"], wall, bad] for m, f, te, wall, bad, _ in results]
    table.append(["defaults", base_train["objective"], base["objective"], base["seed_sd"], None, None])
    print(f"  {'defaults':10s} train {base_train['objective']:.4f}  test {base['objective']:.4f} ± "
          f"{base['seed_sd']:.4f}  x = {np.round(obj.defaults, 3).tolist()}")
    best = min(results, key=lambda r: r[1])  # chosen on the TRAINING objective, judged on the test set
    margin = base["objective"] - best[2]["objective"]
    spread = max(base["seed_sd"], best[2]["seed_sd"])
    print(f"  best on train: {best[0]}; held-out margin over the defaults {margin:+.4f} vs seed-to-seed spread "
          f"(larger sd over test seeds) {spread:.4f}: {'BEATS' if margin > spread else 'does NOT beat'} the defaults "
          "by more than the spread")
    record.note(f"Best on training: {best[0]}; its held-out margin over the defaults {margin:+.4f} against the "
                f"seed-to-seed spread {spread:.4f}: it {'beats' if margin > spread else 'does not beat'} the defaults "
                "by more than the spread.")
    out.mkdir(parents=True, exist_ok=True)
    fig = plot_tuning(rows_by, out / f"convergence_{obj.name}.png", title=f"{obj.name}: training objective")
    print("  figure:", fig[0])


def population_call(obj, record: Record) -> None:
    rng = np.random.default_rng(0)
    b = obj.bounds
    pop = (b.low + rng.random((64, b.dim)) * (b.high - b.low)).astype(np.float32)
    ev = obj.evaluate(pop, "train")
    N, R = len(obj.splits["train"].starts), len(obj.splits["train"].seeds)
    print(f"\n== one compiled call: 64 weight vectors x {N} scenarios x {R} seeds = {64 * N * R} IACO runs: "
          f"compile {ev.compile_s:.1f} s, run {ev.time_s:.2f} s ({ev.time_s / (64 * N * R) * 1e3:.2f} ms per run); "
          f"NaN/inf {int(np.sum(~np.isfinite(ev.fitness)))} ==", flush=True)
    record.table("population call", ["weight vectors", "scenarios", "seeds", "compile (s)", "run (s)", "ms per run"],
                 "one population of IACO weight vectors evaluated in one compiled call").append(
        [64, N, R, ev.compile_s, ev.time_s, ev.time_s / (64 * N * R) * 1e3])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sets and budget (a smoke run)")
    ap.add_argument("--parts", default="aco,dwa,call")
    ap.add_argument("--out", default="runs/bench_tune")
    a = ap.parse_args()
    record = Record("bench_tune", vars(a), quick=a.quick)
    parts = set(a.parts.split(","))
    P, G = (8, 4) if a.quick else (16, 8)
    out = Path(a.out)
    print(f"jaxplan tuning benchmark ({'quick' if a.quick else 'full'}): population {P}, generations {G}")
    if "aco" in parts or "call" in parts:
        _, obj = aco_setup(a.quick)
        if "aco" in parts:
            run_part("i", obj, P, G, out, gradient=False, record=record)
        if "call" in parts:
            if a.quick:  # the 64 x 32 x 4 call always uses the full training set
                _, obj = aco_setup(False)
            population_call(obj, record)
    if "dwa" in parts:
        _, obj = dwa_setup(a.quick)
        run_part("ii", obj, P, G, out, gradient=True, record=record)
    record.write()


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
