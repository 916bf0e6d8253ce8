"""Moving obstacles: discs that travel piecewise-linear routes at constant speed.

The model (DESIGN §5; li2026's moving obstacles at 1.0 and 1.5 m/s, chu2024's
head-on encounter of Figure 11):

* An obstacle is a disc of radius ``r`` (m) whose centre moves along a route, a polyline
  of ``k >= 1`` vertices in world metres, at constant speed ``v`` (m/s) measured along
  the arc length. At time ``t`` (s) it has travelled ``s(t) = offset + v·t`` metres;
  ``offset`` is its phase (arc length already travelled at ``t = 0``).
* ``loop = False`` (**bounce**, ping-pong): first vertex → last vertex → back along the
  same route → first vertex → …; period ``2·L`` for a route of length ``L``.
  ``loop = True``: after the last vertex it goes straight back to the first one (a
  closing segment, which the generators make zero-length by ending a loop route where
  it starts) and repeats; period ``L + |last − first|``.
* Negative ``s`` (negative times or offsets) continues the periodic motion backwards.
  A route of one vertex, a route of zero length, or speed 0 stands still (velocity 0);
  zero-length segments are skipped. Positions and velocities are finite, and so are
  their derivatives with respect to ``t`` (all square roots and divisions are guarded).
* The velocity is ``±v`` times the unit tangent of the segment being travelled; at a
  vertex it is that of the segment being entered (at the far turning point of a
  bounce, still that of the outgoing pass).

Units: metres, seconds, m/s. Arrays are float32/int32/bool, with the obstacle axis
``M`` last among the batch axes (leading axes, e.g. a batch of scenarios, allowed).

Padding: a batch of scenarios needs one ``M`` and one ``K`` (route vertices). A padding
slot stands still far away, at ``(1e6 + 10·j, 1e6)`` m for slot ``j`` (spread so that
padding discs never coincide, which keeps pairwise distances and their gradients
finite), with radius 0 and speed 0; a route is padded by repeating its last valid
vertex (zero-length segments). `pad_obstacles`, `concat_obstacles`,
`stack_obstacles` and `no_obstacles` keep that convention.

The DWA does not see routes: `discs_at(obs, t)` hands it a `DiscObstacles` snapshot
(positions and velocities at ``t``), which its rollouts extrapolate at constant
velocity over the horizon, ``p(t + τ) ≈ p(t) + v(t)·τ``. That prediction is exact
until the obstacle reaches its next vertex, so near a corner or a bounce it is wrong
by up to ``2·v·τ``; the episode re-snapshots every control step. (The ablation
``NavConfig(prediction="oracle")`` instead hands the DWA each obstacle's true centres at
its rollout times, ``DiscObstacles.track``.)

Generators (host side, numpy RNG from an integer ``seed``: same seed, same arrays)
build routes that a disc of the obstacle's radius travels without touching a blocked
cell (clearance >= radius, as `jaxplan.grid._collision.segment_free` decides it),
verified with an exact segment-to-square test on the host (`_Blocked`, a numpy twin
of that test that needs no compilation per map and path length):
`random_obstacles` (random walkers along A* routes), `crossing_traffic` (traffic
crossing a robot's planned path) and `head_on` (chu2024, Figure 11).

Example:
  >>> import jaxplan as jp
  >>> from jaxplan.nav._obstacles import random_obstacles, discs_at
  >>> scene = jp.demo_warehouse()
  >>> obs = random_obstacles(scene, n=5, speed=1.0, radius=0.25, seed=0)
  >>> discs_at(obs, 2.0).positions.shape
  (5, 2)
"""

from __future__ import annotations

from typing import Any, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from jaxplan.core.geometry import segment_square_distance_np
from jaxplan.dwa import DiscObstacles
from jaxplan.grid import TOUCH, GridMap, clearance_field, grid_from_array
from jaxplan.search import astar

__all__ = [
    "MovingObstacles", "obstacle_state", "discs_at", "trajectories", "route_lengths", "no_obstacles",
    "pad_obstacles", "concat_obstacles", "stack_obstacles", "moving_obstacles", "random_obstacles",
    "crossing_traffic", "head_on", "FAR", "FAR_SPACING",
]

FAR = 1e6
"""Coordinate (m) of padding slots: far beyond any map, yet small enough that squared
distances stay finite in float32."""

FAR_SPACING = 10.0
"""Distance (m) between consecutive padding slots along x (float32 resolves 0.0625 m at 1e6)."""

_MAX_COORD = 0.5 * FAR  # real routes must stay below this, so padding is never mistaken for a route


