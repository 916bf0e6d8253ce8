"""Command line: ``jaxplan demo | plan | navigate | run | figures | export | reproduce | tune | study | bench``.

``jaxplan --help`` and every ``jaxplan CMD --help`` answer without importing JAX or numba: this
module imports only the standard library at the top, and each command imports what it needs.
Before a command runs, the process opts in to one JAX CPU host device per core
(`jaxplan.use_host_devices`; ``$JAXPLAN_HOST_DEVICES`` overrides the count, ``off`` leaves JAX's
default, and an ``XLA_FLAGS`` device count stands), so batched calls shard over the cores. Compiled programs
are kept on disk and loaded by the next command (`jaxplan.core.compile_cache`: ``$JAXPLAN_CACHE`` or
``~/.cache/jaxplan``); every command's ``--no-cache``, or ``JAXPLAN_CACHE=off``, turns that off.

Long commands (``run``, ``reproduce``, ``tune``, ``figures``, ``demo``, ``bench``, ``plan``, ``navigate``) draw a
progress bar with the time left (or a spinner for a stage such as compiling) on stderr when it is a terminal;
``--no-progress`` turns it off, and piped output never has one (`jaxplan.core.progress`).

A failure ends in one line naming the cause and what to do, with exit code 2 (bad input) or 1 (a fault of
the environment); Ctrl-C ends with 130 and says how to resume; ``jaxplan --debug CMD`` adds the traceback
(`jaxplan.core.failure`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Sequence

__all__ = ["main"]


def _compilation_cache() -> None:
    """The on-disk compilation caches (`jaxplan.core.compile_cache`: ``$JAXPLAN_CACHE`` or ``~/.cache/jaxplan``),
    turned on now rather than at the first compiled module (compiled programs are most of the demo's time)."""
    from jaxplan.core.compile_cache import on_first_use

    on_first_use()


_NO_CACHE = ("do not use the on-disk compilation caches (JAX's and numba's in $JAXPLAN_CACHE or ~/.cache/jaxplan; "
             "JAXPLAN_CACHE=off does the same for every command)")


def cmd_demo(args: argparse.Namespace) -> int:
    """``jaxplan demo``: IACO-DWA beside ACO-DWA among moving discs on the built-in warehouse (no data)."""
    import time

    from jaxplan.core.version import VERSION
    from jaxplan.experiments.demo import demo_table, run_demo

    t0 = time.perf_counter()
    if not args.no_cache:
        _compilation_cache()
    print(f"jaxplan {VERSION} demo: iaco_dwa and aco_dwa among moving obstacles"
          + (" (quick variant)" if args.quick else ""), flush=True)
    result = run_demo(args.out_dir, seed=args.seed, quick=args.quick, gif=not args.no_gif,
                      progress=not args.no_progress)
    print(demo_table(result))
    print("  wall time includes each pipeline's one-off compilation; planning time is the warm global plan")
    extra = ", ".join(f"{k} {result.wall_s[k]:.1f} s" for k in ("figure", "animation") if k in result.wall_s)
    print("wrote " + ", ".join(result.files) + f" ({extra}); demo wall time {time.perf_counter() - t0:.1f} s")
    return 0


def _literal(text: str):
    """A ``--set`` value: ``true``/``false``, ``none``/``null``, a Python number, tuple or list literal, else the
    text itself (``heuristic=geodesic``)."""
    import ast

    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    if low in ("none", "null"):
        return None
    try:
        value = ast.literal_eval(text.strip())
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return text.strip()
    return value if isinstance(value, (int, float, tuple, list, str)) else text.strip()


def _parse_sets(items: Sequence[str] | None) -> dict:
    """``--set KEY=VALUE`` options as a dict (a later key wins); ``ValueError`` for an item without ``=``."""
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set {item!r}: expected KEY=VALUE (e.g. --set ants=64 --set heuristic=geodesic)")
        out[key.strip()] = _literal(text)
    return out


def _planner_params(planner: str, overrides: dict, options: dict | None = None) -> dict:
    """Every parameter of ``planner`` with ``overrides`` applied, checked against its registered parameters and
    values; the ``ValueError`` names the bad ``--set`` key or value (or the option ``options[key]`` that gave it,
    e.g. ``--connectivity``) and what the planner takes."""
    from jaxplan.core.names import closest
    from jaxplan.planning import planners
    from jaxplan.registry import resolve

    specs = planners()
    if planner not in specs:
        near = closest(planner, specs)
        raise ValueError(f"--planner {planner!r} is not a planner{f' (did you mean {near!r}?)' if near else ''}; "
                         f"choose from {', '.join(sorted(specs))}")
    spec = specs[planner]
    options = options or {}
    said = lambda k: f"{options[k]} {overrides[k]!r}" if k in options else f"--set {k}={overrides[k]!r}"  # noqa: E731
    for k in overrides:
        if k not in spec.defaults:
            near = closest(k, spec.defaults)
            raise ValueError(f"{said(k)}: planner {planner!r} has no parameter {k!r}"
                             f"{f' (did you mean {near!r}?)' if near else ''}; it takes: "
                             f"{', '.join(sorted(spec.defaults)) or 'none'}")
    try:
        return resolve(planner, overrides)[1]
    except (ValueError, TypeError) as e:
        raise ValueError(f"{' '.join(map(said, overrides))}: {e}") from None


def _why_failed(grid, start, goal, planner: str, params: dict, res) -> str:
    """Why ``res`` (no path) failed, from what `PlanResult` keeps: is the goal reachable under the planner's move
    rules (exact A*), and for a colony its iterations, ants, dead-end rule and step limit (a failed colony keeps
    no partial path: ``path`` is empty and every iteration's ``successes`` is 0)."""
    import numpy as np

    from jaxplan.planning import plan

    moves = {k: params[k] for k in ("connectivity", "vehicle_height") if k in params}
    exact = plan(grid, start, goal, planner="astar", **moves)
    rule = f"{moves.get('connectivity', 8)}-connected" + (
        f", vehicle height {moves['vehicle_height']}" if moves.get("vehicle_height") is not None else "")
    if not exact.success:
        return (f"the goal is unreachable from the start ({rule} moves, no corner cutting: exact A* finds no path "
                f"either)")
    reach = f"the goal is reachable ({rule}: exact shortest path {exact.length:.2f} m, {len(exact.path)} cells)"
    if "ants" in params:
        ants = int(params["ants"]) * int(params.get("colonies", 1))
        its = len(res.history)
        succ = np.asarray(res.info.get("successes", np.zeros(0)))
        steps = params.get("max_steps") or "min(free cells, 4·(H + W))"
        hints = []
        if params.get("dead_end") == "die":
            hints.append("--set dead_end=retreat (ants stuck in a dead end die now)")
        if params.get("heuristic") == "euclidean":
            hints.append("--set heuristic=geodesic (the exact goal distance as η)")
        hints.append(f"more --set iterations= or ants= (now {its} x {ants})")
        if params.get("max_steps"):
            hints.append(f"a larger --set max_steps= (now {params['max_steps']}; the exact path has {len(exact.path)} "
                         f"cells)")
        return (f"{reach}, but no ant of {ants} reached it in any of {its} iterations (ants at the goal: "
                f"{int(succ.sum())}; dead-end rule {params.get('dead_end')!r}, at most {steps} steps per ant; a failed "
                f"colony keeps no partial path). Try " + ", ".join(hints))
    if "iterations" in params:  # the sampling planners
        return (f"{reach}, but the tree did not connect the goal in {params['iterations']} samples: try more "
                f"--set iterations= or another --seed")
    return reach


_RESOLUTION_HELP = ("metres per cell (default: 1.0 for a MovingAI .map; a ROS .yaml map keeps its own, and with a "
                   "value it is resampled: a coarse cell is blocked if any fine cell it covers is)")


def _add_map_args(parser: argparse.ArgumentParser) -> None:
    """``--resolution`` and a ROS map's Nav2 filter masks (`jaxplan.grid.load_ros_map`)."""
    parser.add_argument("--resolution", type=float, default=None, help=_RESOLUTION_HELP)
    parser.add_argument("--keepout", default=None, metavar="YAML", help="a Nav2 keep-out mask of a ROS map: its "
                        "occupied cells become blocked")
    parser.add_argument("--speed-mask", default=None, metavar="YAML", help="a Nav2 speed mask of a ROS map (percent "
                        "of top speed, Nav2's type 1 filter with base 100 and multiplier -1): the map's speed limits")
    parser.add_argument("--unknown", default=None, choices=("blocked", "free"), help="a ROS map's unknown cells "
                        "(default blocked)")


def _add_metre_args(parser: argparse.ArgumentParser) -> None:
    """``--start-m``/``--goal-m``: the endpoints in metres of the map's world frame, instead of cells."""
    for which in ("start", "goal"):
        parser.add_argument(f"--{which}-m", type=float, nargs=2, default=None, metavar=("X", "Y"),
                            help=f"{which} in metres of the map's world frame (a ROS map's origin applies), instead "
                                 f"of --{which}")


def _load_map_args(args: argparse.Namespace):
    """The map of ``plan``/``navigate`` and the ROS options given (for the output record)."""
    from jaxplan.grid import load_map

    ros = {k: v for k, v in (("keepout", args.keepout), ("speed", args.speed_mask), ("unknown", args.unknown))
           if v is not None}
    for path in (args.map, args.keepout, args.speed_mask):
        _check_file_arg(path)
    return load_map(args.map, resolution=args.resolution, **ros), ros


def _check_file_arg(path: str | None) -> None:
    """A missing map file named relative to the data folder (``ros/warehouse.yaml``, as a config writes it) fails
    saying where it is: paths on the command line are relative to the working folder (docs/decisions.md)."""
    if path is None or Path(path).exists() or Path(path).is_absolute():
        return
    from jaxplan.experiments.config import default_data_dir

    there = default_data_dir() / path
    if there.is_file():
        raise FileNotFoundError(f"map file not found: {path} (a path on the command line is relative to the working "
                                f"folder, not to the data folder as in a config: give {there})")


def _endpoint(args: argparse.Namespace, grid, which: str) -> tuple[int, int]:
    """The ``which`` (``"start"``/``"goal"``) cell of ``plan``/``navigate``: ``--start X Y`` (a cell) or
    ``--start-m X Y`` (metres in the map's world frame, through its origin: a ROS user's coordinates); exactly one.
    A point outside the map or on a blocked cell is refused naming the option, the point and the map's extent."""
    import math

    import numpy as np

    cell, metres = getattr(args, which), getattr(args, f"{which}_m")
    if cell is not None and metres is not None:
        raise ValueError(f"--{which} and --{which}-m both give the {which}: use one (--{which} X Y in cells, "
                         f"--{which}-m X Y in metres of the map's world frame)")
    if cell is None and metres is None:
        raise ValueError(f"the {which} is missing: give --{which} X Y (a cell) or --{which}-m X Y (metres in the "
                         "map's world frame)")
    if cell is not None:
        return int(cell[0]), int(cell[1])
    x, y = (float(v) for v in metres)
    said = f"--{which}-m {x:g} {y:g}"
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"{said}: the point must be two finite numbers (metres)")
    (ox, oy), res, (H, W) = (float(v) for v in grid.origin), float(grid.resolution), grid.shape
    cx, cy = (int(v) for v in grid.cell_at(np.array([x, y])))
    if not (0 <= cx < W and 0 <= cy < H):
        raise ValueError(f"{said}: the point is outside the map, which covers x {ox:g}..{ox + W * res:g} m and "
                         f"y {oy:g}..{oy + H * res:g} m (world frame, origin ({ox:g}, {oy:g}), {res:g} m cells)")
    if not bool(np.asarray(grid.free)[cy, cx]):
        raise ValueError(f"{said}: the point is on an obstacle (cell ({cx}, {cy}) is blocked)")
    print(f"{which}: ({x:g}, {y:g}) m is cell ({cx}, {cy})", file=sys.stderr)
    return cx, cy


