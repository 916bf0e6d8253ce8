"""Episode metrics of a navigation run (docs/guide/smoothing-and-metrics.md): success, collisions, tracking RMSE,
energy, timing.

An executed trajectory is ``positions [..., T, 2]`` in world metres (the ``(x, y)`` of the
robot's state, sample ``t`` at time ``t·dt``, sample 0 the start) of which the first
``n [...]`` samples are valid. Planned paths are in cell coordinates as everywhere in
`jaxplan.metrics` (world = (cell + 0.5)·resolution). All functions are pure, shape-static
and work under ``jit`` and ``vmap``.

Example:
  >>> import jax.numpy as jnp
  >>> from jaxplan.metrics import energy, EnergyModel
  >>> float(energy(jnp.array([0.0, 1.0, 1.0]), jnp.zeros(3), dt=1.0, model=EnergyModel(mass=2.0, rolling=0.0)))
  1.0
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax.numpy as jnp

from jaxplan.grid import POINT_WINDOW, CollisionMap, point_clearance
from jaxplan.metrics._path import float_dtype
from jaxplan.metrics._polyline import point_polyline_distance

__all__ = [
    "EnergyModel", "EpisodeTiming", "collision_steps", "collisions", "arrival_time", "success", "rmse", "energy",
]


def _valid(shape_t: int, n: jnp.ndarray | None, batch: tuple[int, ...]) -> jnp.ndarray:
    """``bool[..., T]`` valid samples (all when ``n`` is None)."""
    if n is None:
        return jnp.ones(batch + (shape_t,), bool)
    return jnp.arange(shape_t) < jnp.asarray(n)[..., None]


def collision_steps(
    cmap: CollisionMap, positions: jnp.ndarray, radius: float | jnp.ndarray,
    obstacles: jnp.ndarray | None = None, obstacle_radii: jnp.ndarray | None = None, window: int = POINT_WINDOW,
) -> jnp.ndarray:
    """``bool[..., T]``: the robot disc overlaps a blocked square or a moving disc at each sample.

    Args:
      cmap: the map's `CollisionMap`.
      positions: ``[..., T, 2]`` robot centre (m).
      radius: robot radius (m).
      obstacles: optional ``[..., T, O, 2]`` centres (m) of moving discs at the same samples;
        a padding obstacle can be placed at ``+inf``.
      obstacle_radii: ``[..., O]`` their radii (m); required with ``obstacles``.

    A blocked-square collision is clearance < radius (docs/guide/navigation.md: touching is not a
    collision), the clearance being `point_clearance` of the centre: the decision is exact
    for a radius up to ``window`` cells (static; raise it for robots wider than 2 cells,
    e.g. on fine grids); a disc collision is centre distance < radius + obstacle radius.
    """
    pos = jnp.asarray(positions, float_dtype())
    res = cmap.resolution
    clearance = point_clearance(cmap, pos / res - 0.5, window) * res  # world metres -> cell coordinates and back
    hit = clearance < radius
    if obstacles is not None:
        if obstacle_radii is None:
            raise ValueError("obstacles given without obstacle_radii")
        obs = jnp.asarray(obstacles, float_dtype())
        gap = jnp.sqrt(jnp.sum((obs - pos[..., None, :]) ** 2, axis=-1))  # [..., T, O]
        reach = jnp.asarray(obstacle_radii, float_dtype())[..., None, :] + radius
        hit = hit | jnp.any(gap < reach, axis=-1)
    return hit


def collisions(
    cmap: CollisionMap, positions: jnp.ndarray, radius: float | jnp.ndarray,
    obstacles: jnp.ndarray | None = None, obstacle_radii: jnp.ndarray | None = None, n: jnp.ndarray | None = None,
    window: int = POINT_WINDOW,
) -> jnp.ndarray:
    """``int32[...]`` collisions in an episode: contacts, i.e. runs of consecutive colliding samples.

    A robot that scrapes along a wall for ten samples has one collision, not ten; leaving
    and touching again counts again. Arguments as in `collision_steps`; ``n [...]`` valid
    samples (all when None).
    """
    hit = collision_steps(cmap, positions, radius, obstacles, obstacle_radii, window)
    hit = hit & _valid(hit.shape[-1], n, hit.shape[:-1])
    before = jnp.concatenate([jnp.zeros_like(hit[..., :1]), hit[..., :-1]], axis=-1)
    return jnp.sum(hit & ~before, axis=-1, dtype=jnp.int32)


def arrival_time(
    positions: jnp.ndarray, goal: jnp.ndarray, tolerance: float | jnp.ndarray, dt: float | jnp.ndarray,
    n: jnp.ndarray | None = None,
) -> jnp.ndarray:
    """``[...]`` time (s) of the first valid sample within ``tolerance`` (m) of ``goal [..., 2]`` (m); inf if none."""
    pos = jnp.asarray(positions, float_dtype())
    d = jnp.sqrt(jnp.sum((pos - jnp.asarray(goal, pos.dtype)[..., None, :]) ** 2, axis=-1))
    near = (d <= tolerance) & _valid(d.shape[-1], n, d.shape[:-1])
    first = jnp.argmax(near, axis=-1)
    return jnp.where(jnp.any(near, axis=-1), first * dt, jnp.inf)


def success(
    positions: jnp.ndarray, goal: jnp.ndarray, n_collisions: jnp.ndarray, *, tolerance: float | jnp.ndarray,
    dt: float | jnp.ndarray, time_limit: float | jnp.ndarray, n: jnp.ndarray | None = None,
) -> jnp.ndarray:
    """``bool[...]``: the goal was reached within ``tolerance`` (m) by ``time_limit`` (s) without collision.

    Args:
      positions: ``[..., T, 2]`` (m), sample ``t`` at ``t·dt``.
      goal: ``[..., 2]`` (m).
      n_collisions: ``int[...]`` from `collisions` (any collision in the episode fails it).
      tolerance, dt, time_limit: metres, seconds, seconds.
      n: ``int[...]`` valid samples (all when None).
    """
    return (arrival_time(positions, goal, tolerance, dt, n) <= time_limit) & (jnp.asarray(n_collisions) == 0)


def rmse(
    positions: jnp.ndarray, path: jnp.ndarray, n_path: jnp.ndarray, resolution: float | jnp.ndarray,
    n: jnp.ndarray | None = None,
) -> jnp.ndarray:
    """``[...]`` root mean square distance (m) of the executed positions to the planned path polyline.

    Args:
      positions: ``[..., T, 2]`` executed positions (m).
      path: ``[..., L, 2]`` planned path (cells) with ``n_path [...]`` valid points; its
        polyline through the cell-coordinate points, scaled to metres, is the reference
        (a one-point path is that point).
      n_path: ``int[...]``.
      resolution: metres per cell.
      n: ``int[...]`` valid positions (all when None).

    Each distance is exact (point to nearest segment). ``+inf`` when the path or the
    trajectory is empty: there is nothing to measure against. Cost ``O(T·L)``.
    """
    pos = jnp.asarray(positions, float_dtype())
    world = (jnp.asarray(path, float_dtype()) + 0.5) * resolution
    d = point_polyline_distance(pos, world, jnp.asarray(n_path))
    valid = _valid(d.shape[-1], n, d.shape[:-1])
    count = jnp.sum(valid, axis=-1)
    ms = jnp.sum(jnp.where(valid, d * d, 0.0), axis=-1) / jnp.maximum(count, 1)
    return jnp.where((count > 0) & (jnp.asarray(n_path) > 0), jnp.sqrt(ms), jnp.inf)


@dataclasses.dataclass(frozen=True)
class EnergyModel:
    """Constants of the energy proxy ``∫ (m·|a|·|v| + c_r·m·g·|v| + c_w·|ω|) dt`` (docs/guide/smoothing-and-metrics.md).

    Attributes (defaults for the cui2025 robot: 0.25 m radius, v <= 1.2 m/s):
      mass: m, kg. 30 kg: a differential-drive robot of 0.5 m diameter with a light load
        (platforms of that size weigh 20–50 kg).
      rolling: c_r, rolling-resistance coefficient. 0.02: polyurethane or rubber wheels on
        a concrete floor (0.01–0.02).
      gravity: g, m/s².
      turn: c_w, J/rad. 1.18: turning on the spot rolls each wheel half the track width
        (0.2 m for this robot) per radian against the same rolling resistance:
        c_r·m·g·0.2 = 0.02·30·9.81·0.2 ≈ 1.18.

    The first term is the work of speeding up and braking (no regeneration), the second
    rolling resistance, the third turning. It is a proxy to compare runs, not a battery
    model: no motor efficiency, no idle power.
    """

    mass: float = 30.0
    rolling: float = 0.02
    gravity: float = 9.81
    turn: float = 1.18

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"EnergyModel.{f.name} must be a finite number >= 0, got {v!r}")


def _abs_integral(y0: jnp.ndarray, y1: jnp.ndarray, dt: float | jnp.ndarray) -> jnp.ndarray:
    """Exact ``∫ |y| dt`` over one period with ``y`` linear from ``y0`` to ``y1``."""
    same = y0 * y1 >= 0
    a0, a1 = jnp.abs(y0), jnp.abs(y1)
    cross = (y0 * y0 + y1 * y1) / jnp.where(same, 1.0, 2.0 * (a0 + a1))  # the sign change splits the period
    return jnp.where(same, 0.5 * (a0 + a1), cross) * dt


def energy(
    v: jnp.ndarray, omega: jnp.ndarray, dt: float | jnp.ndarray, model: EnergyModel = EnergyModel(),
    n: jnp.ndarray | None = None,
) -> jnp.ndarray:
    """``[...]`` energy proxy (J) of an executed velocity profile.

    Args:
      v: ``[..., T]`` linear velocity samples (m/s; negative is reversing), sample ``t`` at ``t·dt``.
      omega: ``[..., T]`` angular velocity samples (rad/s).
      dt: sample period (s).
      model: the `EnergyModel` constants.
      n: ``int[...]`` valid samples (all when None); 0 or 1 sample gives 0 J.

    Between samples the velocities are linear (constant acceleration ``a = Δv/dt`` over a
    period, as in a dynamic window step), and each term is integrated exactly over each
    period: ``m·|Δv|/dt·∫|v|dt + c_r·m·g·∫|v|dt + c_w·∫|ω|dt``. (With ``v`` of one sign the
    first term is ``m·|v1² − v0²|/2``, the change of kinetic energy.)
    """
    v = jnp.asarray(v, float_dtype())
    w = jnp.asarray(omega, float_dtype())
    v0, v1 = v[..., :-1], v[..., 1:]
    speed = _abs_integral(v0, v1, dt)
    per = (model.mass * jnp.abs(v1 - v0) / dt * speed + model.rolling * model.mass * model.gravity * speed
           + model.turn * _abs_integral(w[..., :-1], w[..., 1:], dt))
    valid = _valid(v.shape[-1], n, v.shape[:-1])[..., 1:]  # period t -> t + 1 needs both samples
    return jnp.sum(jnp.where(valid, per, 0.0), axis=-1)


class EpisodeTiming(NamedTuple):
    """Wall-clock costs of an episode (docs/guide/smoothing-and-metrics.md).

    Attributes:
      plan_time_s: global planning time (s), compilation excluded.
      step_time_s: local-planner time per control step (s): total local-planning time
        divided by the number of control steps, compilation excluded.
    """

    plan_time_s: float
    step_time_s: float

    @staticmethod
    def from_totals(plan_time_s: float, local_time_s: float, steps: int) -> "EpisodeTiming":
        """From the total local-planning time over ``steps`` control steps (0 steps: step time 0)."""
        return EpisodeTiming(float(plan_time_s), float(local_time_s) / steps if steps > 0 else 0.0)
