"""`path_metrics`: the path metrics (docs/guide/smoothing-and-metrics.md) for one path or a padded batch, in one
compiled call.

The host side validates the input (the compiled core cannot raise), pads the path length
up to a power of two so that one compilation serves every length in a bucket, and calls
two jitted cores: the per-path geometry and (grid paths') clearance metrics, and — only
with a reference — the Hausdorff distance; a float path's clearance is measured along its
segments on the host (`jaxplan.metrics._exact_clearance`). Compiled functions are cached by
JAX per input shape, so a second call with the same ``(B, L-bucket)`` and map shape does not trace again.
"""

from __future__ import annotations

import functools
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.grid import CollisionMap, GridMap, cached_collision_map, shortest_lengths
from jaxplan.metrics._clearance import clearance_metrics
from jaxplan.metrics._exact_clearance import polyline_clearance
from jaxplan.metrics._path import geometry_metrics
from jaxplan.metrics._polyline import HAUSDORFF_SAMPLES, hausdorff_bounds
from jaxplan.metrics._result import PATH_METRICS, PathMetrics

__all__ = ["path_metrics", "PATH_METRICS", "PathMetrics", "bucket"]

MIN_BUCKET = 4


def bucket(length: int) -> int:
    """The padded length for ``length`` points: the next power of two, at least `MIN_BUCKET`."""
    return max(MIN_BUCKET, 1 << max(int(length) - 1, 0).bit_length())


@functools.partial(jax.jit, static_argnames="clearance")
def _core(cmap: CollisionMap, paths: jnp.ndarray, n: jnp.ndarray, clearance: bool = True) -> dict:
    """Geometry and (with ``clearance``, static) vertex clearance metrics of ``paths [B, L, 2]``
    with ``n [B]`` valid points. `path_metrics` measures float paths' clearance on the host instead."""
    out = geometry_metrics(paths, n, cmap.resolution)
    if clearance:
        out["min_clearance"], out["mean_clearance"] = clearance_metrics(cmap, paths, n)
    return out


@functools.partial(jax.jit, static_argnames="samples")
def _hausdorff_core(paths: jnp.ndarray, n: jnp.ndarray, refs: jnp.ndarray, n_ref: jnp.ndarray,
                    resolution: jnp.ndarray, samples: int) -> jnp.ndarray:
    """``[B]`` Hausdorff lower bounds of ``paths [B, L, 2]`` against ``refs [B, R, 2]``."""
    return hausdorff_bounds(paths, n, refs, n_ref, resolution, samples)[0]


