"""Scenario generators of moving obstacles: routes on a map, as `MovingObstacles` (`jaxplan.nav._moving`).

The generators run on the host, with a numpy RNG from an integer ``seed`` (same seed, same arrays). They
build routes that a disc of the obstacle's radius travels without touching a blocked
cell (clearance >= radius, as `jaxplan.grid._collision.segment_free` decides it),
verified with an exact segment-to-square test on the host (`_Blocked`, a numpy twin
of that test that needs no compilation per map and path length):
`random_obstacles` (random walkers along A* routes), `crossing_traffic` (traffic
crossing a robot's planned path) and `head_on` (chu2024, Figure 11).

Example:
  >>> import jaxplan as jp
  >>> from jaxplan.nav import discs_at, random_obstacles
  >>> scene = jp.demo_warehouse()
  >>> obs = random_obstacles(scene, n=5, speed=1.0, radius=0.25, seed=0)
  >>> discs_at(obs, 2.0).positions.shape
  (5, 2)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from jaxplan.core.geometry import segment_square_distance_np
from jaxplan.core.names import did_you_mean
from jaxplan.grid import TOUCH, GridMap, clearance_field, grid_from_array
from jaxplan.nav._moving import MovingObstacles, moving_obstacles, no_obstacles, per_obstacle
from jaxplan.search import astar

__all__ = ["BEHAVIORS", "random_obstacles", "crossing_traffic", "head_on"]


def _as_grid(grid: Any) -> GridMap:
    """A `GridMap`, or a `Scene` (``jp.demo_warehouse()``, generators) whose ``.grid`` is one."""
    if isinstance(grid, GridMap):
        return grid
    inner = getattr(grid, "grid", None)
    if isinstance(inner, GridMap):
        return inner
    raise TypeError(f"expected a GridMap or a Scene, got {type(grid).__name__}")


def _rng(seed: Any) -> np.random.Generator:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    return np.random.default_rng(int(seed))


def _np_position(route: np.ndarray, s: float, loop: bool) -> np.ndarray:
    """Host reference of the model: the point at arc length ``s`` of one route (f64)."""
    pts = np.concatenate([route, route[:1]]) if loop else np.concatenate([route, route[-2::-1]])
    seg = np.hypot(*np.diff(pts, axis=0).T)
    total = seg.sum()
    if total <= 0:
        return route[0].copy()
    u = float(np.mod(s, total))
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    i = int(np.clip(np.searchsorted(cum, u, side="right") - 1, 0, len(seg) - 1))
    f = 0.0 if seg[i] == 0 else min((u - cum[i]) / seg[i], 1.0)
    return pts[i] + f * (pts[i + 1] - pts[i])


def _dedupe(cells: np.ndarray) -> np.ndarray:
    keep = np.ones(len(cells), bool)
    keep[1:] = np.any(cells[1:] != cells[:-1], axis=1)
    return cells[keep]


class _Blocked:
    """Blocked unit squares of a map for exact host-side segment tests (cell coordinates).

    The generators run once per scenario on the host, where compiling the JAX segment
    walk for every map shape and path length would cost seconds per call; this numpy
    twin of `jaxplan.grid.segment_clearance` is exact too (the numpy twin of the same
    segment-to-square distance, `jaxplan.core.geometry`, over every blocked square near the
    segment) and needs no compilation. Outside the map counts as blocked.
    """

    def __init__(self, free: np.ndarray):
        self.free = np.asarray(free, bool)
        self.H, self.W = self.free.shape

    def clearance(self, p: np.ndarray, q: np.ndarray, reach: float) -> float:
        """Distance (cells) from segment ``p``–``q`` to the nearest blocked square, exact below ``reach``.

        Squares farther than ``reach`` are not examined (the answer is then ``>= reach``,
        reported as ``inf``).
        """
        w = reach + 1.0  # a square within `reach` of the segment has its centre within reach + 0.5
        x0, y0 = np.floor(np.minimum(p, q) - w).astype(int)
        x1, y1 = np.ceil(np.maximum(p, q) + w).astype(int)
        xs, ys = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1), indexing="xy")
        inside = (xs >= 0) & (xs < self.W) & (ys >= 0) & (ys < self.H)
        blocked = ~inside
        blocked[inside] = ~self.free[ys[inside], xs[inside]]
        c = np.stack([xs[blocked], ys[blocked]], axis=-1).astype(np.float64)
        if len(c) == 0:
            return float("inf")
        return float(segment_square_distance_np(np.asarray(p, np.float64), np.asarray(q, np.float64), c).min())

    def free_for(self, p: np.ndarray, q: np.ndarray, r: float, margin: float = 0.0) -> bool:
        """`segment_free`'s rule: clearance >= max(r, TOUCH) (+ ``margin`` cells)."""
        thr = max(r, TOUCH) + margin
        return self.clearance(p, q, thr + 1.0) >= thr


