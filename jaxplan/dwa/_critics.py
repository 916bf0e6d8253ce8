"""Critics: small pure functions scoring rollouts, and the weighted and classic evaluators.

Every critic maps the S rollouts of one step to ``f32[S]`` in [0, 1], higher is better
(cui2025 Eq. (7) and docs/guide/navigation.md):

* `heading` G = 1 − |Δ|/π, Δ the angle between the rollout's end heading and the
  direction from its end point to the sub-goal ("the angular deviation between the
  current path endpoint and the target point", cui2025);
* `velocity` V = (v − v_min)/(v_max − v_min), i.e. v/v_max for a robot that does not
  reverse;
* `clearance` O = min(c, d_clip)/d_clip, c the rollout's minimum clearance (m): clipped
  so that beyond ``d_clip`` more room does not outweigh progress;
* `path` P = 1 − min(d, path_clip)/path_clip, d the distance (m) from the end point to
  the global path (a polyline);
* `goal` D = 1 − |end − g| / (|p₀ − g| + reach), the end point's distance to the
  sub-goal relative to the largest it could be (``reach`` = the farthest a rollout can
  travel), so D ∈ [0, 1].

`weighted` is Eq. (7) with every critic first normalised across the feasible samples
(divided by its mean over them, the normalisation of Fox et al.'s DWA that chu2024
writes as σ, with the mean floored at `NORM_FLOOR`): each critic then contributes in
proportion to how much it varies relative to its level in this window, not to its
units, and the score is of order ``Σ weights``, which is what the softmax temperature is
relative to. `classic` reproduces PythonRobotics' ``dynamic_window_approach.py``:
``cost = to_goal_gain·|Δ| + speed_gain·(v_max − v) + obstacle_gain/c``, score = −cost.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp

from jaxplan.dwa._config import DWAParams
from jaxplan.dwa._fastmath import abs_angle
from jaxplan.dwa._robot import Robot

__all__ = [
    "Critics", "heading_error", "heading", "velocity", "clearance", "path_distance", "path", "goal",
    "NORM_FLOOR", "normalised_weights", "weighted", "classic", "critics",
]

_TINY = 1e-12

NORM_FLOOR = 0.25
"""Least divisor of the across-sample normalisation (a quarter of a critic's [0, 1] range).

Dividing by the mean alone blows a critic that barely varies near zero up to full
weight: a robot creeping in front of a wall sees speeds 0–0.05 m/s (V ≈ 0–0.04) turned
into a spread as large as the heading's, and circles in the dead end instead of stopping.
Above a mean of 0.25 the floor changes nothing."""


class Critics(NamedTuple):
    """The critic values of S rollouts, each ``f32[S]`` (see module docstring).

    ``heading_error`` is |Δ| (rad) and ``min_clearance`` the raw clearance (m): the
    inputs of the fuzzy and classic evaluators.
    """

    heading: jnp.ndarray
    velocity: jnp.ndarray
    clearance: jnp.ndarray
    path: jnp.ndarray
    goal: jnp.ndarray
    heading_error: jnp.ndarray
    min_clearance: jnp.ndarray


def heading_error(end: jnp.ndarray, subgoal: jnp.ndarray, end_dir: jnp.ndarray | None = None) -> jnp.ndarray:
    """|Δ| (rad, in [0, π]) between end headings and the directions from end points to the sub-goal.

    ``end [S, 3]`` poses, ``subgoal [2]`` m, optionally ``end_dir [S, 2]`` = (cos θ, sin θ)
    of the end headings (computed from θ otherwise). Δ = atan2(heading × dir, heading · dir),
    so no angle wrapping is needed; at the sub-goal itself the direction is undefined and Δ = 0.
    """
    dx, dy = subgoal[0] - end[:, 0], subgoal[1] - end[:, 1]
    if end_dir is None:
        c, s = jnp.cos(end[:, 2]), jnp.sin(end[:, 2])
    else:
        c, s = end_dir[:, 0], end_dir[:, 1]
    # A polynomial arctangent (XLA's CPU atan2 is a scalar call, ~40 ns a sample); it is 0,
    # with a finite gradient, at the sub-goal itself.
    return abs_angle(c * dy - s * dx, c * dx + s * dy)


def heading(err: jnp.ndarray) -> jnp.ndarray:
    """G = 1 − |Δ|/π."""
    return 1.0 - err / math.pi


def velocity(v: jnp.ndarray, robot: Robot) -> jnp.ndarray:
    """V = (v − v_min)/(v_max − v_min), clipped to [0, 1]."""
    return jnp.clip((v - robot.v_min) / (robot.v_max - robot.v_min), 0.0, 1.0)


def clearance(c: jnp.ndarray, d_clip) -> jnp.ndarray:
    """O = min(c, d_clip)/d_clip, floored at 0."""
    return jnp.clip(c, 0.0, d_clip) / d_clip


def path_distance(points: jnp.ndarray, path_xy: jnp.ndarray) -> jnp.ndarray:
    """Distance (m) from ``points [S, 2]`` to the polyline ``path_xy [L, 2]`` (m; pad by repeating the last point).

    ``[S, L-1]`` point-to-segment distances, components spelled out (no reductions over
    a last axis of 2, each of which would be a kernel of its own), then the minimum.
    """
    a = path_xy[:-1] if path_xy.shape[0] > 1 else path_xy
    b = path_xy[1:] if path_xy.shape[0] > 1 else path_xy
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]  # [L-1]
    dd = dx * dx + dy * dy
    rx, ry = points[:, :1] - a[:, 0], points[:, 1:] - a[:, 1]  # [S, L-1]
    t = jnp.clip((rx * dx + ry * dy) / jnp.where(dd > 0, dd, 1.0), 0.0, 1.0)
    ex, ey = rx - t * dx, ry - t * dy
    return jnp.sqrt(jnp.maximum(jnp.min(ex * ex + ey * ey, axis=-1), _TINY))


def path(dist: jnp.ndarray, path_clip) -> jnp.ndarray:
    """P = 1 − min(d, path_clip)/path_clip."""
    return 1.0 - jnp.clip(dist, 0.0, path_clip) / path_clip


def goal(end: jnp.ndarray, start_xy: jnp.ndarray, subgoal: jnp.ndarray, reach) -> jnp.ndarray:
    """D = 1 − |end − g| / (|p₀ − g| + reach), in [0, 1] for any rollout no longer than ``reach``."""
    # Components spelled out: a sum over a last axis of 2 becomes a reduction kernel of its own.
    dx, dy = end[:, 0] - subgoal[0], end[:, 1] - subgoal[1]
    d_end = jnp.sqrt(jnp.maximum(dx * dx + dy * dy, _TINY))
    gx, gy = start_xy[0] - subgoal[0], start_xy[1] - subgoal[1]
    d0 = jnp.sqrt(jnp.maximum(gx * gx + gy * gy, _TINY))
    return jnp.clip(1.0 - d_end / (d0 + reach), 0.0, 1.0)


def critics(end: jnp.ndarray, min_clearance: jnp.ndarray, v: jnp.ndarray, state: jnp.ndarray, subgoal: jnp.ndarray,
            robot: Robot, d_clip, path_clip, reach, path_xy: jnp.ndarray | None,
            end_dir: jnp.ndarray | None = None) -> Critics:
    """All critics of S rollouts (``end [S, 3]``, ``min_clearance [S]``, speeds ``v [S]``; ``end_dir``
    as in `heading_error`)."""
    err = heading_error(end, subgoal, end_dir)
    p = jnp.ones_like(v) if path_xy is None else path(path_distance(end[:, :2], path_xy), path_clip)
    return Critics(heading(err), velocity(v, robot), clearance(min_clearance, d_clip), p,
                   goal(end, state[:2], subgoal, reach), err, min_clearance)


def normalised_weights(rows: jnp.ndarray, feasible: jnp.ndarray, weights: jnp.ndarray) -> jnp.ndarray:
    """Coefficients ``c [K + 1]`` with ``c @ rows`` = Σ_k weight_k · critic_k / mean_k.

    ``rows [K + 1, S]`` holds K critics and a last row of ones; mean_k is critic k's mean
    over the feasible samples (≈ over all samples when none is feasible: the feasibility
    weights get 1e-6 added), floored at `NORM_FLOOR`. Both the sums and the final scores are matrix-vector
    products, so the critics are computed once into ``rows`` and read by two dot kernels —
    where separate reductions and slices would each cost a launch and a compilation.
    """
    f = feasible.astype(rows.dtype) + 1e-6
    sums = rows @ f  # [K + 1]; the last entry is Σ f
    mean = jnp.maximum(sums[:-1] / sums[-1], NORM_FLOOR)
    return jnp.concatenate([weights / mean, jnp.zeros(1, rows.dtype)])


def weighted(cr: Critics, params: DWAParams, feasible: jnp.ndarray, with_path: bool = True) -> jnp.ndarray:
    """cui2025 Eq. (7) plus the goal (and path) terms, on critics normalised across feasible samples.

    Without a path (``with_path=False``) the path critic is the constant 1 and is left out:
    a constant adds the same to every score and changes no choice.
    """
    names = ("heading", "velocity", "clearance", "goal") + (("path",) if with_path else ())
    rows = jnp.stack([getattr(cr, k) for k in names] + [jnp.ones_like(cr.heading)])
    weights = jnp.stack([jnp.asarray(getattr(params, k), rows.dtype) for k in names])
    return normalised_weights(rows, feasible, weights) @ rows


def classic(cr: Critics, params: DWAParams, v: jnp.ndarray, robot: Robot) -> jnp.ndarray:
    """PythonRobotics' score (minus its cost): goal-heading cost at the last pose, speed cost, 1/clearance.

    ``heading``, ``velocity`` and ``clearance`` weights play ``to_goal_cost_gain`` (0.15),
    ``speed_cost_gain`` (1) and ``obstacle_cost_gain`` (1); PythonRobotics' obstacle
    distance is to obstacle points, here it is the clearance to blocked squares and disc
    edges. The path and goal critics, if weighted, are added as scores.
    """
    cost = (params.heading * cr.heading_error + params.velocity * (robot.v_max - v)
            + params.clearance / jnp.maximum(cr.min_clearance, 1e-3))
    return -cost + params.path * cr.path + params.goal * cr.goal