class MovingObstacles(NamedTuple):
    """Discs moving along piecewise-linear routes at constant speed. A pytree; batch axes lead.

    Attributes:
      waypoints: ``f32[..., M, K, 2]`` route vertices (m, world), padded by repeating the
        last valid vertex.
      n_waypoints: ``i32[..., M]`` valid vertices (>= 1; 1 = standing still).
      speeds: ``f32[..., M]`` m/s along the route (>= 0).
      radii: ``f32[..., M]`` m (>= 0).
      loop: ``bool[..., M]`` True: after the last vertex straight back to the first, and
        repeat; False: bounce (back along the route, ping-pong).
      offsets: ``f32[..., M]`` arc length (m) already travelled at ``t = 0`` (the phase).

    Build with `moving_obstacles` or a generator; the module docstring gives the model.
    """

    waypoints: jnp.ndarray
    n_waypoints: jnp.ndarray
    speeds: jnp.ndarray
    radii: jnp.ndarray
    loop: jnp.ndarray
    offsets: jnp.ndarray

    @property
    def count(self) -> int:
        """``M``, the number of slots (padding included)."""
        return int(self.radii.shape[-1])


# --------------------------------------------------------------------------------------
# The model (pure, jittable, vmappable)
# --------------------------------------------------------------------------------------


def _safe_norm(d: jnp.ndarray) -> jnp.ndarray:
    """``|d|`` over the last axis, with a finite gradient at 0 (``sqrt`` of 0 has none)."""
    d2 = jnp.sum(d * d, axis=-1)
    pos = d2 > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, d2, 1.0)), 0.0)


def _travelled(obs: MovingObstacles) -> jnp.ndarray:
    """``f32[..., M, K + 1, 2]``: the vertices actually travelled, ending with the closing vertex.

    The valid vertices, then the end vertex repeated: the first vertex for a loop (which
    adds the closing segment), the last one for a bounce (zero-length segments).
    """
    wp = jnp.asarray(obs.waypoints, jnp.float32)
    K = wp.shape[-2]
    n = jnp.clip(jnp.asarray(obs.n_waypoints, jnp.int32), 1, K)
    last = jnp.take_along_axis(wp, (n - 1)[..., None, None], axis=-2)[..., 0, :]  # [..., M, 2]
    end = jnp.where(jnp.asarray(obs.loop, bool)[..., None], wp[..., 0, :], last)
    k = jnp.arange(K + 1)
    body = jnp.take(wp, jnp.minimum(k, K - 1), axis=-2)  # [..., M, K + 1, 2]
    return jnp.where((k < n[..., None])[..., None], body, end[..., None, :])


def route_lengths(obs: MovingObstacles) -> jnp.ndarray:
    """``f32[..., M]``: length (m) of one pass along each route (a loop's closing segment included)."""
    v = _travelled(obs)
    return jnp.sum(_safe_norm(v[..., 1:, :] - v[..., :-1, :]), axis=-1)