def _as_points(a: ArrayLike, what: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ValueError(f"{what} must hold numbers, got dtype {arr.dtype}")
    if arr.ndim not in (2, 3) or arr.shape[-1] != 2:
        raise ValueError(f"{what} must have shape [L, 2] or [B, L, 2], got {arr.shape}")
    return arr


def _counts(n: ArrayLike | None, B: int, L: int, single: bool, what: str) -> np.ndarray:
    if n is None:
        return np.full(B, L, np.int64)
    arr = np.asarray(n)
    if not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(f"{what} must be integers, got dtype {arr.dtype}")
    arr = arr.reshape(1) if (single and arr.ndim == 0) else arr
    if arr.shape != (B,):
        raise ValueError(f"{what} must have shape {'[] or [1]' if single else f'[{B}]'}, got {np.shape(n)}")
    if np.any(arr < 0) or np.any(arr > L):
        raise ValueError(f"{what} must lie in [0, {L}] (the padded length), got {arr.min()}..{arr.max()}")
    return arr.astype(np.int64)


def _check_finite(points: np.ndarray, n: np.ndarray, what: str) -> None:
    if np.issubdtype(points.dtype, np.integer):
        return
    valid = np.arange(points.shape[1])[None, :] < n[:, None]
    bad = valid & ~np.isfinite(points).all(axis=-1)
    if bad.any():
        b, i = np.argwhere(bad)[0]
        where = f"point {i}" if points.shape[0] == 1 else f"path {b}, point {i}"
        raise ValueError(f"{what} has NaN or infinite coordinates ({where}: {points[b, i].tolist()})")


def _pad(points: np.ndarray, length: int) -> np.ndarray:
    """``[B, L, 2]`` -> ``[B, length, 2]``, padding with zeros; NaN in the padding is zeroed too."""
    out = np.zeros((points.shape[0], length, 2), points.dtype)
    out[:, : points.shape[1]] = points
    if np.issubdtype(out.dtype, np.floating):
        out[~np.isfinite(out)] = 0.0
    return out


def _is_grid_path(paths: np.ndarray, n: np.ndarray) -> bool:
    """Integer points whose every valid step moves to one of the 8 neighbours (or stays)."""
    if not np.issubdtype(paths.dtype, np.integer):
        return False
    step = np.abs(np.diff(paths.astype(np.int64), axis=1)).max(axis=-1)  # [B, L-1]
    valid = np.arange(step.shape[1])[None, :] < (n[:, None] - 1)
    return bool(np.all(step[valid] <= 1))


def _check_grid_moves(free: np.ndarray, paths: np.ndarray, n: np.ndarray) -> None:
    """Raises unless every valid point of the integer ``paths [B, L, 2]`` is a free cell and every
    diagonal step keeps both orthogonal neighbours free (the move rule, `jaxplan.grid._neighbours`).

    The octile optimum is only a lower bound for paths made of legal moves: a path through a
    blocked cell or across a blocked corner can be shorter, and its gap would read negative.
    """
    H, W = free.shape
    B, L = paths.shape[:2]
    p = paths.astype(np.int64)
    x, y = p[..., 0], p[..., 1]
    inside = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    ok = inside & free[np.clip(y, 0, H - 1), np.clip(x, 0, W - 1)]
    valid = np.arange(L)[None, :] < n[:, None]

    def where(b: int) -> str:
        return "path" if B == 1 else f"path {b}"

    bad = valid & ~ok
    if bad.any():
        b, i = np.argwhere(bad)[0]
        what = "outside the map" if not inside[b, i] else "a blocked cell"
        if i == 0:
            raise ValueError(f"{where(b)} starts at {p[b, 0].tolist()}, {what}; pass optimal= explicitly")
        raise ValueError(f"{where(b)} step {i - 1}, {p[b, i - 1].tolist()} -> {p[b, i].tolist()}, enters "
                         f"{p[b, i].tolist()}, {what}; pass optimal= explicitly")
    if L < 2:
        return
    d = np.diff(p, axis=1)  # [B, L-1, 2]
    diag = (np.abs(d) == 1).all(axis=-1) & (np.arange(L - 1)[None, :] < (n[:, None] - 1))
    # Both orthogonal neighbours of a diagonal step: (x + dx, y) and (x, y + dy), inside the map here.
    x0, y0 = np.clip(x[:, :-1], 0, W - 1), np.clip(y[:, :-1], 0, H - 1)
    side_x = free[y0, np.clip(x0 + d[..., 0], 0, W - 1)]
    side_y = free[np.clip(y0 + d[..., 1], 0, H - 1), x0]
    cut = diag & ~(side_x & side_y)
    if cut.any():
        b, i = np.argwhere(cut)[0]
        a = p[b, i]
        corner = [int(a[0] + d[b, i, 0]), int(a[1])] if not side_x[b, i] else [int(a[0]), int(a[1] + d[b, i, 1])]
        raise ValueError(f"{where(b)} step {i}, {a.tolist()} -> {p[b, i + 1].tolist()}, cuts a corner of blocked "
                         f"cell {corner} (no corner cutting); pass optimal= explicitly")


def _optimal(grid: GridMap, paths: np.ndarray, n: np.ndarray, optimal: ArrayLike | None,
             single: bool) -> np.ndarray | None:
    """``f64[B]`` optimal lengths (m), or None when there is no sound reference."""
    B = paths.shape[0]
    if optimal is not None:
        opt = np.asarray(optimal, dtype=np.float64)
        if opt.ndim == 0:
            opt = np.full(B, float(opt))
        if opt.shape != (B,):
            raise ValueError(f"optimal must be a number{'' if single else f' or have shape [{B}]'}, got shape "
                             f"{np.shape(optimal)}")
        # 0 stays legal: it is the optimum of a start = goal scenario (gap 0 for a path that stays).
        bad = ~np.isfinite(opt) | (opt < 0)
        if bad.any():
            raise ValueError(f"optimal must be finite and >= 0 (metres), got {opt[bad][0]}")
        return opt
    if not _is_grid_path(paths, n):
        return None
    _check_grid_moves(np.asarray(grid.free, bool), paths, n)
    opt = np.full(B, np.inf)
    has = n > 0
    if has.any():
        idx = np.flatnonzero(has)
        starts, goals = paths[idx, 0], paths[idx, n[idx] - 1]
        # Legal moves join the ends, so every optimum here is finite.
        opt[idx] = shortest_lengths(grid, starts, goals, connectivity=8)
    return opt


def _gap(length: np.ndarray, opt: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``length / optimal − 1``; 0 for 0/0 (start = goal), inf for x/0 and for empty paths."""
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = length / opt - 1.0
    gap = np.where(opt == 0, np.where(length == 0, 0.0, np.inf), gap)
    return np.where(n == 0, np.inf, gap)


def path_metrics(
    path: ArrayLike,
    grid: GridMap,
    reference: ArrayLike | None = None,
    optimal: ArrayLike | None = None,
    n: ArrayLike | None = None,
    *,
    reference_n: ArrayLike | None = None,
    hausdorff_samples: int = HAUSDORFF_SAMPLES,
    cost: ArrayLike | None = None,
    objective_optimum: ArrayLike | None = None,
) -> PathMetrics:
    """The path metrics (docs/guide/smoothing-and-metrics.md) for one path or a padded batch of paths.

    Args:
      path: ``[L, 2]`` one path, or ``[B, L, 2]`` a batch, of points ``(x, y)`` in cell
        coordinates: integers for raw grid paths, floats for smoothed or any-angle paths.
      grid: the map (its resolution turns cells into metres; its blocked cells give clearance).
      reference: optional path to compare with (cells): ``[R, 2]`` (shared by a whole
        batch) or ``[B, R, 2]``.
      optimal: optional optimal length(s) in metres, a number or ``[B]``, finite and ``>= 0``
        (0 for a start = goal scenario).
      n: ``int[B]`` (or a number for one path) valid points per path; default: all ``L``.
      reference_n: ``int[B]`` valid points per reference (for a padded ``[B, R, 2]``);
        default: all ``R``.
      hausdorff_samples: points per segment for the Hausdorff distance (static; see
        `jaxplan.metrics.hausdorff_bounds`).
      cost, objective_optimum: opt-in, together: the planner's own cost of each path (a number or
        ``[B]``, e.g. `PlanResult.cost` or `jaxplan.search.path_objective`) and the exact minimum of
        that cost (`jaxplan.search.exact_objective`); the result then also holds ``objective_gap``.

    Returns:
      `PathMetrics`, a field per metric (`PATH_METRICS`, then ``objective_gap``). For one path the values are
      Python ``float`` / ``int`` (or None), for a batch ``np.ndarray [B]`` (or None):

      * ``length`` (m), ``turns`` (heading change > 1e-6 rad), ``sharp_turns`` (>= 45°),
        ``smoothness`` (1 − mean|Δheading|/π), ``max_curvature`` (1/m, Menger, at the
        vertices) — see `jaxplan.metrics._path`; repeated points are skipped;
      * ``min_clearance``, ``mean_clearance`` (m), exact distances to the nearest blocked
        square (the outside counts). The dtype decides where they are measured: an
        integer (raw grid) path at its vertices, the cell centres — minimum and plain mean
        over the vertices; a float (smoothed, any-angle, executed) path along its
        segments — the minimum over the whole polyline, and the mean weighted by arc
        length (∫ clearance ds / length, midpoint rule on pieces of at most 1/4 cell, see
        `jaxplan.metrics._exact_clearance`), so a line-of-sight path with few vertices
        still sees the obstacle its long segment passes, and sparse and dense samplings of
        one curve agree. A float path without length reads its point's clearance;
      * ``hausdorff`` (m) between the path and ``reference`` as polylines (a lower bound
        within ``segment/(2·hausdorff_samples)`` of the exact value, usually exact); None
        without a reference;
      * ``optimality_gap`` = length / optimal − 1 with ``optimal`` as given; without it,
        for integer raw grid paths (every step to one of the 8 neighbours, or staying) the
        optimum is `jaxplan.shortest_lengths` between each path's ends (8-connected,
        octile, no corner cutting), and each step must be a legal move on the map; for any
        other path None — a smoothed or any-angle path must be compared with the same
        smoothing of the exact path (docs/guide/smoothing-and-metrics.md), so pass it. A
        start = goal path has gap 0.
      * ``objective_gap`` (only with ``cost`` and ``objective_optimum``) = cost / objective_optimum − 1:
        how far the path is from the optimum of its planner's own objective (IACO's fitness, the risk
        cost, ...), beside the length gap; the same 0/0 and empty-path rules; None without them.

      Degenerate paths: with no point or one point, length 0, turns 0, sharp turns 0,
      smoothness 1, curvature 0; with no point, clearances, Hausdorff distance and
      optimality gap are ``inf`` (nothing was planned). Values are float32-precise
      (relative ~1e-6: an optimal path's gap may read ±1e-7).

    Raises:
      ValueError: a path or reference of the wrong shape or dtype, NaN or infinite
        coordinates among the valid points, ``n`` outside ``[0, L]``, a negative, infinite
        or NaN ``optimal``, an empty reference, or (automatic gap) a grid path with a point
        on a blocked cell or outside the map, or a diagonal step that cuts a blocked corner
        (the message names the step).

    The compiled cores (`jit`) see the paths padded to a power-of-two length, so each
    ``(B, bucket(L))`` and map shape compiles once. Called directly inside ``jit``, they
    cannot raise: NaN coordinates propagate into length, smoothness and curvature, and
    turns compare false.

    Example:
      >>> import numpy as np, jaxplan as jp
      >>> grid = jp.grid_from_array(np.ones((4, 4), bool), resolution=0.5)
      >>> m = jp.metrics.path_metrics(np.array([[0, 0], [1, 1], [2, 1]]), grid)
      >>> round(m.length, 4), m.turns, m.sharp_turns, round(m.optimality_gap, 6)
      (1.2071, 1, 1, 0.0)
    """
    paths = _as_points(path, "path")
    single = paths.ndim == 2
    if single:
        paths = paths[None]
    B, L = paths.shape[0], paths.shape[1]
    counts = _counts(n, B, L, single, "n")
    _check_finite(paths, counts, "path")
    if hausdorff_samples < 1:
        raise ValueError(f"hausdorff_samples must be >= 1, got {hausdorff_samples}")

    refs = ref_counts = None
    if reference is not None:
        refs = _as_points(reference, "reference")
        if refs.ndim == 2:
            refs = np.broadcast_to(refs[None], (B,) + refs.shape)
        elif single or refs.shape[0] != B:
            raise ValueError(f"reference must have shape [R, 2]{'' if single else f' or [{B}, R, 2]'} to match the "
                             f"path's {paths.shape if not single else paths.shape[1:]}, got {np.shape(reference)}")
        ref_counts = _counts(reference_n, B, refs.shape[1], single, "reference_n")
        _check_finite(refs, ref_counts, "reference")
        if (ref_counts == 0).any():
            raise ValueError("reference has no points")
    elif reference_n is not None:
        raise ValueError("reference_n given without a reference")

    opt = _optimal(grid, paths, counts, optimal, single)
    cmap = cached_collision_map(grid)
    padded = jnp.asarray(_pad(paths, bucket(L)))
    n_dev = jnp.asarray(counts, jnp.int32)
    grid_path = np.issubdtype(paths.dtype, np.integer)
    out: dict[str, Any] = {k: np.asarray(v) for k, v in _core(cmap, padded, n_dev, clearance=grid_path).items()}
    if not grid_path:
        # A continuous path passes obstacles between its vertices: measured along the segments.
        lo, mean = polyline_clearance(np.asarray(grid.free, bool), paths, counts)
        res = float(grid.resolution)
        dtype = out["length"].dtype
        out["min_clearance"], out["mean_clearance"] = (lo * res).astype(dtype), (mean * res).astype(dtype)
    out["hausdorff"] = None
    if refs is not None:
        out["hausdorff"] = np.asarray(_hausdorff_core(
            padded, n_dev, jnp.asarray(_pad(refs, bucket(refs.shape[1]))), jnp.asarray(ref_counts, jnp.int32),
            cmap.resolution, samples=int(hausdorff_samples)))
        out["hausdorff"] = np.where(counts == 0, np.inf, out["hausdorff"])
    out["optimality_gap"] = None if opt is None else _gap(out["length"].astype(np.float64), opt, counts)
    result: dict[str, Any] = {k: out[k] for k in PATH_METRICS}
    if (cost is None) != (objective_optimum is None):
        raise ValueError("cost and objective_optimum go together: pass both for objective_gap, or neither")
    if cost is not None:
        c = np.broadcast_to(np.asarray(cost, np.float64), (B,))
        o = np.broadcast_to(np.asarray(objective_optimum, np.float64), (B,))
        if np.isnan(c).any() or np.isnan(o).any() or (o < 0).any() or not np.isfinite(o).all():
            raise ValueError("cost must be a number and objective_optimum finite and >= 0 for every path, got "
                             f"{c.tolist()} and {o.tolist()}")
        result["objective_gap"] = _gap(c, o, counts)
    if single:
        result = {k: None if v is None else v[0].item() for k, v in result.items()}
    return PathMetrics(**result)
