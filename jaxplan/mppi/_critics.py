"""MPPI critics: small pure functions that charge a sequence's points, controls or end, each in [0, 1].

A sequence's cost is ``Σ weight_i · critic_i`` (weights in `MPPIParams`) plus ``collision`` if it is
infeasible; lower is better. The critics follow Nav2's MPPI controller (``nav2_mppi_controller``),
normalised so that the weights compare:

* `obstacle` — per point, ``1 − min(c, d_clip)/d_clip`` for clearance ``c`` (m) to the map: 0 beyond
  ``d_clip``, 1 at contact (Nav2's obstacle critic's repulsion term); averaged over the points.
* `dynamic` — the same for the moving discs, ``1 − min(c, disc_clip)/disc_clip`` with ``c`` the clearance
  to their (inflated) predicted edges: walkers are given more room than walls.
* `path_align` — per period, the distance (m) of the period's end point to the local global path,
  ``min(d, path_clip)/path_clip``; averaged (Nav2's path-align critic).
* `path_follow` — progress towards the sub-goal: ``(|p_T − g| − |p_0 − g| + reach) / (2·reach)`` clipped
  to [0, 1] — 0 for a sequence that gains ``reach`` (the farthest any can travel) on the sub-goal, ½ for
  one that stands, 1 for one that loses ``reach`` (Nav2's path-follow critic, in units of the reach so
  that a far sub-goal still tells sequences apart).
* `goal` — within ``goal_radius`` of the goal only, the points' mean distance to the goal over
  ``goal_radius`` (Nav2's goal critic with its ``threshold_to_consider``); 0 farther away.
* `goal_heading` — the angle between the end heading and the direction from the end point to the
  sub-goal, over π (Nav2's path-angle critic; the DWA's heading critic G = 1 − this).
* `prefer_forward` — per period, ``max(0, −v)/v_max``; averaged (Nav2's prefer-forward critic).
* `constraint` — per period, how far the raw (noisy) control lay outside what the robot can reach
  in one period, in units of that reach, ``(|v_raw − v|/(a·P) + |ω_raw − ω|/(α·P)) / 2`` clipped to
  1; averaged (Nav2's constraint critic, for a model that clamps): it pulls the mean sequence back
  into the dynamic window.

The rollout (`jaxplan.mppi._rollout`) sums the per-point and per-period values as it goes
(`add_point`, `add_control`); `finish_terms` turns the sums into means and adds the end critics.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

from jaxplan.core.geometry import point_segment_distance
from jaxplan.dwa import abs_angle

__all__ = [
    "Context", "End", "Terms", "obstacle", "dynamic", "path_distance", "path_align", "path_follow", "goal",
    "goal_heading",
    "prefer_forward", "constraint", "zero_sums", "add_point", "add_control", "finish_terms", "cost",
]


class Context(NamedTuple):
    """What the critics compare a sequence with (one robot; a pytree).

    Attributes:
      subgoal: ``f32[2]`` the point the robot heads for now (m).
      goal: ``f32[2]`` the goal (m).
      path: ``f32[L, 2]`` the local stretch of the global path (m), ``n_path`` points valid.
      n_path: ``i32`` valid points of ``path`` (0: no path; the path-align critic is then 0).
      origin: ``f32[2]`` the robot's position now (m).
      reach: the farthest a sequence can travel (m): ``max(|v_min|, v_max) · horizon``.
      near_goal: ``bool`` the robot is within ``goal_radius`` of the goal (the goal critic is on).
    """

    subgoal: jnp.ndarray
    goal: jnp.ndarray
    path: jnp.ndarray
    n_path: jnp.ndarray
    origin: jnp.ndarray
    reach: jnp.ndarray
    near_goal: jnp.ndarray


class End(NamedTuple):
    """End state of K sequences: position ``x, y [K]`` (m), heading ``h`` (complex unit ``[K]``), v, ω ``[K]``."""

    x: jnp.ndarray
    y: jnp.ndarray
    h: jnp.ndarray
    v: jnp.ndarray
    w: jnp.ndarray


class Terms(NamedTuple):
    """Every critic's value ``f32[K]`` in [0, 1] (fields as the `MPPIParams` weights), and the end state."""

    obstacle: jnp.ndarray
    dynamic: jnp.ndarray
    path_align: jnp.ndarray
    path_follow: jnp.ndarray
    goal: jnp.ndarray
    goal_heading: jnp.ndarray
    prefer_forward: jnp.ndarray
    constraint: jnp.ndarray
    end: End


# Per-point and per-period critics (elementwise over the K sequences).

def obstacle(c: jnp.ndarray, d_clip) -> jnp.ndarray:
    """``1 − min(c, d_clip)/d_clip`` for clearance ``c`` (m; negative inside an obstacle counts as 0)."""
    return 1.0 - jnp.clip(c, 0.0, d_clip) / d_clip


def dynamic(c: jnp.ndarray, disc_clip) -> jnp.ndarray:
    """``1 − min(c, disc_clip)/disc_clip`` for clearance ``c`` (m) to the moving discs."""
    return obstacle(c, disc_clip)