def obstacle_state(obs: MovingObstacles, t) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Positions and velocities of the discs at time ``t``.

    Args:
      obs: the obstacles (``[..., M]`` slots).
      t: time (s); a scalar, possibly traced (or an array broadcastable to ``[..., M]``).

    Returns:
      ``(positions f32[..., M, 2] (m), velocities f32[..., M, 2] (m/s))``.
    """
    verts = _travelled(obs)  # [..., M, K + 1, 2]
    d = verts[..., 1:, :] - verts[..., :-1, :]  # [..., M, K, 2] segment vectors
    seg = _safe_norm(d)  # [..., M, K]
    K = seg.shape[-1]
    cum = jnp.concatenate([jnp.zeros_like(seg[..., :1]), jnp.cumsum(seg, axis=-1)], axis=-1)  # [..., M, K + 1]
    length = cum[..., -1]
    loop = jnp.asarray(obs.loop, bool)
    period = jnp.where(loop, length, 2.0 * length)
    moving = period > 0
    s = jnp.asarray(obs.offsets, jnp.float32) + jnp.asarray(obs.speeds, jnp.float32) * jnp.asarray(t, jnp.float32)
    u = jnp.where(moving, jnp.mod(s, jnp.where(moving, period, 1.0)), 0.0)  # in [0, period]
    back = ~loop & (u > length)  # second half of a bounce: reflected
    u = jnp.where(back, 2.0 * length - u, u)
    # Segment index: the segment being entered in the direction of travel, so at a vertex
    # the velocity already points along the next segment. Forward: vertices passed
    # (cum <= u), capped at the last segment of positive length; backward: cum < u,
    # raised to the first one. Either way zero-length segments are never chosen (unless
    # the route has no length), so the tangent is defined.
    k = jnp.arange(K)
    passed = jnp.where(back, jnp.sum(cum[..., 1:] < u[..., None], axis=-1), jnp.sum(cum[..., 1:] <= u[..., None], axis=-1))
    last_pos = jnp.max(jnp.where(seg > 0, k, 0), axis=-1)
    first_pos = jnp.min(jnp.where(seg > 0, k, K - 1), axis=-1)
    idx = jnp.clip(passed, jnp.minimum(first_pos, last_pos), last_pos)[..., None]  # [..., M, 1]
    seg_i = jnp.take_along_axis(seg, idx, axis=-1)[..., 0]
    along = jnp.clip(u - jnp.take_along_axis(cum, idx, axis=-1)[..., 0], 0.0, seg_i)
    unit = jnp.take_along_axis(d, idx[..., None], axis=-2)[..., 0, :] / jnp.where(seg_i > 0, seg_i, 1.0)[..., None]
    start = jnp.take_along_axis(verts, idx[..., None], axis=-2)[..., 0, :]
    positions = start + unit * along[..., None]
    sign = jnp.where(back, -1.0, 1.0)
    velocities = (sign * jnp.asarray(obs.speeds, jnp.float32))[..., None] * unit
    return positions, velocities


def discs_at(obs: MovingObstacles, t) -> DiscObstacles:
    """The `DiscObstacles` snapshot at time ``t`` (s) that a DWA step consumes (constant-velocity prediction)."""
    positions, velocities = obstacle_state(obs, t)
    return DiscObstacles(positions, velocities, jnp.asarray(obs.radii, jnp.float32))


def trajectories(obs: MovingObstacles, times: ArrayLike) -> jnp.ndarray:
    """``f32[T, ..., M, 2]``: positions (m) at each of ``times f32[T]`` (s), for metrics and plots.

    One compiled call per shape (op by op, the model would compile each of its ~50
    operations on first use: about 10 s of a cold run).
    """
    return _TRAJECTORIES(obs, jnp.asarray(times, jnp.float32))


_TRAJECTORIES = jax.jit(lambda obs, times: jax.vmap(lambda t: obstacle_state(obs, t)[0])(times))


# --------------------------------------------------------------------------------------
# Padding, concatenation, batching (jnp; shapes are static)
# --------------------------------------------------------------------------------------


def _far(m: int, first: int = 0) -> jnp.ndarray:
    """``f32[m, 2]``: the parking places of padding slots ``first .. first + m - 1``."""
    j = jnp.arange(first, first + m, dtype=jnp.float32)
    return jnp.stack([FAR + FAR_SPACING * j, jnp.full_like(j, FAR)], axis=-1)


def no_obstacles(m: int = 0, k: int = 1) -> MovingObstacles:
    """``m`` padding slots (``K = k`` vertices each): far away, standing still, radius 0."""
    if m < 0 or k < 1:
        raise ValueError(f"no_obstacles needs m >= 0 and k >= 1, got m={m}, k={k}")
    wp = jnp.broadcast_to(_far(m)[:, None, :], (m, k, 2))
    return MovingObstacles(
        waypoints=jnp.asarray(wp, jnp.float32), n_waypoints=jnp.ones((m,), jnp.int32),
        speeds=jnp.zeros((m,), jnp.float32), radii=jnp.zeros((m,), jnp.float32),
        loop=jnp.zeros((m,), bool), offsets=jnp.zeros((m,), jnp.float32),
    )


def _is_padding(obs: MovingObstacles) -> jnp.ndarray:
    """``bool[..., M]``: slots parked far away (real routes are validated to stay below 5e5 m)."""
    return (obs.waypoints[..., 0, 0] >= _MAX_COORD) & (obs.radii == 0) & (obs.speeds == 0)


def _respread(obs: MovingObstacles) -> MovingObstacles:
    """Re-parks every padding slot at the place of its index, so that no two coincide."""
    M = obs.count
    pad = _is_padding(obs)[..., None, None]
    far = jnp.broadcast_to(_far(M)[:, None, :], obs.waypoints.shape[-3:])
    return obs._replace(waypoints=jnp.where(pad, far, obs.waypoints))


def _pad_k(obs: MovingObstacles, k: int) -> MovingObstacles:
    """Pads the route axis to ``k`` vertices by repeating each route's last valid vertex."""
    wp = jnp.asarray(obs.waypoints, jnp.float32)
    K = wp.shape[-2]
    if k < K:
        raise ValueError(f"cannot pad routes of {K} vertices down to {k}")
    if k == K:
        return obs
    n = jnp.clip(jnp.asarray(obs.n_waypoints, jnp.int32), 1, K)
    last = jnp.take_along_axis(wp, (n - 1)[..., None, None], axis=-2)  # [..., M, 1, 2]
    extra = jnp.broadcast_to(last, wp.shape[:-2] + (k - K, 2))
    return obs._replace(waypoints=jnp.concatenate([wp, extra], axis=-2))


def pad_obstacles(obs: MovingObstacles, m: int, k: int | None = None) -> MovingObstacles:
    """Pads to ``m`` slots (and routes to ``k`` vertices, default unchanged) with parked padding slots.

    Raises:
      ValueError: if ``obs`` already has more than ``m`` slots or ``k`` vertices.
    """
    M = obs.count
    if m < M:
        raise ValueError(f"cannot pad {M} obstacles down to {m} slots")
    obs = _pad_k(obs, obs.waypoints.shape[-2] if k is None else k)
    if m == M:
        return _respread(obs)
    batch = obs.radii.shape[:-1]
    K = obs.waypoints.shape[-2]
    extra = no_obstacles(m - M, K)
    extra = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, batch + x.shape), extra)
    return concat_obstacles(obs, extra)


