"""The files `jaxplan plan --out` and `jaxplan navigate --out` write, chosen by suffix.

One plan (`plan_record`, `write_plan`):
  * ``.json``: the map (size, resolution, origin), start and goal, the planner with every parameter (defaults and
    ``--set`` overrides), the seed, the result (success, length m, cost, turns, history, time), the path in cells
    and in world metres (cell centres, the map's origin included: `GridMap.centre`), the smoothed path when asked,
    the path metrics (docs/guide/smoothing-and-metrics.md), why a failed plan failed, and the provenance record
    (`jaxplan.core.provenance`:
    jaxplan version, git revision, library versions, machine). Non-finite numbers (the ``inf`` length of a failed
    plan) are ``null``.
  * ``.csv``: one row per path point: ``step, x, y`` (cells) and ``x_m, y_m`` (world metres); the smoothed polyline
    when smoothing was asked, else the grid path.
  * ``.png`` (or ``.svg``, ``.pdf``): the map with the path (and the smoothed path) over it, start and goal.

One episode (`write_episode`): ``.json`` (`jaxplan.nav.Episode.to_dict` with the run's settings and provenance),
``.gif`` (the robot's trail among the walkers; needs Pillow, which matplotlib installs) or ``.png`` (the trail
over the map).

Images follow `jaxplan.experiments.style`: start green circle, goal red star, legend outside the map, a ROS map
in its world frame (y up) with its keep-out zones hatched and its speed zones tinted (not drawn as walls); an
episode's picture adds the walkers' paths and discs and the robot's footprint to scale
(`jaxplan.experiments.pictures`).
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from jaxplan.core.export import json_text, plain
from jaxplan.core.io import atomic_write

__all__ = ["PLAN_SUFFIXES", "EPISODE_SUFFIXES", "plan_record", "write_plan", "write_episode"]

PLAN_SUFFIXES = (".json", ".csv", ".png", ".svg", ".pdf")
EPISODE_SUFFIXES = (".json", ".gif", ".png", ".svg", ".pdf")


def check_suffix(path: str | os.PathLike, suffixes: tuple[str, ...], what: str) -> Path:
    """``path`` as a `Path`, or ``ValueError`` naming the suffixes ``what`` writes."""
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"{what} --out {p}: the suffix decides the format; use one of {', '.join(suffixes)}")
    return p


def plan_record(*, map_path: str, grid: Any, start, goal, planner: str, seed: int, params: Mapping[str, Any],
                overrides: Mapping[str, Any], result: Any, metrics: Mapping[str, Any] | None,
                smoothed: Any = None, smooth_method: str | None = None, failure: str | None = None,
                map_options: Mapping[str, Any] | None = None) -> dict:
    """The ``.json`` record of one plan (see the module docstring)."""
    from jaxplan.core.provenance import provenance

    path = np.asarray(result.path).reshape(-1, 2)
    info = {k: v for k, v in result.info.items() if k != "tau"}
    rec = {
        "map": {"path": str(map_path), "height": int(grid.shape[0]), "width": int(grid.shape[1]),
                "resolution_m": float(grid.resolution), "origin_m": [float(v) for v in grid.origin],
                **({"options": plain(dict(map_options))} if map_options else {})},
        "start": [int(v) for v in start], "goal": [int(v) for v in goal],
        "planner": planner, "seed": int(seed), "parameters": plain(dict(params)), "overrides": plain(dict(overrides)),
        "success": bool(result.success), "length_m": float(result.length), "cost": float(result.cost),
        "turns": int(result.turns), "iterations": int(len(result.history)), "history": plain(result.history),
        "time_s": float(result.time_s), "info": plain(info),
        "path_cells": path.tolist(), "path_m": grid.centre(path).tolist(),
        "metrics": plain(dict(metrics)) if metrics is not None else None,
    }
    if smoothed is not None:
        pts = np.asarray(smoothed.points).reshape(-1, 2)
        rec["smoothed"] = {"method": smooth_method, "points_cells": pts.tolist(),
                           "points_m": grid.centre(pts).tolist(), "removed": int(smoothed.removed),
                           "fallbacks": int(smoothed.fallbacks)}
    if failure is not None:
        rec["failure"] = failure
    rec["provenance"] = provenance(devices=False)
    return rec


def _csv_points(points: np.ndarray, grid: Any) -> bytes:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["step", "x", "y", "x_m", "y_m"])
    m = grid.centre(points)
    for k, (p, q) in enumerate(zip(points, m, strict=True)):
        w.writerow([k, *(repr(float(v)) if points.dtype.kind == "f" else int(v) for v in p), *map(repr, q.tolist())])
    return buf.getvalue().encode()


def _map_view(map_path: str, options: Mapping[str, Any] | None, grid: Any) -> dict:
    """`plot_map`'s ``keepout`` and ``y_up`` for a map file: a ROS map in its world frame with its keep-out cells
    apart from its walls (`jaxplan.experiments.style.keepout_mask`); a MovingAI map as before."""
    from jaxplan.experiments.style import keepout_mask
    from jaxplan.grid import is_ros_map

    if not is_ros_map(map_path):
        return {"keepout": None, "y_up": False}
    return {"keepout": keepout_mask(map_path, grid, options or {}), "y_up": True}


def write_plan(out: str | os.PathLike, record: dict, grid: Any, result: Any, smoothed: Any = None) -> Path:
    """Writes one plan to ``out`` (``.json``, ``.csv`` or an image); returns the path."""
    p = check_suffix(out, PLAN_SUFFIXES, "jaxplan plan")
    p.parent.mkdir(parents=True, exist_ok=True)
    suffix = p.suffix.lower()
    if suffix == ".json":
        atomic_write(p, json_text(record).encode())
    elif suffix == ".csv":
        pts = np.asarray(smoothed.points if smoothed is not None else result.path).reshape(-1, 2)
        atomic_write(p, _csv_points(pts, grid))
    else:
        from jaxplan.experiments import plots, style

        start, goal = np.asarray(record["start"]), np.asarray(record["goal"])
        paths, labels = [np.asarray(result.path).reshape(-1, 2)], [record["planner"]]
        if smoothed is not None:
            paths.append(np.asarray(smoothed.points).reshape(-1, 2))
            labels.append(f"smoothed ({record['smoothed']['method']})")
        head = (f"{record['planner']} on {Path(record['map']['path']).name}: "
                + (f"{result.length:.2f} m, {result.turns} turns" if result.success else "no path"))
        fig, ax = plots.plt.subplots(figsize=style.map_figsize(grid), constrained_layout=True)
        plots.plot_map(ax, grid, colorbar=False, **_map_view(record["map"]["path"], record["map"].get("options"),
                                                             grid))
        plots.plot_paths(ax, grid, paths, labels, start=start, goal=goal)
        plots.legend_outside(ax, ncol=3)
        ax.set_title(head, fontsize=9)
        plots.save_figure(fig, str(p))
        plots.plt.close(fig)
    return p


def write_episode(out: str | os.PathLike, episode: Any, grid: Any, record: Mapping[str, Any],
                  frames: int = 40, footprint: Any = None) -> Path:
    """Writes one navigation episode to ``out`` (``.json``, ``.gif`` or an image); returns the path.

    ``footprint``: the robot's, drawn to scale (default: `jaxplan.nav.NavConfig`'s robot, which `jaxplan
    navigate` drives).

    Raises:
      ImportError: ``.gif`` without Pillow.
    """
    p = check_suffix(out, EPISODE_SUFFIXES, "jaxplan navigate")
    p.parent.mkdir(parents=True, exist_ok=True)
    suffix = p.suffix.lower()
    label = str(record.get("pipeline", "robot"))
    if suffix == ".json":
        from jaxplan.core.provenance import provenance

        atomic_write(p, json_text({**record, "episode": episode.to_dict(),
                                   "provenance": provenance(devices=False)}).encode())
    elif suffix == ".gif":
        import importlib.util

        if importlib.util.find_spec("PIL") is None:
            raise ImportError("jaxplan navigate --out *.gif needs Pillow (matplotlib's GIF writer): pip install "
                              "pillow; or write .json or .png")
        from jaxplan.experiments.pictures import animate_episodes

        animate_episodes({label: episode}, grid, p, frames, footprint=footprint,
                         **_map_view(str(record.get("map", "")), record.get("map_options"), grid))
    else:
        from jaxplan.experiments.pictures import episode_figure
        from jaxplan.experiments.plots import plt, save_figure

        head = (f"{label} on {Path(str(record.get('map', ''))).name}: {episode.reason}, {episode.time_s:.1f} s, "
                f"{episode.collisions} collisions")
        fig = episode_figure(grid, {label: episode}, footprint=footprint, title=head,
                             **_map_view(str(record.get("map", "")), record.get("map_options"), grid))
        fig.axes[0].title.set_fontsize(9)
        save_figure(fig, str(p))
        plt.close(fig)
    return p
