"""Host devices and threads on this CPU: batched throughput with 1 vs 2 (or more) XLA host devices.

Run:  python benchmarks/bench_scale.py [--quick] [--devices 1,2] [--only aco,nav,tune]

XLA's host device count is fixed when the backend starts, so every configuration runs in a
fresh interpreter (``XLA_FLAGS=--xla_force_host_platform_device_count=D``, plus the thread
settings of the row; `jaxplan.use_host_devices` leaves that count as it is) and reports back as
JSON; the parent prints one table per workload with each row's ratio against the first row
(1 device, default threads) of the same run.

Workloads (default / ``--quick``):

  aco   `jp.plan_batch(…, planner="iaco")` on ``jp.RandomMapGenerator(100, 100, 0.2)(0)``:
        16 / 8 scenarios (free start-goal pairs drawn with numpy seed 0) x 2 seeds, 256 ants x
        10 / 5 iterations; runs (scenario x seed) per second, with ``mesh=batch_mesh()`` over
        all devices of the child (no mesh with 1 device).
  nav   `jp.navigate_batch(…, pipeline="iaco_dwa", config=NavConfig(replan_group=2))` on the
        default `jp.WarehouseGenerator()(0)` map, 16 / 8 scenarios (free pairs of the inflated
        planning map with exact length <= 40 cells) x 1 seed; episodes per second of the whole
        call (global planning, smoothing and the episode program).
  tune  one generation of a `jaxplan.tune.aco_objective` (iaco α, β; random 32x32 map, 8 / 4
        scenarios x 2 seeds, 64 ants x 10 / 5 iterations): population members per second for a
        population of 16 / 8, the objective sharded over all devices (`Objective.with_mesh`).

The aco workload also runs with XLA's Eigen thread pool off (``--xla_cpu_multi_thread_eigen=false``).
In the 2-device process the call is timed with the mesh and with ``mesh=None`` (one device) in turn,
so that the machine's drift hits both alike; that ratio is the figure to quote. Each figure is
the median of 5 timed calls after one untimed call (which compiles). Other
processes sharing the cores make every figure noisy: run on an idle machine. The tables also go to a JSON
record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap

from _timing import Record, Steal, machine_line

CHILD = r"""
import json, statistics, sys, time
import numpy as np
import jax
import jaxplan as jp
from jaxplan.scale import batch_mesh

jp.use_host_devices()  # the opt-in of the CLI; it leaves the row's XLA_FLAGS device count as it is

work, quick = sys.argv[1], sys.argv[2] == "1"
D = len(jax.devices())
mesh = batch_mesh() if D > 1 else None

def med(*fns, n=5):
    # median seconds of each of fns, called in turn n times after one untimed round: turns share the drift
    for f in fns:
        f()
    ts = [[] for _ in fns]
    for _ in range(n):
        for f, t in zip(fns, ts):
            t0 = time.perf_counter(); f(); t.append(time.perf_counter() - t0)
    return [statistics.median(t) for t in ts]

def pairs(grid, n, seed=0):
    free = np.argwhere(np.asarray(grid.free))[:, ::-1]
    idx = np.random.default_rng(seed).choice(len(free), (n, 2), replace=n * 2 > len(free))
    return free[idx[:, 0]], free[idx[:, 1]]

if work == "aco":
    scene = jp.RandomMapGenerator(100, 100, 0.2)(0)
    n, it = (8, 5) if quick else (16, 10)
    s, g = pairs(scene.grid, n)
    run = lambda m: lambda: jp.plan_batch(scene.grid, s, g, planner="iaco", seeds=[0, 1], ants=256, iterations=it,
                                          mesh=m)
    t = med(run(mesh), run(None)) if mesh is not None else med(run(None))
    out = dict(rate=2 * n / t[0], unit="runs/s", n=2 * n, one=2 * n / t[-1])
elif work == "nav":
    from jaxplan.nav import NavConfig
    from jaxplan.nav import planning_grid
    grid = jp.WarehouseGenerator()(0).grid
    n = 8 if quick else 16
    pg = planning_grid(grid, 0.3)  # cells the robot's inflated footprint can use
    s, g = pairs(pg, 20 * n)
    d = jp.shortest_lengths(pg, s, g)
    keep = np.nonzero(np.isfinite(d) & (d > 0) & (d <= 40))[0][:n]
    s, g = s[keep], g[keep]
    cfg = NavConfig(replan_group=2)
    run = lambda m: lambda: jp.navigate_batch(grid, s, g, pipeline="iaco_dwa", seeds=[0], config=cfg, mesh=m)
    t = med(run(mesh), run(None)) if mesh is not None else med(run(None))
    out = dict(rate=n / t[0], unit="episodes/s", n=n, one=n / t[-1])