_SHORTCUT_MARGIN = 1e-4  # cells: shortcuts keep this much beyond the radius, so float32 checks agree


def _pruned_route(blocked: _Blocked, cells: np.ndarray, r_cells: float) -> np.ndarray | None:
    """Line-of-sight pruning of a cell path for a disc of ``r_cells`` (the rule of `los_prune`).

    From the anchor (last kept vertex), vertex ``j`` is dropped while the segment from the
    anchor to vertex ``j + 1`` is free. Returns the kept vertices (cell coordinates), or
    None if some segment of the result is not free (exact test).
    """
    pts = cells.astype(np.float64)
    kept = [pts[0]]
    for j in range(1, len(pts) - 1):
        if not blocked.free_for(kept[-1], pts[j + 1], r_cells, _SHORTCUT_MARGIN):
            kept.append(pts[j])
    if len(pts) > 1:
        kept.append(pts[-1])
    route = np.stack(kept)
    ok = all(blocked.free_for(a, b, r_cells) for a, b in zip(route[:-1], route[1:], strict=True))
    return route if ok else None


def _start_pool(i: int, ok: np.ndarray, centres: np.ndarray, av: np.ndarray, avoid_radius: float, r: float,
                placed: list) -> np.ndarray:
    """``int[P, 2]`` cells ``(x, y)`` where obstacle ``i`` (radius ``r`` m) may start: free for the disc
    (``ok [H, W]``), ``avoid_radius + r`` from every ``avoid`` point, and clear of the discs placed
    before it (``placed``: (point, radius) pairs) when the map has room for that."""
    start_ok = ok.copy()
    for p in av:
        start_ok &= np.hypot(*(centres - p).transpose(2, 0, 1)) >= avoid_radius + r
    if not start_ok.any():
        raise ValueError(
            f"obstacle {i}: the map has no free cell where a disc of radius {r} m can start "
            f"{avoid_radius} m from the avoid points" if len(av) else
            f"obstacle {i}: the map has no free cell with {r} m of clearance for a disc of that radius")
    preferred = start_ok.copy()
    for q, rq in placed:
        preferred &= np.hypot(*(centres - q).transpose(2, 0, 1)) >= r + rq
    return np.argwhere(preferred if preferred.any() else start_ok)[:, ::-1]  # (x, y)


def _random_route(rng: np.random.Generator, pool: np.ndarray, labels: np.ndarray, inflated: GridMap,
                  blocked: _Blocked, waypoints: int, loop: bool, r: float, res: float,
                  tries: int) -> np.ndarray | None:
    """A route ``f64[k, 2]`` (m) through ``waypoints`` random cells of one connected region of the inflated
    map, its first drawn from ``pool``, joined by LOS-pruned A* legs; None if ``tries`` draws all failed
    the exact check."""
    for _ in range(tries):
        first = pool[rng.integers(len(pool))]
        region = np.argwhere(labels == labels[first[1], first[0]])[:, ::-1]
        stops = [first] + [region[rng.integers(len(region))] for _ in range(waypoints - 1)]
        if loop and waypoints > 1:
            stops.append(first)
        # Each leg is pruned on its own, so the random stops stay vertices: pruning a
        # whole loop would cut from the first cell straight back to itself.
        pieces, ok_route = [first[None].astype(np.float64)], True
        for a, b in zip(stops[:-1], stops[1:], strict=True):
            if np.array_equal(a, b):
                continue
            leg = _pruned_route(blocked, np.asarray(astar(inflated, a, b).path, np.int64), r / res)
            if leg is None:
                ok_route = False
                break
            pieces.append(leg[1:])
        if ok_route:
            return (_dedupe(np.concatenate(pieces)) + 0.5) * res
    return None


def _phase(rng: np.random.Generator, route: np.ndarray, loop: bool, av: np.ndarray, avoid_radius: float,
           r: float, placed: list) -> float:
    """The offset (m of arc length) of a route's disc at ``t = 0``: random phases first; offset 0 (the first
    vertex, drawn among the allowed starts) always honours ``avoid``. Clear of the earlier discs if
    possible, else just ``avoid``."""
    seg = np.hypot(*np.diff(route, axis=0).T).sum()
    period = seg if loop else 2.0 * seg
    candidates = list(rng.uniform(0.0, period, size=16)) if period > 0 else []
    candidates.append(0.0)
    for strict in (True, False):
        for c in candidates:
            p = _np_position(route, c, loop)
            if len(av) and np.hypot(*(av - p).T).min() < avoid_radius + r + 1e-5:  # float32 slack
                continue
            if strict and any(np.hypot(*(q - p)) < r + rq for q, rq in placed):
                continue
            return float(c)
    return 0.0


