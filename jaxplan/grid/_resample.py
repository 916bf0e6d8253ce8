"""Changing a map's resolution: `resample`.

The rule: the coarse (or fine) grid keeps the map's origin (the outer corner of cell ``(0, 0)``); its cell
``(i, j)`` covers the square ``[i R, (i + 1) R) × [j R, (j + 1) R)`` metres from that corner (``R`` the new
resolution), and is **blocked if any cell of the old map it overlaps (with positive area) is blocked** —
the area beyond the old map counts as blocked, as everywhere in jaxplan, so a last row or column that
sticks out of the old map is blocked. A path on the resampled map therefore crosses only old free cells
(it is conservative: a gap narrower than about two new cells may close). The other layers take the value
that keeps this promise: the speed limit and clearance height their minimum over the overlapped cells,
risk and the turn rule their maximum; terrain height its mean.
"""

from __future__ import annotations

import math

import numpy as np

from jaxplan.grid._gridmap import GridMap, grid_from_array

__all__ = ["resample", "resampled_shape"]

_EPS = 1e-9  # cell edges that agree to 1e-9 cells are the same edge (0.3 / 0.03 is 10.000000000000002)


def resampled_shape(grid: GridMap, resolution: float) -> tuple[int, int]:
    """``(H', W')`` of `resample` ``(grid, resolution)``: enough new cells to cover the old map."""
    r, R = float(grid.resolution), float(resolution)
    H, W = grid.shape
    return (max(1, math.ceil(H * r / R - _EPS)), max(1, math.ceil(W * r / R - _EPS)))


def _ranges(n_old: int, n_new: int, ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """For each new cell along one axis, the old cells ``[lo, hi)`` it overlaps (``hi`` may exceed ``n_old``)."""
    i = np.arange(n_new, dtype=np.float64)
    lo = np.floor(i * ratio + _EPS).astype(np.int64)
    hi = np.ceil((i + 1) * ratio - _EPS).astype(np.int64)
    return lo, np.maximum(hi, lo + 1)


def _reduce(a: np.ndarray, lo: np.ndarray, hi: np.ndarray, axis: int, op: str, outside: float | None) -> np.ndarray:
    """Reduces ``a`` along ``axis`` over each range ``[lo, hi)`` with ``op`` (any/min/max/mean); indices
    beyond the array read ``outside`` (None: ignored)."""
    n = a.shape[axis]
    span = int(np.max(hi - lo))
    parts, masks = [], []
    for t in range(span):  # at most ceil(R / r) + 1 offsets: a short loop over whole arrays
        idx = lo + t
        inside = (idx < hi) & (idx < n)
        taken = np.take(a, np.minimum(idx, n - 1), axis=axis)
        shape = [1] * a.ndim
        shape[axis] = len(lo)
        parts.append(taken)
        masks.append(np.broadcast_to(inside.reshape(shape), taken.shape))
        if outside is not None:
            beyond = ((idx < hi) & (idx >= n)).reshape(shape)
            parts[-1] = np.where(beyond, outside, taken)
            masks[-1] = np.broadcast_to((idx < hi).reshape(shape), taken.shape)
    stack, mask = np.stack(parts), np.stack(masks)
    if op == "any":
        return np.any(stack & mask, axis=0)
    if op == "min":
        return np.min(np.where(mask, stack, np.inf), axis=0).astype(a.dtype)
    if op == "max":
        return np.max(np.where(mask, stack, -np.inf), axis=0).astype(a.dtype)
    return (np.sum(np.where(mask, stack, 0.0), axis=0) / np.maximum(mask.sum(axis=0), 1)).astype(a.dtype)


def _layer(a: np.ndarray, ranges: tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]], op: str,
           outside: float | None = None) -> np.ndarray:
    (ylo, yhi), (xlo, xhi) = ranges
    return _reduce(_reduce(a, xlo, xhi, 1, op, outside), ylo, yhi, 0, op, outside)


def resample(grid: GridMap, resolution: float) -> GridMap:
    """``grid`` at ``resolution`` metres per cell (coarser or finer), by the module's rule: a new cell is
    blocked if any old cell it overlaps is. Origin, and so world coordinates, are unchanged.

    Args:
      grid: the map.
      resolution: the new metres per cell, finite and > 0.

    Returns:
      A `GridMap` of `resampled_shape` cells; the same map (every layer equal) if ``resolution`` equals
      ``grid.resolution``.
    """
    R = float(resolution)
    if not math.isfinite(R) or R <= 0:
        raise ValueError(f"resolution must be a finite number of metres per cell > 0, got {resolution!r}")
    r = float(grid.resolution)
    if R == r:
        return grid
    H, W = grid.shape
    H2, W2 = resampled_shape(grid, R)
    ratio = R / r
    ranges = (_ranges(H, H2, ratio), _ranges(W, W2, ratio))
    blocked = _layer(~np.asarray(grid.free, bool), ranges, "any", outside=True)
    speed = None if grid.speed_limit is None else _layer(np.asarray(grid.speed_limit), ranges, "min")
    return grid_from_array(
        ~blocked, resolution=R, origin=grid.origin, speed_limit=speed,
        height=_layer(np.asarray(grid.height), ranges, "mean"),
        risk=_layer(np.asarray(grid.risk), ranges, "max"),
        clearance_height=_layer(np.asarray(grid.clearance_height), ranges, "min"),
        turn_rule=_layer(np.asarray(grid.turn_rule), ranges, "max"),
    )