def cmd_plan(args: argparse.Namespace) -> int:
    """``jaxplan plan MAP --start X Y --goal X Y``: one path, a table, and with ``--out`` a .json/.csv/.png file."""
    from jaxplan.experiments.tables import PATH_ROWS, path_column, text_table
    from jaxplan.planning import plan

    overrides = _parse_sets(args.set)
    # Only grid planners take a connectivity (the sampling planners have none), so pass it only when asked.
    if args.connectivity is not None:
        overrides["connectivity"] = args.connectivity
    params = _planner_params(args.planner, overrides, {"connectivity": "--connectivity"})
    if args.out is not None:
        from jaxplan.experiments.outputs import PLAN_SUFFIXES, check_suffix

        check_suffix(args.out, PLAN_SUFFIXES, "jaxplan plan")  # before any work
    grid, masks = _load_map_args(args)
    start, goal = _endpoint(args, grid, "start"), _endpoint(args, grid, "goal")
    from jaxplan.core.progress import ProgressBar

    with ProgressBar(f"{args.planner}: planning (compiled on first use)", None, enabled=not args.no_progress):
        res = plan(grid, start, goal, planner=args.planner, seed=args.seed, **overrides)
    print(text_table([(args.planner, path_column(res, grid))], PATH_ROWS, f"{args.planner} on {args.map}"))
    smoothed, metrics, failure = None, None, None
    if res.success:
        from jaxplan.metrics import path_metrics

        metrics = path_metrics(res.path, grid)
        if args.smooth:
            from jaxplan.smooth import smooth

            smoothed = smooth(res.path, grid, tuple(args.smooth.split(",")))
            sm = path_metrics(smoothed.points, grid)
            metrics = {**metrics, **{f"smoothed_{k}": v for k, v in sm.items()}}
            print(f"smoothed ({args.smooth}): {len(smoothed.points)} points, length {sm['length']:.3f} m, "
                  f"{int(smoothed.removed)} vertices removed, {int(smoothed.fallbacks)} fallbacks")
    else:
        failure = _why_failed(grid, start, goal, args.planner, params, res)
        print(f"{args.planner} found no path: {failure}", file=sys.stderr)
    if args.out is not None:
        from jaxplan.experiments.outputs import plan_record, write_plan

        record = plan_record(map_path=args.map, map_options=masks, grid=grid, start=start, goal=goal,
                             planner=args.planner, seed=args.seed, params=params, overrides=overrides, result=res,
                             metrics=metrics, smoothed=smoothed, smooth_method=args.smooth, failure=failure)
        print(f"wrote {write_plan(args.out, record, grid, res, smoothed)}")
    return 0 if res.success else 1


