"""Host front for the smoothers: units, validation, padding buckets, compiled-function reuse."""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.core.cache import lru_cache
from jaxplan.grid import GridMap, cached_collision_map
from jaxplan.smoothing._bspline import bspline
from jaxplan.smoothing._corners import bezier_corners, fillet
from jaxplan.smoothing._prune import key_nodes, los_prune
from jaxplan.smoothing._result import Smoothed

__all__ = ["SMOOTHERS", "smooth"]

# name -> (function, {option: (default, unit)}); unit "m" options are given in metres and
# passed in cells, "deg" in degrees and passed in radians; static options change shapes.
SMOOTHERS: dict[str, tuple[Callable[..., Smoothed], dict[str, tuple[Any, str]]]] = {
    "los": (los_prune, {}),
    "key_nodes": (key_nodes, {"threshold": (20.0, "deg")}),
    "fillet": (fillet, {"radius_max": (1.0, "m"), "samples": (9, "static")}),
    "bezier": (bezier_corners, {"cut_max": (1.0, "m"), "kappa": (0.5, ""), "samples": (9, "static")}),
    "bspline": (bspline, {"spacing": (0.25, "m"), "max_samples": (16, "static"), "rounds": (8, "static")}),
}
_STATIC_ALWAYS = {"threshold"}  # used to pick branches at trace time
# Options with an upper bound besides being positive: past κ = 1 the Bezier's control points
# pass the corner and the curve loops beyond it.
_AT_MOST = {"kappa": 1.0}

@lru_cache(maxsize=None)
def _compiled(name: str, radius: float, static: tuple) -> Callable[..., Smoothed]:
    """The jitted, vmapped smoother ``name`` for this radius and these static options (one per combination)."""
    fn, _ = SMOOTHERS[name]
    st = dict(static)

    def run(cmap, points, n, traced):
        return jax.vmap(lambda p, m: fn(cmap, p, m, radius=radius, **st, **traced))(points, n)

    return jax.jit(run)


def _bucket(n: int) -> int:
    # Powers of two from 16: paths of a few vertices (the second pass of a chain) share one
    # program; each smoother program costs about 2 s to compile and microseconds to run.
    return max(16, 1 << math.ceil(math.log2(max(n, 1))))


def _options(name: str, res: float, given: dict) -> tuple[tuple, dict]:
    _, spec = SMOOTHERS[name]
    unknown = set(given) - set(spec)
    if unknown:
        raise ValueError(f"smoother {name!r}: unknown option(s) {sorted(unknown)}; it takes {sorted(spec)}")
    static: list[tuple[str, Any]] = []
    traced: dict[str, Any] = {}
    for k, (default, unit) in spec.items():
        v = given.get(k, default)
        if unit == "static":
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"smoother {name!r}: {k} must be a positive integer, got {v!r}")
            static.append((k, int(v)))
            continue
        v = float(v)
        if not math.isfinite(v) or v <= 0:
            raise ValueError(f"smoother {name!r}: {k} must be a finite positive number, got {v!r}")
        if k in _AT_MOST and v > _AT_MOST[k]:
            raise ValueError(f"smoother {name!r}: {k} must lie in (0, {_AT_MOST[k]:g}], got {v!r}")
        v = v / res if unit == "m" else math.radians(v) if unit == "deg" else v
        if k in _STATIC_ALWAYS:
            static.append((k, v))
        else:
            traced[k] = jnp.float32(v)
    return tuple(static), traced


