"""One visual language for every picture jaxplan draws: the experiment figures, `jaxplan plan/navigate --out`
images and GIFs, and the demo.

The rules, each a constant or a helper here so that no figure re-invents them:

* **Start and goal**: a green circle and a red star (`START`, `GOAL`), the same in every figure; a team's other
  robots get the same shapes hollow (`TEAM_START`, `TEAM_GOAL`).
* **Walkers** (moving discs) are discs at their true radius in data units (`draw_walkers`), with the path each
  walked dashed and light (`WALKER_PATH`).
* **The robot** is its footprint to scale (`draw_footprint`: a disc, or the rectangle along the heading).
* **Zones are not walls**: walls are dark grey squares; Nav2 keep-out zones are hatched red (`KEEPOUT`), speed zones
  tinted yellow (`SPEED_ZONE`), each its own legend entry (`draw_keepout`, `draw_speed_zones`).
* **Legends outside the map** (`legend_outside`), and every line, marker and zone labelled.
* **Metres on the axes**, from the map's origin; a ROS map is drawn in its world (map) frame, y up (``y_up``).
* **GIFs** are sized to the map's aspect with the robot at least `MIN_ROBOT_PX` pixels across; a map too large
  for that is followed in a window around the robot beside an overview of the whole map (`gif_layout`), and
  every frame carries its time stamp.

Colours are matplotlib's tab palette: one robot is blue (`ROBOT`), several take `ROBOTS` (the cycle without
the walkers' orange and the start's and goal's green and red); figures comparing planners' paths keep the default
colour cycle for them.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from matplotlib.patches import Circle, PathPatch, Rectangle
from matplotlib.path import Path as MplPath
from matplotlib.transforms import Affine2D, ScaledTranslation

__all__ = [
    "START", "GOAL", "TEAM_START", "TEAM_GOAL", "ROBOT", "ROBOTS", "PLAN", "WALKER", "WALKER_PATH", "KEEPOUT",
    "SPEED_ZONE", "WALL", "WALL_LABEL", "MIN_ROBOT_PX", "robot_colour", "mark_start_goal", "draw_footprint",
    "footprint_size", "draw_walkers", "closest_approach", "real_walkers", "mask_patch", "draw_keepout",
    "draw_speed_zones", "draw_wall_key", "keepout_mask", "legend_outside", "map_figsize", "GifLayout", "gif_layout",
    "follow_window",
]

# ---------------------------------------------------------------------------------------------
# The constants

START: dict[str, Any] = {"marker": "o", "color": "tab:green", "ms": 11, "mec": "k", "mew": 1.0, "ls": "none",
                         "zorder": 6, "label": "start"}
"""`Axes.plot` keywords of the start marker (every figure)."""
GOAL: dict[str, Any] = {"marker": "*", "color": "tab:red", "ms": 16, "mec": "k", "mew": 1.0, "ls": "none",
                        "zorder": 6, "label": "goal"}
"""`Axes.plot` keywords of the goal marker (every figure)."""
TEAM_START: dict[str, Any] = {**START, "ms": 7, "mfc": "none", "mec": "tab:green", "mew": 1.5,
                              "label": "teammates' starts"}
TEAM_GOAL: dict[str, Any] = {**GOAL, "ms": 10, "mfc": "none", "mec": "tab:red", "mew": 1.2,
                             "label": "teammates' goals"}
ROBOT = "tab:blue"
"""The (single) robot's colour: its executed trajectory and its footprint."""
ROBOTS = ("tab:blue", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray")
"""Robots' colours when several share a picture: the colour cycle without the walkers' orange and the start's
green and goal's red."""
PLAN: dict[str, Any] = {"color": "0.35", "ls": "--", "lw": 1.0, "label": "global plan"}
"""The global plan a robot tracks: thin, dashed, grey (under the executed trajectory)."""
WALKER: dict[str, Any] = {"facecolor": "tab:orange", "edgecolor": "k", "lw": 0.6, "alpha": 0.75, "zorder": 4}
"""A walker's disc (`matplotlib.patches.Circle` keywords)."""
WALKER_PATH: dict[str, Any] = {"color": "tab:orange", "ls": "--", "lw": 0.8, "alpha": 0.55, "zorder": 2}
"""The path a walker walked: dashed and light, under the robot's."""
WALL = "0.25"
"""Blocked cells (walls and unknown space)."""
WALL_LABEL = "blocked (wall or unknown)"
KEEPOUT: dict[str, Any] = {"facecolor": (0.84, 0.15, 0.16, 0.18), "edgecolor": "tab:red", "hatch": "////",
                           "lw": 0.0, "zorder": 1.5}
"""A Nav2 keep-out zone: hatched red over a light red tint (drawn over the blocked cells it makes)."""
SPEED_ZONE: dict[str, Any] = {"facecolor": (1.0, 0.8, 0.0, 0.35), "edgecolor": "none", "lw": 0.0, "zorder": 0.5}
"""A speed zone: a yellow tint (darker for a lower limit when there are several)."""

MIN_ROBOT_PX = 10
"""A GIF shows the robot's footprint at least this many pixels across."""
FIT_PX = 640
"""A GIF's map (or its window onto the map) is enlarged until its longer side has this many pixels..."""
MAX_MAP_PX = 1024
"""... and is shown whole while its longer side needs at most this many; a larger one is followed in a window."""
WINDOW_PX = (640, 480)
"""The window (width, height px) onto a map too large to show whole at `MIN_ROBOT_PX`."""
GIF_DPI = 100
LEGEND_GAP_IN = 0.5
"""A legend below a map starts this far (inches) under the axes: below the tick labels and the axis label."""


# ---------------------------------------------------------------------------------------------
# Markers, robots, walkers


def robot_colour(k: int, n: int = 1) -> str:
    """Robot ``k``'s colour among ``n``: `ROBOT` for one, else `ROBOTS` in turn."""
    return ROBOT if n == 1 else ROBOTS[k % len(ROBOTS)]


def mark_start_goal(ax, start_m: Any = None, goal_m: Any = None, *, team: bool = False, label: bool = True):
    """The start (green circle) and goal (red star) at world points ``[2]`` (m); None skips one. ``team`` draws
    a teammate's (hollow); ``label=False`` leaves them out of the legend (a second panel's copy). Returns the
    lines drawn."""
    out = []
    for point, kw in ((start_m, TEAM_START if team else START), (goal_m, TEAM_GOAL if team else GOAL)):
        if point is None:
            continue
        c = np.asarray(point, np.float64)
        if c.shape != (2,):
            raise ValueError(f"{kw['label']} must be a point (x, y) in metres, got shape {c.shape}")
        (line,) = ax.plot(c[0], c[1], **{**kw, **({} if label else {"label": None})})
        out.append(line)
    return out


def draw_footprint(ax, pose: Any, footprint: Any, *, color: str = ROBOT, label: str | None = None,
                   fill: bool = True, alpha: float = 0.6, zorder: float = 5):
    """The robot's footprint at ``pose`` ``(x, y[, theta])`` (m, rad), to scale: a `jaxplan.dwa.Disc` as a
    circle of its radius, a `jaxplan.dwa.Rectangle` as its ``length x width`` rectangle along the heading
    (centred on the reference point). A plain number is a disc of that radius. Returns the patch."""
    p = np.asarray(pose, np.float64).reshape(-1)
    if p.size < 2:
        raise ValueError(f"pose must be (x, y) or (x, y, theta), got {p.size} numbers")
    kw = {"facecolor": color if fill else "none", "edgecolor": "k" if fill else color, "lw": 0.8,
          "alpha": alpha, "zorder": zorder, "label": label}
    if isinstance(footprint, (int, float, np.floating)):
        patch = Circle((p[0], p[1]), float(footprint), **kw)
    elif hasattr(footprint, "length") and hasattr(footprint, "width"):
        length, width = float(footprint.length), float(footprint.width)
        theta = float(p[2]) if p.size > 2 else 0.0
        patch = Rectangle((-length / 2, -width / 2), length, width, **kw)
        patch.set_transform(Affine2D().rotate(theta).translate(p[0], p[1]) + ax.transData)
    elif hasattr(footprint, "radius"):
        patch = Circle((p[0], p[1]), float(footprint.radius), **kw)
    else:
        raise ValueError(f"footprint must be a jaxplan.dwa.Disc, Rectangle or a radius in metres, got {footprint!r}")
    ax.add_patch(patch)
    return patch


def footprint_size(footprint: Any) -> float:
    """The footprint's smallest extent (m): a disc's diameter, a rectangle's width (what `MIN_ROBOT_PX` bounds)."""
    if isinstance(footprint, (int, float, np.floating)):
        return 2.0 * float(footprint)
    if hasattr(footprint, "width"):
        return float(footprint.width)
    return 2.0 * float(footprint.radius)


def real_walkers(radii: Any) -> np.ndarray:
    """Indices of the walkers that exist: padding slots (`jaxplan.nav.pad_obstacles`) have radius 0."""
    return np.flatnonzero(np.asarray(radii, np.float64) > 0)


def draw_walkers(ax, positions: Any, radii: Any, at: Any = None, *, paths: bool = True,
                 disc_label: str | None = "walkers (to scale)", path_label: str | None = "walkers' paths"):
    """Walkers as discs of their true radius, with the paths they walked.

    Args:
      ax: the map axes.
      positions: ``[T, M, 2]`` the walkers' centres (m) at each step (`Episode.obstacle_positions`).
      radii: ``[M]`` their radii (m); radius-0 padding slots are skipped.
      at: the step to draw the discs at: one int for all, ``int[M]`` one per walker, or None (no discs).
      paths: draw each walker's whole path, dashed and light.
      disc_label, path_label: legend text (once per kind).

    Returns:
      ``(discs, lines)``: the `Circle` patches (radius = the walker's, in data units) and path lines.
    """
    pos = np.asarray(positions, np.float64)
    r = np.asarray(radii, np.float64)
    if pos.ndim != 3 or pos.shape[-1] != 2 or pos.shape[1] != r.shape[0]:
        raise ValueError(f"positions must be [T, M, 2] with M = len(radii) = {r.shape[0]}, got {pos.shape}")
    idx = real_walkers(r)
    lines, discs = [], []
    if paths:
        for k, j in enumerate(idx):
            (ln,) = ax.plot(pos[:, j, 0], pos[:, j, 1], **{**WALKER_PATH, "label": path_label if k == 0 else None})
            lines.append(ln)
    if at is not None:
        steps = np.broadcast_to(np.asarray(at, np.int64), r.shape)
        for k, j in enumerate(idx):
            s = int(np.clip(steps[j], 0, len(pos) - 1))
            disc = Circle(tuple(pos[s, j]), float(r[j]), **{**WALKER, "label": disc_label if k == 0 else None})
            ax.add_patch(disc)
            discs.append(disc)
    return discs, lines


def closest_approach(robot_xy: Any, positions: Any) -> np.ndarray:
    """``int[M]``: for each walker, the step at which the robot (``[T, 2]`` m) was closest to it (``[T', M, 2]``;
    the shorter of the two sets the steps compared)."""
    xy = np.asarray(robot_xy, np.float64)[:, :2]
    pos = np.asarray(positions, np.float64)
    n = min(len(xy), len(pos))
    d = np.hypot(*(pos[:n] - xy[:n, None, :]).transpose(2, 0, 1))  # [T, M]
    return d.argmin(axis=0)


# ---------------------------------------------------------------------------------------------
# Zones


def _runs(mask: np.ndarray) -> list[tuple[int, int, int]]:
    """``(row, first column, length)`` of each horizontal run of True cells: few rectangles for a zone."""
    out = []
    m = np.asarray(mask, bool)
    padded = np.zeros((m.shape[0], m.shape[1] + 2), bool)
    padded[:, 1:-1] = m
    d = np.diff(padded.astype(np.int8), axis=1)
    for y in np.flatnonzero(m.any(axis=1)):
        starts, ends = np.flatnonzero(d[y] == 1), np.flatnonzero(d[y] == -1)
        out += [(int(y), int(a), int(b - a)) for a, b in zip(starts, ends, strict=True)]
    return out


def mask_patch(mask: Any, grid: Any, **kw: Any) -> PathPatch | None:
    """One `PathPatch` covering the cells of ``mask`` ``bool[H, W]`` in world metres (cell ``(x, y)`` spans
    ``origin + [x, x + 1] · res × [y, y + 1] · res``), or None when the mask is empty. One patch: one legend
    entry and one hatch pattern, however many cells."""
    m = np.asarray(mask, bool)
    if m.shape != tuple(grid.shape):
        raise ValueError(f"mask must have the map's shape {tuple(grid.shape)}, got {m.shape}")
    runs = _runs(m)
    if not runs:
        return None
    res = float(grid.resolution)
    x0, y0 = (float(v) for v in grid.origin)
    verts, codes = [], []
    for y, x, n in runs:
        a, b, c, d = x0 + x * res, x0 + (x + n) * res, y0 + y * res, y0 + (y + 1) * res
        verts += [(a, c), (b, c), (b, d), (a, d), (a, c)]
        codes += [MplPath.MOVETO, MplPath.LINETO, MplPath.LINETO, MplPath.LINETO, MplPath.CLOSEPOLY]
    return PathPatch(MplPath(verts, codes), **kw)


def draw_keepout(ax, grid: Any, keepout: Any, label: str = "keep-out zone (Nav2 mask)"):
    """Hatches the keep-out cells ``bool[H, W]`` (`keepout_mask`); returns the patch or None."""
    patch = mask_patch(keepout, grid, **KEEPOUT, label=label)
    if patch is not None:
        ax.add_patch(patch)
    return patch


def draw_speed_zones(ax, grid: Any, max_levels: int = 4) -> list:
    """Tints the free cells with a speed limit below the top speed (`GridMap.speed_limit`), one patch and legend
    entry per limit (``speed zone: 80 % of top speed``); more than ``max_levels`` distinct limits are grouped
    into ``max_levels`` bands (labelled with their range). Returns the patches."""
    limit = getattr(grid, "speed_limit", None)
    if limit is None:
        return []
    lim = np.asarray(limit, np.float64)
    slow = (lim < 1.0) & np.asarray(grid.free)
    if not slow.any():
        return []
    values = np.unique(lim[slow])
    if len(values) > max_levels:
        edges = np.quantile(values, np.linspace(0, 1, max_levels + 1))
        bands = [(edges[i], edges[i + 1]) for i in range(max_levels)]
    else:
        bands = [(v, v) for v in values]
    patches = []
    for k, (lo, hi) in enumerate(bands):
        last = k == len(bands) - 1
        cells = slow & (lim >= lo) & ((lim <= hi) if (last or lo == hi) else (lim < hi))
        # a lower limit is a deeper tint: the slowest zone reads as the most cautious
        alpha = 0.25 + 0.35 * (1.0 - (k / max(len(bands) - 1, 1))) if len(bands) > 1 else SPEED_ZONE["facecolor"][3]
        text = f"{100 * lo:.0f} %" if lo == hi else f"{100 * lo:.0f}-{100 * hi:.0f} %"
        patch = mask_patch(cells, grid, **{**SPEED_ZONE, "facecolor": (*SPEED_ZONE["facecolor"][:3], alpha)},
                           label=f"speed zone: {text} of top speed")
        if patch is not None:
            ax.add_patch(patch)
            patches.append(patch)
    return patches


def draw_wall_key(ax, grid: Any):
    """A legend entry for the blocked cells (an image has none): added when zones are drawn beside walls, so the
    legend tells the three apart. Returns the proxy patch: of zero size at the map's origin, so it neither shows
    nor moves the axes' limits."""
    x0, y0 = (float(v) for v in grid.origin)
    proxy = Rectangle((x0, y0), 0.0, 0.0, facecolor=WALL, edgecolor="none", label=WALL_LABEL)
    ax.add_patch(proxy)
    return proxy


def keepout_mask(map_path: str | os.PathLike, grid: Any, options: Mapping[str, Any]) -> np.ndarray | None:
    """The cells a Nav2 keep-out mask blocked on ``grid`` (a ROS map loaded with ``options``' ``keepout``): the
    map loaded again without it, at ``grid``'s resolution, minus ``grid``'s free cells. None without a mask.

    `jaxplan.grid.load_ros_map` folds the mask into ``free`` (a planner needs nothing else); a figure needs it
    apart, to draw keep-out zones unlike walls."""
    if not options or options.get("keepout") is None:
        return None
    from jaxplan.grid import load_map, resample

    rest = {k: v for k, v in options.items() if k in ("unknown", "speed_filter", "top_speed") and v is not None}
    bare = load_map(map_path, **rest)
    if tuple(bare.shape) != tuple(grid.shape) or not math.isclose(float(bare.resolution), float(grid.resolution)):
        bare = resample(bare, float(grid.resolution))
    if tuple(bare.shape) != tuple(grid.shape):
        raise ValueError(f"{map_path}: the map without its keep-out mask is {bare.shape}, not {tuple(grid.shape)}")
    return np.asarray(bare.free) & ~np.asarray(grid.free)


# ---------------------------------------------------------------------------------------------
# Legends


def map_figsize(grid: Any, extra_h: float = 1.4) -> tuple[float, float]:
    """Inches for a map figure with its legend below: the map's aspect, wide maps wider (about 12 m per inch
    between 6 and 13 inches), tall ones capped at 10 inches of map."""
    H, W = grid.shape
    wm, hm = W * float(grid.resolution), H * float(grid.resolution)
    w = min(13.0, max(6.0, wm / 12.0))
    h = w * hm / wm
    if h > 10.0:
        w, h = w * 10.0 / h, 10.0
    return w, h + extra_h




def legend_outside(ax, ncol: int = 2, fontsize: float = 8, where: str = "below"):
    """Puts ``ax``'s legend (every labelled line, marker and patch) outside the axes: ``"below"`` (clear of a
    map and of its colour bar) or ``"right"``. Returns the legend, or None when nothing is labelled."""
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        return None
    if where == "right":
        return ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), ncol=1, fontsize=fontsize,
                         borderaxespad=0.0, frameon=False)
    if where != "below":
        raise ValueError(f"where must be 'below' or 'right', got {where!r}")
    # A fixed distance below the axes (clear of tick and axis labels), not a fraction of its height: a tall
    # map's legend would float far below it.
    below = ax.transAxes + ScaledTranslation(0.0, -LEGEND_GAP_IN, ax.figure.dpi_scale_trans)
    return ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below,
                     ncol=ncol, fontsize=fontsize, borderaxespad=0.0, frameon=False)