def cmd_navigate(args: argparse.Namespace) -> int:
    """``jaxplan navigate MAP --start X Y --goal X Y``: one two-level episode among random walkers."""
    import numpy as np

    from jaxplan.core.names import closest
    from jaxplan.nav import navigate, pipelines, random_obstacles

    overrides = _parse_sets(args.set)
    names = pipelines()
    if args.pipeline not in names:
        near = closest(args.pipeline, names)
        raise ValueError(f"--pipeline {args.pipeline!r} is not a pipeline{f' (did you mean {near!r}?)' if near else ''}"
                         f"; choose from {', '.join(names)}")
    pipe = names[args.pipeline]
    _planner_params(pipe.global_planner, {**pipe.planner_overrides, **overrides})  # a bad --set fails before any work
    if args.out is not None:
        from jaxplan.experiments.outputs import EPISODE_SUFFIXES, check_suffix

        check_suffix(args.out, EPISODE_SUFFIXES, "jaxplan navigate")
    if args.walkers < 0:
        raise ValueError(f"--walkers must be >= 0, got {args.walkers}")
    if args.behavior is not None and args.walkers == 0:
        raise ValueError(f"--behavior {args.behavior} describes walkers, but --walkers is 0: give --walkers N")
    behavior = args.behavior or "blind"
    grid, masks = _load_map_args(args)
    start, goal = _endpoint(args, grid, "start"), _endpoint(args, grid, "goal")
    res = float(grid.resolution)
    avoid = grid.centre(np.array([start, goal], np.float64))  # world metres, as random_obstacles takes
    obs = None if args.walkers == 0 else random_obstacles(
        grid, n=args.walkers, speed=args.walker_speed, radius=args.walker_radius, seed=args.seed, avoid=avoid,
        avoid_radius=1.5, behavior=behavior)
    ep = navigate(grid, start, goal, pipeline=args.pipeline, seed=args.seed, obstacles=obs,
                  time_limit=args.time_limit, progress=not args.no_progress, **overrides)
    m = ep.metrics
    print(f"{args.pipeline} on {args.map}: {'success' if ep.success else 'failed'} ({ep.reason}); "
          f"time {ep.time_s:.1f} s, path {m['path_length']:.2f} m, collisions {ep.collisions}, recoveries "
          f"{int(m['recoveries'])}, re-plans {int(m['replans'])}, walkers {args.walkers}"
          + (f" ({behavior})" if args.walkers else ""))
    if args.out is not None:
        from jaxplan.experiments.outputs import write_episode

        record = {"map": str(args.map), **({"map_options": masks} if masks else {}), "resolution_m": res,
                  "origin_m": [float(v) for v in grid.origin],
                  "start": list(start), "goal": list(goal),
                  "pipeline": args.pipeline, "seed": args.seed, "overrides": overrides, "walkers":
                  {"n": args.walkers, "speed": args.walker_speed, "radius": args.walker_radius, "behavior": behavior}}
        print(f"wrote {write_episode(args.out, ep, grid, record)}")
    return 0 if ep.success else 1


