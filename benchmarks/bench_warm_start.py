"""Warm starts: how long a new process takes for one plan or one episode, with and without the compilation caches.

Run:  nice -n 19 python benchmarks/bench_warm_start.py [--repeats 3] [--modes cold,off,warm] [--cases navigate,...]

Every figure is one new process, timed from outside (wall clock, and the CPU seconds of the child: user +
system, which a busy machine inflates less than the wall clock). Cases, on MovingAI's
warehouse-10-20-10-2-1 (161x63) from cell (134, 28) to (91, 6), a scenario row of its ``-random-1.scen``:

  navigate  ``jaxplan navigate MAP --start 134 28 --goal 91 6`` (the default `iaco_dwa` pipeline, 2 random
            walkers): the whole command.
  plan      ``jaxplan plan MAP --start 134 28 --goal 91 6 --planner iaco``: the whole command.
  python    a fresh ``python`` running ``import jaxplan as jp; jp.navigate(jp.load_map(MAP), start, goal)``
            (no walkers): the whole process, and inside it the first ``jp.navigate`` call alone, split into
            XLA (compiling, or loading from the cache: JAX's backend-compile events), the numba walk's
            registration (compiling or loading its handlers) and the rest (tracing the programs to jaxprs
            and lowering them, which no cache skips, plus running them).

Modes (each case runs ``--repeats`` times per mode; the table shows medians):

  cold  ``JAXPLAN_CACHE=off`` and a new empty ``NUMBA_CACHE_DIR`` for every run: nothing cached, as the first
        run in a fresh clone.
  off   ``JAXPLAN_CACHE=off`` with numba's cache warmed by one untimed run: what every run cost before
        jaxplan turned JAX's persistent cache on for every command (numba's kernels were cached already).
  warm  the caches on in a new folder (``JAXPLAN_CACHE=TMP``) warmed by one untimed run: every later run.

The commands run as ``python -m jaxplan.cli`` (the ``jaxplan`` script's code), with stdout and stderr captured
(no progress display). Other processes on the cores inflate every figure: run on an idle machine, or under
``nice -n 19`` beside other work and say so (the load average is printed and saved). The JSON record (the tables,
and every run under ``results``) goes to benchmarks/results/ (`_timing.Record`, or ``--json PATH``);
docs/benchmarks.md is made from it.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _timing import Record, Steal, machine_line  # noqa: E402 (the benchmarks folder is not a package)

ROOT = Path(__file__).resolve().parents[1]
MAP = "movingai/warehouse-10-20-10-2-1.map"
START, GOAL = (134, 28), (91, 6)
TARGETS = {"navigate": 3.0, "plan": 3.0, "python": 5.0}
"""Issue 43's targets for the warm mode, seconds of wall time on 2 cores (python: the first navigate call)."""

# The child of the python case: prints one JSON line with its phases (seconds).
PYTHON_CHILD = textwrap.dedent("""
    import json, sys, time
    t0 = time.perf_counter()
    import jaxplan as jp
    navigate = jp.navigate  # imports the navigation package (and JAX, numba)
    import jax.monitoring
    from jax._src.dispatch import BACKEND_COMPILE_EVENT
    xla = [0.0]
    hits = [0]
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, s, **kw: xla.__setitem__(0, xla[0] + s) if event == BACKEND_COMPILE_EVENT else None)
    jax.monitoring.register_event_listener(
        lambda event, **kw: hits.__setitem__(0, hits[0] + 1) if event == "/jax/compilation_cache/cache_hits" else None)
    t1 = time.perf_counter()
    grid = jp.load_map(sys.argv[1])
    t2 = time.perf_counter()
    from jaxplan.aco._walk_ffi import register
    register()  # the numba walk's handlers: compiled, or loaded from numba's cache
    t3 = time.perf_counter()
    start, goal = (int(sys.argv[2]), int(sys.argv[3])), (int(sys.argv[4]), int(sys.argv[5]))
    ep = navigate(grid, start, goal, seed=0)
    t4 = time.perf_counter()
    navigate(grid, start, goal, seed=0)
    t5 = time.perf_counter()
    print(json.dumps({"import_s": t1 - t0, "load_map_s": t2 - t1, "numba_walk_s": t3 - t2,
                      "first_navigate_s": t4 - t2, "xla_s": xla[0], "cache_hits": hits[0],
                      "second_navigate_s": t5 - t4, "success": bool(ep.success)}))
    """)