# ---------------------------------------------------------------------------------------------
# GIF layout


@dataclass(frozen=True)
class GifLayout:
    """How a GIF shows a map.

    Attributes:
      px_per_m: the map axes' scale (pixels per metre), the same along x and y.
      view_m: ``(width, height)`` (m) of the map area shown in each frame: the whole map, or the window that
        follows the robot (``cropped``).
      cropped: the map is too large to show whole with the robot `MIN_ROBOT_PX` across: a window follows the
        robot and an overview of the whole map sits beside it.
      robot_px: the robot footprint's smallest extent in pixels.
    """

    px_per_m: float
    view_m: tuple[float, float]
    cropped: bool
    robot_px: float

    @property
    def view_px(self) -> tuple[int, int]:
        """``(width, height)`` pixels of the map axes."""
        return (round(self.view_m[0] * self.px_per_m), round(self.view_m[1] * self.px_per_m))


def gif_layout(map_m: tuple[float, float], robot_m: float, *, min_robot_px: float = MIN_ROBOT_PX,
               fit_px: float = FIT_PX, max_map_px: float = MAX_MAP_PX,
               window_px: tuple[int, int] = WINDOW_PX) -> GifLayout:
    """The scale and view of a GIF of a ``map_m`` = ``(width, height)`` m map with a robot ``robot_m`` m across.

    The rule: the scale is the larger of (a) the map's longer side at ``fit_px`` pixels and (b) the robot at
    ``min_robot_px``. If the whole map then fits in ``max_map_px`` on its longer side, it is shown whole (the
    frame has the map's aspect). Otherwise a ``window_px`` window at the robot's scale follows the robot (clamped
    to the map; a map narrower than the window in one direction is shown whole in that direction).

    Raises:
      ValueError: a non-positive map size or robot size.
    """
    w, h = (float(v) for v in map_m)
    if not (w > 0 and h > 0):
        raise ValueError(f"map size must be positive (m), got {map_m}")
    if not robot_m > 0:
        raise ValueError(f"robot size must be positive (m), got {robot_m}")
    need = min_robot_px / robot_m
    scale = max(fit_px / max(w, h), need)
    if max(w, h) * scale <= max_map_px:
        return GifLayout(scale, (w, h), False, robot_m * scale)
    view = (min(w, window_px[0] / need), min(h, window_px[1] / need))
    return GifLayout(need, view, True, robot_m * need)


def follow_window(centre: Any, view_m: tuple[float, float], bounds: tuple[float, float, float, float]):
    """``(x0, x1, y0, y1)`` of a ``view_m`` window centred on ``centre`` (m), shifted to stay inside ``bounds``
    ``(xmin, xmax, ymin, ymax)``."""
    cx, cy = (float(v) for v in np.asarray(centre, np.float64)[:2])
    xmin, xmax, ymin, ymax = bounds
    vw, vh = view_m
    x0 = min(max(cx - vw / 2, xmin), xmax - vw)
    y0 = min(max(cy - vh / 2, ymin), ymax - vh)
    return x0, x0 + vw, y0, y0 + vh
