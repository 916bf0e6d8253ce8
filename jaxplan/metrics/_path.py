"""Geometry metrics of padded paths (docs/guide/smoothing-and-metrics.md): length, heading changes, turns, smoothness,
curvature.

A path is ``[..., L, 2]`` points ``(x, y)`` in cell coordinates (integers for raw grid
paths, floats for smoothed or any-angle paths) of which the first ``n [...]`` are valid;
the rest is padding and never reaches a result. Lengths come back in metres (times the
map's resolution), angles in radians, curvature in 1/m. Extra leading axes are batch
axes; every public function is pure, shape-static, and works under ``jit`` and ``vmap``.

Repeated points (zero-length segments) carry no heading, so they are skipped: the
heading change at a vertex is taken between the previous and the next segment of
non-zero length.

Angles come from ``atan2(|cross|, dot)`` of the two segment vectors rather than from a
difference of two headings: for integer paths the cross and dot products are exact, so
a straight run gives exactly 0 and the 45° test is decided exactly.

The definitions are written once against an array module ``xp``: `jax.numpy` here, and
`numpy` (float64, no compilation) for the one-path host functions of
`jaxplan.metrics._host`, which planners call once per path, where a compiled call would
cost more than the metric.

Example:
  >>> import jax.numpy as jnp
  >>> from jaxplan.metrics import count_turns_padded
  >>> int(count_turns_padded(jnp.array([[0, 0], [1, 0], [1, 1], [0, 0]]), 3))
  1
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "TURN_EPS", "SHARP_TURN", "SHARP_TOL", "float_dtype", "segments", "vertex_turns", "path_length_padded",
    "count_turns_padded", "count_sharp_turns_padded", "smoothness_padded", "max_curvature_padded",
    "geometry_metrics",
]

TURN_EPS = 1e-6
"""A vertex is a turn when its heading change exceeds this (rad)."""

SHARP_TURN = math.pi / 4
"""A turn is sharp when its heading change is at least this (rad): 45°."""

SHARP_TOL = 1e-9
"""Tolerance (rad) below 45° still counted sharp, so an exact 45° turn is never lost to rounding."""

Arr = Any
"""A NumPy or a JAX array: the private helpers below run on both (``xp``), for the host twins and the batch."""

# tan of the sharp threshold: `h >= 45° - tol`  <=>  `dot <= 0 or |cross| >= dot * tan(45° - tol)`.
# In float32 this is exactly 1.0 (the tolerance is below float32 resolution), so a grid
# path's 45° turn, whose |cross| equals its dot exactly, is always sharp.
_SHARP_TAN = math.tan(SHARP_TURN - SHARP_TOL)


def float_dtype(xp: ModuleType = jnp) -> Any:
    """The float type of the computation: float64 for numpy; for JAX float32, or float64 with
    ``jax_enable_x64``."""
    return np.float64 if xp is np else jnp.zeros((), float).dtype


def _cummax(xp: ModuleType, a: Arr) -> Arr:
    if xp is np:
        return np.maximum.accumulate(a, axis=-1)
    return jax.lax.cummax(a, axis=a.ndim - 1)


def _take(xp: ModuleType, a: Arr, idx: Arr) -> Arr:
    """``a[..., idx[..., i]]`` along the last axis (plain indexing for one numpy path: numpy's
    take_along_axis costs several times more than the arithmetic around it)."""
    if xp is np and a.ndim == 1:
        return a[idx]
    return xp.take_along_axis(a, idx, axis=-1)


def _segments(path: Arr, n: Arr, xp: ModuleType) -> tuple[Arr, ...]:
    """``(dx, dy, length, moving)``, each ``[..., L-1]``: segment vectors (0 on padding), lengths,
    and valid segments of non-zero length. Components rather than ``[..., 2]`` pairs: no
    reductions over a size-2 axis, which cost numpy more than the arithmetic."""
    p = xp.asarray(path, float_dtype(xp))
    n = xp.asarray(n)
    valid = xp.arange(p.shape[-2] - 1) < (n[..., None] - 1) if p.shape[-2] else xp.zeros(p.shape[:-2] + (0,), bool)
    # Padding (possibly NaN or huge) never reaches a result.
    dx = xp.where(valid, p[..., 1:, 0] - p[..., :-1, 0], 0.0)
    dy = xp.where(valid, p[..., 1:, 1] - p[..., :-1, 1], 0.0)
    length = xp.sqrt(dx * dx + dy * dy)
    return dx, dy, length, valid & (length > 0)


def _turn_terms(dx: Arr, dy: Arr, moving: Arr, xp: ModuleType) -> tuple[Arr, ...]:
    """Per segment ``i``: the previous moving segment's index and vector, the cross and dot
    products with segment ``i``, the heading change, and ``vertex`` (both segments exist).
    Entries with ``vertex`` False are unspecified (finite); callers mask them."""
    last = _cummax(xp, xp.where(moving, xp.arange(moving.shape[-1]), -1))
    # The previous moving segment of segment i is the last one strictly before i.
    prev = xp.concatenate([xp.full(last.shape[:-1] + (1,), -1, last.dtype), last[..., :-1]], axis=-1)
    prev = prev[..., : last.shape[-1]]  # no segment, no entry
    vertex = moving & (prev >= 0)
    at = xp.maximum(prev, 0)
    px, py = _take(xp, dx, at), _take(xp, dy, at)
    cross = px * dy - py * dx
    dot = px * dx + py * dy
    return at, px, py, cross, dot, xp.arctan2(xp.abs(cross), dot), vertex


def _vertex_turns(path: Arr, n: Arr, xp: ModuleType) -> tuple[Arr, ...]:
    dx, dy, length, moving = _segments(path, n, xp)
    at, px, py, cross, dot, heading, vertex = _turn_terms(dx, dy, moving, xp)
    prev_len = _take(xp, length, at)
    sx, sy = px + dx, py + dy
    chord = xp.sqrt(sx * sx + sy * sy)
    zero = lambda a: xp.where(vertex, a, 0.0)  # noqa: E731
    return zero(heading), zero(cross), zero(dot), zero(prev_len), zero(length), zero(chord), vertex


def _sharp(cross: Arr, dot: Arr, vertex: Arr, xp: ModuleType) -> Arr:
    # Decided on the products rather than the angle: exact for integer paths (see _SHARP_TAN).
    return vertex & ((dot <= 0) | (xp.abs(cross) >= dot * _SHARP_TAN))


def _smoothness(heading: Arr, vertex: Arr, xp: ModuleType) -> Arr:
    count = xp.sum(vertex, axis=-1)
    mean = xp.sum(xp.where(vertex, heading, 0.0), axis=-1) / xp.maximum(count, 1)
    return xp.where(count > 0, 1.0 - mean / math.pi, 1.0)


def _menger(cross: Arr, prev_len: Arr, next_len: Arr, chord: Arr, vertex: Arr, xp: ModuleType) -> Arr:
    # Menger curvature 4·area/(a·b·c) with area = |cross|/2. The three points are distinct
    # except when the path folds back onto its previous point (chord 0): skipped (0).
    denom = prev_len * next_len * chord
    ok = vertex & (denom > 0)
    return xp.where(ok, 2.0 * xp.abs(cross) / xp.where(ok, denom, 1.0), 0.0)


def _turn_metrics(cross: Arr, dot: Arr, heading: Arr, vertex: Arr, which: tuple[str, ...], xp: ModuleType) -> dict:
    rules = {
        "turns": lambda: xp.sum(vertex & (heading > TURN_EPS), axis=-1, dtype=xp.int32),
        "sharp_turns": lambda: xp.sum(_sharp(cross, dot, vertex, xp), axis=-1, dtype=xp.int32),
        "smoothness": lambda: _smoothness(heading, vertex, xp),
    }
    return {k: rules[k]() for k in which}


TURN_METRICS = ("turns", "sharp_turns", "smoothness")


def _turn_counts(path: Arr, n: Arr, xp: ModuleType, which: tuple[str, ...] = TURN_METRICS) -> dict:
    """The turn metrics named in ``which`` only (a planner filling `PlanResult.turns` on the
    host wants just one of them, and numpy pays per operation)."""
    dx, dy, _, moving = _segments(path, n, xp)
    _, _, _, cross, dot, heading, vertex = _turn_terms(dx, dy, moving, xp)
    return _turn_metrics(cross, dot, heading, vertex, which, xp)


def _geometry(path: Arr, n: Arr, resolution: float | Arr, xp: ModuleType) -> dict:
    dx, dy, length, moving = _segments(path, n, xp)
    at, px, py, cross, dot, heading, vertex = _turn_terms(dx, dy, moving, xp)
    sx, sy = px + dx, py + dy
    kappa = _menger(cross, _take(xp, length, at), length, xp.sqrt(sx * sx + sy * sy), vertex, xp)
    return {
        "length": xp.sum(length, axis=-1) * resolution,
        **_turn_metrics(cross, dot, heading, vertex, TURN_METRICS, xp),
        "max_curvature": xp.max(kappa, axis=-1, initial=0.0) / resolution,
    }


def segments(path: jnp.ndarray, n: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """Segment vectors of a padded path and which of them count.

    Args:
      path: ``[..., L, 2]`` points (cells).
      n: ``int[...]`` valid points.

    Returns:
      ``d [..., L-1, 2]`` segment vectors ``p[i+1] - p[i]`` (cells, float, 0 on padding),
      ``length [..., L-1]`` their lengths, and ``moving bool[..., L-1]``: valid segments
      of non-zero length.
    """
    dx, dy, length, moving = _segments(path, n, jnp)
    return jnp.stack([dx, dy], axis=-1), length, moving


def vertex_turns(path: jnp.ndarray, n: jnp.ndarray) -> tuple[jnp.ndarray, ...]:
    """Heading changes at the interior vertices of a padded path, repeated points skipped.

    Entry ``i`` describes the vertex at the start of segment ``i``: the turn from the last
    earlier segment of non-zero length to segment ``i``.

    Args:
      path: ``[..., L, 2]`` points (cells).
      n: ``int[...]`` valid points.

    Returns:
      A tuple ``(heading, cross, dot, prev_len, next_len, chord, vertex)``, each ``[..., L-1]``:
      the heading change (rad, in [0, π]); the cross and dot products of the two segment
      vectors (cells²); the lengths of the previous and next segment and the chord from
      the previous distinct point to the next (cells); and ``vertex``, True where a heading
      change is defined (both segments exist). Entries with ``vertex`` False hold zeros.
    """
    return _vertex_turns(path, n, jnp)


def path_length_padded(path: jnp.ndarray, n: jnp.ndarray, resolution: float | jnp.ndarray = 1.0) -> jnp.ndarray:
    """``[...]`` summed segment lengths in metres (0 for fewer than 2 points).

    Args:
      path: ``[..., L, 2]`` points (cells).
      n: ``int[...]`` valid points.
      resolution: metres per cell.
    """
    return jnp.sum(_segments(path, n, jnp)[2], axis=-1) * resolution


def count_turns_padded(path: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` vertices whose heading change exceeds `TURN_EPS` (0 for fewer than 3 points)."""
    return _turn_counts(path, n, jnp, ("turns",))["turns"]


