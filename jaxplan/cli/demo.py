"""`jaxplan demo`: cui2025's IACO-DWA beside its ACO-DWA baseline among moving obstacles, with no data.

Both pipelines drive the same robot from the same start to the same goal on the built-in
48x32 warehouse (`jaxplan.demo_warehouse`) among the same moving discs (random routes
that keep clear of the start and goal). The table compares the episodes; ``demo.png``
shows the executed trajectories over their global paths and the speed profiles, and
``demo.gif`` animates both robots with the discs (matplotlib's pillow writer). Both go to
``runs/demo/`` by default, a folder git ignores: a clone stays clean after its first command. The
committed ``figures/demo.png`` and ``demo.gif`` are regenerated on purpose with
``jaxplan demo --out-dir figures``.

Speed. Each pipeline compiles its global planner and its episode program once (most of
the demo's time); the settings below keep the demo short on a small CPU, the first run
after install included (timings: docs/benchmarks.md): in-episode re-planning off (it would
compile a second planner program), a 10 x 20 velocity window without unrolling (less to
compile), colonies of 20 ants x 20 iterations walked and updated in JAX
(``walk_backend="jax", update_backend="jax"``: the numba walk is the faster engine for
large colonies, but its one-time compilation per install would be most of a first demo
whose colonies take milliseconds either way; the results are the same). `jaxplan demo` also keeps JAX's persistent
compilation cache (``~/.cache/jaxplan/jax``), so later runs skip most of it. ``quick=True`` (tests) uses
a generated 14x10 warehouse, a 5 x 9 window, small colonies and a 30 s limit.

Min clearance is the smallest gap (m) over the executed steps between the robot's disc
footprint and the nearest blocked square or moving disc (negative: overlap); it is a
display quantity of this demo (`min_clearance`), from the executed positions, the blocked
squares and the episode's obstacle positions.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from jaxplan.cli.tables import text_table
from jaxplan.core.progress import ProgressBar
from jaxplan.experiments import plots

__all__ = ["DemoResult", "run_demo", "demo_table", "animate_episodes", "ROWS", "PIPELINES"]

plt = plots.plt

PIPELINES = ("iaco_dwa", "aco_dwa")
"""The compared pipelines: cui2025's IACO-DWA and its Ant System + weighted-DWA baseline."""

ROWS = ("success", "time to goal (s)", "path length (m)", "collisions", "min clearance (m)", "max curvature (1/m)",
        "energy (J)", "planning time (ms)", "wall time (s)")


@dataclass(frozen=True)
class DemoResult:
    """The demo's scene, episodes (pipeline -> `Episode`), table columns, wall times and files written."""

    scene: Any
    episodes: dict
    columns: dict
    wall_s: dict
    files: tuple[str, ...]


def _settings(quick: bool):
    """(scene, NavConfig, planner overrides, obstacle settings)."""
    from jaxplan.grid import WarehouseGenerator, demo_warehouse
    from jaxplan.nav import NavConfig

    base = NavConfig()
    engine = {"walk_backend": "jax", "update_backend": "jax"}  # no numba compilation (module docstring)
    if quick:
        scene = WarehouseGenerator(width=14, height=10, shelf_length=4, shelf_depth=2, aisle=1, cross_aisle=2)(0)
        dwa = dataclasses.replace(base.dwa, n_v=5, n_omega=9)
        return scene, dataclasses.replace(base, replan=False, max_time=30.0, dwa=dwa), \
            {"ants": 8, "iterations": 5, **engine}, {"n": 2, "speed": 0.4, "radius": 0.2}
    dwa = dataclasses.replace(base.dwa, n_v=10, n_omega=20, unroll=1)  # unroll 1: less to compile per pipeline
    return demo_warehouse(), dataclasses.replace(base, replan=False, max_time=150.0, dwa=dwa), \
        {"ants": 20, "iterations": 20, **engine}, {"n": 4, "speed": 0.5, "radius": 0.25}


def min_clearance(grid, ep, robot_radius: float, window: int = 3) -> float:
    """Smallest gap (m) between the robot's footprint and any blocked square or moving disc over the episode.

    The static part is the exact distance from each executed position to the blocked unit squares
    (outside the map counts as blocked) within ``window`` cells; farther squares are not looked at,
    so a gap above ``window`` cells is reported as ``window`` cells (numpy: no compilation).
    """
    res = float(grid.resolution)
    free = np.asarray(grid.free)
    H, W = free.shape
    pos = np.asarray(ep.trajectory[:, :2], np.float64)  # world metres
    # cell coordinates (map frame): cell (x, y) is the unit square centred on (x, y)
    p = np.asarray(grid.to_local(pos), np.float64) / res - 0.5
    off = np.stack(np.meshgrid(np.arange(-window, window + 1), np.arange(-window, window + 1)), -1).reshape(-1, 2)
    cells = np.round(p).astype(np.int64)[:, None, :] + off[None]  # [T, K, 2]
    inside = (cells[..., 0] >= 0) & (cells[..., 0] < W) & (cells[..., 1] >= 0) & (cells[..., 1] < H)
    blocked = ~inside | ~free[np.clip(cells[..., 1], 0, H - 1), np.clip(cells[..., 0], 0, W - 1)]
    d = np.hypot(*np.maximum(np.abs(p[:, None, :] - cells) - 0.5, 0.0).transpose(2, 0, 1))
    static = np.where(blocked, d, float(window)).min(axis=1) * res
    gap = float(static.min()) if static.size else np.inf
    op = np.asarray(ep.obstacle_positions, np.float64)
    if op.size:
        radii = np.asarray(ep.obstacles.radii, np.float64)
        dd = np.hypot(*(op - pos[:, None, :]).transpose(2, 0, 1)) - radii[None, :]
        gap = min(gap, float(dd.min()))
    return gap - robot_radius


