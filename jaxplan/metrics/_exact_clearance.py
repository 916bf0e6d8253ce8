"""Exact clearance of continuous points and polylines from the blocked cells, host side (numpy, float64).

`path_metrics` measures float (smoothed, any-angle, executed) paths here. The JAX
`point_clearance` searches a fixed 5x5 window, so beyond 2 cells it returns an upper bound
(up to √2 cells high); a static shape cannot hold an exact search whose reach grows with
the answer, but a k-d tree over the blocked-cell centres can. A blocked cell is the closed
unit square centred at its cell (docs/guide/maps-and-scenarios.md#conventions); one ring of blocked centres around the
map
stands for the blocked outside (its nearest part to any inside point is in that ring).

Bounds used to find every square that can be nearest: a unit square centred at ``b`` holds
the disc of radius 1/2 about ``b`` and lies in the disc of radius √½, so its distance to a
point ``x`` is within ``[|x − b| − √½, |x − b| − ½]``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from jaxplan.core.cache import digest, memoize
from jaxplan.core.geometry import point_square_distance_np, segment_square_distance_np

__all__ = ["exact_point_clearance", "polyline_clearance", "SAMPLE_CELLS"]

SAMPLE_CELLS = 0.25
"""Longest piece (cells) of a segment whose midpoint samples the length-weighted mean
clearance. Clearance is 1-Lipschitz, so the midpoint rule is off by at most
``SAMPLE_CELLS / 4`` cells anywhere and, being exact for linear stretches, much less in
practice (below 1e-3 cells on the shared maps)."""

_HALF_DIAG = math.sqrt(0.5)
_SLACK = 1e-9  # float64 rounding in the ball radii: a candidate too many costs nothing
_K_NEAR = 8  # nearest centres fetched per point; rows needing more fall back to a ball query

@memoize(maxsize=8, key=lambda free: digest(free))
def _blocked_tree(free: np.ndarray) -> tuple[np.ndarray, cKDTree]:
    """``(centres f64[K, 2] (x, y), tree)`` of the blocked cells plus one outside ring, memoised by content."""
    blocked = np.pad(~free, 1, constant_values=True)
    y, x = np.nonzero(blocked)
    centres = np.stack([x - 1.0, y - 1.0], axis=1)
    return centres, cKDTree(centres)


def _candidates(tree: cKDTree, pts: np.ndarray, radius: np.ndarray,
                near: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, centres)`` index pairs: every centre within ``radius [N]`` of ``pts [N, 2]``.

    ``near`` is a ``tree.query(pts, k)`` result to reuse; rows whose k nearest all lie
    within the radius may have more, and get a ball query.
    """
    k = min(_K_NEAR, tree.n)
    d, idx = near if near is not None else tree.query(pts, k=k)
    d, idx = d.reshape(len(pts), -1), idx.reshape(len(pts), -1)
    inside = d <= radius[:, None]
    full = inside[:, -1] & (tree.n > k)
    keep = inside & ~full[:, None]
    rows, cols = [np.nonzero(keep)[0]], [idx[keep]]
    more = np.flatnonzero(full)
    if more.size:
        lists = tree.query_ball_point(pts[more], radius[more], return_sorted=False)
        lens = np.array([len(a) for a in lists])
        rows.append(np.repeat(more, lens))
        cols.append(np.concatenate([np.asarray(a, np.int64) for a in lists]))
    return np.concatenate(rows), np.concatenate(cols).astype(np.int64)


def _outside(free: np.ndarray, pts: np.ndarray) -> np.ndarray:
    H, W = free.shape
    return ~np.all((pts >= -0.5) & (pts <= np.array([W - 0.5, H - 0.5])), axis=-1)


