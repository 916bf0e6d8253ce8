"""Clearance of trajectory points: to the map's blocked squares and to moving discs.

Clearance (docs/guide/navigation.md) is the distance from a point to the nearest blocked cell's
boundary (a blocked cell is the closed unit square around its centre; outside the map
is blocked) or to the edge of a moving disc. The rollouts ask it for every one of
S·T points per robot and step, so the static part is a table lookup built once per
map on the host (`clearance_table`). Three lookups, selected by name:

* ``"hybrid"`` (default) — **exact below 1.5 cells, an interpolation above.** The
  point's interpolation cell (the square between the four cell centres around it) is
  looked up in four tables, one gather each at the same index. Each table holds the
  clearance of one of the four centres and, packed into the four lowest mantissa bits
  (a relative change below 2⁻¹⁹), the blocked flags of one 2×2 quarter of the 4×4
  cells around the interpolation cell. Every blocked square closer than 1.5 cells to
  the point is among those 16, so the minimum exact point-to-square distance over the
  flagged ones is the true clearance whenever it is below 1.5 cells. Beyond, the value
  is the bilinear interpolation of the four centres' exact clearances (the
  ``CollisionMap.field``), clipped to [1.5, that minimum]: an interpolation of a
  1-Lipschitz field, which may over-estimate by a small fraction of a cell and
  under-estimates near ridges of the field. Feasibility
  at d_safe is therefore decided exactly whenever d_safe < 1.5 cells (every map
  coarser than 0.2 m per cell for the default 0.3 m).
* ``"bilinear"`` — the plain bilinear interpolation of the cell-centre clearance field
  (blocked centres at −0.5 cell, so a wall face interpolates to exactly 0 between a
  free and a blocked centre; floored at 0). About half the cost of ``"hybrid"``, but an
  interpolation everywhere: at a convex obstacle corner it over-estimates by up to 0.30
  cells, so a rollout judged feasible can graze a corner.
* ``"exact"`` — `jaxplan.grid._collision.point_clearance`: exact up to 2 cells (a
  5×5 window of point-to-square distances); tens of times slower — for checking.

Moving obstacles are discs predicted at constant velocity (`DiscObstacles`), or along
given tracks sampled at the rollout's times (``DiscObstacles.track``: the navigation
episodes' ``prediction="oracle"`` ablation hands the DWA the walkers' true futures).

All lookups are differentiable almost everywhere in the point (square roots are
guarded so that points inside obstacles give zero, not NaN, gradients).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import lax

from jaxplan.grid import PAD as CMAP_PAD
from jaxplan.grid import CollisionMap, point_clearance

__all__ = [
    "ClearanceTable", "clearance_table", "static_clearance", "DiscObstacles", "no_obstacles", "disc_clearance",
    "HYBRID_EXACT_CELLS",
]

PAD = 3
"""Blocked cells kept around the map in the tables (the 4×4 window of a clipped point stays inside)."""

HYBRID_EXACT_CELLS = 1.5
"""The hybrid lookup is exact for clearances below this many cells."""

_BIG = 1e6  # squared distance (cells²) standing for "no blocked square in the window"
_EPS2 = 1e-12  # floor under squared distances: keeps sqrt's gradient finite at 0


class ClearanceTable(NamedTuple):
    """Lookup tables of a map's static clearance. A pytree; build with `clearance_table`.

    Attributes:
      quads: ``f32[4, (H + 2·PAD)·(W + 2·PAD)]``. Entry ``i`` of table ``r = dx + 2·dy``
        belongs to the interpolation cell whose lower corner is the centre of cell
        ``(x, y)``, ``i = (y + PAD)·(W + 2·PAD) + x + PAD``: the clearance (cells) of the
        centre of cell ``(x + dx, y + dy)`` (−0.5 if blocked), with the blocked flags of
        the cells ``x + 2dx − 1 .. x + 2dx`` × ``y + 2dy − 1 .. y + 2dy`` in its 4 low
        mantissa bits (bit ``a + 2b`` for the a-th column and b-th row of that quarter).
      cmap: the `CollisionMap` (for ``"exact"``).
      resolution: metres per cell (f32 scalar).
      inv_resolution: cells per metre (f32 scalar; precomputed so that the compiled step
        needs no division kernel of its own).
      speed_limit: None, or ``f32[H, W]`` the map's `jaxplan.grid.GridMap.speed_limit` (fraction of the
        top speed per cell): `dwa_control` and `jaxplan.mppi.mppi_control` then cap their top speed at
        the robot's cell (`speed_cap`). None (the default) leaves the pytree, and every result, as before.
    """

    quads: jnp.ndarray
    cmap: CollisionMap
    resolution: jnp.ndarray
    inv_resolution: jnp.ndarray
    speed_limit: jnp.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` of the map."""
        return self.cmap.shape


