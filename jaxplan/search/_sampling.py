"""Sampling-based global planners: RRT* and li2026's multi-region biased sampling (MRBS).

Both are continuous RRT* (Karaman & Frazzoli 2011) in *cell coordinates* (the centre of
cell ``(x, y)`` is the point ``(x, y)``; metres = ``(point + 0.5) · res``) over the free
space of the map: sample, nearest node, steer by at most ``step``, exact collision test of
the new edge, choose the cheapest parent among the near nodes, rewire the near nodes
through the new one. The near radius shrinks as ``min(γ·sqrt(log n / n), step)`` with
``n`` the tree size (``radius`` = γ). A node within ``step`` of the goal whose segment to
the goal is free is a goal connection; the best connection's cost is the result and is
recorded after every iteration (``history``). Nodes are kept in square bins of side
``max(step, 1)`` cells, so the nearest node is found by scanning rings of bins outwards
and the near nodes in the 3×3 bins around the new one (faster than brute-force scans, and
more so as the tree grows).

Collision test: a segment is free when it keeps at least ``max(robot_radius, TOUCH)``
cells from every blocked unit square (outside the map counts as blocked), the semantics
of `jaxplan.grid._collision.segment_free`, computed exactly in float64 over the squares
near the segment (a compiled numba loop: one call of the jitted JAX test costs more in
dispatch than the numba test of a short edge, and RRT* tests tens of edges per
iteration). A margin of `clear_margin` cells on top (growing with the map, as float32
spacing does) keeps every accepted segment free under the float32 JAX test too.

Sampling (li2026, Eq. 9–12). Each iteration draws four uniforms ``u [4]``; `mrbs_sample`
maps them to a point and a region:

* with probability ``goal_bias``: the goal itself (the classic RRT goal bias);
* otherwise one of four regions with probabilities ``p_start + p_end + p_obs + p_norm = 1``
  (Eq. 9): a disc of radius ``R_start`` around the start, a disc of radius ``R_end``
  around the goal, the obstacle border (free cells whose clearance is at most
  ``robot_radius + obs_band``; a point uniform in such a cell), or the whole free space
  (uniform over the free cells of the start's component; other components can never
  join the tree, so sampling them would only waste iterations).

The radii follow Eq. 10 and 12 as we read them (the printed formulas use norms of tree
node vectors without saying relative to what): ``R_start`` = the mean distance of the
tree's nodes from the start (Eq. 10: the region grows with the tree), and ``R_end`` =
the smallest distance of a tree node to the goal (Eq. 12's minimum; its division by n
would shrink the disc to a point, which the goal bias already covers), so goal-region
samples cover the gap between the tree and the goal and focus as the tree closes in.
Both are floored at ``step``. `rrt_star` is the same program with ``p_norm = 1``. The
discs alone need not reach around obstacles (``R_start`` grows only as the tree does), so
keep ``p_norm`` or ``p_obs`` above 0. Like every RRT, both struggle with narrow passages:
on warehouse-10-20-10-2-1 (one-cell aisles) the default budget misses a few goals that
lie deep in an aisle (see ``benchmarks/bench_sampling.py``).

Mapping to `PlanResult` (any-angle polylines vs. the cell-path contract):

* ``info["points"]``: ``f64[L, 2]`` the exact polyline in cell coordinates, start and goal
  cell centres at its ends; every segment is free under the exact test with the robot
  radius. This is the path a robot should follow.
* ``path``: ``int64[M, 2]`` a valid grid path that follows the polyline: the cells each
  segment passes through, in order (8-connected, no corner cutting, loops erased, all
  free), so consumers that expect cells keep working. Rounding the polyline's vertices
  to cells would not be collision-free in general. The grid path is only as wide as a
  cell: with ``robot_radius > 0`` its clearance is not guaranteed, the polyline's is.
* ``length``, ``cost``: the polyline's length in metres (``info["grid_length"]`` is the
  grid path's); ``turns``: the polyline's turning vertices; ``history``: ``f64[iterations]``
  best goal cost in metres after each iteration (``inf`` before the first connection);
  ``info["nodes"]`` tree size, ``info["first_solution"]`` the first iteration with a
  connection. A failure (`PlanResult.failure`) says why in ``info["reason"]``.

Reproducibility: all randomness comes from ``numpy.random.default_rng(seed)``, drawn up
front, so the same seed gives the same path, bit for bit, on the same machine.
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike
from scipy import ndimage

from jaxplan.core.compile_cache import on_first_use
from jaxplan.core.geometry import point_segment_distance_nb, segment_square_distance_nb
from jaxplan.grid import TOUCH, GridMap, cached_collision_map, check_cell
from jaxplan.metrics import count_turns, path_length
from jaxplan.result import PlanResult

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = [
    "rrt_star", "mrbs_rrt", "SamplingRegions", "sampling_regions", "region_probabilities", "mrbs_sample",
    "segment_clear", "polyline_cells", "REGIONS", "CLEAR_MARGIN", "clear_margin",
]

REGIONS = ("goal", "start", "end", "obs", "norm")
"""Region labels returned by `mrbs_sample`, in order (0 = the goal point of the goal bias)."""

CLEAR_MARGIN = 1e-5
"""Least margin (cells) added to the clearance threshold of the float64 test; the margin
used grows with the map (`clear_margin`)."""

_F32_ULPS = 4.0
"""float32 rounding, in units of the spacing of float32 numbers near the map's largest
coordinate, that the JAX test's distance may be off by: the end points' rounding (half a
unit each) and the few operations of the segment-to-square distance; 4 leaves a factor
of two over what segments passing a blocked corner just outside the margin needed."""


def clear_margin(shape: tuple[int, int]) -> float:
    """Cells added to the float64 clearance threshold on a map of ``shape (H, W)``, so that an
    accepted segment also passes the float32 JAX test (`segment_free`) whatever its rounding.

    float32 coordinates near ``x`` are ``x·2⁻²³`` apart, so the error of the JAX distance
    grows with the map: a fixed 1e-5 cells failed 4 of 4000 near-touching segments at
    x ≈ 500 (spacing 6e-5). 3e-5 cells on a 64-wide map, 2.9e-4 at 600 wide.
    """
    return max(CLEAR_MARGIN, _F32_ULPS * max(shape) * 2.0 ** -23)

_QUICK = 0.70711  # > √2/2: a square is at least (distance to its centre − √2/2) away


# ---------------------------------------------------------------------------------------------
# Exact geometry (float64, cell coordinates; a blocked cell (x, y) is the square [x±½]×[y±½]; the
# distances are the numba twins of jaxplan.core.geometry)


@njit(cache=True, nogil=True)
def _clear(blocked, px, py, qx, qy, thr):
    """True if segment p–q keeps at least ``thr`` cells from every blocked square (and the outside)."""
    H, W = blocked.shape
    reach = thr + 0.5
    x0, x1 = int(math.ceil(min(px, qx) - reach)), int(math.floor(max(px, qx) + reach))
    y0, y1 = int(math.ceil(min(py, qy) - reach)), int(math.floor(max(py, qy) + reach))
    for y in range(y0, y1 + 1):
        for x in range(x0, x1 + 1):
            if 0 <= x < W and 0 <= y < H and not blocked[y, x]:
                continue
            if point_segment_distance_nb(float(x), float(y), px, py, qx, qy) - _QUICK >= thr:
                continue
            if segment_square_distance_nb(px, py, qx, qy, float(x), float(y)) < thr:
                return False
    return True


def _threshold(radius_cells: float, shape: tuple[int, int]) -> float:
    return max(float(radius_cells), TOUCH) + clear_margin(shape)


def segment_clear(grid: GridMap, p: ArrayLike, q: ArrayLike, robot_radius: float = 0.0) -> bool:
    """Whether the segment ``p``–``q`` (cell coordinates, ``[2]`` each) keeps ``robot_radius``
    metres (and more than touching, plus `clear_margin`) from every blocked cell — the test
    the sampling planners apply to each edge."""
    blocked = ~np.asarray(grid.free, dtype=bool)
    p, q = np.asarray(p, np.float64), np.asarray(q, np.float64)
    return bool(_clear(blocked, p[0], p[1], q[0], q[1], _threshold(robot_radius / float(grid.resolution), grid.shape)))


# ---------------------------------------------------------------------------------------------
# Sampling regions (li2026, Eq. 9–12)


class SamplingRegions(NamedTuple):
    """What `mrbs_sample` draws from.

    Attributes:
      start, goal: ``f64[2]`` the start and goal cell centres (cell coordinates).
      free_cells: ``int64[F, 2]`` cells ``(x, y)`` of the uniform ("norm") region: the free
        cells of the start's component.
      border_cells: ``int64[B, 2]`` cells of the obstacle-border region (a subset of
        ``free_cells`` whose clearance is at most ``robot_radius + obs_band``); may be empty,
        then obstacle-region draws fall back to the uniform region.
      cum: ``f64[5]`` cumulative probabilities of the regions `REGIONS`
        (goal point, start disc, end disc, obstacle border, uniform); ``cum[-1] == 1``.
    """

    start: np.ndarray
    goal: np.ndarray
    free_cells: np.ndarray
    border_cells: np.ndarray
    cum: np.ndarray


def region_probabilities(goal_bias: float, p_start: float, p_end: float, p_obs: float, p_norm: float) -> np.ndarray:
    """``f64[5]`` probabilities of `REGIONS`: the goal bias first, the four MRBS regions share the rest."""
    p = np.array([goal_bias, *((1.0 - goal_bias) * np.array([p_start, p_end, p_obs, p_norm]))], np.float64)
    return p / p.sum()


def _components(free: np.ndarray) -> np.ndarray:
    # The continuous free space (closed blocked squares removed) is connected exactly where
    # the free cells are 4-connected: diagonal neighbours meet only at a blocked-corner point.
    labels, _ = ndimage.label(free, structure=[[0, 1, 0], [1, 1, 1], [0, 1, 0]])
    return labels


def sampling_regions(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, probabilities: ArrayLike,
    robot_radius: float = 0.0, obs_band: float | None = None,
) -> SamplingRegions:
    """Builds the sampling regions of one query.

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells (validated: inside the map and free).
      probabilities: ``[5]`` probabilities of `REGIONS` (see `region_probabilities`).
      robot_radius: metres; widens the obstacle border.
      obs_band: metres of the obstacle border beyond the robot radius (None: 1.5 cells).
    """
    s = check_cell(grid, start, "start")
    g = check_cell(grid, goal, "goal")
    res = float(grid.resolution)
    band = 1.5 if obs_band is None else float(obs_band) / res
    free = np.asarray(grid.free, dtype=bool)
    labels = _components(free)
    comp = labels == labels[s[1], s[0]]
    field = np.asarray(cached_collision_map(grid).field, np.float64)  # cells
    border = comp & (field <= robot_radius / res + band)
    ys, xs = np.nonzero(comp)
    by, bx = np.nonzero(border)
    p = np.asarray(probabilities, np.float64)
    return SamplingRegions(
        start=np.array(s, np.float64), goal=np.array(g, np.float64),
        free_cells=np.stack([xs, ys], axis=1).astype(np.int64),
        border_cells=np.stack([bx, by], axis=1).astype(np.int64),
        cum=np.concatenate([np.cumsum(p[:-1]), [1.0]]),
    )


@njit(cache=True, nogil=True)
def _map_sample(u0, u1, u2, u3, cum, sx, sy, gx, gy, r_start, r_end, free_cells, border_cells):
    """Four uniforms -> (x, y, region) as described in the module docstring."""
    region = 4
    for k in range(4):
        if u0 < cum[k]:
            region = k
            break
    if region == 3 and border_cells.shape[0] == 0:
        region = 4
    if region == 0:
        return gx, gy, region
    if region == 1 or region == 2:
        cx, cy, r = (sx, sy, r_start) if region == 1 else (gx, gy, r_end)
        rho = r * math.sqrt(u1)  # uniform over the disc's area
        ang = 2.0 * math.pi * u2
        return cx + rho * math.cos(ang), cy + rho * math.sin(ang), region
    cells = border_cells if region == 3 else free_cells
    c = min(int(u1 * cells.shape[0]), cells.shape[0] - 1)
    return cells[c, 0] + (u2 - 0.5), cells[c, 1] + (u3 - 0.5), region


@njit(cache=True, nogil=True)
def _map_samples(u, cum, sx, sy, gx, gy, r_start, r_end, free_cells, border_cells):
    n = u.shape[0]
    pts = np.empty((n, 2))
    reg = np.empty(n, np.int64)
    for i in range(n):
        x, y, k = _map_sample(u[i, 0], u[i, 1], u[i, 2], u[i, 3], cum, sx, sy, gx, gy, r_start, r_end,
                              free_cells, border_cells)
        pts[i, 0], pts[i, 1], reg[i] = x, y, k
    return pts, reg


def mrbs_sample(regions: SamplingRegions, u: ArrayLike, r_start: float, r_end: float) -> tuple[np.ndarray, np.ndarray]:
    """Maps uniforms ``u f64[N, 4]`` (in [0, 1)) to samples — the planners' own sampler.

    Args:
      regions: from `sampling_regions`.
      u: ``f64[N, 4]`` uniforms, e.g. ``np.random.default_rng(seed).random((N, 4))``.
      r_start, r_end: radii (cells) of the start and end discs.

    Returns:
      ``(points f64[N, 2], region int64[N])``: points in cell coordinates and their region
      index into `REGIONS`.
    """
    u = np.asarray(u, np.float64)
    if u.ndim != 2 or u.shape[1] != 4:
        raise ValueError(f"u must be uniforms of shape [N, 4], got {u.shape}")
    return _map_samples(u, regions.cum, regions.start[0], regions.start[1], regions.goal[0], regions.goal[1],
                        float(r_start), float(r_end), regions.free_cells, regions.border_cells)


# ---------------------------------------------------------------------------------------------
# RRT*


@njit(cache=True, nogil=True, inline="always")
def _bin(v, size, n):
    return min(max(int(math.floor((v + 0.5) / size)), 0), n - 1)


@njit(cache=True, nogil=True)
def _scan_bin(head, nxt, b, xs, ys, x, y, best, bd):
    k = head[b]
    while k != -1:
        d = (xs[k] - x) ** 2 + (ys[k] - y) ** 2
        if d < bd:
            best, bd = k, d
        k = nxt[k]
    return best, bd


@njit(cache=True, nogil=True)
def _nearest(head, nxt, nbx, nby, size, xs, ys, x, y):
    """Nearest tree node to (x, y): scan square rings of bins outwards until no unseen bin
    can hold a closer node. Returns (node, squared distance)."""
    bx, by = _bin(x, size, nbx), _bin(y, size, nby)
    best, bd = -1, np.inf
    r = 0
    while True:
        for j in range(by - r, by + r + 1):
            if j < 0 or j >= nby:
                continue
            edge = j == by - r or j == by + r
            i = bx - r
            while i <= bx + r:
                if 0 <= i < nbx:
                    best, bd = _scan_bin(head, nxt, j * nbx + i, xs, ys, x, y, best, bd)
                i += 1 if edge or r == 0 else 2 * r
        if bx - r <= 0 and by - r <= 0 and bx + r >= nbx - 1 and by + r >= nby - 1:
            return best, bd
        # Unseen nodes lie outside the box of bins scanned so far.
        x_lo, x_hi = (bx - r) * size - 0.5, (bx + r + 1) * size - 0.5
        y_lo, y_hi = (by - r) * size - 0.5, (by + r + 1) * size - 0.5
        if best >= 0 and x_lo <= x <= x_hi and y_lo <= y <= y_hi:
            bound = min(x - x_lo, x_hi - x, y - y_lo, y_hi - y)
            if bd <= bound * bound:
                return best, bd
        r += 1


@njit(cache=True, nogil=True)
def _rrt_star(blocked, u, cum, sx, sy, gx, gy, free_cells, border_cells, step, gamma, thr):
    """The RRT* loop over the pre-drawn uniforms ``u [iterations, 4]`` (all lengths in cells).

    Returns ``(xs [n], ys [n], parent [n], cost [n], n, goal_parent, history [iterations])``:
    the tree (root 0, ``parent = -1``), the node the best goal connection leaves from (-1:
    none) and the best goal cost after each iteration.
    """
    N = u.shape[0] + 1
    xs, ys = np.empty(N), np.empty(N)
    parent = np.full(N, -1, np.int64)
    cost = np.zeros(N)
    first_child = np.full(N, -1, np.int64)
    next_sib = np.full(N, -1, np.int64)
    cand = np.empty(N, np.int64)  # goal connections: node, edge length
    cand_d = np.empty(N)
    near = np.empty(N, np.int64)
    near_c = np.empty(N)
    stack = np.empty(N, np.int64)
    history = np.empty(N - 1)
    # Nodes are binned in squares of at least the near radius, for the nearest/near queries.
    H, W = blocked.shape
    size = max(step, 1.0)
    nbx, nby = int(W / size) + 1, int(H / size) + 1
    head = np.full(nbx * nby, -1, np.int64)
    nxt = np.full(N, -1, np.int64)
    xs[0], ys[0] = sx, sy
    head[_bin(sy, size, nby) * nbx + _bin(sx, size, nbx)] = 0
    n, nc = 1, 0
    sum_ds = 0.0  # summed distance of tree nodes from the start (Eq. 10)
    min_dg = math.hypot(sx - gx, sy - gy)  # closest approach of the tree to the goal (Eq. 12)
    if min_dg <= step and _clear(blocked, sx, sy, gx, gy, thr):
        cand[0], cand_d[0], nc = 0, min_dg, 1
    goal_cost, goal_parent = (min_dg, 0) if nc == 1 else (np.inf, -1)
    for i in range(N - 1):
        x, y, _ = _map_sample(u[i, 0], u[i, 1], u[i, 2], u[i, 3], cum, sx, sy, gx, gy,
                              max(sum_ds / n, step), max(min_dg, step), free_cells, border_cells)
        j, dj = _nearest(head, nxt, nbx, nby, size, xs, ys, x, y)
        dj = math.sqrt(dj)
        if dj < 1e-9:
            history[i] = goal_cost
            continue
        if dj > step:  # steer
            x, y = xs[j] + (x - xs[j]) * (step / dj), ys[j] + (y - ys[j]) * (step / dj)
            dj = step
        if not _clear(blocked, xs[j], ys[j], x, y, thr):
            history[i] = goal_cost
            continue
        rn = min(gamma * math.sqrt(math.log(n) / n), step) if n > 1 else 0.0
        near[0], near_c[0], m = j, cost[j] + dj, 1
        bx, by = _bin(x, size, nbx), _bin(y, size, nby)
        for bj in range(max(by - 1, 0), min(by + 2, nby)):  # rn <= step <= bin size
            for bi in range(max(bx - 1, 0), min(bx + 2, nbx)):
                k = head[bj * nbx + bi]
                while k != -1:
                    d2 = (xs[k] - x) ** 2 + (ys[k] - y) ** 2
                    if k != j and d2 <= rn * rn:
                        near[m], near_c[m] = k, cost[k] + math.sqrt(d2)
                        m += 1
                    k = nxt[k]
        # Cheapest collision-free parent: try candidates by cost; the nearest is known free.
        cj = cost[j] + dj
        best = j
        order = np.argsort(near_c[:m])
        for t in order:
            if near_c[t] >= cj:
                break
            if _clear(blocked, xs[near[t]], ys[near[t]], x, y, thr):
                best = near[t]
                break
        new = n
        xs[new], ys[new] = x, y
        parent[new] = best
        cost[new] = cost[best] + math.hypot(xs[best] - x, ys[best] - y)
        next_sib[new] = first_child[best]
        first_child[new] = -1
        first_child[best] = new
        b = _bin(y, size, nby) * nbx + _bin(x, size, nbx)
        nxt[new], head[b] = head[b], new
        n += 1
        # Rewire the near nodes through the new one where that is shorter.
        for t in range(m):
            k = near[t]
            if k == best:
                continue
            c = cost[new] + math.hypot(xs[k] - x, ys[k] - y)
            if c < cost[k] - 1e-12 and _clear(blocked, x, y, xs[k], ys[k], thr):
                p = parent[k]  # unlink k from its parent's children
                if first_child[p] == k:
                    first_child[p] = next_sib[k]
                else:
                    s = first_child[p]
                    while next_sib[s] != k:
                        s = next_sib[s]
                    next_sib[s] = next_sib[k]
                parent[k] = new
                next_sib[k] = first_child[new]
                first_child[new] = k
                delta = c - cost[k]
                top = 0  # propagate the saving to k's subtree
                stack[top] = k
                top += 1
                while top > 0:
                    top -= 1
                    v = stack[top]
                    cost[v] += delta
                    ch = first_child[v]
                    while ch != -1:
                        stack[top] = ch
                        top += 1
                        ch = next_sib[ch]
        sum_ds += math.hypot(x - sx, y - sy)
        dg = math.hypot(x - gx, y - gy)
        min_dg = min(min_dg, dg)
        if dg <= step and _clear(blocked, x, y, gx, gy, thr):
            cand[nc], cand_d[nc] = new, dg
            nc += 1
        goal_cost, goal_parent = np.inf, -1
        for t in range(nc):
            c = cost[cand[t]] + cand_d[t]
            if c < goal_cost:
                goal_cost, goal_parent = c, cand[t]
        history[i] = goal_cost
    return xs[:n], ys[:n], parent[:n], cost[:n], n, goal_parent, history


# ---------------------------------------------------------------------------------------------
# Polyline -> grid path


@njit(cache=True, nogil=True)
def _trace(points):
    """Cells the segments pass through, in order (4-connected steps; repeats across joints dropped)."""
    total = 1
    for i in range(points.shape[0] - 1):
        total += abs(int(math.floor(points[i + 1, 0] + 0.5)) - int(math.floor(points[i, 0] + 0.5)))
        total += abs(int(math.floor(points[i + 1, 1] + 0.5)) - int(math.floor(points[i, 1] + 0.5)))
    out = np.empty((total, 2), np.int64)
    cx, cy = int(math.floor(points[0, 0] + 0.5)), int(math.floor(points[0, 1] + 0.5))
    out[0, 0], out[0, 1] = cx, cy
    m = 1
    for i in range(points.shape[0] - 1):
        px, py, qx, qy = points[i, 0], points[i, 1], points[i + 1, 0], points[i + 1, 1]
        ex, ey = int(math.floor(qx + 0.5)), int(math.floor(qy + 0.5))
        nx, ny = abs(ex - cx), abs(ey - cy)
        sx, sy = (1 if ex > cx else -1), (1 if ey > cy else -1)
        dx, dy = qx - px, qy - py
        # Parameter of the next vertical / horizontal cell boundary crossed (Amanatides & Woo).
        tx = (cx + 0.5 * sx - px) / dx if dx != 0.0 else np.inf
        ty = (cy + 0.5 * sy - py) / dy if dy != 0.0 else np.inf
        ix = iy = 0
        while ix < nx or iy < ny:  # exactly nx + ny steps: the walk ends in q's cell
            if ix < nx and (iy >= ny or tx <= ty):
                cx += sx
                ix += 1
                tx += 1.0 / abs(dx)
            else:
                cy += sy
                iy += 1
                ty += 1.0 / abs(dy)
            out[m, 0], out[m, 1] = cx, cy
            m += 1
    return out[:m]


def _erase_loops(cells: np.ndarray) -> np.ndarray:
    out: list[tuple[int, int]] = []
    where: dict[tuple[int, int], int] = {}
    for c in map(tuple, cells.tolist()):
        if c in where:  # back on a cell already visited: drop the loop in between
            k = where[c]
            for d in out[k + 1:]:
                del where[d]
            del out[k + 1:]
            continue
        where[c] = len(out)
        out.append(c)
    return np.asarray(out, np.int64).reshape(-1, 2)


def _cut_corners(cells: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Replaces an orthogonal L (a, b, c with a, c diagonal neighbours) by the diagonal a→c where
    both orthogonal cells are free (the no-corner-cutting rule)."""
    out = [cells[0]]
    i = 1
    while i < len(cells):
        a = out[-1]
        if i + 1 < len(cells):
            c = cells[i + 1]
            d = c - a
            if abs(d[0]) == 1 and abs(d[1]) == 1 and free[a[1], c[0]] and free[c[1], a[0]]:
                out.append(c)
                i += 2
                continue
        out.append(cells[i])
        i += 1
    return np.asarray(out, np.int64).reshape(-1, 2)