def _column(grid, ep, robot_radius: float, wall: float) -> list[str]:
    m = ep.metrics
    arrival = f"{ep.time_s:.1f}" if ep.success else f"- ({ep.reason})"
    return [str(bool(ep.success)), arrival, f"{m['path_length']:.2f}", str(int(ep.collisions)),
            f"{min_clearance(grid, ep, robot_radius):.3f}", f"{m['max_curvature']:.3f}", f"{m['energy']:.1f}",
            f"{m['plan_time_s'] * 1e3:.1f}", f"{wall:.1f}"]


def demo_table(result: DemoResult) -> str:
    """The comparison as a text table (rows `ROWS`, one column per pipeline)."""
    return text_table(list(result.columns.items()), list(ROWS),
                  f"{result.scene.name}: two-level navigation among {result.episodes[PIPELINES[0]].obstacles.count} "
                  "moving discs (same start, goal, discs and seed)")


def _figure(result: DemoResult, grid, path: Path, footprint: Any = None) -> list[str]:
    from jaxplan.experiments.pictures import draw_episodes
    from jaxplan.experiments.style import robot_colour

    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 5.4), gridspec_kw={"width_ratios": [1.6, 1]},
                               constrained_layout=True)
    draw_episodes(a, grid, result.episodes, footprint=footprint,
                  title="executed trajectories (solid) over global paths (dashed)")
    for k, (name, ep) in enumerate(result.episodes.items()):
        b.plot(ep.times[:-1], ep.controls[:, 0], color=robot_colour(k, len(result.episodes)), lw=1.3,
               label=f"{name} v")
    b.set_xlabel("time (s)")
    b.set_ylabel("linear velocity v (m/s)")
    b.set_title("speed profiles")
    b.legend(fontsize=8)
    written = plots.save_figure(fig, str(path))
    plt.close(fig)
    return written


def animate_episodes(episodes: Mapping[str, Any], grid, path: str | Path, frames: int = 30, **kw: Any) -> list[str]:
    """A GIF of ``episodes`` on ``grid`` (`jaxplan.experiments.pictures.animate_episodes`, in the style of every
    picture: footprints and walkers to scale, sized to the map); returns the files written."""
    from jaxplan.experiments.pictures import animate_episodes as animate

    return animate(episodes, grid, path, frames, **kw)


def run_demo(out_dir: str | Path = "runs/demo", *, seed: int = 0, quick: bool = False, gif: bool = True,
             frames: int = 30, progress: bool = False) -> DemoResult:
    """Runs both pipelines and writes ``OUT/demo.png`` (and ``demo.gif``); see the module docstring.

    Args:
      out_dir: where the figures go (default ``runs/demo``, not tracked; see the module docstring).
      seed: the colonies' seed and the discs' draw.
      quick: the small test variant (a generated 14x10 warehouse).
      gif: write the animation.
      frames: animation frames (evenly spaced over the longer episode).
      progress: a bar over the steps (each pipeline's compile and episode, the figure, the animation) on stderr
        (`jaxplan.core.progress`: only on a terminal).
    """
    from jaxplan.nav import navigate, random_obstacles

    scene, cfg, overrides, o = _settings(quick)
    grid = scene.grid
    avoid = grid.centre(np.stack([np.asarray(scene.start), np.asarray(scene.goal)]))
    obs = random_obstacles(grid, n=o["n"], speed=o["speed"], radius=o["radius"], seed=seed, avoid=avoid,
                           avoid_radius=1.5)
    episodes, wall = {}, {}
    steps = len(PIPELINES) + 1 + int(gif)
    with ProgressBar("demo", steps, unit="steps", enabled=progress) as bar:
        for k, name in enumerate(PIPELINES):
            bar.update(k, description=f"demo: {name} (compile + run)")
            t0 = time.perf_counter()
            episodes[name] = navigate(grid, scene.start, scene.goal, pipeline=name, seed=seed, obstacles=obs,
                                      config=cfg, **overrides)
            wall[name] = time.perf_counter() - t0
        radius = float(cfg.dwa.robot.footprint.radius)
        columns = {name: _column(grid, ep, radius, wall[name]) for name, ep in episodes.items()}
        result = DemoResult(scene, episodes, columns, wall, ())
        out = Path(out_dir)
        bar.update(len(PIPELINES), description="demo: figure")
        t0 = time.perf_counter()
        files = _figure(result, grid, out / "demo.png", cfg.dwa.robot.footprint)
        wall["figure"] = time.perf_counter() - t0
        if gif:
            bar.update(len(PIPELINES) + 1, description="demo: animation")
            t0 = time.perf_counter()
            files += animate_episodes(result.episodes, grid, out / "demo.gif", frames,
                                      footprint=cfg.dwa.robot.footprint)
            wall["animation"] = time.perf_counter() - t0
        bar.update(steps, description="demo")
    return dataclasses.replace(result, files=tuple(files))