def clearance_table(cmap: CollisionMap) -> ClearanceTable:
    """Builds the lookup tables of a `CollisionMap` (host side, numpy; once per map)."""
    H, W = cmap.shape
    blocked_map = np.asarray(cmap.blocked)[CMAP_PAD:CMAP_PAD + H, CMAP_PAD:CMAP_PAD + W]
    field = np.where(blocked_map, -0.5, np.asarray(cmap.field, np.float32)).astype(np.float32)
    # Two extra rings so that every quarter of every table entry can be read without bounds checks.
    E = PAD + 2
    blk = np.pad(blocked_map, E, constant_values=True)
    fld = np.pad(field, E, constant_values=-0.5).astype(np.float32)
    Hp, Wp = H + 2 * PAD, W + 2 * PAD
    ys, xs = np.mgrid[0:Hp, 0:Wp]  # table coordinates; cell (x, y) = (xs - PAD, ys - PAD)
    quads = []
    for dy in (0, 1):
        for dx in (0, 1):
            value = fld[ys + 2 + dy, xs + 2 + dx]
            bits = np.zeros((Hp, Wp), np.uint32)
            for b in (0, 1):
                for a in (0, 1):
                    flag = blk[ys + 2 + 2 * dy - 1 + b, xs + 2 + 2 * dx - 1 + a]
                    bits |= flag.astype(np.uint32) << np.uint32(a + 2 * b)
            packed = (value.view(np.uint32) & np.uint32(0xFFFFFFF0)) | bits
            quads.append(packed.view(np.float32).reshape(-1))
    res = float(cmap.resolution)
    return ClearanceTable(jnp.asarray(np.stack(quads)), cmap, jnp.asarray(res, jnp.float32),
                          jnp.asarray(1.0 / res, jnp.float32))


def speed_cap(table: ClearanceTable, xy: jnp.ndarray, v_max) -> jnp.ndarray:
    """The top speed allowed at the cell of point ``xy [..., 2]`` (m, the map's frame): ``v_max`` times the
    table's speed limit there (a point off the map reads the nearest cell); ``v_max`` if the table has none."""
    if table.speed_limit is None:
        return jnp.asarray(v_max)
    H, W = table.shape
    cx = jnp.clip(jnp.floor(xy[..., 0] * table.inv_resolution), 0, W - 1).astype(jnp.int32)
    cy = jnp.clip(jnp.floor(xy[..., 1] * table.inv_resolution), 0, H - 1).astype(jnp.int32)
    return jnp.minimum(v_max, v_max * table.speed_limit[cy, cx])


def _lookup(table: ClearanceTable, u: jnp.ndarray, v: jnp.ndarray):
    """Gathers the four corner entries of the interpolation cell of cell-coordinate points."""
    H, W = table.shape
    # Beyond one cell outside the map everything is blocked; clipping keeps indices in range.
    u = jnp.clip(u, -1.0, float(W))
    v = jnp.clip(v, -1.0, float(H))
    fu, fv = jnp.floor(u), jnp.floor(v)
    a, b = u - fu, v - fv
    idx = ((fv + PAD) * (W + 2 * PAD) + (fu + PAD)).astype(jnp.int32)
    q = [jnp.take(table.quads[r], idx, mode="clip") for r in range(4)]
    return q, a, b


def _bilinear(q, a, b):
    return (1 - a) * (1 - b) * q[0] + a * (1 - b) * q[1] + (1 - a) * b * q[2] + a * b * q[3]