def path_distance(x: jnp.ndarray, y: jnp.ndarray, path: jnp.ndarray, n: jnp.ndarray) -> jnp.ndarray:
    """Distance (m) from points ``x, y [K]`` to the polyline ``path [L, 2]`` with ``n`` valid points (+inf if 0)."""
    p = jnp.stack([x, y], axis=-1)[:, None, :]  # [K, 1, 2]
    a, b = path[:-1], path[1:]  # [L - 1, 2]
    seg = jnp.arange(path.shape[0] - 1) < n - 1
    d = jnp.where(seg, point_segment_distance(p, a, b), jnp.inf)  # [K, L - 1]
    single = jnp.sqrt(jnp.sum((p[:, 0] - path[0]) ** 2, axis=-1))  # a one-point path is that point
    return jnp.where(n == 1, single, jnp.where(n > 1, jnp.min(d, axis=-1), jnp.inf))


def path_align(x, y, path, n, path_clip) -> jnp.ndarray:
    """``min(d, path_clip)/path_clip``, d the distance of ``x, y [K]`` to the local path (0 without a path)."""
    d = path_distance(x, y, path, n)
    return jnp.where(n > 0, jnp.minimum(d, path_clip) / path_clip, 0.0)


def path_follow(x, y, subgoal, origin, reach) -> jnp.ndarray:
    """``(|p − g| − |p_0 − g| + reach) / (2·reach)`` in [0, 1]: the end point's progress on the sub-goal."""
    d = jnp.sqrt((x - subgoal[0]) ** 2 + (y - subgoal[1]) ** 2)
    return jnp.clip((d - jnp.sqrt(jnp.sum((origin - subgoal) ** 2)) + reach) / (2.0 * reach), 0.0, 1.0)


def goal(x, y, goal_xy, radius) -> jnp.ndarray:
    """``min(|p − goal|, radius)/radius`` per point."""
    return jnp.minimum(jnp.sqrt((x - goal_xy[0]) ** 2 + (y - goal_xy[1]) ** 2), radius) / radius


def goal_heading(x, y, h, subgoal) -> jnp.ndarray:
    """Angle between the heading ``h`` (complex unit) and the direction to the sub-goal, over π (0 at the sub-goal)."""
    dx, dy = subgoal[0] - x, subgoal[1] - y
    return abs_angle(h.real * dy - h.imag * dx, h.real * dx + h.imag * dy) / math.pi


def prefer_forward(v, v_max) -> jnp.ndarray:
    """``max(0, −v)/v_max``."""
    return jnp.maximum(-v, 0.0) / v_max


def constraint(v, w, v_raw, w_raw, robot, period) -> jnp.ndarray:
    """How far the raw control lay outside one period's reach, in units of that reach (clipped to 1)."""
    dv = jnp.abs(v_raw - v) / jnp.maximum(robot.accel * period, 1e-6)
    dw = jnp.abs(w_raw - w) / jnp.maximum(robot.alpha * period, 1e-6)
    return jnp.minimum(0.5 * (dv + dw), 1.0)


# Running sums kept by the rollout loop.

def zero_sums(zero: jnp.ndarray) -> dict:
    return dict(obstacle=zero, dynamic=zero, goal=zero, path_align=zero, prefer_forward=zero, constraint=zero)


def add_point(sums: dict, config, ctx: Context, x, y, c_map, c_dyn) -> dict:
    """The sums after one rollout point (clearances ``c_map`` to the map and ``c_dyn`` to the discs at ``x, y``)."""
    return dict(sums, obstacle=sums["obstacle"] + obstacle(c_map, config.d_clip),
                dynamic=sums["dynamic"] + dynamic(c_dyn, config.disc_clip),
                goal=sums["goal"] + goal(x, y, ctx.goal, config.goal_radius))


def add_control(sums: dict, config, ctx: Context, x, y, v, w, v_raw, w_raw) -> dict:
    """The sums after one period (its end point ``x, y``, clamped and raw controls)."""
    return dict(sums, path_align=sums["path_align"] + path_align(x, y, ctx.path, ctx.n_path, config.path_clip),
                prefer_forward=sums["prefer_forward"] + prefer_forward(v, config.robot.v_max),
                constraint=sums["constraint"] + constraint(v, w, v_raw, w_raw, config.robot, config.period))


def finish_terms(sums: dict, config, ctx: Context, end: End, steps: int) -> Terms:
    """Means of the sums, the goal critic gated by ``ctx.near_goal``, and the end critics."""
    points = steps * config.substeps
    return Terms(
        obstacle=sums["obstacle"] / points,
        dynamic=sums["dynamic"] / points,
        path_align=sums["path_align"] / steps,
        path_follow=path_follow(end.x, end.y, ctx.subgoal, ctx.origin, ctx.reach),
        goal=jnp.where(ctx.near_goal, sums["goal"] / points, 0.0),
        goal_heading=goal_heading(end.x, end.y, end.h, ctx.subgoal),
        prefer_forward=sums["prefer_forward"] / steps,
        constraint=sums["constraint"] / steps,
        end=end,
    )


def cost(terms: Terms, params) -> jnp.ndarray:
    """``Σ weight_i · critic_i`` ``f32[K]`` (without the collision cost and the control cost)."""
    return (params.obstacle * terms.obstacle + params.dynamic * terms.dynamic + params.path_align * terms.path_align
            + params.path_follow * terms.path_follow + params.goal * terms.goal
            + params.goal_heading * terms.goal_heading + params.prefer_forward * terms.prefer_forward
            + params.constraint * terms.constraint)
