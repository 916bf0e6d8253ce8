"""TSP mode: tour quality against TSPLIB optima, and time per iteration.

Run:  python benchmarks/bench_tsp.py [--seeds 10] [--data-dir ../shared/benchmarks] [--only quality speed reference]

Quality: for eil51 and berlin52 (optima 426 and 7542 from the MANIFEST), runs ``praco``
(yu2020's defaults: 5 colonies x 35 ants, 200 iterations) and ``aco`` (Ant System: 50 ants,
200 iterations), without local search, with ``--seeds`` seeds each, and prints mean / min /
max tour length, the mean gap to the optimum (target for praco: <= 5 %), median run time and
compile time.

Speed: median time per iteration with 500 ants on eil51 (``aco`` with ants=500 split over the
host devices as `solve_tsp` does by default, on one device, and with ``candidates=20``, and a
single-colony ``praco`` with 500 ants), compilation excluded, over ``--speed-seeds`` runs of
``--speed-iterations`` iterations. Reference: scikit-opt's ``ACA_TSP`` takes about 0.7 s per
iteration for 500 ants on a problem this size; the target is >= 90x faster (<= 7.7 ms).

Against the C reference: Ant System with 500 ants on eil51, no local search, in jaxplan and in
ACOTSP (Stützle's reference implementation of the ACO algorithms for the TSP, v1.03, GPL: not part
of this repository), same run, same rules: alpha = 1, beta = 5 (jaxplan's AS default; ACOTSP is
told ``-b 5``), rho = 0.5, tau0 = 1 / (rho L_nn) with L_nn the nearest-neighbour tour from city 0
(ACOTSP starts it from a random city), every ant deposits 1 / L (``q = 1``), each ant starts at a
random city. Left different: ACOTSP's heuristic is 1 / (d + 0.1), jaxplan's 1 / d; ACOTSP computes
in double precision, jaxplan in float32. Rows: the full candidate list (``-g n-1``; jaxplan's default,
bit-identical to every earlier release) and ``--candidates`` (``-g k``, jaxplan's ``candidates=k``).
Per row: median time per iteration over ``--ref-seeds`` runs of ``--ref-iterations`` iterations
(jaxplan: wall time, compilation excluded; ACOTSP: its own trial timer, user CPU time of the trial,
which excludes waiting for a core and so favours ACOTSP on a loaded machine), the ratio, and the
tour quality of both (mean and best final length, mean gap to the optimum 426). The ACOTSP runs
and the jaxplan runs alternate seed by seed, so load changes hit both.

ACOTSP is found through ``$ACOTSP_BIN`` (a built ``acotsp``; several, separated by ``:``, give a
row each, e.g. two builds with different compiler flags) or built from ``$ACOTSP_SRC`` (its
unpacked sources, e.g. ``git archive`` of commit f8e47e7 of github.com/juherask/ACOTSP, "the version
from ACOTSP.V1.03.tgz by Thomas Stützle") into a temporary folder with its own Makefile:
``make TIMER=unix CFLAGS="-O -fcommon"`` (the Makefile's -O; -fcommon because GCC >= 10 rejects the
1.03 sources' tentative definitions otherwise; ``$ACOTSP_CFLAGS`` replaces these flags). Without
either, the section says so and is skipped.

For a fair comparison on a shared machine, also run it pinned to one core
(``taskset -c 0 python benchmarks/bench_tsp.py --only reference``): both then get the same core.

The tables also go to a JSON record in benchmarks/results/ (`_timing.Record`; docs/benchmarks.md is made from it).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import jax
import numpy as np
from _timing import Record, Steal, machine_line

from jaxplan.aco._tsp import solve_tsp
from jaxplan.aco._tsplib import TSPProblem, load_tsplib, tour_length

REFERENCE_S_PER_ITERATION = 0.7  # scikit-opt ACA_TSP, 500 ants (the figure)
TARGET_SPEEDUP = 90.0
SECTIONS = ("quality", "speed", "reference")


def _manifest(folder: Path) -> dict[str, float]:
    lines = (folder / "MANIFEST.tsv").read_text().splitlines()
    head = lines[0].split("\t")
    rows = [dict(zip(head, line.split("\t"), strict=True)) for line in lines[1:] if line.strip()]
    return {r["file"][: -len(".tsp")]: float(r["optimum"]) for r in rows if r["file"].endswith(".tsp")}


def _acotsp_binaries(build_dir: Path) -> list[tuple[str, Path]]:
    """(label, path) of the ACOTSP binaries to compare with: ``$ACOTSP_BIN`` (``:``-separated), else one built
    from ``$ACOTSP_SRC`` into ``build_dir``; empty (with a message) when neither is set or the build fails."""
    if os.environ.get("ACOTSP_BIN"):
        found = [Path(b) for b in os.environ["ACOTSP_BIN"].split(os.pathsep) if b]
        missing = [str(b) for b in found if not (b.is_file() and os.access(b, os.X_OK))]
        if missing:
            print(f"ACOTSP_BIN: not an executable file: {', '.join(missing)}")
        return [(b.name, b) for b in found if str(b) not in missing]
    src = os.environ.get("ACOTSP_SRC")
    if not src:
        print("ACOTSP comparison skipped: set ACOTSP_BIN to a built acotsp, or ACOTSP_SRC to its sources (see the "
              "docstring).")
        return []
    cflags = os.environ.get("ACOTSP_CFLAGS", "-O -fcommon")
    for f in Path(src).iterdir():
        if f.suffix in (".c", ".h") or f.name == "Makefile":
            shutil.copy(f, build_dir / f.name)
    proc = subprocess.run(["make", "TIMER=unix", f"CFLAGS={cflags}"], cwd=build_dir, capture_output=True, text=True)
    binary = build_dir / "acotsp"
    if proc.returncode != 0 or not binary.exists():
        print(f"ACOTSP comparison skipped: building {src} failed:\n{proc.stderr[-2000:]}")
        return []
    return [(f"acotsp ({cflags})", binary)]


def _nearest_neighbour_length(prob: TSPProblem) -> float:
    """Length of the nearest-neighbour tour from city 0 (ACOTSP's ``nn_tour``, which starts at a random city)."""
    d = np.asarray(prob.dist, np.float64)
    tour, seen = [0], np.zeros(prob.n, bool)
    seen[0] = True
    for _ in range(prob.n - 1):
        nxt = int(np.argmin(np.where(seen, np.inf, d[tour[-1]])))
        tour.append(nxt)
        seen[nxt] = True
    return tour_length(prob, tour)


def _run_acotsp(binary: Path, tsp: Path, ants: int, g: int, iterations: int, seed: int, beta: float, rho: float,
                cwd: Path) -> tuple[float, float, float]:
    """(wall s per iteration, CPU s per iteration, best tour length) of one ACOTSP Ant System run.

    Wall: the process's wall time less that of the same command with one iteration, over ``iterations - 1``
    (start-up, reading and candidate lists cancel). CPU: ACOTSP's own trial timer (user time), per iteration."""

    def once(its: int) -> tuple[float, str]:
        cmd = [str(binary), "--as", "-m", str(ants), "-l", "0", "-g", str(g), "-a", "1", "-b", f"{beta:g}", "-e",
               f"{rho:g}", "-r", "1", "-s", str(ants * its), "-t", "0", "-o", "0", "--seed", str(seed), "--quiet",
               "-i", str(tsp)]
        t0 = time.perf_counter()
        out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=True).stdout
        return time.perf_counter() - t0, out

    short, _ = once(1)
    wall, out = once(iterations)
    total = re.search(r"t_avgtotal = ([0-9.eE+-]+)", out)
    best = re.search(r"Best Solution in try 0 is (\d+)", out)
    if total is None or best is None:
        raise RuntimeError(f"unexpected ACOTSP output:\n{out[-2000:]}")
    return (wall - short) / (iterations - 1), float(total.group(1)) / iterations, float(best.group(1))


