"""Exact geometry of points and segments against the blocked cells of a map, in JAX.

A blocked cell ``(x, y)`` is the closed unit square centred at ``(x, y)`` in cell
coordinates (the cell-centre convention, docs/guide/maps-and-scenarios.md#conventions, before scaling by the
resolution); everything outside the map counts as blocked. Smoothers, metrics and
the local planner ask two questions of it:

* how far is a point from the nearest blocked square (``point_clearance``), and
* does a segment keep at least a radius from every blocked square
  (``segment_free``) — the test every smoothed path must pass.

Both are pure functions of a ``CollisionMap`` pytree and batch with ``vmap``.
A segment is checked exactly, not by sampling alone: it is walked in steps of at
most one cell, and around every step the blocked squares of a small window are
tested with the exact segment-to-square distance (`jaxplan.core.geometry`), the window
being wide enough that any square within the radius of the segment is seen from some step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.core.cache import digest, memoize
from jaxplan.core.geometry import point_square_distance, segment_square_distance
from jaxplan.grid._fields import clearance_field
from jaxplan.grid._gridmap import GridMap

__all__ = [
    "CollisionMap", "collision_map", "cached_collision_map", "point_clearance", "segment_clearance", "segment_free",
    "polyline_free", "segment_window", "PAD", "POINT_WINDOW", "TOUCH",
]

PAD = 4
"""Blocked border kept around the map so that every window stays inside the array."""

POINT_WINDOW = 2
"""Half-width (cells) of the window searched exactly around a point."""

TOUCH = 1e-6
"""A segment must stay this far (cells) from blocked squares even at radius 0: touching a
blocked corner is a collision, which is the no-corner-cutting rule of the grid moves."""



class CollisionMap(NamedTuple):
    """The blocked squares of a map, padded, with the exact clearance of cell centres.

    Attributes:
      blocked: ``bool[H + 2·PAD, W + 2·PAD]``; cell ``(x, y)`` is ``blocked[y + PAD, x + PAD]``.
      field: ``f32[H, W]`` exact distance (cells) from each cell centre to the nearest
        blocked square (the map border counts), 0 on blocked cells.
      resolution: metres per cell (scalar).
    """

    blocked: jnp.ndarray
    field: jnp.ndarray
    resolution: jnp.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` of the map."""
        return (self.field.shape[0], self.field.shape[1])


def collision_map(grid: GridMap) -> CollisionMap:
    """Builds the ``CollisionMap`` of a grid (host side, once per map)."""
    free = np.asarray(grid.free, dtype=bool)
    blocked = np.pad(~free, PAD, constant_values=True)
    res = float(grid.resolution)
    field = clearance_field(grid) / res
    return CollisionMap(jnp.asarray(blocked), jnp.asarray(field, jnp.float32), jnp.asarray(res, jnp.float32))


@memoize(maxsize=8, key=lambda grid: (digest(np.asarray(grid.free, dtype=bool)), float(grid.resolution)))
def cached_collision_map(grid: GridMap) -> CollisionMap:
    """`collision_map(grid)`, memoised on the map's free cells and resolution (building one runs a
    distance transform, which would otherwise dominate repeated calls on the same map)."""
    return collision_map(grid)


def _window(w: int) -> jnp.ndarray:
    r = jnp.arange(-w, w + 1)
    return jnp.stack(jnp.meshgrid(r, r, indexing="xy"), axis=-1).reshape(-1, 2)  # [(2w+1)^2, 2] (dx, dy)


def _blocked_at(cmap: CollisionMap, cells: jnp.ndarray) -> jnp.ndarray:
    """``bool[...]`` for integer cells ``[..., 2]``; anything beyond the padding is blocked."""
    Hp, Wp = cmap.blocked.shape
    x, y = cells[..., 0] + PAD, cells[..., 1] + PAD
    inside = (x >= 0) & (x < Wp) & (y >= 0) & (y < Hp)
    return jnp.where(inside, cmap.blocked[jnp.clip(y, 0, Hp - 1), jnp.clip(x, 0, Wp - 1)], True)