BEHAVIORS = ("blind", "social")
"""How random walkers move: ``"blind"`` on their routes by time, regardless of anything (the walkers of the first
release); ``"social"`` along the same routes but avoiding the robots, each other and the walls with the social force
model (Helbing & Molnár 1995; `jaxplan.nav._social`)."""


def random_obstacles(grid: Any, n: int = 5, speed: Any = 1.0, radius: Any = 0.25, seed: int = 0, *,
                     waypoints: int = 4, avoid: ArrayLike | None = None, avoid_radius: float = 1.0,
                     loop: bool = False, tries: int = 20, behavior: str = "blind") -> MovingObstacles:
    """Random walkers: discs bouncing (or looping) along short polylines through random free points.

    Each route joins ``waypoints`` random cells by exact A* paths (8-connected, no corner
    cutting) on the map inflated for the disc (cells whose centre clearance is at least
    ``radius``), LOS-pruned with the exact segment test at that radius, and converted to
    world metres (cell centres). A looping route returns to its first cell along A*
    paths, so its closing segment has zero length and never cuts through a wall. All of
    an obstacle's cells lie in one connected region of the inflated map. Phases are
    uniform over the period (random positions at ``t = 0``).

    Starts (positions at ``t = 0``) keep ``avoid_radius + radius`` from every ``avoid``
    point; they also keep clear of the discs placed before them when the map has room
    (a preference, not a guarantee). Obstacles do not avoid each other later on.

    Args:
      grid: a `GridMap`, or a `Scene` such as ``jp.demo_warehouse()``.
      n: number of obstacles (>= 0).
      speed: m/s, >= 0: a scalar or ``[n]`` (li2026 runs 1.0 and 1.5).
      radius: disc radius (m), >= 0: a scalar or ``[n]``.
      seed: integer seed of the numpy RNG (same seed, same obstacles).
      waypoints: random cells per route (>= 1; 1 stands still).
      avoid: optional ``[P, 2]`` world points (m), e.g. the robots' starts and goals.
      avoid_radius: minimum distance (m) from ``avoid`` points to a disc's edge at ``t = 0``.
      loop: True: loop routes; False (default): bounce.
      tries: attempts per obstacle before giving up (a route is redrawn only if the exact
        check fails, which the inflation makes rare).
      behavior: ``"blind"`` (default) or ``"social"`` (`BEHAVIORS`): the same routes and phases either way,
        so the two kinds of walker can be compared scenario by scenario.

    Returns:
      `MovingObstacles` with ``M = n`` (``reactive`` all True for ``"social"``, None for ``"blind"``).

    Raises:
      ValueError: bad arguments, or no free cell where a disc of the radius can start.
    """
    g = _as_grid(grid)
    rng = _rng(seed)
    if behavior not in BEHAVIORS:
        raise ValueError(f"unknown walker behavior {behavior!r}{did_you_mean(str(behavior), BEHAVIORS)} "
                         f"(choose from {', '.join(BEHAVIORS)})")
    if not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    if not isinstance(waypoints, (int, np.integer)) or waypoints < 1:
        raise ValueError(f"waypoints must be an integer >= 1, got {waypoints!r}")
    if not np.isfinite(avoid_radius) or avoid_radius < 0:
        raise ValueError(f"avoid_radius must be finite and >= 0, got {avoid_radius}")
    speeds = per_obstacle("speed", speed, n)
    radii = per_obstacle("radius", radius, n)
    av = np.zeros((0, 2)) if avoid is None else np.asarray(avoid, np.float64).reshape(-1, 2)
    if not np.isfinite(av).all():
        raise ValueError("avoid contains a non-finite coordinate")
    av = g.to_local(av)  # world -> the map's frame (the origin, if any, subtracted); routes go back below
    if n == 0:
        return no_obstacles(0)
    res = float(g.resolution)
    free = np.asarray(g.free, bool)
    clear = clearance_field(g)  # metres, exact at cell centres
    blocked = _Blocked(free)
    H, W = free.shape
    ys, xs = np.mgrid[0:H, 0:W]
    centres = np.stack([(xs + 0.5) * res, (ys + 0.5) * res], axis=-1)  # [H, W, 2] m
    regions: dict[float, tuple[np.ndarray, np.ndarray, GridMap]] = {}
    routes, offsets, placed = [], [], []  # placed: (start point, radius) of earlier discs
    for i in range(n):
        r = float(radii[i])
        if r not in regions:
            ok = free & (clear >= np.float32(r))
            labels, _ = ndimage.label(ok)  # 4-connected = reachable without corner cutting
            regions[r] = (ok, labels, grid_from_array(ok, resolution=res))
        ok, labels, inflated = regions[r]
        pool = _start_pool(i, ok, centres, av, avoid_radius, r, placed)
        route = _random_route(rng, pool, labels, inflated, blocked, waypoints, loop, r, res, tries)
        if route is None:
            raise ValueError(f"obstacle {i}: no collision-free route found in {tries} tries")
        offset = _phase(rng, route, loop, av, avoid_radius, r, placed)
        routes.append(route)
        offsets.append(offset)
        placed.append((_np_position(route, offset, loop), r))
    return moving_obstacles([g.to_world(r) for r in routes], speeds, radii, loop=loop, offsets=offsets,
                            reactive=True if behavior == "social" else None)