def cmd_export(args: argparse.Namespace) -> int:
    """``jaxplan export RUN --format npz|parquet``: a run's trials, paths, histories and trajectories as tables."""
    from jaxplan.experiments.export import export_run

    files = export_run(args.run, args.out, args.format)
    print("wrote " + ", ".join(map(str, files)))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    """``jaxplan run CONFIG``: validate the whole config, then run (or resume) it; exit 2 listing every problem."""
    from jaxplan.experiments.runner import run_experiment

    run_dir = run_experiment(args.config, args.out, quick=args.quick, data_dir=args.data_dir,
                             progress=not args.no_progress, chunk=args.chunk)
    print((run_dir / "summary.md").read_text())
    print(f"wrote {run_dir}/ (trials.csv, summary.csv, summary.md, report.md)")
    return 0


def cmd_figures(args: argparse.Namespace) -> int:
    """``jaxplan figures RUN``: every ``[[figures]]`` entry of the run's config as PNG and SVG, plus index.md."""
    from jaxplan.experiments.figures import default_figures_root, draw_figures

    out = Path(args.out) if args.out is not None else default_figures_root(args.run)  # never the tracked figures/
    drawn, problems = draw_figures(args.run, out, data_dir=args.data_dir, partial=args.partial,
                                   progress=not args.no_progress)
    name = Path(args.run).resolve().name
    print(f"wrote {len(drawn)} figures to {out / name}/ (index.md lists them)")
    for d in drawn:
        if d.partial:
            print(f"  partial: {d.name}: {d.partial}", file=sys.stderr)
    for p in problems:
        print(f"  not drawn: {p}", file=sys.stderr)
    return 0 if not problems else 1