else:
    from jaxplan.tune import Split, aco_objective
    scene = jp.RandomMapGenerator(32, 32, 0.2)(0)
    n, it, P = (4, 5, 8) if quick else (8, 10, 16)
    s, g = pairs(scene.grid, 2 * n)
    opt = jp.shortest_lengths(scene.grid, s, g)
    ok = np.isfinite(opt)
    s, g, opt = s[ok][: 2 * n], g[ok][: 2 * n], opt[ok][: 2 * n]
    train = Split(s[:n], g[:n], opt[:n], (0, 1))
    test = Split(s[n:], g[n:], opt[n:], (2, 3))
    obj = aco_objective(scene.grid, train, test, "iaco", space={"alpha": (0.5, 3.0), "beta": (1.0, 10.0)},
                        overrides=dict(ants=64, iterations=it))
    pop = np.random.default_rng(0).uniform([0.5, 1.0], [3.0, 10.0], (P, 2)).astype(np.float32)
    run = lambda m: (lambda o: lambda: o.evaluate(pop))(obj.with_mesh(m))
    t = med(run(mesh), run(None)) if mesh is not None else med(run(None))
    out = dict(rate=P / t[0], unit="members/s", n=P, one=P / t[-1])
out["devices"] = D
print(json.dumps(out))
"""

ROWS = (
    # label, host devices, extra environment
    ("1 device, default threads", 1, {}),
    ("1 device, XLA Eigen pool off", 1, {"XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false"}),
    ("2 devices, mesh over both", 2, {}),
)


def run_child(work: str, devices: int, extra: dict, quick: bool) -> dict:
    env = dict(os.environ)
    flags = f"--xla_force_host_platform_device_count={devices} " + extra.get("XLA_FLAGS", "")
    env.update({k: v for k, v in extra.items() if k != "XLA_FLAGS"})
    env["XLA_FLAGS"] = flags.strip()
    proc = subprocess.run([sys.executable, "-c", CHILD, work, "1" if quick else "0"], capture_output=True,
                          text=True, env=env, timeout=1800)
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else f"exit {proc.returncode}"}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", default="aco,nav,tune", help="comma-separated workloads: aco, nav, tune")
    args = ap.parse_args(argv)
    steal = Steal()
    record = Record("bench_scale", vars(args), quick=args.quick)
    print(f"machine: {machine_line()}")
    for work in args.only.split(","):
        what = textwrap.shorten(__doc__.split(work + '  ')[1].split(chr(10) + chr(10))[0], 300)
        print(f"\n{work}: {what}")
        table = record.table(work, ["configuration", "rate", "unit", "÷ row 1"], what)
        print(f"{'configuration':38s} {'rate':>10s} {'unit':>11s} {'vs row 1':>9s}")
        base = None
        for label, d, extra in (ROWS if work == "aco" else (ROWS[0], ROWS[2])):
            r = run_child(work, d, extra, args.quick)
            if "error" in r:
                print(f"{label:38s} failed: {r['error']}")
                continue
            base = base or r["rate"]
            print(f"{label:38s} {r['rate']:10.2f} {r['unit']:>11s} {r['rate'] / base:8.2f}x", flush=True)
            table.append([label, r["rate"], r["unit"], r["rate"] / base])
            if d > 1:  # the same process, mesh=None (one device), timed in turn with the mesh
                print(f"{'  same process, mesh=None (1 device)':38s} {r['one']:10.2f} {r['unit']:>11s} "
                      f"{r['one'] / base:8.2f}x   mesh / mesh=None: {r['rate'] / r['one']:.2f}x", flush=True)
                table.append(["  same process, mesh=None (1 device)", r["one"], r["unit"], r["one"] / base])
                record.note(f"With the mesh against mesh=None in the same process, timed in turn: "
                            f"{r['rate'] / r['one']:.2f}× (the figure to quote).")
    print(steal.summary())
    record.write()


if __name__ == "__main__":
    main()