def smooth(path: ArrayLike, grid: GridMap, method: str | Sequence[str] = "los", *, n: ArrayLike | None = None,
           radius: float = 0.0, **options: Any) -> Smoothed:
    """Smooths one path ``[L, 2]`` or a batch ``[B, L, 2]`` (with ``n [B]``) in cell coordinates.

    Args:
      path: points in cell coordinates (x, y); integer grid paths or float polylines.
      grid: the map the path must stay clear of.
      method: a smoother name (``"los"``, ``"key_nodes"``, ``"fillet"``, ``"bezier"``,
        ``"bspline"``) or a sequence applied in order, e.g. ``("los", "fillet")``.
      n: valid points per path of a batch (default: all).
      radius: robot inflation radius in metres; every output segment keeps at least
        this clearance (and never touches a blocked cell).
      **options: the smoothers' options, lengths in metres and angles in degrees:
        ``threshold`` (key_nodes, 20°), ``radius_max`` (fillet, 1 m), ``cut_max`` and
        ``kappa`` (bezier, 1 m, 0.5, in (0, 1]), ``spacing`` (bspline, 0.25 m), and the static
        ``samples`` / ``max_samples`` / ``rounds``. An option no chosen smoother takes is
        an error.

    Returns:
      `Smoothed` with numpy fields. One path: ``points [m, 2]`` trimmed to its ``n``;
      batch: ``points [B, M, 2]`` padded (repeating the last point) with ``n [B]``. With
      several methods, ``removed`` and ``fallbacks`` add up and ``max_curvature`` is the
      last curve stage's; ``input_free`` is the first stage's.

    Raises:
      ValueError: empty paths, NaN/inf coordinates, points outside the map, bad ``n``,
        no or unknown methods, unknown or out-of-range options, negative radius.
    """
    methods = (method,) if isinstance(method, str) else tuple(method)
    if not methods:
        raise ValueError(f"method must name at least one smoother, got {method!r}")
    for m in methods:
        if m not in SMOOTHERS:
            raise ValueError(f"unknown smoother {m!r}; choose from {sorted(SMOOTHERS)}")
    taken = set().union(*(SMOOTHERS[m][1] for m in methods))
    if set(options) - taken:
        raise ValueError(f"option(s) {sorted(set(options) - taken)} are not taken by {list(methods)}")
    radius = float(radius)
    if not math.isfinite(radius) or radius < 0:
        raise ValueError(f"radius must be a finite number >= 0 (metres), got {radius!r}")
    pts = np.asarray(path, dtype=np.float64)
    single = pts.ndim == 2
    if single:
        pts = pts[None]
    if pts.ndim != 3 or pts.shape[-1] != 2:
        raise ValueError(f"path must be [L, 2] or [B, L, 2], got shape {np.shape(path)}")
    B, L, _ = pts.shape
    if L == 0:
        raise ValueError("path is empty")
    lens = np.full(B, L) if n is None else np.asarray(n, dtype=np.int64).reshape(-1)
    if lens.shape != (B,) or np.any(lens < 1) or np.any(lens > L):
        raise ValueError(f"n must give 1..{L} valid points for each of the {B} paths, got {n!r}")
    valid = np.arange(L)[None, :] < lens[:, None]
    if not np.all(np.isfinite(pts[valid])):
        raise ValueError("path has NaN or infinite coordinates")
    H, W = grid.shape
    v = pts[valid]
    if np.any(v < -0.5) or np.any(v[:, 0] > W - 0.5) or np.any(v[:, 1] > H - 0.5):
        raise ValueError(f"path leaves the {W}x{H} map (cell coordinates)")
    res = float(grid.resolution)
    cmap = cached_collision_map(grid)
    cur = np.where(valid[..., None], pts, pts[np.arange(B), lens - 1][:, None, :]).astype(np.float32)
    cur_n = lens.astype(np.int32)
    removed = np.zeros(B, np.int64)
    fallbacks = np.zeros(B, np.int64)
    kmax = np.zeros(B, np.float32)
    input_free = np.ones(B, bool)  # replaced by the first smoother's check
    for i, m in enumerate(methods):
        static, traced = _options(m, res, {k: v for k, v in options.items() if k in SMOOTHERS[m][1]})
        size = _bucket(int(cur_n.max()))
        cur = cur[:, :size] if cur.shape[1] >= size else np.concatenate(
            [cur, np.repeat(cur[:, -1:], size - cur.shape[1], axis=1)], axis=1)
        out = _compiled(m, radius / res, static)(cmap, jnp.asarray(cur), jnp.asarray(cur_n), traced)
        cur, cur_n = np.asarray(out.points), np.asarray(out.n)
        removed += np.asarray(out.removed)
        fallbacks += np.asarray(out.fallbacks)
        if m in ("fillet", "bezier", "bspline"):
            kmax = np.asarray(out.max_curvature)
        if i == 0:
            input_free = np.asarray(out.input_free)
    res_ = Smoothed(cur, cur_n, removed, fallbacks, kmax, input_free)
    if single:
        return Smoothed(cur[0, : cur_n[0]], int(cur_n[0]), int(removed[0]), int(fallbacks[0]), float(kmax[0]),
                        bool(input_free[0]))
    return res_