def _reproduce_study(args: argparse.Namespace, results: str):
    """li2026's optimiser study (not an experiment config): its page and figure (`cmd_reproduce` rewrites the
    index after it)."""
    import time

    from jaxplan import benchmark_functions as bf
    from jaxplan.experiments.reproduce import Reproduced, describe_error

    t0 = time.perf_counter()
    try:
        page = bf.write_study(results, args.figures, bf.QUICK if args.quick else bf.FULL)
    except Exception as e:  # noqa: BLE001 - reported like a config's failure, after the others
        return Reproduced(Path(bf.NAME), None, time.perf_counter() - t0, 0.0, 0, (), describe_error(e))
    return Reproduced(Path(bf.NAME), None, time.perf_counter() - t0, 0.0, 1, (), page=page)


def cmd_reproduce(args: argparse.Namespace) -> int:
    """``jaxplan reproduce [--quick]``: every ``configs/<paper>_*.toml`` run (or resumed), then its figures."""
    import time

    from jaxplan.experiments.reproduce import reproduce, reproduction_configs

    if not args.no_cache:
        _compilation_cache()
    from fnmatch import fnmatch

    from jaxplan.benchmark_functions import NAME as STUDY

    # Results pages by default only for the project's own full reproduction (configs/, not --quick); a smoke run's
    # figures go beside its runs, not over the committed ones.
    if args.figures is None:
        args.figures = str(Path(args.out) / "figures") if args.quick else "figures"
    default = "docs/results" if not args.quick and args.configs == "configs" else None
    results = None if args.no_results else args.results or default
    studies = results is not None and (args.pattern is None or fnmatch(STUDY, args.pattern)
                                       or fnmatch(f"{STUDY}.toml", args.pattern))
    try:
        configs = reproduction_configs(args.configs, args.pattern)
    except FileNotFoundError:
        if not (studies and args.pattern is not None and Path(args.configs).is_dir()):
            raise
        configs = []  # only the study matches the pattern
    t0 = time.perf_counter()
    done = reproduce(configs, args.out, args.figures, quick=args.quick, data_dir=args.data_dir,
                     progress=not args.no_progress, results=results)
    if studies:
        done.append(_reproduce_study(args, results))
    if results is not None and any(r.page is not None for r in done):
        from jaxplan.experiments.claims import load_claims
        from jaxplan.experiments.results import load_notes, write_index_page

        # Once more, last: the study's page is in it and the wall time is the whole command's.
        here = Path(args.configs) / "results"
        write_index_page(results, load_notes(here / "notes.toml"), load_claims(here / "claims.toml"),
                         quick=args.quick, wall_s=time.perf_counter() - t0, cache=not args.no_cache,
                         figures_dir=args.figures)
    rows = [(r.config.name, "FAILED" if r.error else r.run_dir.name if r.run_dir else "-", f"{r.run_s:.1f}",
             f"{r.figures_s:.1f}", str(r.figures)) for r in done]
    heads = ("config", "run folder", "run (s)", "figures (s)", "figures")
    widths = [max(len(h), *(len(r[j]) for r in rows)) for j, h in enumerate(heads)]
    print("  ".join(h.ljust(w) for h, w in zip(heads, widths, strict=True)))
    for r in rows:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)))
    print(f"total {time.perf_counter() - t0:.1f} s; figures in {args.figures}/index.md"
          + (f"; results pages in {results}/index{'-quick' if args.quick else ''}.md" if results else ""))
    bad = 0
    for r in done:
        if r.error:
            bad += 1
            print(f"jaxplan: error: {r.config.name}: {r.error}", file=sys.stderr)
        # a quick run lacks some figures' planners, maps or scenarios: listed, not a failure of the reproduction
        for p in r.problems:
            print(f"  {r.config.name}: not drawn: {p}", file=sys.stderr)
    return 2 if bad else 0