def count_sharp_turns_padded(path: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``int32[...]`` vertices whose heading change is at least 45° (less `SHARP_TOL`)."""
    return _turn_counts(path, n, jnp, ("sharp_turns",))["sharp_turns"]


def smoothness_padded(path: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """``[...]`` ``1 − mean|Δheading|/π`` over interior vertices, in [0, 1].

    1 for a straight path and for a path with no interior vertex (fewer than 3 distinct points).
    """
    return _turn_counts(path, n, jnp, ("smoothness",))["smoothness"]


def max_curvature_padded(path: jnp.ndarray, n: jnp.ndarray, resolution: float | jnp.ndarray = 1.0) -> jnp.ndarray:
    """``[...]`` largest discrete (Menger) curvature in 1/m over interior vertices.

    The curvature at a vertex is the inverse radius of the circle through it and the
    previous and next distinct points: ``4·area / (a·b·c)`` of their triangle. Points on a
    circle of radius R give exactly 1/R; three collinear points give 0 (so does a path
    that folds back onto its previous point; its heading change of π is counted by the
    turn metrics). 0 for fewer than 3 distinct points. Smoothers report the analytic
    curvature of their curves themselves; this is the metric for vertex lists.
    """
    return _geometry(path, n, resolution, jnp)["max_curvature"]


def geometry_metrics(path: jnp.ndarray, n: jnp.ndarray, resolution: float | jnp.ndarray = 1.0) -> dict:
    """All geometry metrics of a padded path from one pass over its vertices.

    Args:
      path: ``[..., L, 2]`` points (cells).
      n: ``int[...]`` valid points.
      resolution: metres per cell.

    Returns:
      dict of ``[...]`` arrays: ``length`` (m), ``turns`` and ``sharp_turns`` (int32),
      ``smoothness``, ``max_curvature`` (1/m), as defined by the functions above.
    """
    return _geometry(path, n, resolution, jnp)
