"""Command line: ``jaxplan demo | plan | run | figures``.

Subcommands for experiments, tuning, figures and benchmarks join as they are built.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Sequence

__all__ = ["main"]


def _table(columns: Sequence[tuple[str, list[str]]], labels: list[str], title: str) -> str:
    """A text table: one row per label, one column per (header, values)."""
    heads = ["metric"] + [h for h, _ in columns]
    rows = [[lab] + [vals[i] for _, vals in columns] for i, lab in enumerate(labels)]
    widths = [max(len(r[j]) for r in rows + [heads]) for j in range(len(heads))]
    line = "+" + "+".join("-" * (w + 2) for w in widths) + "+"

    def fmt(r):
        return "| " + " | ".join(c.ljust(w) if j == 0 else c.rjust(w) for j, (c, w) in enumerate(zip(r, widths))) + " |"

    return "\n".join([title, line, fmt(heads), line] + [fmt(r) for r in rows] + [line])


ROW_LABELS = [
    "success", "length (m)", "cells on path", "turns", "sharp turns (>= 45 deg)", "smoothness",
    "min clearance (m)", "mean clearance (m)", "planning time (ms)",
]


def _path_column(res, grid) -> list[str]:
    from jaxplan.metrics import path_metrics

    # The table shows no gap: the planner's own length as `optimal` skips a second exact search.
    m = path_metrics(res.path, grid, optimal=res.length) if res.success else {
        "sharp_turns": 0, "smoothness": 1.0, "min_clearance": float("nan"), "mean_clearance": float("nan")}
    return [
        str(res.success), f"{res.length:.3f}", str(len(res.path)), str(res.turns), str(m["sharp_turns"]),
        f"{m['smoothness']:.3f}", f"{m['min_clearance']:.3f}", f"{m['mean_clearance']:.3f}", f"{res.time_s * 1e3:.2f}",
    ]


def cmd_demo(args: argparse.Namespace) -> int:
    import matplotlib.pyplot as plt

    import jaxplan as jp
    from jaxplan.experiments.plots import plot_map, plot_paths, save_figure

    scene = jp.demo_warehouse()
    grid = scene.grid
    start, goal = tuple(scene.start.tolist()), tuple(scene.goal.tolist())
    print(f"jaxplan {jp.__version__} demo: {scene.name}, start {start} -> goal {goal}")
    results = {}
    for name in ("astar", "iaco", "praco"):
        # The first call compiles (ACO) or loads (A*) the planner; the table reports a second, warm call.
        first = jp.plan(grid, scene.start, scene.goal, planner=name, seed=args.seed)
        results[name] = jp.plan(grid, scene.start, scene.goal, planner=name, seed=args.seed)
        if name != "astar":
            print(f"  {name}: compiled in {first.info['compile_s']:.1f} s (once per configuration)")
    columns = [(name, _path_column(r, grid)) for name, r in results.items()]
    print(_table(columns, ROW_LABELS, "Paths across the warehouse (8-connected, no corner cutting; ACO with defaults)"))
    opt = results["astar"].length
    for name in ("iaco", "praco"):
        print(f"  {name}: optimality gap {results[name].length / opt - 1:.2%} "
              f"(converged at iteration {results[name].info['converged_iteration']})")
    fig, ax = plt.subplots(figsize=(8, 5.6))
    plot_map(ax, grid, title=f"{scene.name}: A* {opt:.1f} m, iaco {results['iaco'].length:.1f} m, "
                             f"praco {results['praco'].length:.1f} m")
    plot_paths(ax, grid, [r.path for r in results.values()], labels=list(results), start=scene.start, goal=scene.goal)
    written = save_figure(fig, args.out)
    plt.close(fig)
    print("wrote " + ", ".join(written))
    return 0


def cmd_plan(args: argparse.Namespace) -> int:
    import jaxplan as jp

    grid = jp.load_map(args.map, resolution=args.resolution)
    res = jp.plan(grid, tuple(args.start), tuple(args.goal), planner=args.planner, connectivity=args.connectivity)
    print(_table([(args.planner, _path_column(res, grid))], ROW_LABELS, f"{args.planner} on {args.map}"))
    return 0 if res.success else 1


def cmd_run(args: argparse.Namespace) -> int:
    """``jaxplan run CONFIG``: validate the whole config, then run (or resume) it; exit 2 listing every problem."""
    from jaxplan.experiments.config import ConfigError
    from jaxplan.experiments.runner import RunFolderError, run_experiment

    try:
        run_dir = run_experiment(args.config, args.out, quick=args.quick, data_dir=args.data_dir,
                                 progress=not args.no_progress, chunk=args.chunk)
    except ConfigError as e:
        print(f"jaxplan: error: invalid config {e}", file=sys.stderr)
        return 2
    except RunFolderError as e:
        print(f"jaxplan: error: {e}", file=sys.stderr)
        return 2
    print((run_dir / "summary.md").read_text())
    print(f"wrote {run_dir}/ (trials.csv, summary.csv, summary.md, report.md)")
    return 0


def cmd_figures(args: argparse.Namespace) -> int:
    """``jaxplan figures RUN``: every ``[[figures]]`` entry of the run's config as PNG and SVG, plus index.md."""
    from jaxplan.experiments.figures import draw_figures

    drawn, problems = draw_figures(args.run, args.out, data_dir=args.data_dir)
    name = Path(args.run).resolve().name
    print(f"wrote {len(drawn)} figures to {Path(args.out) / name}/ (index.md lists them)")
    for p in problems:
        print(f"  not drawn: {p}", file=sys.stderr)
    return 0 if not problems else 1


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="jaxplan", description="Grid path planning for warehouse robots, in JAX.")
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="plan on the built-in warehouse, print metrics, write figures/demo.png")
    d.add_argument("--out", default="figures/demo.png", help="figure file (default: figures/demo.png)")
    d.add_argument("--seed", type=int, default=0, help="seed of the ant colonies (default 0)")
    d.set_defaults(func=cmd_demo)
    q = sub.add_parser("plan", help="plan one path on a MovingAI map")
    q.add_argument("map", help="MovingAI .map file")
    q.add_argument("--start", type=int, nargs=2, required=True, metavar=("X", "Y"))
    q.add_argument("--goal", type=int, nargs=2, required=True, metavar=("X", "Y"))
    q.add_argument("--planner", default="astar")
    q.add_argument("--connectivity", type=int, default=8, choices=(4, 8, 16))
    q.add_argument("--resolution", type=float, default=1.0, help="metres per cell")
    q.set_defaults(func=cmd_plan)
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
    f.add_argument("--out", default="figures", help="figure root (default: figures; files go to OUT/RUN/)")
    f.add_argument("--data-dir", default=None, help="folder that the config's map paths are relative to")
    f.set_defaults(func=cmd_figures)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError) as e:
        print(f"jaxplan: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
