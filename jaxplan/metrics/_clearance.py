"""Clearance of a padded path's vertices from the blocked cells of a map (docs/guide/smoothing-and-metrics.md), in JAX.

The clearance of a point is its distance to the nearest blocked unit square (the map's
outside counts as blocked), in metres. The points measured are the path's **vertices**.
For a raw (integer) grid path they are cell centres, read from the exact centre field:
this is how `path_metrics` measures grid paths, and what the tuner uses inside ``jit``.
Float points go through `jaxplan.grid._collision.point_clearance`, exact within its
2-cell window and beyond it an upper bound (up to √2 cells high) — a static shape cannot
hold an exact search whose reach grows with the answer. `path_metrics` therefore measures
float (smoothed, any-angle, executed) paths on the host, exactly and along their segments
(`jaxplan.metrics._exact_clearance.polyline_clearance`).
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxplan.grid import CollisionMap, point_clearance
from jaxplan.metrics._path import float_dtype

__all__ = ["vertex_clearance", "clearance_metrics"]


def _centre_clearance(cmap: CollisionMap, cells: jnp.ndarray) -> jnp.ndarray:
    """Clearance (cells) of integer points: the exact centre field, 0 outside the map."""
    H, W = cmap.shape
    x, y = cells[..., 0], cells[..., 1]
    inside = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    return jnp.where(inside, cmap.field[jnp.clip(y, 0, H - 1), jnp.clip(x, 0, W - 1)], 0.0)


def vertex_clearance(cmap: CollisionMap, path: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``[..., L]`` clearance (m) of each valid vertex; ``+inf`` on padding.

    Args:
      cmap: the map's `CollisionMap` (its resolution converts cells to metres).
      path: ``[..., L, 2]`` points (cells). An integer path is read from ``cmap.field``, the
        exact clearance of cell centres, which is what `point_clearance` returns there
        (one gather per point instead of its 5x5 window).
      n: ``int[...]`` valid points.

    A vertex outside the map gets 0 (it is in the blocked outside). Float vertices more
    than 2 cells from every blocked square read up to √2 cells high (`point_clearance`);
    `jaxplan.metrics._exact_clearance.exact_point_clearance` is the exact host version.
    """
    path = jnp.asarray(path)
    valid = jnp.arange(path.shape[-2]) < jnp.asarray(n)[..., None]
    if jnp.issubdtype(path.dtype, jnp.integer):
        c = _centre_clearance(cmap, path)
    else:
        # Padding may hold anything (NaN, huge values): measure a harmless point instead.
        p = jnp.asarray(path, float_dtype())
        c = point_clearance(cmap, jnp.where(valid[..., None], p, 0.0))
    return jnp.where(valid, c * cmap.resolution, jnp.inf)


def clearance_metrics(cmap: CollisionMap, path: jnp.ndarray, n: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(min_clearance, mean_clearance)``, each ``[...]`` in metres, over the valid vertices.

    An empty path (``n == 0``) has no vertex near anything: both are ``+inf``.
    """
    c = vertex_clearance(cmap, path, n)
    n = jnp.asarray(n)
    valid = jnp.arange(c.shape[-1]) < n[..., None]
    lo = jnp.min(c, axis=-1, initial=jnp.inf)
    mean = jnp.sum(jnp.where(valid, c, 0.0), axis=-1) / jnp.maximum(n, 1)
    return lo, jnp.where(n > 0, mean, jnp.inf)