def concat_obstacles(a: MovingObstacles, b: MovingObstacles) -> MovingObstacles:
    """The slots of ``a`` then those of ``b`` (routes padded to the longer ``K``; same batch axes)."""
    k = max(a.waypoints.shape[-2], b.waypoints.shape[-2])
    a, b = _pad_k(a, k), _pad_k(b, k)
    axes = MovingObstacles(-3, -1, -1, -1, -1, -1)  # the M axis of each field
    out = jax.tree_util.tree_map(
        lambda x, y, ax: jnp.concatenate([jnp.asarray(x), jnp.asarray(y).astype(jnp.asarray(x).dtype)], axis=ax),
        a, b, axes,
    )
    return _respread(out)


def stack_obstacles(sets: Sequence[MovingObstacles]) -> MovingObstacles:
    """Stacks obstacle sets along a new leading batch axis, padding ``K`` and ``M`` to the maximum."""
    sets = list(sets)
    if not sets:
        raise ValueError("stack_obstacles needs at least one obstacle set")
    m = max(o.count for o in sets)
    k = max(o.waypoints.shape[-2] for o in sets)
    padded = [_PAD(o, m, k) for o in sets]
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *padded)


_PAD = jax.jit(pad_obstacles, static_argnums=(1, 2))  # sets of one shape share one compiled call


# --------------------------------------------------------------------------------------
# Host constructor and validation
# --------------------------------------------------------------------------------------