def cmd_tune(args: argparse.Namespace) -> int:
    """``jaxplan tune CONFIG``: run (or resume) a tuning config; writes OUT/NAME/ with the best weights."""
    from jaxplan.tune import run_tuning

    run_dir = run_tuning(args.config, out=args.out, quick=args.quick, data_dir=args.data_dir,
                         progress=not args.no_progress, resume=not args.no_resume)
    print(f"wrote {run_dir}/ (generations.csv, summary.json, best.toml: a [[planners]] entry for `jaxplan run`, "
          f"convergence.png)")
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    """``jaxplan study CONFIG``: run (or resume) a tuning study; writes OUT/NAME/ with its log, figure and page."""
    from jaxplan.tune import run_study

    only = None if args.only is None else [m.strip() for m in args.only.split(",") if m.strip()]
    folder = run_study(args.config, out=args.out, quick=args.quick, data_dir=args.data_dir,
                       progress=not args.no_progress, resume=not args.no_resume, results=args.results,
                       confirm=args.confirm, only=only)
    if only is not None:
        print(f"ran {', '.join(only)} in {folder}/runs/; run the command without --only for the page")
        return 0
    print(f"wrote {folder}/ (log.csv, summary.json, convergence.png, best.toml, confirm.toml, page.md"
          + (", confirm.md)" if args.confirm else ")"))
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """``jaxplan bench``: the checkout's benchmarks/run_all.py (every benchmark, one table, JSON)."""
    import subprocess

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "run_all.py"
    if not script.exists():
        print(f"jaxplan: error: {script} not found: `jaxplan bench` runs from a source checkout "
              f"(pip install -e .)", file=sys.stderr)
        return 2
    rest = args.rest[1:] if args.rest[:1] == ["--"] else args.rest
    return subprocess.call([sys.executable, str(script), *rest])


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="jaxplan", description="Grid path planning for warehouse robots, in JAX.",
        epilog="Exit codes: 0 done; 2 bad input (fix the command, config or data); 1 a fault (disk, memory, a "
               "damaged checkpoint, a folder in use; retry once fixed); 130 interrupted (the same command resumes).")
    p.add_argument("--debug", action="store_true", help="print the traceback of a failure (default: one line)")
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="iaco_dwa vs aco_dwa among moving obstacles on the built-in warehouse; "
                                    "prints a table, writes runs/demo/demo.png and demo.gif")
    d.add_argument("--out-dir", "--out", default="runs/demo", help="figure folder (default: runs/demo, not tracked; "
                   "--out-dir figures regenerates the committed figures/demo.png and demo.gif on purpose)")
    d.add_argument("--seed", type=int, default=0, help="seed of the colonies and the moving discs (default 0)")
    d.add_argument("--quick", action="store_true", help="a small generated warehouse (seconds, for tests)")
    d.add_argument("--no-gif", action="store_true", help="skip the animation")
    d.add_argument("--no-cache", action="store_true", help=_NO_CACHE)
    d.add_argument("--no-progress", action="store_true", help="no progress bar on stderr (drawn only on a terminal)")
    d.set_defaults(func=cmd_demo)
    q = sub.add_parser("plan", help="plan one path on a map; --out writes .json, .csv or .png")
    q.add_argument("map", help="map file: MovingAI .map or ROS map_server .yaml")
    q.add_argument("--start", type=int, nargs=2, metavar=("X", "Y"), help="start cell (column, row)")
    q.add_argument("--goal", type=int, nargs=2, metavar=("X", "Y"), help="goal cell (column, row)")
    _add_metre_args(q)
    q.add_argument("--planner", default="astar", help="a planner of jaxplan.planners() (default astar)")
    q.add_argument("--seed", type=int, default=0, help="the planner's seed (default 0; exact planners ignore it)")
    q.add_argument("--set", action="append", metavar="KEY=VALUE", help="a planner parameter, repeatable: --set "
                   "ants=64 --set heuristic=geodesic --set lambdas=0.6,0.3,0.1 (checked against the planner's)")
    q.add_argument("--smooth", default=None, metavar="METHOD", help="smooth the path: los, key_nodes, fillet, bezier, "
                                                                   "bspline, or a chain such as los,fillet")
    q.add_argument("--connectivity", type=int, default=None, choices=(4, 8, 16),
                   help="grid moves per cell (default: the planner's own, 8 for the grid planners)")
    _add_map_args(q)
    q.add_argument("--out", default=None, metavar="FILE", help="write the plan: .json (path in cells and metres, "
                   "metrics, planner and parameters, provenance), .csv (path points) or .png/.svg/.pdf (path on map)")
    q.add_argument("--no-progress", action="store_true", help="no progress spinner on stderr")
    q.set_defaults(func=cmd_plan)
    v = sub.add_parser("navigate", help="one two-level navigation episode among random walkers; --out writes .json, "
                                        ".gif or .png")
    v.add_argument("map", help="map file: MovingAI .map or ROS map_server .yaml")
    v.add_argument("--start", type=int, nargs=2, metavar=("X", "Y"), help="start cell (column, row)")
    v.add_argument("--goal", type=int, nargs=2, metavar=("X", "Y"), help="goal cell (column, row)")
    _add_metre_args(v)
    v.add_argument("--pipeline", default="iaco_dwa", help="a pipeline of jaxplan.pipelines() (default iaco_dwa)")
    v.add_argument("--seed", type=int, default=0, help="seed of the global planner and of the walkers (default 0)")
    v.add_argument("--set", action="append", metavar="KEY=VALUE", help="a global planner parameter, repeatable")
    v.add_argument("--walkers", type=int, default=2, help="random walkers (moving discs; default 2, 0 for none)")
    v.add_argument("--walker-speed", type=float, default=0.5, help="walkers' speed in m/s (default 0.5)")
    v.add_argument("--walker-radius", type=float, default=0.25, help="walkers' radius in m (default 0.25)")
    # jaxplan.nav's walker behaviours (`random_obstacles(behavior=...)`), written out: --help must not import JAX
    v.add_argument("--behavior", default=None, choices=("blind", "social"), help="how the walkers move: blind (on "
                   "their routes regardless of the robot; the default) or social (the same routes, but they see and "
                   "avoid the robot, each other and the walls: the social force model)")
    v.add_argument("--time-limit", type=float, default=None, help="seconds (default: from the path length)")
    _add_map_args(v)
    v.add_argument("--out", default=None, metavar="FILE", help="write the episode: .json (trajectory, controls, "
                   "metrics, walkers, provenance), .gif (animation; needs Pillow) or "
                   ".png/.svg/.pdf (trajectory, start, goal, walkers' paths)")
    v.add_argument("--no-progress", action="store_true", help="no progress stages on stderr")
    v.set_defaults(func=cmd_navigate)
    r = sub.add_parser("run", help="run (or resume) the experiment of a TOML config; writes OUT/NAME/")
    r.add_argument("config", help="experiment config (TOML; schema: jaxplan.experiments.config)")
    r.add_argument("--quick", action="store_true", help="apply the config's [experiment.quick] changes (a smoke run, "
                                                        "written to OUT/NAME-quick/)")
    r.add_argument("--out", default="runs", help="parent folder of the run folder (default: runs)")
    r.add_argument("--data-dir", default=None, help="folder that map paths are relative to (default: $JAXPLAN_DATA "
                                                    "or ../shared/benchmarks)")
    r.add_argument("--chunk", type=int, default=None, help="scenarios per compiled call (default: the config's)")
    r.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    r.set_defaults(func=cmd_run)
    f = sub.add_parser("figures", help="draw the figures a run's config names into OUT/RUN/ (PNG, SVG, index.md)")
    f.add_argument("run", help="a run folder written by `jaxplan run` (e.g. runs/NAME)")
    f.add_argument("--out", default=None, help="figure root; files go to OUT/RUN/ (default: figures/ beside the run "
                   "folder, e.g. runs/figures, not tracked)")
    f.add_argument("--data-dir", default=None, help="folder that the config's map paths are relative to")
    f.add_argument("--partial", action="store_true", help="draw a figure even if some of its chunks' arrays are "
                                                          "missing or damaged, labelled partial (default: refuse it)")
    f.add_argument("--no-progress", action="store_true", help="no progress bar on stderr (drawn only on a terminal)")
    f.set_defaults(func=cmd_figures)
    x = sub.add_parser("export", help="a run's trials, paths, histories and trajectories as npz or parquet tables")
    x.add_argument("run", help="a run folder written by `jaxplan run` (e.g. runs/NAME)")
    x.add_argument("--format", default="npz", choices=("npz", "parquet"),
                   help="npz (one file, always available) or parquet (one file per table; needs pyarrow)")
    x.add_argument("--out", default=None, help="npz file or parquet folder (default RUN/export.npz or RUN/export/)")
    x.set_defaults(func=cmd_export)
    g = sub.add_parser("reproduce", help="run every paper's reproduction config (configs/<paper>_*.toml, e.g. "
                                         "cui2025_table2.toml), then draw its figures")
    g.add_argument("--quick", action="store_true", help="the configs' [experiment.quick] smoke runs (CI)")
    g.add_argument("--configs", default="configs", help="folder of the configs (default: configs)")
    g.add_argument("--pattern", default=None, help="which configs (glob; default: every <paper>_*.toml)")
    g.add_argument("--out", default="runs", help="parent folder of the run folders (default: runs)")
    g.add_argument("--figures", default=None, help="figure root (default: figures for the full runs, which "
                   "regenerate the committed figures; OUT/figures for --quick, so a smoke run writes no tracked file)")
    g.add_argument("--data-dir", default=None, help="folder that map paths are relative to")
    g.add_argument("--results", default=None, help="results pages root: <paper>/<table>.md and index.md, the paper's "
                                                   "numbers beside ours (default: docs/results for the full runs of "
                                                   "configs/; none with --quick or another --configs)")
    g.add_argument("--no-results", action="store_true", help="write no results pages")
    g.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    g.add_argument("--no-cache", action="store_true", help=_NO_CACHE)
    g.set_defaults(func=cmd_reproduce)
    t = sub.add_parser("tune", help="tune a planner's weights from a TOML config (resumable); writes OUT/NAME/")
    t.add_argument("config", help="tuning config (TOML; schema: jaxplan.tune._config)")
    t.add_argument("--quick", action="store_true", help="apply the config's [tune.quick] changes (OUT/NAME-quick/)")
    t.add_argument("--out", default="runs", help="parent folder of the run folder (default: runs)")
    t.add_argument("--data-dir", default=None, help="folder that map paths are relative to")
    t.add_argument("--no-resume", action="store_true", help="start afresh instead of resuming from the last checkpoint")
    t.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    t.set_defaults(func=cmd_tune)
    st = sub.add_parser("study", help="a tuning study: every method at an equal counted budget, judged on held-out "
                                      "scenarios (resumable); writes OUT/NAME/")
    st.add_argument("config", help="study config (TOML: a tuning config plus [study]; jaxplan.tune._study)")
    st.add_argument("--quick", action="store_true", help="apply [study.quick] and [tune.quick] (OUT/NAME-quick/)")
    st.add_argument("--out", default="runs", help="parent folder of the study folder (default: runs)")
    st.add_argument("--data-dir", default=None, help="folder that map paths are relative to")
    st.add_argument("--results", default=None, help="also write the page, figure, best.toml and confirm.toml here "
                                                    "(e.g. docs/results/tuning)")
    st.add_argument("--confirm", action="store_true", help="then run confirm.toml (defaults vs tuned on fresh "
                                                             "scenarios) with `jaxplan run` and write its page")
    st.add_argument("--no-resume", action="store_true", help="start afresh instead of resuming")
    st.add_argument("--only", default=None, metavar="METHOD[,METHOD]", help="a worker: run only these methods' "
                    "runs (in the same study folder; workers with disjoint methods run side by side, one per core), "
                    "then stop; the command without --only writes the page")
    st.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    st.set_defaults(func=cmd_study)
    b = sub.add_parser("bench", help="every benchmark of the library in one table (benchmarks/run_all.py; "
                                     "options after --, e.g. jaxplan bench -- --quick)")
    b.add_argument("rest", nargs=argparse.REMAINDER, help="options of benchmarks/run_all.py")
    b.set_defaults(func=cmd_bench)
    for name, cmd in sub.choices.items():  # every command has --no-cache (bench's benchmarks run in their own process)
        if name not in ("demo", "reproduce", "bench"):  # declared above
            cmd.add_argument("--no-cache", action="store_true", help=_NO_CACHE)
    return p


