"""Vertex pruning: line-of-sight node reduction (yu2020) and key-node guidance (li2026).

Both walk the path once, keeping an anchor (the last kept vertex) and deciding for
each interior vertex whether the path may go straight from the anchor to the next
vertex instead. The output's vertices are a subset of the input's, so every
output segment is checked against the map with the exact segment test of
`jaxplan.grid._collision`.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp

from jaxplan.grid import CollisionMap, polyline_free, segment_free
from jaxplan.metrics import count_sharp_turns_padded as sharp_turn_count
from jaxplan.smoothing._result import Smoothed, compact

__all__ = ["los_prune", "key_nodes"]


def _prune(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, radius: float, min_turn: float | None) -> Smoothed:
    points = jnp.asarray(points, jnp.float32)
    L = points.shape[0]
    last = jnp.maximum(n - 1, 0)

    def step(anchor, j):
        interior = (j >= 1) & (j < last)
        p, nxt = points[j], points[jnp.minimum(j + 1, last)]
        # A padded or end vertex tests a zero-length segment, which costs one window.
        visible = segment_free(cmap, anchor, jnp.where(interior, nxt, anchor), radius)
        drop = interior & visible
        if min_turn is not None:
            a, b = p - anchor, nxt - p
            cos = jnp.sum(a * b) / jnp.maximum(jnp.linalg.norm(a) * jnp.linalg.norm(b), 1e-30)
            undefined = (jnp.linalg.norm(a) == 0) | (jnp.linalg.norm(b) == 0)
            small = undefined | (jnp.arccos(jnp.clip(cos, -1.0, 1.0)) < min_turn)
            drop = drop & small
        keep = (j <= last) & ~drop
        return jnp.where(keep, p, anchor), keep

    _, keep = jax.lax.scan(step, points[0], jnp.arange(L))
    out, m = compact(points, keep)
    free_in = jnp.all(polyline_free(cmap, points, n, radius))
    worse = sharp_turn_count(out, m) > sharp_turn_count(points, n)
    back = worse | ~free_in
    return Smoothed(
        points=jnp.where(back, points, out), n=jnp.where(back, n, m), removed=jnp.where(back, 0, n - m),
        fallbacks=worse.astype(jnp.int32), max_curvature=jnp.float32(0.0), input_free=free_in,
    )


def los_prune(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, radius: float = 0.0) -> Smoothed:
    """Line-of-sight node reduction: drops each vertex the path can cut straight past.

    From the anchor (the last kept vertex), vertex ``j`` is dropped while the segment from
    the anchor to vertex ``j + 1`` stays ``radius`` cells (static) from every blocked
    square. The result is never longer than the input (triangle inequality) and is
    collision-free whenever the input is. If it would have more sharp turns (>= 45°) than
    the input, the input is returned (``fallbacks = 1``).

    Args:
      cmap: the map's `CollisionMap`.
      points: ``f32[L, 2]`` padded path in cell coordinates.
      n: valid points.
      radius: the robot's inflation radius in cells (static).
    """
    return _prune(cmap, points, n, radius, None)


def key_nodes(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, threshold: float = math.radians(20.0),
              radius: float = 0.0) -> Smoothed:
    """Key-node guidance (li2026): keeps the vertices where the path turns by ``threshold`` or more.

    The heading change of vertex ``j`` is measured between the direction from the last
    kept key node to ``j`` and the direction from ``j`` to ``j + 1``, so slow drifts add up
    instead of being dropped one small step at a time. A vertex whose removal would make
    the segment from the last key node collide is kept as well. Same fallback as
    `los_prune`. The kept vertices are the sub-goals a local planner tracks.

    Args:
      threshold: radians (static; 20° as in li2026).
    """
    return _prune(cmap, points, n, radius, float(threshold))