def _per_obstacle(name: str, value: Any, m: int, *, nonneg: bool = True) -> np.ndarray:
    """A scalar or one value per obstacle -> ``f64[m]``, checked finite (and >= 0)."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(m, float(arr))
    elif arr.ndim != 1 or arr.shape[0] != m:
        raise ValueError(f"{name} must be a scalar or have one entry per obstacle ({m}), got shape {arr.shape}")
    for i, v in enumerate(arr):
        if not np.isfinite(v):
            raise ValueError(f"obstacle {i}: {name} must be finite, got {v}")
        if nonneg and v < 0:
            raise ValueError(f"obstacle {i}: {name} must be >= 0, got {v}")
    return arr


def moving_obstacles(routes: Sequence[ArrayLike], speeds: Any, radii: Any, loop: Any = False,
                     offsets: Any = 0.0) -> MovingObstacles:
    """Builds validated `MovingObstacles` from host data.

    Args:
      routes: ``M`` routes, each ``[k_i, 2]`` world points (m), ``k_i >= 1``.
      speeds: m/s along the route, >= 0: a scalar or ``[M]``.
      radii: disc radii (m), >= 0: a scalar or ``[M]``.
      loop: bool, scalar or ``[M]`` (True: loop, False: bounce).
      offsets: arc length (m) travelled at ``t = 0``, any finite value: a scalar or ``[M]``.

    Returns:
      `MovingObstacles` with ``K = max k_i`` (shorter routes repeat their last vertex).

    Raises:
      ValueError: naming the obstacle index and the problem (shape, non-finite or
        negative value, coordinates beyond 5e5 m, where padding slots live).
    """
    routes = list(routes)
    m = len(routes)
    pts = []
    for i, r in enumerate(routes):
        try:
            a = np.asarray(r, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"obstacle {i}: route is not a numeric [k, 2] array") from None
        if a.ndim == 1 and a.shape == (2,):
            a = a[None]  # a single point: standing still
        if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < 1:
            raise ValueError(f"obstacle {i}: route must have shape [k, 2] with k >= 1, got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"obstacle {i}: route contains a non-finite coordinate")
        if np.abs(a).max() >= _MAX_COORD:
            raise ValueError(f"obstacle {i}: route coordinates must stay below {_MAX_COORD:g} m "
                             f"(padding slots live at {FAR:g} m)")
        pts.append(a)
    sp = _per_obstacle("speed", speeds, m)
    rad = _per_obstacle("radius", radii, m)
    off = _per_obstacle("offset", offsets, m, nonneg=False)
    lp = np.asarray(loop)
    if lp.ndim == 0:
        lp = np.full(m, bool(lp))
    elif lp.shape != (m,):
        raise ValueError(f"loop must be a scalar or have one entry per obstacle ({m}), got shape {lp.shape}")
    if m == 0:
        return no_obstacles(0)
    K = max(len(a) for a in pts)
    wp = np.stack([np.concatenate([a, np.repeat(a[-1:], K - len(a), axis=0)]) for a in pts])
    return MovingObstacles(
        waypoints=jnp.asarray(wp, jnp.float32),
        n_waypoints=jnp.asarray([len(a) for a in pts], jnp.int32),
        speeds=jnp.asarray(sp, jnp.float32),
        radii=jnp.asarray(rad, jnp.float32),
        loop=jnp.asarray(lp.astype(bool)),
        offsets=jnp.asarray(off, jnp.float32),
    )


# --------------------------------------------------------------------------------------
# Generators (host side)
# --------------------------------------------------------------------------------------

def _as_grid(grid: Any) -> GridMap:
    """A `GridMap`, or a `Scene` (``jp.demo_warehouse()``, generators) whose ``.grid`` is one."""
    if isinstance(grid, GridMap):
        return grid
    inner = getattr(grid, "grid", None)
    if isinstance(inner, GridMap):
        return inner
    raise TypeError(f"expected a GridMap or a Scene, got {type(grid).__name__}")


def _rng(seed: Any) -> np.random.Generator:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    return np.random.default_rng(int(seed))


def _np_position(route: np.ndarray, s: float, loop: bool) -> np.ndarray:
    """Host reference of the model: the point at arc length ``s`` of one route (f64)."""
    pts = np.concatenate([route, route[:1]]) if loop else np.concatenate([route, route[-2::-1]])
    seg = np.hypot(*np.diff(pts, axis=0).T)
    total = seg.sum()
    if total <= 0:
        return route[0].copy()
    u = float(np.mod(s, total))
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    i = int(np.clip(np.searchsorted(cum, u, side="right") - 1, 0, len(seg) - 1))
    f = 0.0 if seg[i] == 0 else min((u - cum[i]) / seg[i], 1.0)
    return pts[i] + f * (pts[i + 1] - pts[i])


def _dedupe(cells: np.ndarray) -> np.ndarray:
    keep = np.ones(len(cells), bool)
    keep[1:] = np.any(cells[1:] != cells[:-1], axis=1)
    return cells[keep]


class _Blocked:
    """Blocked unit squares of a map for exact host-side segment tests (cell coordinates).

    The generators run once per scenario on the host, where compiling the JAX segment
    walk for every map shape and path length would cost seconds per call; this numpy
    twin of `jaxplan.grid.segment_clearance` is exact too (the numpy twin of the same
    segment-to-square distance, `jaxplan.core.geometry`, over every blocked square near the
    segment) and needs no compilation. Outside the map counts as blocked.
    """

    def __init__(self, free: np.ndarray):
        self.free = np.asarray(free, bool)
        self.H, self.W = self.free.shape

    def clearance(self, p: np.ndarray, q: np.ndarray, reach: float) -> float:
        """Distance (cells) from segment ``p``–``q`` to the nearest blocked square, exact below ``reach``.

        Squares farther than ``reach`` are not examined (the answer is then ``>= reach``,
        reported as ``inf``).
        """
        w = reach + 1.0  # a square within `reach` of the segment has its centre within reach + 0.5
        x0, y0 = np.floor(np.minimum(p, q) - w).astype(int)
        x1, y1 = np.ceil(np.maximum(p, q) + w).astype(int)
        xs, ys = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1), indexing="xy")
        inside = (xs >= 0) & (xs < self.W) & (ys >= 0) & (ys < self.H)
        blocked = ~inside
        blocked[inside] = ~self.free[ys[inside], xs[inside]]
        c = np.stack([xs[blocked], ys[blocked]], axis=-1).astype(np.float64)
        if len(c) == 0:
            return float("inf")
        return float(segment_square_distance_np(np.asarray(p, np.float64), np.asarray(q, np.float64), c).min())

    def free_for(self, p: np.ndarray, q: np.ndarray, r: float, margin: float = 0.0) -> bool:
        """`segment_free`'s rule: clearance >= max(r, TOUCH) (+ ``margin`` cells)."""
        thr = max(r, TOUCH) + margin
        return self.clearance(p, q, thr + 1.0) >= thr


_SHORTCUT_MARGIN = 1e-4  # cells: shortcuts keep this much beyond the radius, so float32 checks agree


def _pruned_route(blocked: _Blocked, cells: np.ndarray, r_cells: float) -> np.ndarray | None:
    """Line-of-sight pruning of a cell path for a disc of ``r_cells`` (the rule of `los_prune`).

    From the anchor (last kept vertex), vertex ``j`` is dropped while the segment from the
    anchor to vertex ``j + 1`` is free. Returns the kept vertices (cell coordinates), or
    None if some segment of the result is not free (exact test).
    """
    pts = cells.astype(np.float64)
    kept = [pts[0]]
    for j in range(1, len(pts) - 1):
        if not blocked.free_for(kept[-1], pts[j + 1], r_cells, _SHORTCUT_MARGIN):
            kept.append(pts[j])
    if len(pts) > 1:
        kept.append(pts[-1])
    route = np.stack(kept)
    ok = all(blocked.free_for(a, b, r_cells) for a, b in zip(route[:-1], route[1:]))
    return route if ok else None