def _timed_solve(prob: TSPProblem, seed: int, **over) -> tuple[float, float, float]:
    """(wall s per iteration, CPU s per iteration of this process, tour length) of one `solve_tsp` Ant System run
    (compiled beforehand). The CPU time sums all threads: with several devices it counts every core's share."""
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    r = solve_tsp(prob, "aco", seed=seed, **over)
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    its = len(r.history)
    return r.time_s / its, cpu / its, r.length


def reference_section(folder: Path, optimum: float, args: argparse.Namespace, record: Record) -> None:
    """Ant System in jaxplan against ACOTSP, same run (see the module docstring)."""
    ants, its, beta, rho = 500, args.ref_iterations, 5.0, 0.5
    print(f"\nAnt System against ACOTSP: eil51, {ants} ants, {its} iterations per run, {args.ref_seeds} seeds, "
          f"no local search; alpha 1, beta {beta:g}, rho {rho:g}, tau0 = 1/(rho L_nn), deposit 1/L")
    with tempfile.TemporaryDirectory(prefix="acotsp-") as tmp:
        binaries = _acotsp_binaries(Path(tmp))
        if not binaries:
            return
        tsp = folder / "eil51.tsp"
        prob = load_tsplib(tsp)
        tau0 = 1.0 / (rho * _nearest_neighbour_length(prob))
        print(f"{'candidate list':<16}{'code':<40}{'wall ms/it':>11}{'ratio':>7}{'CPU ms/it':>10}{'ratio':>7}"
              f"{'mean':>8}{'best':>6}{'mean gap':>10}")
        table = record.table("against ACOTSP", ["candidates", "code", "wall ms/it", "ratio", "CPU ms/it", "ratio",
                                                "mean tour", "best", "mean gap (%)"],
                             f"Ant System, {ants} ants on eil51, {its} iterations, {args.ref_seeds} seeds, "
                             "no local search")
        for k in [None] + args.candidates:
            g = prob.n - 1 if k is None else k
            over = dict(ants=ants, iterations=its, alpha=1.0, beta=beta, rho=rho, q=1.0, tau0=tau0, candidates=k)
            first = solve_tsp(prob, "aco", seed=0, **over)  # compiles
            ours: list[tuple[float, float, float]] = []
            theirs: dict[str, list[tuple[float, float, float]]] = {label: [] for label, _ in binaries}
            for s in range(args.ref_seeds):  # alternate, so load changes hit both
                ours.append(_timed_solve(prob, s + 1, **over))
                for label, binary in binaries:
                    theirs[label].append(_run_acotsp(binary, tsp, ants, g, its, s + 1, beta, rho, Path(tmp)))
            wall0 = statistics.median(r[0] for r in ours)
            cpu0 = statistics.median(r[1] for r in ours)
            name = "full (default)" if k is None else f"k = {k}"
            devices = first.info["devices"]
            rows = [(f"jaxplan aco, {devices} device{'s' * (devices > 1)}", ours)] + list(theirs.items())
            for label, res in rows:
                wall = statistics.median(r[0] for r in res)
                cpu = statistics.median(r[1] for r in res)
                lengths = np.array([r[2] for r in res])
                ratios = ("", "") if res is ours else (f"{wall / wall0:>6.2f}x", f"{cpu / cpu0:>6.2f}x")
                print(f"{name:<16}{label[:39]:<40}{1e3 * wall:>11.3f}{ratios[0]:>7}{1e3 * cpu:>10.3f}{ratios[1]:>7}"
                      f"{lengths.mean():>8.1f}{lengths.min():>6.0f}{100 * (lengths.mean() / optimum - 1):>9.2f}%")
                table.append([name, label, 1e3 * wall, None if res is ours else wall / wall0, 1e3 * cpu,
                              None if res is ours else cpu / cpu0, lengths.mean(), lengths.min(),
                              100 * (lengths.mean() / optimum - 1)])
        print(f"(ratio: ACOTSP's time per iteration over jaxplan's, wall and CPU; jaxplan's CPU time sums its "
              f"threads; ACOTSP -g {prob.n - 1} is the full list on eil51; compile {first.info['compile_s']:.2f} s, "
              f"excluded)")
        record.note("ratio: ACOTSP's time per iteration over jaxplan's (above 1: jaxplan faster), wall and CPU; "
                    "jaxplan's CPU time sums its threads. ACOTSP 1.03, built, not vendored (`$ACOTSP_BIN`).")


