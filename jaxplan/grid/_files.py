"""`load_map` and `save_map`: one entry point for every map file format jaxplan reads, chosen by the suffix.

* ``.yaml`` / ``.yml``: a ROS ``map_server`` map (`jaxplan.grid.load_ros_map`, PGM or PNG image);
* anything else: a MovingAI ``.map`` file (`jaxplan.grid.load_movingai_map`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from jaxplan.grid._gridmap import GridMap
from jaxplan.grid._movingai import load_movingai_map, save_movingai_map
from jaxplan.grid._resample import resample
from jaxplan.grid._ros import load_ros_map, save_ros_map

__all__ = ["load_map", "save_map", "is_ros_map"]


def is_ros_map(path: str | os.PathLike) -> bool:
    """True if ``path`` names a ROS map (its YAML file)."""
    return Path(path).suffix.lower() in (".yaml", ".yml")


def load_map(path: str | os.PathLike, resolution: float | None = None, **ros: Any) -> GridMap:
    """Reads a map file: a ROS map's YAML (``.yaml``/``.yml``) or a MovingAI ``.map``.

    Args:
      path: the file.
      resolution: metres per cell. A MovingAI map is unitless: its cells get this size (1.0 if None).
        A ROS map has its own: with a number, the map is `resample`-d to it (a new cell is blocked if any
        cell it overlaps is).
      **ros: for ROS maps only — ``unknown``, ``keepout``, ``speed``, ``speed_filter``, ``top_speed``
        (`jaxplan.grid.load_ros_map`).

    Returns:
      `GridMap`.
    """
    if is_ros_map(path):
        grid = load_ros_map(path, **ros)
        return grid if resolution is None else resample(grid, resolution)
    if ros:
        raise ValueError(f"{path}: {', '.join(sorted(ros))} apply to ROS maps (.yaml) only, not MovingAI .map files")
    return load_movingai_map(path, resolution=1.0 if resolution is None else resolution)


def save_map(grid: GridMap, path: str | os.PathLike) -> None:
    """Writes ``grid``: as a ROS map (YAML + PGM, and a speed mask if the grid has a speed limit) for a
    ``.yaml``/``.yml`` path, else as a MovingAI ``.map`` (occupancy only)."""
    if is_ros_map(path):
        save_ros_map(grid, path)
    else:
        save_movingai_map(grid, path)