def polyline_cells(grid: GridMap, points: ArrayLike) -> np.ndarray:
    """A grid path ``int64[M, 2]`` following a collision-free polyline ``points f64[L, 2]`` (cell coordinates).

    The cells each segment passes through, in order, with loops erased and orthogonal
    corners replaced by diagonal moves where no corner is cut. If every segment keeps more
    than touching distance from the blocked squares (as `segment_clear` accepts), every
    such cell is free and the result is an 8-connected path without corner cutting.

    Raises:
      ValueError: a cell of the result is blocked (the polyline was not collision-free).
    """
    pts = np.asarray(points, np.float64).reshape(-1, 2)
    free = np.asarray(grid.free, dtype=bool)
    H, W = free.shape
    cells = _trace(pts)
    if np.any((cells < 0) | (cells >= [W, H])) or not free[cells[:, 1], cells[:, 0]].all():
        raise ValueError("polyline crosses a blocked or outside cell; it is not collision-free")
    return _cut_corners(_erase_loops(cells), free)


# ---------------------------------------------------------------------------------------------
# Front


def _positive_or_none(name: str, v: Any, unit: str) -> None:
    if v is None:
        return
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number of {unit} or None, got {v!r}")
    if not math.isfinite(float(v)) or float(v) <= 0:
        raise ValueError(f"{name} must be a finite number of {unit} > 0 (or None for the default), got {v!r}")


