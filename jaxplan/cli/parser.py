"""The parser of ``jaxplan``: every command, its options and their help (standard library only: ``--help`` answers
without JAX or numba)."""

from __future__ import annotations

import argparse

from jaxplan.cli.commands import (
    cmd_bench,
    cmd_demo,
    cmd_export,
    cmd_figures,
    cmd_navigate,
    cmd_plan,
    cmd_reproduce,
    cmd_run,
    cmd_study,
    cmd_tune,
)

__all__ = ["build_parser", "add_execution_options", "add_map_args", "add_endpoint_args"]

_NO_CACHE = ("do not use the on-disk compilation caches (JAX's and numba's in $JAXPLAN_CACHE or ~/.cache/jaxplan; "
             "JAXPLAN_CACHE=off does the same for every command)")


_RESOLUTION_HELP = ("metres per cell (default: 1.0 for a MovingAI .map; a ROS .yaml map keeps its own, and with a "
                   "value it is resampled: a coarse cell is blocked if any fine cell it covers is)")


def add_execution_options(parser: argparse.ArgumentParser, *, units: str | None = None) -> None:
    """The options of how work runs, shared by the commands that run configs (``run``, ``reproduce``, ``tune``,
    ``study``): the data folder, the progress line and, for a command whose work is independent ``units`` (an
    experiment's chunks, a study's runs), ``--ray`` (`jaxplan.core.executor`)."""
    parser.add_argument("--data-dir", default=None, help="folder that map paths are relative to (default: "
                                                         "$JAXPLAN_DATA or ../shared/benchmarks)")
    parser.add_argument("--no-progress", action="store_true", help="no progress line on stderr (drawn only on a "
                                                                   "terminal)")
    if units is not None:
        parser.add_argument("--ray", default=None, metavar="ADDRESS", help=f"run the {units} as Ray tasks (needs "
                            f"jaxplan[ray]): 'auto' joins the cluster started on this machine (ray start --head) or "
                            f"else starts one with its cores; HOST:PORT joins that cluster's head (e.g. "
                            f"head-node:6379). This process stays the only writer of the run folder; the files are "
                            f"the same bytes as without --ray")


def add_map_args(parser: argparse.ArgumentParser) -> None:
    """``--resolution`` and a ROS map's Nav2 filter masks (`jaxplan.grid.load_ros_map`)."""
    parser.add_argument("--resolution", type=float, default=None, help=_RESOLUTION_HELP)
    parser.add_argument("--keepout", default=None, metavar="YAML", help="a Nav2 keep-out mask of a ROS map: its "
                        "occupied cells become blocked")
    parser.add_argument("--speed-mask", default=None, metavar="YAML", help="a Nav2 speed mask of a ROS map (percent "
                        "of top speed, Nav2's type 1 filter with base 100 and multiplier -1): the map's speed limits")
    parser.add_argument("--unknown", default=None, choices=("blocked", "free"), help="a ROS map's unknown cells "
                        "(default blocked)")


def add_endpoint_args(parser: argparse.ArgumentParser) -> None:
    """The map and the start and goal of ``plan``/``navigate``: ``MAP``, ``--start``/``--goal`` (cells) or
    ``--start-m``/``--goal-m`` (metres in the map's world frame)."""
    parser.add_argument("map", help="map file: MovingAI .map or ROS map_server .yaml")
    for which in ("start", "goal"):
        parser.add_argument(f"--{which}", type=int, nargs=2, metavar=("X", "Y"), help=f"{which} cell (column, row)")
    for which in ("start", "goal"):
        parser.add_argument(f"--{which}-m", type=float, nargs=2, default=None, metavar=("X", "Y"),
                            help=f"{which} in metres of the map's world frame (a ROS map's origin applies), instead "
                                 f"of --{which}")


