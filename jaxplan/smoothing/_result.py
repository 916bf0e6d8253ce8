"""What every smoother returns, and the compaction of padded point arrays."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jax.typing import ArrayLike

__all__ = ["Smoothed", "compact", "drop_repeats"]


class Smoothed(NamedTuple):
    """A smoothed path and a report of what the smoother changed. A pytree; batch axes lead.

    Attributes:
      points: ``f32[M, 2]`` cell coordinates (x, y); slots from ``n`` on repeat the last point.
      n: ``i32`` valid points.
      removed: ``i32`` input vertices that are not in the output (pruning), or corners
        replaced by a curve (curve smoothers).
      fallbacks: ``i32`` places where the smoothed geometry would have come closer to a
        blocked cell than allowed and the unsmoothed path was kept there instead
        (corners kept sharp, spline spans pinned to the polyline, or the whole path
        when the result would have had more sharp turns than the input).
      max_curvature: ``f32`` analytic maximum curvature of the curve pieces in 1/m (0 for a
        polyline; the kinks a polyline keeps are not counted — use the discrete metric).
      input_free: ``bool`` whether the input polyline itself passed the collision check;
        when it did not, the input is returned unchanged.
    """

    # ArrayLike: JAX arrays from the smoothers, NumPy arrays (a batch) or Python numbers (one path) from `smooth`.
    points: ArrayLike
    n: ArrayLike
    removed: ArrayLike
    fallbacks: ArrayLike
    max_curvature: ArrayLike
    input_free: ArrayLike


def compact(points: jnp.ndarray, keep: jnp.ndarray, size: int | None = None) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Moves the kept rows of ``points [L, 2]`` to the front, in order.

    Returns ``(out [size, 2], m)`` with ``m`` kept rows; rows from ``m`` on repeat the last
    kept row, so padding adds zero-length segments only. ``size`` defaults to ``L``.
    """
    L = points.shape[0]
    size = L if size is None else size
    rank = jnp.cumsum(keep.astype(jnp.int32))  # rank[i] = kept rows up to and including i
    m = rank[-1]
    slot = jnp.arange(size)
    src = jnp.searchsorted(rank, jnp.minimum(slot, jnp.maximum(m - 1, 0)) + 1, side="left")
    return points[jnp.clip(src, 0, L - 1)], m


def drop_repeats(points: jnp.ndarray, n: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Removes consecutive repeated points of a padded path (``[L, 2]``, ``n`` valid)."""
    i = jnp.arange(points.shape[0])
    same = jnp.all(points[1:] == points[:-1], axis=-1)
    keep = (i < n) & jnp.concatenate([jnp.array([True]), ~same])
    return compact(points, keep)
