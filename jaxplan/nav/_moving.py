"""Moving obstacles: discs that travel piecewise-linear routes at constant speed (the motion model).

The model (docs/guide/navigation.md; li2026's moving obstacles at 1.0 and 1.5 m/s, chu2024's
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

The scenario generators that build routes on a map are in `jaxplan.nav._traffic`.
"""

from __future__ import annotations

from typing import Any, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from jaxplan.dwa import DiscObstacles

__all__ = [
    "MovingObstacles", "obstacle_state", "route_target", "with_reactive", "discs_at", "trajectories", "route_lengths",
    "no_obstacles",
    "pad_obstacles", "concat_obstacles", "stack_obstacles", "moving_obstacles", "per_obstacle", "FAR",
    "FAR_SPACING",
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
      reactive: ``bool[..., M]`` walkers that see (`jaxplan.nav._social`: they keep to their route but avoid
        the robots, each other and the walls, simulated in the episode), or None: every disc blind, on its
        route by time. None keeps a set of blind walkers' episode program free of the simulation.

    Build with `moving_obstacles` or a generator; the module docstring gives the model.
    """

    waypoints: jnp.ndarray
    n_waypoints: jnp.ndarray
    speeds: jnp.ndarray
    radii: jnp.ndarray
    loop: jnp.ndarray
    offsets: jnp.ndarray
    reactive: jnp.ndarray | None = None

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
    positions, velocities, _, _ = _placement(obs, t)
    return positions, velocities


def route_target(obs: MovingObstacles, t) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The route vertex each disc heads for at time ``t``, and whether it travels its route forwards.

    Returns:
      ``(target i32[..., M] (a route vertex index), forward bool[..., M])``: what a reactive walker
      (`jaxplan.nav._social`) starts from.
    """
    _, _, idx, back = _placement(obs, t)
    n = jnp.clip(jnp.asarray(obs.n_waypoints, jnp.int32), 1, None)
    nxt = jnp.where(back, idx, idx + 1)
    loop = jnp.asarray(obs.loop, bool)
    nxt = jnp.where(nxt >= n, jnp.where(loop, 0, n - 1), nxt)
    return nxt.astype(jnp.int32), ~back


def _placement(obs: MovingObstacles, t):
    """Positions, velocities, the travelled segment's index and whether on a bounce's way back, at time ``t``."""
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
    passed = jnp.where(back, jnp.sum(cum[..., 1:] < u[..., None], axis=-1),
                       jnp.sum(cum[..., 1:] <= u[..., None], axis=-1))
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
    return positions, velocities, idx[..., 0], back


def discs_at(obs: MovingObstacles, t) -> DiscObstacles:
    """The `DiscObstacles` snapshot at time ``t`` (s) that a DWA step consumes (constant-velocity prediction)."""
    positions, velocities = obstacle_state(obs, t)
    return DiscObstacles(positions, velocities, jnp.asarray(obs.radii, jnp.float32))


def trajectories(obs: MovingObstacles, times: ArrayLike) -> jnp.ndarray:
    """``f32[T, ..., M, 2]``: positions (m) at each of ``times f32[T]`` (s), for metrics and plots.

    One compiled call per shape (op by op, the model would compile each of its ~50
    operations on first use, seconds of a cold run).
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


def with_reactive(obs: MovingObstacles) -> MovingObstacles:
    """``obs`` with an explicit ``reactive`` array (all blind where it was None)."""
    if obs.reactive is not None:
        return obs
    return obs._replace(reactive=jnp.zeros(obs.radii.shape, bool))


def concat_obstacles(a: MovingObstacles, b: MovingObstacles) -> MovingObstacles:
    """The slots of ``a`` then those of ``b`` (routes padded to the longer ``K``; same batch axes)."""
    k = max(a.waypoints.shape[-2], b.waypoints.shape[-2])
    a, b = _pad_k(a, k), _pad_k(b, k)
    if (a.reactive is None) != (b.reactive is None):
        a, b = with_reactive(a), with_reactive(b)
    axes = MovingObstacles(-3, -1, -1, -1, -1, -1, None if a.reactive is None else -1)  # each field's M axis
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
    if any(o.reactive is not None for o in sets):
        sets = [with_reactive(o) for o in sets]
    padded = [_PAD(o, m, k) for o in sets]
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *padded)


_PAD = jax.jit(pad_obstacles, static_argnums=(1, 2))  # sets of one shape share one compiled call


# --------------------------------------------------------------------------------------
# Host constructor and validation
# --------------------------------------------------------------------------------------


def per_obstacle(name: str, value: Any, m: int, *, nonneg: bool = True) -> np.ndarray:
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
                     offsets: Any = 0.0, reactive: Any = None) -> MovingObstacles:
    """Builds validated `MovingObstacles` from host data.

    Args:
      routes: ``M`` routes, each ``[k_i, 2]`` world points (m), ``k_i >= 1``.
      speeds: m/s along the route, >= 0: a scalar or ``[M]``.
      radii: disc radii (m), >= 0: a scalar or ``[M]``.
      loop: bool, scalar or ``[M]`` (True: loop, False: bounce).
      offsets: arc length (m) travelled at ``t = 0``, any finite value: a scalar or ``[M]``.
      reactive: None (every disc blind), or a bool scalar or ``[M]``: walkers that see (`jaxplan.nav._social`).

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
    sp = per_obstacle("speed", speeds, m)
    rad = per_obstacle("radius", radii, m)
    off = per_obstacle("offset", offsets, m, nonneg=False)
    lp = np.asarray(loop)
    if lp.ndim == 0:
        lp = np.full(m, bool(lp))
    elif lp.shape != (m,):
        raise ValueError(f"loop must be a scalar or have one entry per obstacle ({m}), got shape {lp.shape}")
    react = None
    if reactive is not None:
        react = np.asarray(reactive)
        if react.ndim == 0:
            react = np.full(m, bool(react))
        elif react.shape != (m,):
            raise ValueError(f"reactive must be None, a bool or one entry per obstacle ({m}), got shape {react.shape}")
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
        reactive=None if react is None else jnp.asarray(react.astype(bool)),
    )
