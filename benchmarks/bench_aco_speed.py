"""ACO engine speed: ant-steps per second, step-slot use, compile time, chen2023-sized runs, memory.

Run:  python benchmarks/bench_aco_speed.py [--iterations 5] [--repeats 5]

Prints, for 128, 1,024 and 8,192 ants of the default `aco` and of `iaco` on a 100x100
random map with 20 % obstacles (start and goal in opposite corners), for both walk
backends side by side (``walk_backend="jax"``: the `lax.while_loop` walk; ``"numba"``: one
native call per iteration, the default on a CPU; both give identical results):
  * ant-steps/s: moves made by ants that were still walking, per second of run time
    (compilation excluded; median of ``--repeats`` runs with different seeds), and the
    share of the step slots the JAX loop processes that they use (a slot = one ant in one
    loop step; after compaction the loop carries A/4 ants; the numba walk has no idle slots);
  * compile time of the configuration: XLA's (lower + compile), and the first call's time
    minus the steady-state run time (adds numba's one-off load or compilation);
then the compile time of every planner's configuration (its defaults, and with 1,024 ants), and
the time of a chen2023-sized run (20x20 warehouse, risk_aco defaults: 100 ants,
50 iterations; the paper reports 8.468 s in MATLAB) per backend, and the peak memory of
iaco with 1,024 ants on brc202d (measured first, in a fresh child process of its own). The
speed figures are measured three times, each in a child process: with XLA's default threads,
pinned to one core, and with XLA's intra-op threading off (``XLA_FLAGS=--xla_cpu_multi_thread_eigen=false
intra_op_parallelism_threads=1``) while the numba walk keeps both cores, which shows what
XLA's intra-op threads gain or cost next to the walk's threads on a small CPU. The tables also go to a JSON record
in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

from _timing import Record, Steal, machine_line

BACKENDS = ("jax", "numba")
SINGLE_THREADED_XLA = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
# (label, pin the child to one core, extra XLA_FLAGS): each configuration runs in a child process of its own.
CONFIGS = (
    ("default threads", False, ""),
    ("pinned to 1 core", True, ""),
    # XLA's own ops on one thread; the numba walk still uses both cores (its threads are numba's).
    ("XLA single-threaded, 2 cores", False, SINGLE_THREADED_XLA),
)


def measure(iterations: int, repeats: int) -> dict:
    import jax
    import numpy as np

    import jaxplan as jp
    from jaxplan.aco._planners import _run_colony
    from jaxplan.registry import resolve

    out: dict = {"rows": []}
    scene = jp.RandomMapGenerator(100, 100, 0.2)(0)
    starts, goals = np.asarray([scene.start]), np.asarray([scene.goal])
    for planner in ("aco", "iaco"):
        for ants in (128, 1024, 8192):
            row = dict(planner=planner, ants=ants)
            for backend in BACKENDS:
                _, p = resolve(planner, dict(ants=ants, iterations=iterations, walk_backend=backend))
                t0 = time.perf_counter()
                o, _, compile_s, _ = _run_colony(planner, scene.grid, starts, goals, [0], p)
                first = time.perf_counter() - t0
                times, steps = [], []
                for s in range(repeats):
                    o, dt, _, _ = _run_colony(planner, scene.grid, starts, goals, [s + 1], p)
                    times.append(dt)
                    steps.append(int(np.asarray(o.ant_steps).sum()))
                slots = int(np.asarray(o.slots)[0, 0].sum())
                rates = [n / t for n, t in zip(steps, times, strict=True)]
                row[backend] = dict(ant_steps_per_s=statistics.median(rates), run_s=statistics.median(times),
                                    slot_use=steps[-1] / max(slots, 1), compile_s=compile_s,
                                    first_minus_run_s=first - statistics.median(times),
                                    success=float(np.asarray(o.success).mean()))
            out["rows"].append(row)
    # Compile time of every planner's configuration: its defaults, and with 1,024 ants (default backend).
    out["compile"] = {}
    for planner in ("aco", "iaco", "risk_aco", "opt_ant", "praco"):
        for label, extra in (("defaults", {}), ("1024 ants", dict(ants=1024))):
            _, p = resolve(planner, extra)
            out["compile"][f"{planner}/{label}"] = _run_colony(planner, scene.grid, starts, goals, [0], p)[2]
    ware = jp.warehouse_chen2023(0)
    grid = jp.poisson_risk(ware.grid, 0, lam=1.0)
    out["chen2023_ms"] = {}
    for backend in BACKENDS:
        jp.plan(grid, ware.start, ware.goal, planner="risk_aco", seed=0, walk_backend=backend)
        times = [jp.plan(grid, ware.start, ware.goal, planner="risk_aco", seed=s, walk_backend=backend).time_s
                 for s in range(max(repeats, 5))]
        out["chen2023_ms"][backend] = 1e3 * statistics.median(times)
    out["devices"] = str(jax.devices())
    return out


BRC202D = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "benchmarks", "movingai",
                       "brc202d.map")


def measure_memory(ants: int, iterations: int) -> dict:
    """Peak RSS of a fresh process that runs iaco with ``ants`` ants on brc202d (default backend).

    Runs in its own child process, before anything else was allocated there: the process's peak RSS
    (``ru_maxrss``) then is the run's own footprint (Python, JAX, numba and the compiled program
    included), not the high-water mark of earlier, larger runs.
    """
    import resource

    import numpy as np

    import jaxplan as jp

    out: dict = {"rss_start_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    big = jp.load_map(BRC202D)
    C = big.n_cells
    H, W = big.shape
    L = min(int(big.free.sum()), 4 * (H + W))
    # Tabu bits (JAX walk), path buffers (cells i32 + moves i8), move tables (index, valid, weights).
    out["walk_estimate_MB"] = (ants * ((C + 31) // 32) * 4 + ants * (L + 1) * 4 + ants * L + C * 8 * 4 * 3) / 2**20
    free = np.argwhere(big.free)[:, ::-1]
    out["before_run_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    r = jp.plan_batch(big, free[:1], free[-1:], planner="iaco", seeds=[0], ants=ants, iterations=iterations)
    out["peak_rss_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out["run_s"] = r.time_s
    out["compile_s"] = r.compile_s
    out["success"] = bool(r.success.all())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--iterations", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=5, help="timed runs per configuration (the median is printed)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--memory-child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(measure(args.iterations, args.repeats)))
        return
    if args.memory_child:
        print(json.dumps(measure_memory(1024, 2)))
        return
    steal = Steal()
    record = Record("bench_aco_speed", {k: v for k, v in vars(args).items() if k not in ("child", "memory_child")})
    memory = None
    if os.path.exists(BRC202D):
        proc = subprocess.run([sys.executable, __file__, "--memory-child"], capture_output=True, text=True, check=True)
        memory = json.loads(proc.stdout.strip().splitlines()[-1])
    results = {}
    for label, pin, xla_flags in CONFIGS:
        pre = (lambda: os.sched_setaffinity(0, {0})) if pin else None
        env = dict(os.environ)
        if xla_flags:
            env["XLA_FLAGS"] = (env.get("XLA_FLAGS", "") + " " + xla_flags).strip()
        proc = subprocess.run([sys.executable, __file__, "--child", "--iterations", str(args.iterations),
                               "--repeats", str(args.repeats)], capture_output=True, text=True, preexec_fn=pre,
                              env=env, check=True)
        results[label] = json.loads(proc.stdout.strip().splitlines()[-1])
    print(f"machine: {machine_line()}; {results['default threads']['devices']}")
    speed = record.table("ant-steps", ["threads", "planner", "ants", "jax walk (M ant-steps/s)", "slot use",
                                       "numba walk (M ant-steps/s)", "numba ÷ jax"],
                         "ant-steps per second on a 100×100 random map (20 % obstacles), compilation excluded")
    for label, res in results.items():
        print(f"\n{label}: M ant-steps/s (slot use of the JAX loop), compile s = XLA compile / first call minus run")
        print(f"{'planner':<8}{'ants':>6} | {'jax':>8}{'slots':>7}{'compile':>9}{'first-run':>10} | "
              f"{'numba':>8}{'compile':>9}{'first-run':>10} | {'speed-up':>8}")
        for row in res["rows"]:
            j, n = row["jax"], row["numba"]
            print(f"{row['planner']:<8}{row['ants']:>6} | {j['ant_steps_per_s'] / 1e6:>8.2f}{j['slot_use']:>7.0%}"
                  f"{j['compile_s']:>9.2f}{j['first_minus_run_s']:>10.2f} | {n['ant_steps_per_s'] / 1e6:>8.2f}"
                  f"{n['compile_s']:>9.2f}{n['first_minus_run_s']:>10.2f} | "
                  f"{n['run_s'] and j['run_s'] / n['run_s']:>7.1f}x")
            speed.append([label, row["planner"], row["ants"], j["ant_steps_per_s"] / 1e6, j["slot_use"],
                          n["ant_steps_per_s"] / 1e6, n["run_s"] and j["run_s"] / n["run_s"]])
    labels = list(results)
    print("\ncompile time per configuration, s (trace, lower and XLA compile; 100x100 bench map, default backend; "
          "target <= 2 s)")
    print(f"{'planner':<10}{'setting':<11}" + "".join(f"{lab:>30}" for lab in labels))
    compile_rows = record.table("compile time", ["planner", "setting", *(f"{lab} (s)" for lab in labels)],
                                "per configuration: trace, lower and XLA compile, default backend (target ≤ 2 s)")
    for key in results[labels[0]]["compile"]:
        planner, setting = key.split("/")
        print(f"{planner:<10}{setting:<11}" + "".join(f"{results[lab]['compile'][key]:>30.2f}" for lab in labels))
        compile_rows.append([planner, setting, *(results[lab]["compile"][key] for lab in labels)])
    print()
    chen = record.table("chen2023-sized run", ["threads", "jax walk (ms)", "numba walk (ms)"],
                        "risk_aco defaults (100 ants × 50 iterations) on a 20×20 warehouse")
    for label, r in results.items():
        ms = r["chen2023_ms"]
        print(f"chen2023-sized run (20x20, risk_aco, 100 ants x 50 iterations), {label}: jax {ms['jax']:.1f} ms, "
              f"numba {ms['numba']:.1f} ms (target <= 30 ms; paper: 8,468 ms in MATLAB)")
        chen.append([label, ms["jax"], ms["numba"]])
    record.note("Target: at most 30 ms. chen2023 reports 8,468 ms in MATLAB (the paper's figure, not measured here).")
    if memory is None:
        print(f"walk memory: skipped ({BRC202D} not found)")
    else:
        m = memory
        print("memory, iaco with 1,024 ants x 2 iterations on brc202d (default backend, fresh child process): "
              "peak RSS "
              f"{m['peak_rss_MB']:.0f} MB (bound 2,048 MB; {m['before_run_MB']:.0f} MB after imports and map loading); "
              f"walk buffers and move tables {m['walk_estimate_MB']:.0f} MB estimated; compile {m['compile_s']:.2f} s, "
              f"run {m['run_s']:.2f} s")
        record.table("memory", ["peak RSS (MB)", "after imports and map (MB)", "walk buffers, estimated (MB)",
                                "compile (s)", "run (s)"],
                     "iaco with 1,024 ants × 2 iterations on brc202d, a fresh process (bound 2,048 MB)").append(
            [m["peak_rss_MB"], m["before_run_MB"], m["walk_estimate_MB"], m["compile_s"], m["run_s"]])
    print(steal.summary())
    record.write()

if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