def command(case: str, map_path: Path) -> list[str]:
    """The child's argument list for ``case``."""
    s, g = [str(v) for v in START], [str(v) for v in GOAL]
    if case == "navigate":
        return [sys.executable, "-m", "jaxplan.cli", "navigate", str(map_path), "--start", *s, "--goal", *g,
                "--no-progress"]
    if case == "plan":
        return [sys.executable, "-m", "jaxplan.cli", "plan", str(map_path), "--start", *s, "--goal", *g,
                "--planner", "iaco", "--no-progress"]
    if case == "python":
        return [sys.executable, "-c", PYTHON_CHILD, str(map_path), *s, *g]
    raise ValueError(f"unknown case {case!r}: navigate, plan or python")


def child_env(cache: str, numba_dir: str | None) -> dict[str, str]:
    """The environment of a child: ``JAXPLAN_CACHE=cache``, ``NUMBA_CACHE_DIR=numba_dir`` (None: unset, so that
    jaxplan points numba at its own folder), and no JAX cache settings of the caller."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR", "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS")}
    env["JAXPLAN_CACHE"] = cache
    if numba_dir is not None:
        env["NUMBA_CACHE_DIR"] = numba_dir
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    return env


def run_once(argv: list[str], env: dict[str, str]) -> dict:
    """One child: ``{"wall_s", "cpu_s", "phases"}`` (phases: the python child's JSON line, else None).

    ``RuntimeError`` with the child's last lines if it fails (a benchmark of a failing command means nothing).
    """
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, env=env, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-5:])
        raise RuntimeError(f"{' '.join(argv[:6])} … exited with {proc.returncode}:\n{tail}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    phases = None
    if argv[1] == "-c":
        phases = json.loads(proc.stdout.strip().splitlines()[-1])
    return {"wall_s": wall, "cpu_s": cpu, "phases": phases}


def run_mode(case: str, mode: str, repeats: int, map_path: Path, work: Path) -> list[dict]:
    """``repeats`` timed runs of ``case`` in ``mode`` (cold, off, warm), after the untimed run that warms it."""
    argv = command(case, map_path)
    runs = []
    if mode == "cold":
        for i in range(repeats):
            runs.append(run_once(argv, child_env("off", str(work / f"numba-{case}-cold-{i}"))))
        return runs
    if mode == "off":
        env = child_env("off", str(work / f"numba-{case}-off"))
    elif mode == "warm":
        env = child_env(str(work / f"cache-{case}"), None)
    else:
        raise ValueError(f"unknown mode {mode!r}: cold, off or warm")
    run_once(argv, env)  # warms the caches (untimed)
    return [run_once(argv, env) for _ in range(repeats)]


def summary(runs: list[dict]) -> dict:
    """Medians (and extremes) of the runs' wall and CPU seconds, and of the python child's phases."""
    walls = [r["wall_s"] for r in runs]
    out = {"n": len(runs), "wall_s": statistics.median(walls), "wall_min_s": min(walls), "wall_max_s": max(walls),
           "cpu_s": statistics.median(r["cpu_s"] for r in runs), "runs": runs}
    if runs and runs[0]["phases"] is not None:
        out["phases"] = {k: statistics.median(float(r["phases"][k]) for r in runs)
                         for k in runs[0]["phases"] if k != "success"}
    return out


PHASES = ("import_s", "load_map_s", "numba_walk_s", "first_navigate_s", "xla_s", "cache_hits", "second_navigate_s")
"""The python child's phases, in the order the tables show them."""


def record_tables(record: Record, results: dict, modes: list[str]) -> None:
    """The two tables of `print_tables` as tables of ``record``."""
    table = record.table("warm starts", ["case", *(f"{m}: {x}" for m in modes for x in ("wall (s)", "CPU (s)")),
                                         "target (s)"],
                         "a new process timed from outside, median of the runs: nothing cached (cold), the "
                         "compilation caches off (off), on and warmed (warm)")
    for case, by_mode in results.items():
        table.append([case, *(by_mode[m][k] if m in by_mode else None for m in modes for k in ("wall_s", "cpu_s")),
                      TARGETS[case]])
    record.note("Targets apply to the warm mode; the python case's target is its first jp.navigate call "
                "(the first_navigate_s phase below).")
    py = results.get("python", {})
    if py:
        phases = record.table("python phases", ["mode", *PHASES],
                              "inside the python child, medians (s): import = import jaxplan + jp.navigate's package; "
                              "first_navigate includes numba_walk; xla = compiling or loading programs; the rest of "
                              "first_navigate is tracing, lowering and running")
        phases += [[m, *(py[m]["phases"][k] for k in PHASES)] for m in modes if m in py]


def print_tables(results: dict, modes: list[str]) -> None:
    """The wall-time table (median, range, CPU) and the python child's phases."""
    print(f"\n{'case':<10}" + "".join(f"{m + ' wall (range) cpu':>32}" for m in modes) + f"{'target':>9}")
    for case, by_mode in results.items():
        cells = []
        for m in modes:
            s = by_mode.get(m)
            cells.append(f"{s['wall_s']:7.1f} ({s['wall_min_s']:.1f}-{s['wall_max_s']:.1f}) {s['cpu_s']:6.1f}"
                         if s else "-")
        target = f"<= {TARGETS[case]:.0f} s"
        print(f"{case:<10}" + "".join(f"{c:>32}" for c in cells) + f"{target:>9}")
    py = results.get("python", {})
    if py:
        keys = PHASES
        print("\npython child, medians (s): import = import jaxplan + jp.navigate's package; first_navigate "
              "includes numba_walk; xla = compiling or loading programs; the rest of first_navigate is tracing, "
              "lowering and running")
        print(f"{'mode':<6}" + "".join(f"{k:>19}" for k in keys))
        for m in modes:
            if m in py:
                p = py[m]["phases"]
                print(f"{m:<6}" + "".join(f"{p[k]:>19.2f}" for k in keys))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per case and mode (default 3)")
    ap.add_argument("--modes", default="cold,off,warm", help="cold, off, warm (default: all three)")
    ap.add_argument("--cases", default="navigate,plan,python", help="navigate, plan, python (default: all)")
    ap.add_argument("--data-dir", default=None, help="benchmark data (default: $JAXPLAN_DATA or ../shared/benchmarks)")
    ap.add_argument("--json", default=None, help="output JSON (default benchmarks/results/warm_start-<date>.json)")
    args = ap.parse_args(argv)
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    bad = [m for m in modes if m not in ("cold", "off", "warm")] + [c for c in cases if c not in TARGETS]
    if bad or args.repeats < 1:
        ap.error(f"unknown modes or cases {bad}" if bad else "--repeats must be at least 1")
    data = Path(args.data_dir or os.environ.get("JAXPLAN_DATA") or ROOT.parent / "shared" / "benchmarks")
    map_path = (data / MAP).resolve()
    if not map_path.is_file():
        ap.error(f"{map_path} not found (give --data-dir, the folder holding movingai/)")
    load = os.getloadavg()
    print(f"machine: {machine_line()}; load average at start {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f}")
    print(f"map {map_path.name}, start {START}, goal {GOAL}; {args.repeats} timed runs per case and mode")
    record = Record("bench_warm_start", {k: v for k, v in vars(args).items() if k != "json"})
    steal = Steal()
    results: dict = {}
    with tempfile.TemporaryDirectory(prefix="jaxplan-warm-") as tmp:
        for case in cases:
            for mode in modes:
                s = summary(run_mode(case, mode, args.repeats, map_path, Path(tmp)))
                results.setdefault(case, {})[mode] = s
                print(f"  {case:<9} {mode:<5} wall {s['wall_s']:6.1f} s (median of {s['n']}), cpu {s['cpu_s']:6.1f} s",
                      flush=True)
    print_tables(results, modes)
    fraction = steal.fraction()
    print(steal.summary(fraction))
    record_tables(record, results, modes)
    record.extra.update(load_end=list(os.getloadavg()), map=MAP, start=START, goal=GOAL, targets_s=TARGETS,
                        results=results)
    record.write(args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