def point_clearance(cmap: CollisionMap, points: jnp.ndarray, window: int = POINT_WINDOW) -> jnp.ndarray:
    """Distance (cells) from points ``[..., 2]`` (cell coordinates) to the nearest blocked square.

    Exact at cell centres (integer points) and, elsewhere, exact whenever the answer is
    below ``window`` cells (static; a square outside the window is at least that far);
    otherwise it returns the smaller of the exact distance to
    the window's squares and ``field(centre) + |point − centre|``: an upper bound, at most
    ``2·|point − centre| <= √2`` cells above the truth. Points outside the map get 0.
    """
    points = jnp.asarray(points, jnp.float32)
    H, W = cmap.shape
    centre = jnp.round(points).astype(jnp.int32)
    win = _window(window)
    cells = centre[..., None, :] + win  # [..., K, 2]
    d = point_square_distance(points[..., None, :], cells.astype(jnp.float32))
    near = jnp.min(jnp.where(_blocked_at(cmap, cells), d, jnp.inf), axis=-1)
    cx, cy = jnp.clip(centre[..., 0], 0, W - 1), jnp.clip(centre[..., 1], 0, H - 1)
    bound = cmap.field[cy, cx] + jnp.sqrt(jnp.sum((points - centre) ** 2, axis=-1))
    inside = jnp.all((points >= -0.5) & (points <= jnp.asarray([W - 0.5, H - 0.5])), axis=-1)
    return jnp.where(inside, jnp.minimum(near, bound), 0.0)


def segment_window(radius: float, step: float = 1.0) -> int:
    """Window half-width that makes the segment walk exact for distances up to ``radius`` cells.

    A square within ``radius`` of the segment is within ``radius + step/2`` of some sample,
    so its centre is within ``radius + step/2 + 1`` (Chebyshev) of the sample's cell.
    """
    return int(math.floor(radius + step / 2 + 1.0))


def segment_clearance(cmap: CollisionMap, p: jnp.ndarray, q: jnp.ndarray, radius: float | jnp.ndarray,
                      reach: float | None = None, chunk: int = 8, step: float = 1.0) -> jnp.ndarray:
    """Distance (cells) from the segment ``p``–``q`` (``[2]`` each) to the nearest blocked square.

    The walk stops at the first square closer than ``radius`` (cells, at least ``TOUCH``; may
    be traced), so a blocked segment costs little: the result is below the radius exactly
    when the true distance is, and is never below the true distance. ``reach`` (static,
    cells) bounds the radius and sets the window; it defaults to ``radius``, which must
    then be a Python number. A traced radius above ``reach`` counts as blocked. ``chunk``
    (static) samples are examined per loop step: small for short segments (curve chords),
    larger for long ones. ``step`` (static, cells) is the sample spacing: a smaller step
    needs a smaller window (``segment_window``), which pays off for short chords.
    ``vmap`` it over segments.
    """
    if reach is None:
        reach = float(radius)
    thr = jnp.maximum(jnp.asarray(radius, jnp.float32), TOUCH)
    win = _window(segment_window(max(float(reach), TOUCH), step))
    p = jnp.asarray(p, jnp.float32)
    q = jnp.asarray(q, jnp.float32)
    n = jnp.maximum(jnp.ceil(jnp.sqrt(jnp.sum((q - p) ** 2)) / step).astype(jnp.int32), 1) + 1  # spacing <= step
    k = jnp.arange(chunk)

    def body(carry):
        i, best = carry
        idx = jnp.minimum(i + k, n - 1)
        t = (idx / (n - 1).astype(jnp.float32))[:, None]
        s = p + t * (q - p)  # [CHUNK, 2]
        cells = jnp.round(s).astype(jnp.int32)[:, None, :] + win  # [CHUNK, Wn, 2]
        d = segment_square_distance(p, q, cells.astype(jnp.float32))
        d = jnp.where(_blocked_at(cmap, cells), d, jnp.inf)
        return i + chunk, jnp.minimum(best, jnp.min(d))

    def cond(carry):
        i, best = carry
        return (i < n) & (best >= thr)

    _, best = jax.lax.while_loop(cond, body, (jnp.int32(0), jnp.float32(jnp.inf)))
    return jnp.where(thr > max(float(reach), TOUCH), 0.0, best)


def segment_free(cmap: CollisionMap, p: jnp.ndarray, q: jnp.ndarray, radius: float | jnp.ndarray = 0.0,
                 reach: float | None = None, chunk: int = 8, step: float = 1.0) -> jnp.ndarray:
    """True if the segment ``p``–``q`` stays at least ``radius`` cells (and more than touching) from
    every blocked square. Clearance equal to the radius is not a collision (docs/guide/navigation.md).
    ``reach``, ``chunk`` and ``step`` as in `segment_clearance`."""
    thr = jnp.maximum(jnp.asarray(radius, jnp.float32), TOUCH)
    return segment_clearance(cmap, p, q, radius, reach, chunk, step) >= thr


def polyline_free(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, radius: float = 0.0) -> jnp.ndarray:
    """``bool[L-1]``: which segments of a padded polyline ``points [L, 2]`` with ``n`` valid points
    are free (padding segments count as free)."""
    ok = jax.vmap(lambda a, b: segment_free(cmap, a, b, radius))(points[:-1], points[1:])
    return ok | (jnp.arange(points.shape[0] - 1) >= n - 1)