def random_obstacles(grid: Any, n: int = 5, speed: Any = 1.0, radius: Any = 0.25, seed: int = 0, *,
                     waypoints: int = 4, avoid: ArrayLike | None = None, avoid_radius: float = 1.0,
                     loop: bool = False, tries: int = 20) -> MovingObstacles:
    """Random walkers: discs bouncing (or looping) along short polylines through random free points.

    Each route joins ``waypoints`` random cells by exact A* paths (8-connected, no corner
    cutting) on the map inflated for the disc (cells whose centre clearance is at least
    ``radius``), LOS-pruned with the exact segment test at that radius, and converted to
    world metres (cell centres). A looping route returns to its first cell along A*
    paths, so its closing segment has zero length and never cuts through a wall. All of
    an obstacle's cells lie in one connected region of the inflated map. Phases are
    uniform over the period (random positions at ``t = 0``).

    Starts (positions at ``t = 0``) keep ``avoid_radius + radius`` from every ``avoid``
    point; they also keep clear of the discs placed before them when the map has room
    (a preference, not a guarantee). Obstacles do not avoid each other later on.

    Args:
      grid: a `GridMap`, or a `Scene` such as ``jp.demo_warehouse()``.
      n: number of obstacles (>= 0).
      speed: m/s, >= 0: a scalar or ``[n]`` (li2026 runs 1.0 and 1.5).
      radius: disc radius (m), >= 0: a scalar or ``[n]``.
      seed: integer seed of the numpy RNG (same seed, same obstacles).
      waypoints: random cells per route (>= 1; 1 stands still).
      avoid: optional ``[P, 2]`` world points (m), e.g. the robots' starts and goals.
      avoid_radius: minimum distance (m) from ``avoid`` points to a disc's edge at ``t = 0``.
      loop: True: loop routes; False (default): bounce.
      tries: attempts per obstacle before giving up (a route is redrawn only if the exact
        check fails, which the inflation makes rare).

    Returns:
      `MovingObstacles` with ``M = n``.

    Raises:
      ValueError: bad arguments, or no free cell where a disc of the radius can start.
    """
    g = _as_grid(grid)
    rng = _rng(seed)
    if not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    if not isinstance(waypoints, (int, np.integer)) or waypoints < 1:
        raise ValueError(f"waypoints must be an integer >= 1, got {waypoints!r}")
    if not np.isfinite(avoid_radius) or avoid_radius < 0:
        raise ValueError(f"avoid_radius must be finite and >= 0, got {avoid_radius}")
    speeds = _per_obstacle("speed", speed, n)
    radii = _per_obstacle("radius", radius, n)
    av = np.zeros((0, 2)) if avoid is None else np.asarray(avoid, np.float64).reshape(-1, 2)
    if not np.isfinite(av).all():
        raise ValueError("avoid contains a non-finite coordinate")
    if n == 0:
        return no_obstacles(0)
    res = float(g.resolution)
    free = np.asarray(g.free, bool)
    clear = clearance_field(g)  # metres, exact at cell centres
    blocked = _Blocked(free)
    H, W = free.shape
    ys, xs = np.mgrid[0:H, 0:W]
    centres = np.stack([(xs + 0.5) * res, (ys + 0.5) * res], axis=-1)  # [H, W, 2] m
    regions: dict[float, tuple[np.ndarray, np.ndarray, GridMap]] = {}
    routes, offsets, placed = [], [], []  # placed: (start point, radius) of earlier discs
    for i in range(n):
        r = float(radii[i])
        if r not in regions:
            ok = free & (clear >= np.float32(r))
            labels, _ = ndimage.label(ok)  # 4-connected = reachable without corner cutting
            regions[r] = (ok, labels, grid_from_array(ok, resolution=res))
        ok, labels, inflated = regions[r]
        start_ok = ok.copy()
        for p in av:
            start_ok &= np.hypot(*(centres - p).transpose(2, 0, 1)) >= avoid_radius + r
        if not start_ok.any():
            raise ValueError(
                f"obstacle {i}: the map has no free cell where a disc of radius {r} m can start "
                f"{avoid_radius} m from the avoid points" if len(av) else
                f"obstacle {i}: the map has no free cell with {r} m of clearance for a disc of that radius")
        preferred = start_ok.copy()
        for q, rq in placed:
            preferred &= np.hypot(*(centres - q).transpose(2, 0, 1)) >= r + rq
        pool = np.argwhere(preferred if preferred.any() else start_ok)[:, ::-1]  # (x, y)
        route = None
        for _ in range(tries):
            first = pool[rng.integers(len(pool))]
            region = np.argwhere(labels == labels[first[1], first[0]])[:, ::-1]
            stops = [first] + [region[rng.integers(len(region))] for _ in range(waypoints - 1)]
            if loop and waypoints > 1:
                stops.append(first)
            # Each leg is pruned on its own, so the random stops stay vertices: pruning a
            # whole loop would cut from the first cell straight back to itself.
            pieces, ok_route = [first[None].astype(np.float64)], True
            for a, b in zip(stops[:-1], stops[1:]):
                if np.array_equal(a, b):
                    continue
                leg = _pruned_route(blocked, np.asarray(astar(inflated, a, b).path, np.int64), r / res)
                if leg is None:
                    ok_route = False
                    break
                pieces.append(leg[1:])
            if ok_route:
                route = (_dedupe(np.concatenate(pieces)) + 0.5) * res
                break
        if route is None:
            raise ValueError(f"obstacle {i}: no collision-free route found in {tries} tries")
        seg = np.hypot(*np.diff(route, axis=0).T).sum()
        period = seg if loop else 2.0 * seg
        # Random phases first; offset 0 (the first vertex, drawn among the allowed starts)
        # always honours `avoid`. Clear of the earlier discs if possible, else just `avoid`.
        candidates = list(rng.uniform(0.0, period, size=16)) if period > 0 else []
        candidates.append(0.0)
        offset = None
        for strict in (True, False):
            for c in candidates:
                p = _np_position(route, c, loop)
                if len(av) and np.hypot(*(av - p).T).min() < avoid_radius + r + 1e-5:  # float32 slack
                    continue
                if strict and any(np.hypot(*(q - p)) < r + rq for q, rq in placed):
                    continue
                offset = float(c)
                break
            if offset is not None:
                break
        if offset is None:
            offset = 0.0
        routes.append(route)
        offsets.append(offset)
        placed.append((_np_position(route, offset, loop), r))
    return moving_obstacles(routes, speeds, radii, loop=loop, offsets=offsets)