def _min(a: jnp.ndarray, b: jnp.ndarray) -> jnp.ndarray:
    # A select instead of jnp.minimum: no NaN can occur here, and XLA's NaN-propagating
    # minimum costs four vector instructions where a compare and a blend cost two.
    return jnp.where(a < b, a, b)


def _near_squared(q, a, b) -> jnp.ndarray:
    """Squared exact distance (cells²) to the nearest flagged square of the 4×4 window (or `_BIG`).

    Row by row: the nearest flagged square of a row lies on the point's left (columns −1,
    0) or right (1, 2), and on each side the inner column, when flagged, hides the outer
    one; the row's distance is that gap combined with the row's own vertical gap.
    """
    bits = [lax.bitcast_convert_type(x, jnp.int32) for x in q]

    def flag(m: int, n: int) -> jnp.ndarray:  # window column m, row n in 0..3 (cell offsets -1..2)
        return (bits[(m >= 2) + 2 * (n >= 2)] & (1 << ((m % 2) + 2 * (n % 2)))) != 0

    big = jnp.asarray(_BIG, a.dtype)
    gx = (a + 0.5, jnp.maximum(a - 0.5, 0.0), jnp.maximum(0.5 - a, 0.0), 1.5 - a)  # columns -1..2
    gy = (b + 0.5, jnp.maximum(b - 0.5, 0.0), jnp.maximum(0.5 - b, 0.0), 1.5 - b)  # rows -1..2
    best = big
    for n in range(4):
        left = jnp.where(flag(1, n), gx[1], jnp.where(flag(0, n), gx[0], big))
        right = jnp.where(flag(2, n), gx[2], jnp.where(flag(3, n), gx[3], big))
        g = _min(left, right)
        best = _min(best, g * g + gy[n] * gy[n])
    return best


def static_clearance(table: ClearanceTable, x: jnp.ndarray, y: jnp.ndarray, mode: str = "hybrid") -> jnp.ndarray:
    """Clearance (m) of world points ``x, y [...]`` (m) from the map's blocked squares.

    ``mode`` (static) is ``"hybrid"``, ``"bilinear"`` or ``"exact"`` (module docstring).
    Points outside the map have clearance 0.
    """
    res, inv = table.resolution, table.inv_resolution  # a per-point divide costs ten multiplies
    u = x * inv - 0.5  # world metres -> cell coordinates (cell centres at integers)
    v = y * inv - 0.5
    if mode == "exact":
        return point_clearance(table.cmap, jnp.stack([u, v], axis=-1)) * res
    q, a, b = _lookup(table, u, v)
    bil = _bilinear(q, a, b)
    if mode == "bilinear":
        return jnp.maximum(bil, 0.0) * res
    if mode != "hybrid":
        raise ValueError(f"unknown clearance mode {mode!r}; choose 'hybrid', 'bilinear' or 'exact'")
    near = jnp.sqrt(jnp.maximum(_near_squared(q, a, b), _EPS2))
    # Beyond the exact range the truth lies in [1.5, near]: keep the interpolation inside it.
    far = _min(near, jnp.where(bil > HYBRID_EXACT_CELLS, bil, HYBRID_EXACT_CELLS))
    return jnp.where(near < HYBRID_EXACT_CELLS, near, far) * res


class DiscObstacles(NamedTuple):
    """Moving discs, predicted at constant velocity unless a track is given. A pytree; batch axes lead.

    Attributes:
      positions: ``f32[M, 2]`` centres (m) at the time of the step.
      velocities: ``f32[M, 2]`` (m/s).
      radii: ``f32[M]`` (m, >= 0).
      track: None (constant velocity), or ``f32[M, K, 2]`` centres (m) at ``0, dt, …,
        (K − 1)·dt`` after the step, ``dt`` the DWA's rollout step: the prediction to use
        instead (`disc_clearance` takes the sample nearest to ``t``, the last one beyond).
        Navigation's ``prediction="oracle"`` ablation passes the walkers' true futures.

    ``M`` may be 0. Padding slots (a fixed M for a varying number of obstacles) should
    sit far away (e.g. 1e6 m) with radius 0 and zero velocity: finite values keep
    gradients finite.
    """

    positions: jnp.ndarray
    velocities: jnp.ndarray
    radii: jnp.ndarray
    track: jnp.ndarray | None = None

    @property
    def count(self) -> int:
        return int(self.radii.shape[-1])


