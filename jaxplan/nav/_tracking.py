"""How a robot tracks its waypoints in an episode: the current waypoint or look-ahead point, the top speed
near corners, the stall watch after a re-plan, the threat of a closing walker, and the pure path follower.

Pure functions of one robot (``[2]`` positions, ``[K, 2]`` waypoints, vmapped by the episode) or of the
``[B, N]`` batch where their docstrings say so; the episode's stages call them
(`jaxplan.nav._episode`). Distances in metres, speeds in m/s, angles in radians.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import lax

from jaxplan.dwa import dynamic_window
from jaxplan.nav._config import NavConfig

__all__ = ["SIGHT_CLEARANCE", "way_clear", "subgoal_index", "lookahead_point", "corner_cap", "rewatch", "threatened",
           "follow"]

_SIGHT_POINTS = 32
_SIGHT_STEP = 0.1
_WHOLE_POINTS = 64
"""The straight way to a point is checked at ``_SIGHT_POINTS`` points ``_SIGHT_STEP`` m apart (corners within
3.2 m), and with ``whole`` also at ``_WHOLE_POINTS`` evenly spaced points of the whole way."""

SIGHT_CLEARANCE = 0.05
"""m: a point is in sight of another if the straight line between them keeps this far from the map (clear of the
blocked squares: it may brush a corner, but no wall stands in between)."""


def way_clear(pos: jnp.ndarray, target: jnp.ndarray, d_safe, clearance, whole: bool = False) -> jnp.ndarray:
    """Whether the straight way from ``pos [2]`` to ``target [2]`` (m) keeps ``d_safe`` from the map
    (``clearance(x, y)``, m): checked every 0.1 m for its first 3.2 m, and with ``whole`` at 64 evenly spaced
    points end to end too."""
    gap = target - pos
    length = jnp.sqrt(jnp.sum(gap * gap))
    s = jnp.minimum(jnp.arange(1, _SIGHT_POINTS + 1, dtype=pos.dtype) * _SIGHT_STEP, length)
    if whole:
        s = jnp.concatenate([s, jnp.arange(1, _WHOLE_POINTS + 1, dtype=pos.dtype) / _WHOLE_POINTS * length])
    pts = pos + s[:, None] * (gap / jnp.maximum(length, 1e-6))
    return jnp.all(clearance(pts[:, 0], pts[:, 1]) >= d_safe)


def subgoal_index(pos: jnp.ndarray, wp: jnp.ndarray, n: jnp.ndarray, index: jnp.ndarray, radius, near, d_safe,
                  clearance) -> jnp.ndarray:
    """The current waypoint: the first from ``index`` on that is farther than ``radius`` (the last if
    none) — unless the straight way to it from ``pos [2]`` comes closer than ``d_safe`` to the map
    (``clearance(x, y)``, m) within 3.2 m; then the one before it, until that is within ``near``.

    Passing a waypoint a metre early cuts the corner it marks: a robot just short of a corner
    waypoint would take the next one, whose straight way grazes the corner's blocked cell, and
    sit still facing it until the time limit.
    """
    K = wp.shape[0]
    j = jnp.arange(K)
    dist = jnp.sqrt(jnp.sum((wp - pos) ** 2, axis=-1))
    cand = (j >= index) & (j < n) & (dist >= radius)
    nxt = jnp.where(jnp.any(cand), jnp.argmax(cand), n - 1).astype(jnp.int32)
    prev = jnp.maximum(nxt - 1, index)
    blocked = ~way_clear(pos, wp[nxt], d_safe, clearance)
    hold = (nxt > index) & blocked & (dist[prev] >= near)
    return jnp.where(hold, prev, nxt)


def lookahead_point(pos: jnp.ndarray, wp: jnp.ndarray, n: jnp.ndarray, index: jnp.ndarray, ahead,
                    origin: jnp.ndarray) -> tuple:
    """``(point [2], segment index)``: ``ahead`` m past the projection of ``pos`` on segments from ``index`` on.

    Segment ``j`` runs from waypoint ``j − 1`` to ``j``; segment 0 from ``origin`` (where the robot
    started or last re-planned) to ``wp[0]``.
    """
    K = wp.shape[0]
    j = jnp.arange(K)
    a = jnp.concatenate([origin[None], wp[:-1]])
    ab = wp - a
    seg = jnp.sqrt(jnp.sum(ab * ab, axis=-1))
    valid = (j < n)
    seg = jnp.where(valid, seg, 0.0)
    cum = jnp.cumsum(seg)  # arc length at the end of segment j
    u = jnp.clip(jnp.sum((pos - a) * ab, axis=-1) / jnp.maximum(seg * seg, 1e-12), 0.0, 1.0)
    d = jnp.sqrt(jnp.sum((a + u[:, None] * ab - pos) ** 2, axis=-1))
    d = jnp.where(valid & (j >= index), d, jnp.inf)
    k = jnp.argmin(d).astype(jnp.int32)
    s = cum[k] - seg[k] * (1.0 - u[k]) + ahead
    m = jnp.clip(jnp.searchsorted(cum, s), 0, jnp.maximum(n - 1, 0))
    frac = jnp.clip((s - (cum[m] - seg[m])) / jnp.maximum(seg[m], 1e-12), 0.0, 1.0)
    point = jnp.where(s >= cum[jnp.maximum(n - 1, 0)], wp[jnp.maximum(n - 1, 0)], a[m] + frac * ab[m])
    return point, k


def corner_cap(config: NavConfig, pos: jnp.ndarray, wp: jnp.ndarray, n: jnp.ndarray, index: jnp.ndarray,
               decel) -> jnp.ndarray:
    """Top speed (m/s) near corners (see `NavConfig.corner_speed`): ``pos [2]``, ``wp [K, 2]``."""
    K = wp.shape[0]
    v_c = config.corner_speed

    def turn(i):  # turn angle at waypoint i: (i-1 or the robot) -> i -> i+1
        prev = jnp.where(i > 0, wp[jnp.maximum(i - 1, 0)], pos)
        a, b = wp[i] - prev, wp[jnp.minimum(i + 1, K - 1)] - wp[i]
        # No gradient through the angle: with a zero-length leg the sqrt's would be 0 * inf.
        cos = lax.stop_gradient(jnp.sum(a * b) / jnp.maximum(jnp.sqrt(jnp.sum(a * a) * jnp.sum(b * b)), 1e-9))
        real = (i + 1 < n) & (jnp.sum(a * a) > 1e-12) & (jnp.sum(b * b) > 1e-12)
        return real & (cos < jnp.cos(config.corner_angle)), cos

    def speed(cos):  # corner_speed at 90 degrees and sharper, faster through gentler turns
        return jnp.maximum(v_c, v_c / jnp.maximum(1.0 - cos, 1e-6) ** config.corner_exponent)

    d_next = jnp.sqrt(jnp.sum((wp[index] - pos) ** 2))
    is_next, cos_next = turn(index)
    v_n = speed(cos_next)
    ahead = jnp.sqrt(v_n ** 2 + 2.0 * decel * jnp.maximum(d_next - config.switch_radius, 0.0))
    prev = jnp.maximum(index - 1, 0)
    d_prev = jnp.sqrt(jnp.sum((wp[prev] - pos) ** 2))
    is_prev, cos_prev = turn(prev)
    v_p = speed(cos_prev)
    behind = jnp.sqrt(v_p ** 2 + 2.0 * decel * jnp.maximum(d_prev - config.switch_radius, 0.0))
    cap = jnp.where(is_next, ahead, jnp.inf)
    # The goal is a corner too: arrive slowly enough to stop within the tolerance instead of orbiting it.
    d_goal = jnp.sqrt(jnp.sum((wp[jnp.maximum(n - 1, 0)] - pos) ** 2))
    cap = jnp.minimum(cap, jnp.sqrt(v_c ** 2 + 2.0 * decel * jnp.maximum(d_goal - config.goal_tolerance, 0.0)))
    return jnp.minimum(cap, jnp.where((index > 0) & is_prev, behind, jnp.inf))



def rewatch(replanned: jnp.ndarray, target: jnp.ndarray, pos: jnp.ndarray, watch: jnp.ndarray,
            closest: jnp.ndarray, progress_t: jnp.ndarray, t: jnp.ndarray):
    """The stall watch of creeping robots that just re-planned (``replanned [B, N]``): it follows the
    new current waypoint ``target [B, N, 2]`` (m) without restarting the creep, and, where that
    waypoint changed, measures progress towards it from ``pos [B, N, 2]`` and from step ``t`` on —
    against the old waypoint's closest approach a robot whose new waypoint is farther would count
    as stalled at once and re-plan again. Returns ``(watch, closest, progress_t)``."""
    moved = replanned & jnp.any(target != watch, axis=-1)
    d = jnp.sqrt(jnp.sum(lax.stop_gradient(target - pos) ** 2, axis=-1))
    return (jnp.where(replanned[..., None], target, watch), jnp.where(moved, d, closest),
            jnp.where(moved, t, progress_t))


def threatened(config: NavConfig, pos: jnp.ndarray, centres: jnp.ndarray, velocities: jnp.ndarray,
               radii: jnp.ndarray) -> jnp.ndarray:
    """``bool[...]``: a disc whose edge is within `NavConfig.threat_distance` of the robot's centre
    ``pos [..., 2]`` moves towards that centre faster than ``threat_speed`` (``centres``,
    ``velocities [..., D, 2]``, ``radii [..., D]``; D may be 0)."""
    rel = centres - pos[..., None, :]
    dist = jnp.sqrt(jnp.maximum(jnp.sum(rel * rel, axis=-1), 1e-12))
    toward = -jnp.sum(velocities * rel, axis=-1) / dist  # the disc's own speed towards the robot
    close = (dist - radii < config.threat_distance) & (config.threat_distance > 0)  # 0 disables, even inside a disc
    return jnp.any(close & (toward > config.threat_speed), axis=-1)


def follow(config: NavConfig, robot, state: jnp.ndarray, subgoal: jnp.ndarray) -> jnp.ndarray:
    """Pure path following ``[2]``: turn towards the sub-goal, slow with the heading error, inside the window."""
    win = dynamic_window(robot, state, config.dwa.period)
    err = jnp.arctan2(subgoal[1] - state[1], subgoal[0] - state[0]) - state[2]
    err = jnp.arctan2(jnp.sin(err), jnp.cos(err))
    w = jnp.clip(config.follow_gain * err, win.w_lo, win.w_hi)
    v = jnp.clip(robot.v_max * jnp.maximum(jnp.cos(err), 0.0) ** 2, win.v_lo, win.v_hi)
    return jnp.stack([v, w])