def main() -> None:
    root = Path(__file__).resolve().parents[1]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", default=os.environ.get("JAXPLAN_DATA", root.parent / "shared" / "benchmarks"))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--speed-iterations", type=int, default=50)
    ap.add_argument("--speed-seeds", type=int, default=5)
    ap.add_argument("--local-search", action="store_true", help="add praco with local_search='2opt' (slow)")
    ap.add_argument("--ref-iterations", type=int, default=200, help="iterations per run against ACOTSP")
    ap.add_argument("--ref-seeds", type=int, default=5, help="seeds per row against ACOTSP")
    ap.add_argument("--candidates", type=int, nargs="*", default=[20],
                    help="candidate-list lengths compared with ACOTSP's -g besides the full list")
    ap.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS), help="sections to run")
    args = ap.parse_args()
    record = Record("bench_tsp", vars(args))
    folder = Path(args.data_dir) / "tsplib"
    optima = _manifest(folder)
    steal = Steal()
    print(f"machine: {machine_line()}; {jax.devices()}; load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    if "quality" in args.only:
        quality_section(folder, optima, args, record)
    if "speed" in args.only:
        speed_section(folder, args, record)
    if "reference" in args.only:
        reference_section(folder, optima["eil51"], args, record)
    print(steal.summary())
    record.write()


def quality_section(folder: Path, optima: dict[str, float], args: argparse.Namespace, record: Record) -> None:
    """praco and aco tour quality on eil51 and berlin52 (see the module docstring)."""
    print(f"\n{'instance':<10}{'planner':<12}{'runs':>5}{'mean':>9}{'min':>7}{'max':>7}{'mean gap':>10}"
          f"{'opt hits':>9}{'conv it':>8}{'run s':>7}{'ms/it':>7}{'compile s':>10}")
    table = record.table("tour quality", ["instance", "planner", "runs", "mean", "min", "max", "mean gap (%)",
                                          "optimal tours", "converged at", "run (s)", "ms/it", "compile (s)"],
                         f"TSPLIB instances, {args.seeds} seeds, no local search unless marked +2opt")
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
            table.append([name, label, len(res), lengths.mean(), lengths.min(), lengths.max(),
                          100 * (lengths.mean() / opt - 1), int((lengths == opt).sum()),
                          float(np.mean([r.info["converged_iteration"] for r in res])), run_s, 1e3 * run_s / its,
                          res[0].info["compile_s"]])
    record.note(f"Optima: eil51 {optima['eil51']:.0f}, berlin52 {optima['berlin52']:.0f}. Target: praco's mean gap "
                "at most 5 %.")
    print(f"(optima: eil51 {optima['eil51']:.0f}, berlin52 {optima['berlin52']:.0f}; target: praco mean gap <= 5 %; "
          f"no local search unless marked +2opt)")


def speed_section(folder: Path, args: argparse.Namespace, record: Record) -> None:
    """Time per iteration with 500 ants on eil51 against the scikit-opt figure (see the module docstring)."""
    prob = load_tsplib(folder / "eil51.tsp")
    its = args.speed_iterations
    print(f"\n500 ants on eil51, {its} iterations per run, median of {args.speed_seeds} runs (compilation excluded):")
    print(f"{'setting':<34}{'ms/iteration':>13}{'speed-up vs 0.7 s':>19}{'compile s':>11}")
    table = record.table("time per iteration", ["setting", "ms/iteration", "× scikit-opt's 0.7 s", "compile (s)"],
                         f"500 ants on eil51, {its} iterations per run, median of {args.speed_seeds} runs")
    for label, planner, over in (("aco, ants=500", "aco", {"ants": 500}),
                                 ("aco, ants=500, one device", "aco", {"ants": 500, "mesh": None}),
                                 ("aco, ants=500, candidates=20", "aco", {"ants": 500, "candidates": 20}),
                                 ("praco, colonies=1, ants=500", "praco", {"colonies": 1, "ants": 500})):
        first = solve_tsp(prob, planner, seed=0, iterations=its, **over)
        per_it = statistics.median(solve_tsp(prob, planner, seed=s + 1, iterations=its, **over).time_s / its
                                   for s in range(args.speed_seeds))
        print(f"{label:<34}{1e3 * per_it:>13.2f}{REFERENCE_S_PER_ITERATION / per_it:>18.0f}x"
              f"{first.info['compile_s']:>11.2f}")
        table.append([label, 1e3 * per_it, REFERENCE_S_PER_ITERATION / per_it, first.info["compile_s"]])
    target_ms = math.floor(1e4 * REFERENCE_S_PER_ITERATION / TARGET_SPEEDUP) / 10
    print(f"(target: >= {TARGET_SPEEDUP:.0f}x, i.e. <= {target_ms} ms per iteration)")
    record.note(f"scikit-opt's ACA_TSP is quoted at about 0.7 s per iteration for 500 ants (not measured here). "
                f"Target: at least {TARGET_SPEEDUP:.0f}× ({target_ms} ms per iteration).")


if __name__ == "__main__":
    import jaxplan

    jaxplan.use_host_devices()  # as the CLI: one host device per core (an XLA_FLAGS count stands), before JAX starts
    main()