def build_parser() -> argparse.ArgumentParser:
    """The ``jaxplan`` argument parser: every command with its options, each bound to its ``cmd_*`` function."""
    p = argparse.ArgumentParser(
        prog="jaxplan", description="Grid path planning for warehouse robots, in JAX.",
        epilog="Exit codes: 0 done; 2 bad input (fix the command, config or data); 1 a fault (disk, memory, a "
               "damaged checkpoint, a folder in use, a Ray cluster out of reach; retry once fixed); 130 interrupted "
               "(Ctrl-C), 143 terminated (SIGTERM): the same command resumes.")
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
    add_endpoint_args(q)
    q.add_argument("--planner", default="astar", help="a planner of jaxplan.planners() (default astar)")
    q.add_argument("--seed", type=int, default=0, help="the planner's seed (default 0; exact planners ignore it)")
    q.add_argument("--set", action="append", metavar="KEY=VALUE", help="a planner parameter, repeatable: --set "
                   "ants=64 --set heuristic=geodesic --set lambdas=0.6,0.3,0.1 (checked against the planner's)")
    q.add_argument("--smooth", default=None, metavar="METHOD", help="smooth the path: los, key_nodes, fillet, bezier, "
                                                                   "bspline, or a chain such as los,fillet")
    q.add_argument("--connectivity", type=int, default=None, choices=(4, 8, 16),
                   help="grid moves per cell (default: the planner's own, 8 for the grid planners)")
    add_map_args(q)
    q.add_argument("--out", default=None, metavar="FILE", help="write the plan: .json (path in cells and metres, "
                   "metrics, planner and parameters, provenance), .csv (path points) or .png/.svg/.pdf (path on map)")
    q.add_argument("--no-progress", action="store_true", help="no progress spinner on stderr")
    q.set_defaults(func=cmd_plan)
    v = sub.add_parser("navigate", help="one two-level navigation episode among random walkers; --out writes .json, "
                                        ".gif or .png")
    add_endpoint_args(v)
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
    add_map_args(v)
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
    r.add_argument("--chunk", type=int, default=None, help="scenarios per compiled call (default: the config's)")
    add_execution_options(r, units="chunks")
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
    g.add_argument("--results", default=None, help="results pages root: <paper>/<table>.md and index.md, the paper's "
                                                   "numbers beside ours (default: docs/results for the full runs of "
                                                   "configs/; none with --quick or another --configs)")
    g.add_argument("--no-results", action="store_true", help="write no results pages")
    g.add_argument("--no-cache", action="store_true", help=_NO_CACHE)
    add_execution_options(g, units="configs' chunks")
    g.set_defaults(func=cmd_reproduce)
    t = sub.add_parser("tune", help="tune a planner's weights from a TOML config (resumable); writes OUT/NAME/")
    t.add_argument("config", help="tuning config (TOML; schema: jaxplan.tune._config)")
    t.add_argument("--quick", action="store_true", help="apply the config's [tune.quick] changes (OUT/NAME-quick/)")
    t.add_argument("--out", default="runs", help="parent folder of the run folder (default: runs)")
    t.add_argument("--no-resume", action="store_true", help="start afresh instead of resuming from the last checkpoint")
    add_execution_options(t)
    t.set_defaults(func=cmd_tune)
    st = sub.add_parser("study", help="a tuning study: every method at an equal counted budget, judged on held-out "
                                      "scenarios (resumable); writes OUT/NAME/")
    st.add_argument("config", help="study config (TOML: a tuning config plus [study]; jaxplan.tune.study)")
    st.add_argument("--quick", action="store_true", help="apply [study.quick] and [tune.quick] (OUT/NAME-quick/)")
    st.add_argument("--out", default="runs", help="parent folder of the study folder (default: runs)")
    st.add_argument("--results", default=None, help="also write the page, figure, best.toml and confirm.toml here "
                                                    "(e.g. docs/results/tuning)")
    st.add_argument("--confirm", action="store_true", help="then run confirm.toml (defaults vs tuned on fresh "
                                                             "scenarios) with `jaxplan run` and write its page")
    st.add_argument("--no-resume", action="store_true", help="start afresh instead of resuming")
    st.add_argument("--only", default=None, metavar="METHOD[,METHOD]", help="a worker: run only these methods' "
                    "runs (in the same study folder; workers with disjoint methods run side by side, one per core), "
                    "then stop; the command without --only writes the page. The no-dependency way to share a "
                    "study over processes or machines with one shared folder; --ray needs none")
    add_execution_options(st, units="(method, tuner seed) runs")
    st.set_defaults(func=cmd_study)
    b = sub.add_parser("bench", help="every benchmark of the library in one table (benchmarks/run_all.py; "
                                     "options after --, e.g. jaxplan bench -- --quick)")
    b.add_argument("rest", nargs=argparse.REMAINDER, help="options of benchmarks/run_all.py")
    b.set_defaults(func=cmd_bench)
    for name, cmd in sub.choices.items():  # every command has --no-cache (bench's benchmarks run in their own process)
        if name not in ("demo", "reproduce", "bench"):  # declared above
            cmd.add_argument("--no-cache", action="store_true", help=_NO_CACHE)
    return p