def _use_host_devices() -> None:
    """One JAX CPU host device per core for this process (`jaxplan.use_host_devices`), unless JAX already runs
    here: `main` called from a Python process that has computed with JAX keeps that process's devices."""
    from jaxplan.scale import use_host_devices

    try:
        use_host_devices()
    except RuntimeError:
        pass


class _Interrupts:
    """Ctrl-C during a command: every SIGINT raises `KeyboardInterrupt` in the main thread, and after the first
    one SIGINT is sent again every half second until the command has stopped: an interrupt raised while
    Python runs a garbage-collection callback (JAX registers one) is swallowed there, and the command would
    go on for hours. Those swallowed ones are not reported either (no "Exception ignored" traceback)."""

    def __init__(self):
        import threading

        self.hit = False
        self.stopped = threading.Event()
        self.previous = None
        self.hook = sys.unraisablehook

    def __enter__(self) -> "_Interrupts":
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self._handler)
        return self

    def _handler(self, signum, frame) -> None:
        if not self.hit:
            import threading

            self.hit = True
            hook = self.hook
            sys.unraisablehook = lambda u: None if isinstance(u.exc_value, KeyboardInterrupt) else hook(u)
            threading.Thread(target=self._repeat, daemon=True).start()
        raise KeyboardInterrupt

    def _repeat(self) -> None:
        import os
        import signal

        while not self.stopped.wait(0.5):
            os.kill(os.getpid(), signal.SIGINT)

    def __exit__(self, *exc) -> None:
        import signal

        self.stopped.set()
        if self.previous is not None:  # after a Ctrl-C, a repeat still on its way is ignored
            signal.signal(signal.SIGINT, signal.SIG_IGN if self.hit else self.previous)

    def restore(self) -> None:
        """The SIGINT handler and unraisable hook as they were before the command."""
        import signal

        sys.unraisablehook = self.hook
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``jaxplan ARGV``; returns the exit status: 0 done, 2 bad input, 1 a fault, 130 interrupted.

    A failure prints one line on stderr naming the cause and what to do (`jaxplan.core.failure`), and the
    traceback only with ``--debug``. Called as the console script (``argv`` None), an interrupted process
    leaves at once after its message (``os._exit``): JAX's and numba's threads are not waited for.
    """
    args = build_parser().parse_args(argv)
    interrupts = _Interrupts()
    try:
        with interrupts:
            if args.func is not cmd_bench:  # the benchmarks run in a process of their own, which opts in itself
                _use_host_devices()
            if getattr(args, "no_cache", False):  # else the caches turn on when compiled code first loads
                from jaxplan.core.compile_cache import disable_compilation_cache

                disable_compilation_cache()
            return int(args.func(args))
    except (Exception, KeyboardInterrupt) as e:  # noqa: BLE001 - every failure ends in one line and an exit code
        from jaxplan.core.failure import INTERRUPTED, describe_failure

        if args.debug:
            import traceback

            traceback.print_exc()
        code, message = describe_failure(e, args.command)
        print(message if code == INTERRUPTED else f"jaxplan: error: {message}", file=sys.stderr, flush=True)
        if code == INTERRUPTED and argv is None:
            import os

            sys.stdout.flush()
            os._exit(code)
        return code
    finally:
        interrupts.restore()


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