def no_obstacles() -> DiscObstacles:
    """An empty `DiscObstacles` (M = 0)."""
    return DiscObstacles(jnp.zeros((0, 2)), jnp.zeros((0, 2)), jnp.zeros((0,)))


def disc_clearance(obstacles: DiscObstacles, x: jnp.ndarray, y: jnp.ndarray, t, dt: float | None = None) -> jnp.ndarray:
    """Distance (m) from points ``x, y [...]`` to the nearest disc edge at time ``t`` (s); +inf if M = 0.

    ``t`` is a scalar, or one time per point (an array of the points' shape). Negative inside a disc.
    ``dt`` (s) is the spacing of ``obstacles.track``'s samples, needed
    only when a track is given.
    """
    M = obstacles.radii.shape[-1]
    if M == 0:
        return jnp.full(jnp.shape(x), jnp.inf, jnp.result_type(x))
    if jnp.ndim(t) > 0:  # a time per point (the braking check's runs): each point meets the discs at its time
        return _disc_clearance_per_point(obstacles, x, y, jnp.broadcast_to(jnp.asarray(t, jnp.float32),
                                                                           jnp.shape(x)), dt)
    if obstacles.track is not None:
        if dt is None:
            raise ValueError("disc_clearance: obstacles with a track need the track's sample spacing dt")
        k = jnp.clip(jnp.round(jnp.asarray(t, jnp.float32) / dt), 0, obstacles.track.shape[-2] - 1).astype(jnp.int32)
        c = lax.dynamic_index_in_dim(obstacles.track, k, axis=-2, keepdims=False)  # [M, 2]
        cx, cy = c[:, 0], c[:, 1]
    else:
        cx = obstacles.positions[:, 0] + obstacles.velocities[:, 0] * t  # [M]
        cy = obstacles.positions[:, 1] + obstacles.velocities[:, 1] * t
    best = None
    for j in range(M) if M <= 8 else ():
        # Few discs: unrolled, so the distance stays inside the caller's elementwise fusion.
        d = jnp.sqrt(jnp.maximum((x - cx[j]) ** 2 + (y - cy[j]) ** 2, _EPS2)) - obstacles.radii[j]
        best = d if best is None else jnp.minimum(best, d)
    if best is None:
        d2 = (x[..., None] - cx) ** 2 + (y[..., None] - cy) ** 2
        best = jnp.min(jnp.sqrt(jnp.maximum(d2, _EPS2)) - obstacles.radii, axis=-1)
    return best


def _disc_clearance_per_point(obstacles: DiscObstacles, x: jnp.ndarray, y: jnp.ndarray, t: jnp.ndarray,
                              dt: float | None) -> jnp.ndarray:
    """`disc_clearance` with a time per point ``t [...]`` (the points' shape)."""
    if obstacles.track is not None:
        if dt is None:
            raise ValueError("disc_clearance: obstacles with a track need the track's sample spacing dt")
        k = jnp.clip(jnp.round(t / dt), 0, obstacles.track.shape[-2] - 1).astype(jnp.int32)  # [...]
        c = obstacles.track[:, k]  # [M, ..., 2]
        cx, cy = jnp.moveaxis(c[..., 0], 0, -1), jnp.moveaxis(c[..., 1], 0, -1)  # [..., M]
    else:
        cx = obstacles.positions[:, 0] + obstacles.velocities[:, 0] * t[..., None]  # [..., M]
        cy = obstacles.positions[:, 1] + obstacles.velocities[:, 1] * t[..., None]
    d2 = (x[..., None] - cx) ** 2 + (y[..., None] - cy) ** 2
    return jnp.min(jnp.sqrt(jnp.maximum(d2, _EPS2)) - obstacles.radii, axis=-1)