def _number(name: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {v!r}")
    f = float(v)
    if math.isnan(f):
        raise ValueError(f"{name} is NaN")
    return f


def _check_rrt(params: Mapping[str, Any]) -> None:
    """Validates the parameters shared by `rrt_star` and `mrbs_rrt`."""
    it = params["iterations"]
    if isinstance(it, bool) or not isinstance(it, (int, np.integer)) or it < 1:
        raise ValueError(f"iterations must be a positive integer, got {it!r}")
    _positive_or_none("step", params["step"], "metres")
    _positive_or_none("radius", params["radius"], "metres")
    gb = _number("goal_bias", params["goal_bias"])
    if not 0.0 <= gb < 1.0:
        raise ValueError(f"goal_bias must be a probability in [0, 1), got {gb!r}")
    rr = _number("robot_radius", params["robot_radius"])
    if not math.isfinite(rr) or rr < 0:
        raise ValueError(f"robot_radius must be a finite number of metres >= 0, got {rr!r}")


def _check_mrbs(params: Mapping[str, Any]) -> None:
    """Validates `mrbs_rrt`'s parameters: the shared ones, the four region probabilities
    (each in [0, 1], summing to 1, Eq. 9) and the obstacle band."""
    _check_rrt(params)
    ps = {k: _number(k, params[k]) for k in ("p_start", "p_end", "p_obs", "p_norm")}
    for k, v in ps.items():
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"{k} must be a probability in [0, 1], got {v!r}")
    total = sum(ps.values())
    if abs(total - 1.0) > 1e-6:
        raise ValueError(
            "region probabilities must sum to 1 (li2026, Eq. 9): "
            + " + ".join(f"{k}={v:g}" for k, v in ps.items()) + f" = {total:g}"
        )
    _positive_or_none("obs_band", params["obs_band"], "metres")


