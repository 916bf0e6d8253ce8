"""Corner curves: inscribed-arc fillets (chen2023) and cubic Bezier corners.

Each interior vertex ``V`` of a polyline, with incoming direction ``u1``, outgoing
direction ``u2`` and heading change ``θ``, is replaced by a curve from the tangent
point ``T1 = V − t·u1`` to ``T2 = V + t·u2``; the straight parts between corners
are pieces of the input's segments. Adjacent corners share a segment, so each may
use at most half of it: ``t <= min(l1, l2) / 2``.

* fillet: the circle of radius ``R`` tangent to both segments (chen2023's
  construction, eq. 9–12), ``t = R·tan(θ/2)``; ``R`` is the largest value up to
  ``radius_max`` that fits.
* bezier: a cubic Bezier ``T1, T1 + κ(V − T1), T2 + κ(V − T2), T2``; tangent to both
  segments at its ends (G1), ``t`` up to ``cut_max``.

A corner curve is sampled at ``K`` points and checked chord by chord with the exact
segment test, inflated by a bound on how far the curve strays from its chords. A
curve that would come too close to a blocked cell is retried at half size, then a
quarter and an eighth; if all fail the corner stays sharp (a fallback). A sampled
corner turns by at most ``θ/(K−1) <= 180°/(K−1)`` between chords, so with ``K >= 6``
no smoothed corner is a sharp turn and the count of sharp turns never grows.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

from jaxplan.grid import CollisionMap, polyline_free, segment_free
from jaxplan.smoothing._result import Smoothed, compact, drop_repeats

__all__ = ["fillet", "bezier_corners"]

_TRIES = 4  # sizes 1, 1/2, 1/4, 1/8 of the largest that fits
_EPS = 1e-6
_REACH = 0.5  # cells of chord-deviation margin the window covers


def _corner_frames(points: jnp.ndarray, n: jnp.ndarray) -> tuple[jnp.ndarray, ...]:
    """Per vertex ``[L]``: unit directions in/out, segment lengths, heading change, whether a corner."""
    L = points.shape[0]
    prev = points[jnp.maximum(jnp.arange(L) - 1, 0)]
    nxt = points[jnp.minimum(jnp.arange(L) + 1, L - 1)]
    a, b = points - prev, nxt - points
    l1, l2 = jnp.linalg.norm(a, axis=-1), jnp.linalg.norm(b, axis=-1)
    u1 = a / jnp.maximum(l1, 1e-30)[:, None]
    u2 = b / jnp.maximum(l2, 1e-30)[:, None]
    cos = jnp.clip(jnp.sum(u1 * u2, axis=-1), -1.0, 1.0)
    theta = jnp.arccos(cos)
    i = jnp.arange(L)
    corner = (i >= 1) & (i < n - 1) & (l1 > _EPS) & (l2 > _EPS) & (theta > 1e-6) & (theta < jnp.pi - 1e-3)
    return u1, u2, l1, l2, theta, corner


def _arc(v: jnp.ndarray, u1: jnp.ndarray, u2: jnp.ndarray, theta: jnp.ndarray, t: jnp.ndarray,
         K: int) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """``[K, 2]`` samples of the arc tangent at ``v − t·u1`` and ``v + t·u2``; analytic curvature (1/cells)."""
    R = t / jnp.tan(theta / 2)
    left = (u1[0] * u2[1] - u1[1] * u2[0]) > 0
    nrm = jnp.where(left, jnp.stack([-u1[1], u1[0]]), jnp.stack([u1[1], -u1[0]]))
    t1 = v - t * u1
    centre = t1 + R * nrm
    phi = jnp.linspace(0.0, 1.0, K) * theta * jnp.where(left, 1.0, -1.0)
    r0 = t1 - centre
    c, s = jnp.cos(phi), jnp.sin(phi)
    pts = centre + jnp.stack([c * r0[0] - s * r0[1], s * r0[0] + c * r0[1]], axis=-1)
    sagitta = R * (1.0 - jnp.cos(theta / (2 * (K - 1))))
    return pts, sagitta, 1.0 / jnp.maximum(R, 1e-30)


def _bezier(v: jnp.ndarray, u1: jnp.ndarray, u2: jnp.ndarray, theta: jnp.ndarray, t: jnp.ndarray, K: int,
            kappa: float | jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """``[K, 2]`` samples of the cubic corner Bezier; a chord-deviation bound; max curvature (1/cells)."""
    c0, c3 = v - t * u1, v + t * u2
    c1, c2 = c0 + kappa * (v - c0), c3 + kappa * (v - c3)
    ctrl = jnp.stack([c0, c1, c2, c3])

    def at(s):
        w = jnp.stack([(1 - s) ** 3, 3 * s * (1 - s) ** 2, 3 * s ** 2 * (1 - s), s ** 3], axis=-1)
        return w @ ctrl

    pts = at(jnp.linspace(0.0, 1.0, K))
    # |c''| <= 6·max|Δ²ctrl| and a chord of parameter width h strays at most h²·max|c''|/8.
    dd = jnp.maximum(jnp.linalg.norm(c0 - 2 * c1 + c2), jnp.linalg.norm(c1 - 2 * c2 + c3))
    dev = 6.0 * dd / (8.0 * (K - 1) ** 2)
    s = jnp.linspace(0.0, 1.0, 65)[:, None]
    d1 = 3 * ((1 - s) ** 2 * (c1 - c0) + 2 * s * (1 - s) * (c2 - c1) + s ** 2 * (c3 - c2))
    d2 = 6 * ((1 - s) * (c2 - 2 * c1 + c0) + s * (c3 - 2 * c2 + c1))
    cross = jnp.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    kmax = jnp.max(cross / jnp.maximum(jnp.linalg.norm(d1, axis=-1) ** 3, 1e-30))
    return pts, dev, kmax


def _corners(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, radius: float, K: int,
             size_of: Callable[..., jnp.ndarray], curve: Callable[..., tuple]) -> Smoothed:
    if K < 6:
        raise ValueError(f"corner samples must be >= 6 (so no smoothed corner is a sharp turn), got {K}")
    given, n_given = jnp.asarray(points, jnp.float32), n
    # A repeated vertex has a zero-length segment on one side, so it would not count as a
    # corner and the turn it carries would stay sharp; the curves are built on the path without repeats.
    points, n = drop_repeats(given, n)
    L = points.shape[0]
    u1, u2, l1, l2, theta, corner = _corner_frames(points, n)
    # Each neighbouring corner may take half of a shared segment; the ends may take all of theirs.
    i = jnp.arange(L)
    room1 = jnp.where(i - 1 == 0, l1, l1 / 2)
    room2 = jnp.where(i + 1 == n - 1, l2, l2 / 2)
    t_full = jnp.minimum(size_of(theta), jnp.minimum(room1, room2))

    def one(v, a, b, th, t):
        def attempt(k):
            pts, margin, kappa = curve(v, a, b, th, t * 0.5 ** k.astype(jnp.float32))
            # The margin is a small fraction of a cell for any sensible K; past _REACH the check fails.
            ok = jax.vmap(lambda p, q: segment_free(cmap, p, q, radius + margin, radius + _REACH, chunk=2, step=0.5))(
                pts[:-1], pts[1:])
            return pts, jnp.all(ok), kappa

        def body(c):
            k, _, _, _ = c
            return (k + 1, *attempt(k))

        init = (jnp.int32(0), jnp.zeros((K, 2), jnp.float32), jnp.bool_(False), jnp.float32(0.0))
        # Half the size on each failure; stop at the first curve that fits.
        _, pts, ok, kappa = jax.lax.while_loop(lambda c: (c[0] < _TRIES) & ~c[2], body, init)
        return pts, ok, kappa

    # Corners that are not corners still run the (cheap, zero-size) checks: vmap needs one shape.
    th = jnp.where(corner, theta, 0.5)  # a finite angle where there is no corner (t = 0 there)
    pts, ok, kappa = jax.vmap(one)(points, u1, u2, th, jnp.where(corner, t_full, 0.0))
    curved = corner & ok & (t_full > _EPS)
    slots = jnp.where(curved[:, None, None], pts, points[:, None, :])  # [L, K, 2]
    keep = jnp.where(curved[:, None], True, jnp.arange(K)[None, :] == 0) & (i < n)[:, None]
    out, m = compact(slots.reshape(L * K, 2), keep.reshape(L * K))
    out, m = drop_repeats(out, m)
    # A path that is not free comes back as given, repeats included.
    free_in = jnp.all(polyline_free(cmap, given, n_given, radius))
    pad = jnp.concatenate([given, jnp.broadcast_to(given[-1], (L * K - L, 2))]) if K > 1 else given
    last = given[jnp.maximum(n_given - 1, 0)]
    pad = jnp.where((jnp.arange(L * K) < n_given)[:, None], pad, last)
    res = cmap.resolution
    return Smoothed(
        points=jnp.where(free_in, out, pad), n=jnp.where(free_in, m, n_given),
        removed=jnp.where(free_in, jnp.sum(curved), 0), fallbacks=jnp.where(free_in, jnp.sum(corner & ~ok), 0),
        max_curvature=jnp.where(free_in, jnp.max(jnp.where(curved, kappa, 0.0)), 0.0) / res, input_free=free_in,
    )


def fillet(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, radius_max: float = 1.0, radius: float = 0.0,
           samples: int = 9) -> Smoothed:
    """Replaces each corner by the largest inscribed arc (chen2023) of radius <= ``radius_max`` cells.

    Args:
      cmap: the map's `CollisionMap`.
      points: ``f32[L, 2]`` padded polyline (cell coordinates), usually already pruned.
      n: valid points.
      radius_max: largest fillet radius in cells (traced).
      radius: the robot's inflation radius in cells (static).
      samples: points per arc ``K`` (static, >= 6).

    Returns:
      `Smoothed` with ``points [L·K, 2]``; ``removed`` counts the corners replaced by arcs,
      ``max_curvature`` is ``1/R_min`` in 1/m.
    """
    def size(theta):
        return radius_max * jnp.tan(theta / 2)

    return _corners(cmap, points, n, radius, samples, size, lambda v, a, b, th, t: _arc(v, a, b, th, t, samples))


def bezier_corners(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, cut_max: float = 1.0,
                   kappa: float = 0.5, radius: float = 0.0, samples: int = 9) -> Smoothed:
    """Replaces each corner by a cubic Bezier that leaves the path ``<= cut_max`` cells before it.

    The control points sit on the two segments at ``κ`` of the way from the tangent points
    to the corner, ``0 < κ <= 1`` (``κ = 2/3`` is the parabola; smaller is rounder; above 1
    the control points pass the corner and the curve loops beyond it). ``max_curvature`` is
    the maximum of the analytic curvature over 65 parameter values per curve, in 1/m.
    """
    def size(theta):
        return jnp.full_like(theta, cut_max)

    return _corners(cmap, points, n, radius, samples, size,
                    lambda v, a, b, th, t: _bezier(v, a, b, th, t, samples, kappa))
