"""Uniform cubic B-spline smoothing with the path's vertices as control points.

The spline is clamped (end vertices tripled), so it starts and ends where the path
does; it lies in the convex hull of each span's four control points, so it can cut
into a blocked cell inside a corner. Where a span would come too close to a blocked
cell, the vertices it bends around are tripled — a tripled control point pins the
curve to that vertex and straightens the spans next to it onto the path's own
segments — and the spline is rebuilt, for at most ``rounds`` rounds; after that the
polyline itself is returned. Each span is sampled about every ``spacing`` cells
(at most ``max_samples`` points) and the resulting chords are checked exactly,
inflated by a bound on how far the curve strays from them.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.grid import CollisionMap, polyline_free, segment_free
from jaxplan.metrics import count_sharp_turns_padded as sharp_turn_count
from jaxplan.smoothing._result import Smoothed, compact, drop_repeats

__all__ = ["bspline"]

_REACH = 0.5  # cells of chord-deviation margin the window covers
# Basis matrix taking a uniform cubic B-spline span to its Bezier control points (numpy: a JAX
# array at import would start the XLA backend, which must wait for jax.distributed.initialize).
_TO_BEZIER = np.array([[1, 4, 1, 0], [0, 4, 2, 0], [0, 2, 4, 0], [0, 1, 4, 1]], np.float32) / np.float32(6.0)


def _curve(points: jnp.ndarray, n: jnp.ndarray, mult: jnp.ndarray, spacing: float | jnp.ndarray,
           K: int) -> tuple[jnp.ndarray, ...]:
    """Samples the spline of control multiplicities ``mult [L]``.

    Returns samples ``[S·K + 1, 2]`` with a keep mask, the span of each sample, each
    span's chord margin ``[S]`` and analytic max curvature (1/cells).
    """
    L = points.shape[0]
    E = 3 * L
    idx = jnp.repeat(jnp.arange(L), mult, total_repeat_length=E)
    e = jnp.sum(mult)
    S = E - 3
    k = jnp.arange(S)
    span_ok = k < e - 3
    ctrl_idx = idx[jnp.minimum(k[:, None] + jnp.arange(4), e - 1)]  # [S, 4]
    bez = jnp.einsum("ij,sjd->sid", _TO_BEZIER, points[ctrl_idx])  # [S, 4, 2]
    bound = jnp.sum(jnp.linalg.norm(bez[:, 1:] - bez[:, :-1], axis=-1), axis=-1)
    m = jnp.clip(jnp.ceil(bound / spacing), 1, K).astype(jnp.int32)  # samples per span
    j = jnp.arange(K)
    t = (j[None, :] / m[:, None]).astype(jnp.float32)  # [S, K]
    w = jnp.stack([(1 - t) ** 3, 3 * t * (1 - t) ** 2, 3 * t ** 2 * (1 - t), t ** 3], axis=-1)  # [S, K, 4]
    pts = jnp.einsum("skj,sjd->skd", w, bez)
    keep = span_ok[:, None] & (j[None, :] < m[:, None])
    end = bez[jnp.maximum(e - 4, 0), 3]
    samples = jnp.concatenate([pts.reshape(S * K, 2), end[None]])
    keep = jnp.concatenate([keep.reshape(S * K), jnp.array([True])])
    span = jnp.concatenate([jnp.repeat(k, K), jnp.array([S - 1])])
    dd = jnp.maximum(jnp.linalg.norm(bez[:, 0] - 2 * bez[:, 1] + bez[:, 2], axis=-1),
                     jnp.linalg.norm(bez[:, 1] - 2 * bez[:, 2] + bez[:, 3], axis=-1))
    margin = 6.0 * dd / (8.0 * m.astype(jnp.float32) ** 2)
    s = jnp.linspace(0.0, 1.0, 17)[:, None, None]
    d1 = 3 * ((1 - s) ** 2 * (bez[:, 1] - bez[:, 0]) + 2 * s * (1 - s) * (bez[:, 2] - bez[:, 1])
              + s ** 2 * (bez[:, 3] - bez[:, 2]))  # [17, S, 2]
    d2 = 6 * ((1 - s) * (bez[:, 2] - 2 * bez[:, 1] + bez[:, 0]) + s * (bez[:, 3] - 2 * bez[:, 2] + bez[:, 1]))
    cross = jnp.abs(d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])
    speed = jnp.linalg.norm(d1, axis=-1)
    kappa = jnp.where(speed > 1e-6, cross / jnp.maximum(speed, 1e-6) ** 3, 0.0)
    kmax = jnp.max(jnp.where(span_ok, jnp.max(kappa, axis=0), 0.0))
    return samples, keep, span, margin, kmax, ctrl_idx


def bspline(cmap: CollisionMap, points: jnp.ndarray, n: jnp.ndarray, spacing: float = 0.25, radius: float = 0.0,
            max_samples: int = 16, rounds: int = 8) -> Smoothed:
    """Smooths a polyline with a clamped uniform cubic B-spline, pinned where it would collide.

    Args:
      cmap: the map's `CollisionMap`.
      points: ``f32[L, 2]`` padded polyline (cell coordinates), usually already pruned.
      n: valid points.
      spacing: sample spacing in cells along each span (traced; at most ``max_samples`` per span).
      radius: the robot's inflation radius in cells (static).
      max_samples: samples per span (static).
      rounds: pinning rounds before giving up and returning the polyline (static).

    Returns:
      `Smoothed` with ``points [(3L−3)·max_samples + 1, 2]``; ``removed`` counts the vertices
      the curve passes by (not pinned), ``fallbacks`` the vertices pinned to avoid a
      collision (``n`` when the polyline is returned), ``max_curvature`` in 1/m.
    """
    points = jnp.asarray(points, jnp.float32)
    L = points.shape[0]
    i = jnp.arange(L)
    base = jnp.where(i < n, jnp.where((i == 0) | (i == n - 1), 3, 1), 0).astype(jnp.int32)

    def collide(mult):
        samples, keep, span, margin, _, ctrl_idx = _curve(points, n, mult, spacing, max_samples)
        out, m = compact(samples, keep)
        sp, _ = compact(span.astype(jnp.float32)[:, None], keep)
        sp = sp[:, 0].astype(jnp.int32)
        a, b = out[:-1], out[1:]
        mg = margin[jnp.maximum(sp[:-1], sp[1:])]
        mg = jnp.maximum(mg, margin[jnp.minimum(sp[:-1], sp[1:])])
        ok = jax.vmap(lambda p, q, g: segment_free(cmap, p, q, radius + g, radius + _REACH, chunk=2, step=0.5))(
            a, b, mg)
        bad = ~ok & (jnp.arange(out.shape[0] - 1) < m - 1)
        # A bad chord pins the two middle control vertices of the spans at both of its ends.
        hit = jnp.zeros(L, bool)
        for s_ in (sp[:-1], sp[1:]):
            for c in (1, 2):
                hit = hit.at[jnp.where(bad, ctrl_idx[s_, c], L)].set(True, mode="drop")
        return hit

    def body(c):
        r, mult, _ = c
        hit = collide(mult)
        return r + 1, jnp.where(hit & (mult > 0), 3, mult), jnp.any(hit)

    _, mult, still = jax.lax.while_loop(lambda c: (c[0] < rounds) & c[2], body, (0, base, jnp.bool_(True)))
    give_up = still & jnp.any(collide(mult))
    mult = jnp.where(give_up, jnp.where(i < n, 3, 0), mult)
    samples, keep, _, _, kmax, _ = _curve(points, n, mult, spacing, max_samples)
    out, m = compact(samples, keep)
    out, m = drop_repeats(out, m)
    free_in = jnp.all(polyline_free(cmap, points, n, radius))
    worse = sharp_turn_count(out, m) > sharp_turn_count(points, n)
    back = worse | ~free_in | give_up
    size = out.shape[0]
    last = points[jnp.maximum(n - 1, 0)]
    padded = jnp.where((jnp.arange(size) < n)[:, None], jnp.concatenate([points, jnp.zeros((size - L, 2))]), last)
    pinned = jnp.sum((mult == 3) & (i > 0) & (i < n - 1))
    interior = jnp.maximum(n - 2, 0)
    return Smoothed(
        points=jnp.where(back, padded, out), n=jnp.where(back, n, m),
        removed=jnp.where(back, 0, interior - pinned), fallbacks=jnp.where(back, interior, pinned),
        max_curvature=jnp.where(back, 0.0, kmax) / cmap.resolution, input_free=free_in,
    )