def _plan(name: str, grid: GridMap, start: ArrayLike, goal: ArrayLike, seed: int, probabilities: np.ndarray,
          iterations: int, step: float | None, radius: float | None, robot_radius: float,
          obs_band: float | None) -> PlanResult:
    t0 = time.perf_counter()
    res = float(grid.resolution)
    s = check_cell(grid, start, "start")
    g = check_cell(grid, goal, "goal")
    thr = _threshold(robot_radius / res, grid.shape)
    field = np.asarray(cached_collision_map(grid).field, np.float64)  # exact at cell centres (cells)
    for what, c in (("start", s), ("goal", g)):
        if field[c[1], c[0]] < thr:
            raise ValueError(
                f"{what} {c} is closer than robot_radius={robot_radius:g} m to a blocked cell "
                f"(clearance {field[c[1], c[0]] * res:g} m)"
            )
    labels = _components(np.asarray(grid.free, dtype=bool))
    if labels[s[1], s[0]] != labels[g[1], g[0]]:
        return PlanResult.failure(name, time.perf_counter() - t0, history=np.full(iterations, np.inf),
                                  reason="start and goal lie in different components of the free space")
    regions = sampling_regions(grid, s, g, probabilities, robot_radius, obs_band)
    step_c = 3.0 if step is None else float(step) / res
    if radius is None:
        # 1.1 × γ* of Karaman & Frazzoli for d = 2: γ* = 2·sqrt(1 + 1/2)·sqrt(μ(X_free)/π).
        gamma = 1.1 * 2.0 * math.sqrt(1.5) * math.sqrt(len(regions.free_cells) / math.pi)
    else:
        gamma = float(radius) / res
    rng = np.random.default_rng(seed)
    u = rng.random((int(iterations), 4))
    blocked = ~np.asarray(grid.free, dtype=bool)
    xs, ys, parent, _, n, goal_parent, history = _rrt_star(
        blocked, u, regions.cum, float(s[0]), float(s[1]), float(g[0]), float(g[1]),
        regions.free_cells, regions.border_cells, step_c, gamma, thr,
    )
    history = history * res
    if goal_parent < 0:
        return PlanResult.failure(name, time.perf_counter() - t0, history=history, nodes=int(n),
                                  reason=f"iteration budget exhausted: no goal connection in {iterations} iterations")
    chain = [int(goal_parent)]
    while parent[chain[-1]] >= 0:
        chain.append(int(parent[chain[-1]]))
    pts = np.concatenate([np.stack([xs[chain[::-1]], ys[chain[::-1]]], axis=1), [[g[0], g[1]]]])
    keep = np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0, axis=1)])  # a node may sit on the goal
    pts = pts[keep]
    cells = polyline_cells(grid, pts)
    length = path_length(pts, res)
    finite = np.flatnonzero(np.isfinite(history))
    return PlanResult.found(name, cells, length, count_turns(pts), time.perf_counter() - t0, history=history,
                            points=pts, grid_length=path_length(cells, res), nodes=int(n),
                            first_solution=int(finite[0]) if len(finite) else -1)