def _as_path(path: ArrayLike, name: str = "path") -> np.ndarray:
    p = np.asarray(path, np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ValueError(f"{name} must be [L, 2] world points, got shape {p.shape}")
    if not np.isfinite(p).all():
        raise ValueError(f"{name} contains a non-finite coordinate")
    return p


def _free_extent(blocked: _Blocked, origin: np.ndarray, direction: np.ndarray, ext: np.ndarray, r: float) -> float:
    """The largest ``e`` of the increasing grid ``ext`` (``ext[0] = 0``, free) such that the
    segment ``origin → origin + e·direction`` (cells) is free for radius ``r``.

    Free extents form a prefix (a shorter segment is a subset of a longer one), so a
    binary search finds the boundary with about log2(len(ext)) exact tests.
    """
    lo, hi = 0, len(ext) - 1  # ext[lo] free; find the largest free index
    if blocked.free_for(origin, origin + ext[hi] * direction, r, _SHORTCUT_MARGIN):
        return float(ext[hi])
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if blocked.free_for(origin, origin + ext[mid] * direction, r, _SHORTCUT_MARGIN):
            lo = mid
        else:
            hi = mid
    return float(ext[lo])


def crossing_traffic(grid: Any, path: ArrayLike, n: int = 3, speed: Any = 1.0, radius: Any = 0.25, seed: int = 0, *,
                     span: float = 4.0, robot_speed: float | None = None, jitter: float = 0.25) -> MovingObstacles:
    """Traffic crossing a robot's planned route: ``n`` discs bouncing across it perpendicularly.

    Placement: the path (length ``L``) is cut into ``n`` equal slices; slice ``i`` offers
    nine candidate crossing points, its centre ``(i + 0.5)·L/n`` and eight drawn by the
    seed uniformly within ±30 % of the slice around it. At each, the crossing line is the normal of
    the path segment there; it extends up to ``span`` m to each side as far as a disc of
    ``radius`` stays clear of every blocked square (exact segment test; extents resolved
    to 1/8 cell). The candidate with the longest crossing wins (warehouse cross aisles),
    ties going to the one nearer the slice centre; candidates where the disc does not fit
    on the path are skipped. The route runs from one end of the crossing line (which one
    is random) to the other, bouncing.

    Phase rule: the robot is assumed to leave ``path[0]`` at ``t = 0`` and to move along
    the path at ``robot_speed`` (default: the obstacle's own speed), reaching the
    crossing point (arc length ``s``) at ``t* = s / robot_speed``. The offset is chosen
    so that the obstacle is at the crossing point, on its first pass, at ``t* + δ``,
    ``δ ~ U(−jitter, jitter)`` s. An obstacle of speed 0 stands on the crossing point.

    Args:
      grid: a `GridMap` or a `Scene`.
      path: ``[L, 2]`` world points (m) of the robot's planned route (``L >= 2``, length > 0).
      n: number of obstacles (>= 0).
      speed, radius: m/s and m (>= 0), scalars or ``[n]``.
      seed: integer seed (same seed, same obstacles).
      span: maximum extent (m) of a crossing to each side of the path (> 0).
      robot_speed: the robot's assumed speed (m/s, > 0) for the phase rule.
      jitter: half-width (s) of the random shift of the meeting time.

    Raises:
      ValueError: bad arguments, or a slice of the path where the disc fits nowhere.
    """
    g = _as_grid(grid)
    rng = _rng(seed)
    if not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    if not np.isfinite(span) or span <= 0:
        raise ValueError(f"span must be a finite number of metres > 0, got {span}")
    if not np.isfinite(jitter) or jitter < 0:
        raise ValueError(f"jitter must be finite and >= 0, got {jitter}")
    if robot_speed is not None and (not np.isfinite(robot_speed) or robot_speed <= 0):
        raise ValueError(f"robot_speed must be a finite number of m/s > 0, got {robot_speed}")
    p = _as_path(path)
    speeds = _per_obstacle("speed", speed, n)
    radii = _per_obstacle("radius", radius, n)
    seg_vec = np.diff(p, axis=0)
    seg = np.hypot(*seg_vec.T)
    total = float(seg.sum())
    if len(p) < 2 or total <= 0:
        raise ValueError("path must have at least two distinct points")
    if n == 0:
        return no_obstacles(0)
    res = float(g.resolution)
    blocked = _Blocked(g.free)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    moving = np.flatnonzero(seg > 0)
    ext = np.linspace(0.0, span, int(np.ceil(8.0 * span / res)) + 1)  # m, 1/8-cell steps
    routes, offsets = [], []
    for i in range(n):
        r = float(radii[i]) / res  # cells
        width = total / n
        ss = (i + 0.5) * width + np.concatenate([[0.0], rng.uniform(-0.3, 0.3, 8)]) * width
        best = None
        for s in ss:
            k = moving[min(np.searchsorted(cum[moving + 1], s, side="right"), len(moving) - 1)]
            c = p[k] + (s - cum[k]) / seg[k] * seg_vec[k]
            tangent = seg_vec[k] / seg[k]
            normal = np.array([-tangent[1], tangent[0]])
            cc = c / res - 0.5  # cell coordinates
            if not blocked.free_for(cc, cc, r, _SHORTCUT_MARGIN):
                continue  # the disc does not fit on the path here
            e = [_free_extent(blocked, cc, direction / res, ext, r) for direction in (normal, -normal)]
            score = (e[0] + e[1], -abs(s - (i + 0.5) * width))
            if best is None or score > best[0]:
                best = (score, s, c, normal, e)
        if best is None:
            raise ValueError(f"obstacle {i}: a disc of radius {radii[i]} m fits nowhere on the path "
                             f"between {i * total / n:.2f} and {(i + 1) * total / n:.2f} m")
        _, s, c, normal, (e_plus, e_minus) = best
        if rng.integers(2):  # start on the minus side instead
            normal, e_plus, e_minus = -normal, e_minus, e_plus
        a, b = c + e_plus * normal, c - e_minus * normal
        route = np.stack([a, b]) if e_plus + e_minus > 0 else c[None]
        v = float(speeds[i])
        half = e_plus + e_minus
        if v > 0 and half > 0:
            meet = s / (robot_speed if robot_speed is not None else v) + rng.uniform(-jitter, jitter)
            offset = float(np.mod(e_plus - v * meet, 2.0 * half))
        else:
            offset = e_plus  # standing still on the crossing point
        routes.append(route)
        offsets.append(offset)
    return moving_obstacles(routes, speeds, radii, loop=False, offsets=offsets)


def head_on(path: ArrayLike, speed: float = 1.0, radius: float = 0.25, *, delay: float = 0.0) -> MovingObstacles:
    """One disc travelling the robot's planned ``path`` in reverse, from its goal end (chu2024, Figure 11).

    The route is ``path[::-1]``, bouncing (not looping): the disc leaves the goal end,
    meets the robot head-on, reaches the start end and turns back. No map is checked: the
    path is expected to be planned for a footprint at least as large as the disc.

    Args:
      path: ``[L, 2]`` world points (m), start first.
      speed: m/s (>= 0).
      radius: m (>= 0).
      delay: seconds after ``t = 0`` at which the disc leaves the goal end (offset
        ``−speed·delay``). The model has no waiting, so for ``delay > 0`` the disc is,
        before that, on the last ``speed·delay`` metres of the path moving toward the goal
        end (the mirror image of its bounce); ``delay < 0`` means it left earlier.

    Returns:
      `MovingObstacles` with ``M = 1``.
    """
    p = _as_path(path)
    if not np.isfinite(delay):
        raise ValueError(f"delay must be finite, got {delay}")
    v = _per_obstacle("speed", speed, 1)
    return moving_obstacles([p[::-1]], v, radius, loop=False, offsets=-float(v[0]) * float(delay))
