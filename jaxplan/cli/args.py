"""Command-line arguments into library values: ``--set`` literals, a planner's checked parameters, the map and
its ROS masks, a start or goal given as a cell or in metres.

Standard library only at the top (the parser and ``--help`` import this module); each function imports what it
needs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Sequence

__all__ = ["literal", "parse_sets", "planner_params", "load_map_args", "check_file_arg", "endpoint"]


def literal(text: str):
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


def parse_sets(items: Sequence[str] | None) -> dict:
    """``--set KEY=VALUE`` options as a dict (a later key wins); ``ValueError`` for an item without ``=``."""
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set {item!r}: expected KEY=VALUE (e.g. --set ants=64 --set heuristic=geodesic)")
        out[key.strip()] = literal(text)
    return out


def planner_params(planner: str, overrides: dict, options: dict | None = None) -> dict:
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


def load_map_args(args: argparse.Namespace):
    """The map of ``plan``/``navigate`` and the ROS options given (for the output record)."""
    from jaxplan.grid import load_map

    ros = {k: v for k, v in (("keepout", args.keepout), ("speed", args.speed_mask), ("unknown", args.unknown))
           if v is not None}
    for path in (args.map, args.keepout, args.speed_mask):
        check_file_arg(path)
    return load_map(args.map, resolution=args.resolution, **ros), ros


def check_file_arg(path: str | None) -> None:
    """A missing map file named relative to the data folder (``ros/warehouse.yaml``, as a config writes it) fails
    saying where it is: paths on the command line are relative to the working folder (docs/decisions.md)."""
    if path is None or Path(path).exists() or Path(path).is_absolute():
        return
    from jaxplan.experiments.config import default_data_dir

    there = default_data_dir() / path
    if there.is_file():
        raise FileNotFoundError(f"map file not found: {path} (a path on the command line is relative to the working "
                                f"folder, not to the data folder as in a config: give {there})")


def endpoint(args: argparse.Namespace, grid, which: str) -> tuple[int, int]:
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