def rrt_star(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, seed: int = 0, *, iterations: int = 5000,
    step: float | None = None, radius: float | None = None, goal_bias: float = 0.05, robot_radius: float = 0.0,
) -> PlanResult:
    """RRT* with uniform sampling over the free space (and a goal bias).

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells; blocked, outside or closer than ``robot_radius`` to an
        obstacle raises ``ValueError``.
      seed: seed of the numpy Generator all samples come from.
      iterations: samples drawn (the budget; RRT* keeps improving until it is spent).
      step: metres, the longest edge added per iteration and the goal-connection distance
        (None: 3 cells).
      radius: metres, γ of the shrinking near radius ``min(γ·sqrt(log n / n), step)``
        (None: 1.1 × Karaman–Frazzoli's γ* for the free area of the start's component).
      goal_bias: probability in [0, 1) of sampling the goal itself.
      robot_radius: metres; every edge keeps this clearance from blocked cells.

    Returns:
      `PlanResult` as described in the module docstring: ``path`` a grid path following
      the polyline ``info["points"] f64[L, 2]`` (cell coordinates), ``length`` the polyline's
      metres; ``success=False`` (with ``info["reason"]``) when the goal lies in another
      component or no connection was found within the budget.
    """
    params = dict(iterations=iterations, step=step, radius=radius, goal_bias=goal_bias, robot_radius=robot_radius)
    _check_rrt(params)
    probs = region_probabilities(float(goal_bias), 0.0, 0.0, 0.0, 1.0)
    return _plan("rrt_star", grid, start, goal, seed, probs, int(iterations), step, radius, float(robot_radius), None)