def exact_point_clearance(free: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``f64[N]`` exact distance (cells) from points ``[N, 2]`` (cell coordinates) to the nearest
    blocked square; 0 for points outside the map (they are in the blocked outside).

    Args:
      free: ``bool[H, W]`` the map's free cells.
      points: ``[N, 2]`` finite ``(x, y)`` points.
    """
    free = np.asarray(free, bool)
    pts = np.asarray(points, np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return np.zeros(0)
    centres, tree = _blocked_tree(free)
    near = tree.query(pts, k=min(_K_NEAR, tree.n))
    d0 = near[0].reshape(len(pts), -1)[:, 0]
    # The nearest centre's square is at most d0 − ½ away; a nearer square's centre is within d0 − ½ + √½.
    rows, cols = _candidates(tree, pts, d0 + (_HALF_DIAG - 0.5) + _SLACK, near)
    out = np.full(len(pts), np.inf)
    np.minimum.at(out, rows, point_square_distance_np(pts[rows], centres[cols]))
    return np.where(_outside(free, pts), 0.0, out)


def polyline_clearance(free: np.ndarray, paths: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(min_clearance, mean_clearance)``, each ``f64[B]`` in cells, of padded polylines.

    Args:
      free: ``bool[H, W]`` the map's free cells.
      paths: ``[B, L, 2]`` points (cell coordinates); those at or after ``n`` are ignored.
      n: ``int[B]`` valid points per path.

    ``min_clearance`` is the exact distance from the whole polyline (segments, not only the
    vertices) to the nearest blocked square. ``mean_clearance`` is the clearance averaged
    over arc length, ∫ c ds / length, by the midpoint rule on pieces of at most
    `SAMPLE_CELLS`. A path without length (one point, or one point repeated) has both equal
    to that point's clearance; an empty path has ``+inf`` for both.
    """
    free = np.asarray(free, bool)
    paths = np.asarray(paths, np.float64)
    n = np.asarray(n, np.int64)
    B, L = paths.shape[:2]
    if B == 0 or L == 0:
        return np.full(B, np.inf), np.full(B, np.inf)
    # Valid segments, flattened: path index and end points.
    seg_ok = np.arange(L - 1)[None, :] < (n[:, None] - 1)
    sb, si = np.nonzero(seg_ok)
    p, q = paths[sb, si], paths[sb, si + 1]
    seg_len = np.hypot(*(q - p).T)
    pieces = np.maximum(np.ceil(seg_len / SAMPLE_CELLS), 1).astype(np.int64)
    # Midpoints of the pieces, one row per piece.
    owner = np.repeat(np.arange(len(p)), pieces)
    start = np.cumsum(pieces) - pieces
    t = (np.arange(owner.size) - start[owner] + 0.5) / pieces[owner]
    mids = p[owner] + t[:, None] * (q - p)[owner]
    c_mid = exact_point_clearance(free, mids)

    # Vertices: a one-point path has only this; every path's minimum includes its ends.
    vb, vi = np.nonzero(np.arange(L)[None, :] < n[:, None])
    cv = np.full((B, L), np.inf)
    cv[vb, vi] = exact_point_clearance(free, paths[vb, vi])
    lo = cv.min(axis=1)
    mean = np.where(n > 0, cv[:, 0], np.inf)  # replaced below for paths with length

    if len(p):
        weight = (seg_len / pieces)[owner]
        total = np.bincount(sb, weights=seg_len, minlength=B)
        integral = np.bincount(sb[owner], weights=c_mid * weight, minlength=B)
        has_len = total > 0
        mean[has_len] = integral[has_len] / total[has_len]

        # Exact segment minimum: an upper bound U from its samples; any square nearer than U
        # is within h/2 (half a piece) of some midpoint's square distance, so its centre lies
        # within U + h/2 + √½ of that midpoint, and only midpoints with clearance <= U + h/2 matter.
        upper = np.minimum(cv[sb, si], cv[sb, si + 1])
        np.minimum.at(upper, owner, c_mid)
        reach = upper[owner] + 0.5 * (seg_len / pieces)[owner] + _SLACK
        ask = np.flatnonzero(c_mid <= reach)
        centres, tree = _blocked_tree(free)
        rows, cols = _candidates(tree, mids[ask], reach[ask] + _HALF_DIAG)
        segs = owner[ask][rows]
        exact = upper.copy()
        np.minimum.at(exact, segs, segment_square_distance_np(p[segs], q[segs], centres[cols]))
        np.minimum.at(lo, sb, exact)
    return lo, mean

    return lo, mean
