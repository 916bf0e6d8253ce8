"""Exact distances from points and segments to unit squares (blocked cells), as JAX, numpy and numba twins.

A blocked cell ``(x, y)`` is the closed unit square centred at ``(x, y)`` in cell coordinates
(docs/guide/maps-and-scenarios.md#conventions). Every clearance question of jaxplan reduces to three distances:

* point–square: ``|max(|p − c| − ½, 0)|`` (0 inside);
* point–segment: to the nearest point of the segment (clamped projection);
* segment–square: zero when the segment meets the closed square (slab test: the parameter
  intervals in which the line is inside each slab overlap within [0, 1]); otherwise the minimum
  is attained at an end point of the segment or a corner of the square, both sets being convex.

Each is written once over an array module (``xp``: `jax.numpy` or `numpy`, same operations in the
same order) and exposed as twins: the JAX functions (``point_square_distance``, …) run inside
compiled programs (collision maps, smoothers, the local planner), the ``_np`` ones on the host in
float64 (exact clearance metrics, obstacle routes). The ``_nb`` ones are numba scalar kernels with
the same arithmetic for compiled host loops (the sampling planners' segment checks); they give the
numpy twin's results bit for bit (``tests/test_geometry.py``).
"""

from __future__ import annotations

import math
from typing import Any

import jax.numpy as jnp
import numpy as np
from numba import njit

from jaxplan.core.compile_cache import on_first_use

on_first_use()  # jaxplan's cache folders, before numba fixes the cache folder of the kernels below

__all__ = [
    "point_square_distance", "point_segment_distance", "segment_square_distance",
    "point_square_distance_np", "point_segment_distance_np", "segment_square_distance_np",
    "point_square_distance_nb", "point_segment_distance_nb", "segment_square_distance_nb",
]

_CORNERS = ((-.5, -.5), (-.5, .5), (.5, -.5), (.5, .5))


def _point_square(p: Any, c: Any, xp: Any) -> Any:
    d = xp.maximum(xp.abs(p - c) - 0.5, 0.0)
    return xp.sqrt(xp.sum(d * d, axis=-1))


def _point_segment(x: Any, p: Any, q: Any, xp: Any) -> Any:
    d = q - p
    dd = xp.sum(d * d, axis=-1)
    t = xp.clip(xp.sum((x - p) * d, axis=-1) / xp.where(dd > 0, dd, 1.0), 0.0, 1.0)
    e = x - (p + t[..., None] * d)
    return xp.sqrt(xp.sum(e * e, axis=-1))


def _segment_square(p: Any, q: Any, c: Any, xp: Any) -> Any:
    p, q, c = xp.broadcast_arrays(p, q, c)
    d = q - p
    lo, hi = c - 0.5, c + 0.5
    # Slab test: the parameter interval in which the line is inside each slab.
    safe = xp.where(d == 0, 1.0, d)
    t1, t2 = (lo - p) / safe, (hi - p) / safe
    inside_slab = (p >= lo) & (p <= hi)
    tmin = xp.where(d == 0, xp.where(inside_slab, -xp.inf, xp.inf), xp.minimum(t1, t2))
    tmax = xp.where(d == 0, xp.where(inside_slab, xp.inf, -xp.inf), xp.maximum(t1, t2))
    enter = xp.maximum(xp.max(tmin, axis=-1), 0.0)
    leave = xp.minimum(xp.min(tmax, axis=-1), 1.0)
    meets = enter <= leave
    ends = xp.minimum(_point_square(p, c, xp), _point_square(q, c, xp))
    corners = xp.stack([c + xp.asarray(s, c.dtype) for s in _CORNERS], axis=-2)
    to_corners = xp.min(_point_segment(corners, p[..., None, :], q[..., None, :], xp), axis=-1)
    return xp.where(meets, 0.0, xp.minimum(ends, to_corners))


# JAX twins (inside compiled programs; float32 unless x64 is on).