def mrbs_rrt(
    grid: GridMap, start: ArrayLike, goal: ArrayLike, seed: int = 0, *, iterations: int = 5000,
    step: float | None = None, radius: float | None = None, goal_bias: float = 0.05, robot_radius: float = 0.0,
    p_start: float = 0.1, p_end: float = 0.2, p_obs: float = 0.2, p_norm: float = 0.5, obs_band: float | None = None,
) -> PlanResult:
    """RRT* with li2026's multi-region biased sampling (MRBS, Eq. 9–12).

    Same as `rrt_star`, except that the samples that are not the goal (``1 − goal_bias``)
    come from four regions (module docstring):

    Args:
      p_start, p_end, p_obs, p_norm: probabilities of the start disc, the end disc, the
        obstacle border and the uniform free space; each in [0, 1], summing to 1 (Eq. 9).
      obs_band: metres beyond ``robot_radius`` that count as the obstacle border
        (None: 1.5 cells, i.e. the cells next to an obstacle).
    """
    params = dict(iterations=iterations, step=step, radius=radius, goal_bias=goal_bias, robot_radius=robot_radius,
                  p_start=p_start, p_end=p_end, p_obs=p_obs, p_norm=p_norm, obs_band=obs_band)
    _check_mrbs(params)
    probs = region_probabilities(float(goal_bias), float(p_start), float(p_end), float(p_obs), float(p_norm))
    return _plan("mrbs_rrt", grid, start, goal, seed, probs, int(iterations), step, radius, float(robot_radius),
                 obs_band)


_RRT_DEFAULTS = {"iterations": 5000, "step": None, "radius": None, "goal_bias": 0.05, "robot_radius": 0.0}
_MRBS_DEFAULTS = {**_RRT_DEFAULTS, "p_start": 0.1, "p_end": 0.2, "p_obs": 0.2, "p_norm": 0.5, "obs_band": None}


def _register() -> None:
    from jaxplan.registry import register_planner

    register_planner(
        "rrt_star",
        lambda grid, start, goal, seed, **p: rrt_star(grid, start, goal, seed, **p),
        _RRT_DEFAULTS,
        "RRT*: any-angle sampling planner (uniform samples, goal bias, shrinking rewiring radius)",
        _check_rrt,
    )
    register_planner(
        "mrbs_rrt",
        lambda grid, start, goal, seed, **p: mrbs_rrt(grid, start, goal, seed, **p),
        _MRBS_DEFAULTS,
        "MRBS-RRT* (li2026): RRT* sampling start, end, obstacle-border and uniform regions (Eq. 9-12)",
        _check_mrbs,
    )


_register()