def _as_path(path: ArrayLike, name: str = "path") -> np.ndarray:
    p = np.asarray(path, np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ValueError(f"{name} must be [L, 2] world points, got shape {p.shape}")
    if not np.isfinite(p).all():
        raise ValueError(f"{name} contains a non-finite coordinate")
    return p


def _free_extent(blocked: _Blocked, origin: np.ndarray, direction: np.ndarray, ext: np.ndarray, r: float) -> float:
    """The largest ``e`` of the increasing grid ``ext`` (``ext[0] = 0``, free) such that the
    segment ``origin → origin + e·direction`` (cells) is free for radius ``r``.

    Free extents form a prefix (a shorter segment is a subset of a longer one), so a
    binary search finds the boundary with about log2(len(ext)) exact tests.
    """
    lo, hi = 0, len(ext) - 1  # ext[lo] free; find the largest free index
    if blocked.free_for(origin, origin + ext[hi] * direction, r, _SHORTCUT_MARGIN):
        return float(ext[hi])
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if blocked.free_for(origin, origin + ext[mid] * direction, r, _SHORTCUT_MARGIN):
            lo = mid
        else:
            hi = mid
    return float(ext[lo])


def crossing_traffic(grid: Any, path: ArrayLike, n: int = 3, speed: Any = 1.0, radius: Any = 0.25, seed: int = 0, *,
                     span: float = 4.0, robot_speed: float | None = None, jitter: float = 0.25) -> MovingObstacles:
    """Traffic crossing a robot's planned route: ``n`` discs bouncing across it perpendicularly.

    Placement: the path (length ``L``) is cut into ``n`` equal slices; slice ``i`` offers
    nine candidate crossing points, its centre ``(i + 0.5)·L/n`` and eight drawn by the
    seed uniformly within ±30 % of the slice around it. At each, the crossing line is the normal of
    the path segment there; it extends up to ``span`` m to each side as far as a disc of
    ``radius`` stays clear of every blocked square (exact segment test; extents resolved
    to 1/8 cell). The candidate with the longest crossing wins (warehouse cross aisles),
    ties going to the one nearer the slice centre; candidates where the disc does not fit
    on the path are skipped. The route runs from one end of the crossing line (which one
    is random) to the other, bouncing.

    Phase rule: the robot is assumed to leave ``path[0]`` at ``t = 0`` and to move along
    the path at ``robot_speed`` (default: the obstacle's own speed), reaching the
    crossing point (arc length ``s``) at ``t* = s / robot_speed``. The offset is chosen
    so that the obstacle is at the crossing point, on its first pass, at ``t* + δ``,
    ``δ ~ U(−jitter, jitter)`` s. An obstacle of speed 0 stands on the crossing point.

    Args:
      grid: a `GridMap` or a `Scene`.
      path: ``[L, 2]`` world points (m) of the robot's planned route (``L >= 2``, length > 0).
      n: number of obstacles (>= 0).
      speed, radius: m/s and m (>= 0), scalars or ``[n]``.
      seed: integer seed (same seed, same obstacles).
      span: maximum extent (m) of a crossing to each side of the path (> 0).
      robot_speed: the robot's assumed speed (m/s, > 0) for the phase rule.
      jitter: half-width (s) of the random shift of the meeting time.

    Raises:
      ValueError: bad arguments, or a slice of the path where the disc fits nowhere.
    """
    g = _as_grid(grid)
    rng = _rng(seed)
    if not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    if not np.isfinite(span) or span <= 0:
        raise ValueError(f"span must be a finite number of metres > 0, got {span}")
    if not np.isfinite(jitter) or jitter < 0:
        raise ValueError(f"jitter must be finite and >= 0, got {jitter}")
    if robot_speed is not None and (not np.isfinite(robot_speed) or robot_speed <= 0):
        raise ValueError(f"robot_speed must be a finite number of m/s > 0, got {robot_speed}")
    p = g.to_local(_as_path(path))  # world -> the map's frame; routes go back below
    speeds = per_obstacle("speed", speed, n)
    radii = per_obstacle("radius", radius, n)
    seg_vec = np.diff(p, axis=0)
    seg = np.hypot(*seg_vec.T)
    total = float(seg.sum())
    if len(p) < 2 or total <= 0:
        raise ValueError("path must have at least two distinct points")
    if n == 0:
        return no_obstacles(0)
    res = float(g.resolution)
    blocked = _Blocked(g.free)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    moving = np.flatnonzero(seg > 0)
    ext = np.linspace(0.0, span, int(np.ceil(8.0 * span / res)) + 1)  # m, 1/8-cell steps
    routes, offsets = [], []
    for i in range(n):
        r = float(radii[i]) / res  # cells
        width = total / n
        ss = (i + 0.5) * width + np.concatenate([[0.0], rng.uniform(-0.3, 0.3, 8)]) * width
        best = None
        for s in ss:
            k = moving[min(np.searchsorted(cum[moving + 1], s, side="right"), len(moving) - 1)]
            c = p[k] + (s - cum[k]) / seg[k] * seg_vec[k]
            tangent = seg_vec[k] / seg[k]
            normal = np.array([-tangent[1], tangent[0]])
            cc = c / res - 0.5  # cell coordinates
            if not blocked.free_for(cc, cc, r, _SHORTCUT_MARGIN):
                continue  # the disc does not fit on the path here
            e = [_free_extent(blocked, cc, direction / res, ext, r) for direction in (normal, -normal)]
            score = (e[0] + e[1], -abs(s - (i + 0.5) * width))
            if best is None or score > best[0]:
                best = (score, s, c, normal, e)
        if best is None:
            raise ValueError(f"obstacle {i}: a disc of radius {radii[i]} m fits nowhere on the path "
                             f"between {i * total / n:.2f} and {(i + 1) * total / n:.2f} m")
        _, s, c, normal, (e_plus, e_minus) = best
        if rng.integers(2):  # start on the minus side instead
            normal, e_plus, e_minus = -normal, e_minus, e_plus
        a, b = c + e_plus * normal, c - e_minus * normal
        route = np.stack([a, b]) if e_plus + e_minus > 0 else c[None]
        v = float(speeds[i])
        half = e_plus + e_minus
        if v > 0 and half > 0:
            meet = s / (robot_speed if robot_speed is not None else v) + rng.uniform(-jitter, jitter)
            offset = float(np.mod(e_plus - v * meet, 2.0 * half))
        else:
            offset = e_plus  # standing still on the crossing point
        routes.append(route)
        offsets.append(offset)
    return moving_obstacles([g.to_world(r) for r in routes], speeds, radii, loop=False, offsets=offsets)


def head_on(path: ArrayLike, speed: float = 1.0, radius: float = 0.25, *, delay: float = 0.0) -> MovingObstacles:
    """One disc travelling the robot's planned ``path`` in reverse, from its goal end (chu2024, Figure 11).

    The route is ``path[::-1]``, bouncing (not looping): the disc leaves the goal end,
    meets the robot head-on, reaches the start end and turns back. No map is checked: the
    path is expected to be planned for a footprint at least as large as the disc.

    Args:
      path: ``[L, 2]`` world points (m), start first.
      speed: m/s (>= 0).
      radius: m (>= 0).
      delay: seconds after ``t = 0`` at which the disc leaves the goal end (offset
        ``−speed·delay``). The model has no waiting, so for ``delay > 0`` the disc is,
        before that, on the last ``speed·delay`` metres of the path moving toward the goal
        end (the mirror image of its bounce); ``delay < 0`` means it left earlier.

    Returns:
      `MovingObstacles` with ``M = 1``.
    """
    p = _as_path(path)
    if not np.isfinite(delay):
        raise ValueError(f"delay must be finite, got {delay}")
    v = per_obstacle("speed", speed, 1)
    return moving_obstacles([p[::-1]], v, radius, loop=False, offsets=-float(v[0]) * float(delay))
