"""The commands of ``jaxplan``: one function per command, ``cmd_NAME(args) -> exit status``.

Each imports what it needs when it runs (``--help`` imports this module and must not load JAX). The parser
(`jaxplan.cli.parser`) binds each command's options to its function; `jaxplan.cli.main` runs it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from jaxplan.cli.args import endpoint, load_map_args, parse_sets, planner_params

__all__ = ["cmd_demo", "cmd_plan", "cmd_navigate", "cmd_export", "cmd_run", "cmd_figures", "cmd_reproduce",
           "cmd_tune", "cmd_study", "cmd_bench"]


def _compilation_cache() -> None:
    """The on-disk compilation caches (`jaxplan.core.compile_cache`: ``$JAXPLAN_CACHE`` or ``~/.cache/jaxplan``),
    turned on now rather than at the first compiled module (compiled programs are most of the demo's time)."""
    from jaxplan.core.compile_cache import on_first_use

    on_first_use()


def cmd_demo(args: argparse.Namespace) -> int:
    """``jaxplan demo``: IACO-DWA beside ACO-DWA among moving discs on the built-in warehouse (no data)."""
    import time

    from jaxplan.cli.demo import demo_table, run_demo
    from jaxplan.core.version import VERSION

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


def cmd_plan(args: argparse.Namespace) -> int:
    """``jaxplan plan MAP --start X Y --goal X Y``: one path, a table, and with ``--out`` a .json/.csv/.png file."""
    from jaxplan.cli.tables import PATH_ROWS, path_column, text_table
    from jaxplan.planning import plan

    overrides = parse_sets(args.set)
    # Only grid planners take a connectivity (the sampling planners have none), so pass it only when asked.
    if args.connectivity is not None:
        overrides["connectivity"] = args.connectivity
    params = planner_params(args.planner, overrides, {"connectivity": "--connectivity"})
    if args.out is not None:
        from jaxplan.cli.outputs import PLAN_SUFFIXES, check_suffix

        check_suffix(args.out, PLAN_SUFFIXES, "jaxplan plan")  # before any work
    grid, masks = load_map_args(args)
    start, goal = endpoint(args, grid, "start"), endpoint(args, grid, "goal")
    from jaxplan.core.progress import ProgressBar

    with ProgressBar(f"{args.planner}: planning (compiled on first use)", None, enabled=not args.no_progress):
        res = plan(grid, start, goal, planner=args.planner, seed=args.seed, **overrides)
    print(text_table([(args.planner, path_column(res, grid))], PATH_ROWS, f"{args.planner} on {args.map}"))
    smoothed, metrics, failure = None, None, None
    if res.success:
        from jaxplan.metrics import PATH_METRICS, path_metrics

        m = path_metrics(res.path, grid)
        metrics = {k: getattr(m, k) for k in PATH_METRICS}
        if args.smooth:
            from jaxplan.smoothing import smooth

            smoothed = smooth(res.path, grid, tuple(args.smooth.split(",")))
            sm = path_metrics(smoothed.points, grid)
            metrics |= {f"smoothed_{k}": getattr(sm, k) for k in PATH_METRICS}
            print(f"smoothed ({args.smooth}): {len(smoothed.points)} points, length {sm.length:.3f} m, "
                  f"{int(smoothed.removed)} vertices removed, {int(smoothed.fallbacks)} fallbacks")
    else:
        failure = _why_failed(grid, start, goal, args.planner, params, res)
        print(f"{args.planner} found no path: {failure}", file=sys.stderr)
    if args.out is not None:
        from jaxplan.cli.outputs import plan_record, write_plan

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

    overrides = parse_sets(args.set)
    names = pipelines()
    if args.pipeline not in names:
        near = closest(args.pipeline, names)
        raise ValueError(f"--pipeline {args.pipeline!r} is not a pipeline{f' (did you mean {near!r}?)' if near else ''}"
                         f"; choose from {', '.join(names)}")
    pipe = names[args.pipeline]
    planner_params(pipe.global_planner, {**pipe.planner_overrides, **overrides})  # a bad --set fails before any work
    if args.out is not None:
        from jaxplan.cli.outputs import EPISODE_SUFFIXES, check_suffix

        check_suffix(args.out, EPISODE_SUFFIXES, "jaxplan navigate")
    if args.walkers < 0:
        raise ValueError(f"--walkers must be >= 0, got {args.walkers}")
    if args.behavior is not None and args.walkers == 0:
        raise ValueError(f"--behavior {args.behavior} describes walkers, but --walkers is 0: give --walkers N")
    behavior = args.behavior or "blind"
    grid, masks = load_map_args(args)
    start, goal = endpoint(args, grid, "start"), endpoint(args, grid, "goal")
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
        from jaxplan.cli.outputs import write_episode

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
                             progress=not args.no_progress, chunk=args.chunk, executor=args.ray)
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

    from jaxplan.experiments.reproduce import Reproduced, describe_error
    from jaxplan.studies import benchmark_functions as bf

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

    from jaxplan.studies.benchmark_functions import NAME as STUDY

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
                     progress=not args.no_progress, results=results, executor=args.ray)
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
                       confirm=args.confirm, only=only, executor=args.ray)
    if only is not None:
        print(f"ran {', '.join(only)} in {folder}/runs/; run the command without --only for the page")
        return 0
    print(f"wrote {folder}/ (log.csv, summary.json, convergence.png, best.toml, confirm.toml, page.md"
          + (", confirm.md)" if args.confirm else ")"))
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """``jaxplan bench``: the checkout's benchmarks/run_all.py (every benchmark, one table, JSON)."""
    import subprocess

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "run_all.py"
    if not script.exists():
        print(f"jaxplan: error: {script} not found: `jaxplan bench` runs from a source checkout "
              f"(pip install -e .)", file=sys.stderr)
        return 2
    rest = args.rest[1:] if args.rest[:1] == ["--"] else args.rest
    return subprocess.call([sys.executable, str(script), *rest])