def point_square_distance(p: jnp.ndarray, c: jnp.ndarray) -> jnp.ndarray:
    """Distance from points ``p [..., 2]`` to the unit squares centred at ``c [..., 2]`` (0 inside)."""
    return _point_square(p, c, jnp)


def point_segment_distance(x: jnp.ndarray, p: jnp.ndarray, q: jnp.ndarray) -> jnp.ndarray:
    """Distance from points ``x [..., 2]`` to the segments ``p``–``q`` (each ``[..., 2]``)."""
    return _point_segment(x, p, q, jnp)


def segment_square_distance(p: jnp.ndarray, q: jnp.ndarray, c: jnp.ndarray) -> jnp.ndarray:
    """Exact distance between segments ``p``–``q`` and unit squares centred at ``c`` (broadcast ``[..., 2]``).

    Zero when the segment meets the closed square; otherwise the minimum is attained
    at an end point of the segment or a corner of the square (both are convex).
    """
    return _segment_square(p, q, c, jnp)


# numpy twins (host side, in the inputs' precision: float64 for the exact metrics).


def point_square_distance_np(p: np.ndarray, c: np.ndarray) -> np.ndarray:
    """`point_square_distance` in numpy."""
    return _point_square(p, c, np)


def point_segment_distance_np(x: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """`point_segment_distance` in numpy."""
    return _point_segment(x, p, q, np)


def segment_square_distance_np(p: np.ndarray, q: np.ndarray, c: np.ndarray) -> np.ndarray:
    """`segment_square_distance` in numpy (broadcast ``[..., 2]``)."""
    return _segment_square(p, q, c, np)


# numba scalar twins (float64 scalars, inside compiled host loops).


@njit(cache=True, nogil=True, inline="always")
def point_segment_distance_nb(x, y, px, py, qx, qy):
    """`point_segment_distance` of the point ``(x, y)`` and the segment ``(px, py)``–``(qx, qy)``."""
    dx, dy = qx - px, qy - py
    dd = dx * dx + dy * dy
    t = 0.0 if dd == 0.0 else min(max(((x - px) * dx + (y - py) * dy) / dd, 0.0), 1.0)
    ex, ey = x - (px + t * dx), y - (py + t * dy)
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True, nogil=True, inline="always")
def point_square_distance_nb(x, y, cx, cy):
    """`point_square_distance` of the point ``(x, y)`` and the unit square centred at ``(cx, cy)``."""
    ex = max(abs(x - cx) - 0.5, 0.0)
    ey = max(abs(y - cy) - 0.5, 0.0)
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True, nogil=True)
def segment_square_distance_nb(px, py, qx, qy, cx, cy):
    """`segment_square_distance` of the segment ``(px, py)``–``(qx, qy)`` and the unit square at ``(cx, cy)``."""
    dx, dy = qx - px, qy - py
    # Slab test: the parameter interval in which the segment is inside both slabs of the square.
    lo_t, hi_t = 0.0, 1.0
    meets = True
    if dx == 0.0:
        meets = cx - 0.5 <= px <= cx + 0.5
    else:
        t1, t2 = (cx - 0.5 - px) / dx, (cx + 0.5 - px) / dx
        lo_t, hi_t = max(lo_t, min(t1, t2)), min(hi_t, max(t1, t2))
    if dy == 0.0:
        meets = meets and cy - 0.5 <= py <= cy + 0.5
    else:
        t1, t2 = (cy - 0.5 - py) / dy, (cy + 0.5 - py) / dy
        lo_t, hi_t = max(lo_t, min(t1, t2)), min(hi_t, max(t1, t2))
    if meets and lo_t <= hi_t:
        return 0.0
    # Both sets are convex: the minimum is at an end point of the segment or a corner of the square.
    best = min(point_square_distance_nb(px, py, cx, cy), point_square_distance_nb(qx, qy, cx, cy))
    for sx in (-0.5, 0.5):
        for sy in (-0.5, 0.5):
            best = min(best, point_segment_distance_nb(cx + sx, cy + sy, px, py, qx, qy))
    return best
