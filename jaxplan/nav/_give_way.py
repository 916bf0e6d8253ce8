"""Giving way: a robot in a standoff with a walker steps out of the walker's way, waits, and goes on.

A walker that sees (the social force model, `jaxplan.nav._social`) heads for its next route vertex and is
pushed back by a robot standing in its way: where the two meet head-on in a corridor, the walker settles
about 0.4 m from the robot's edge, the robot's local planner finds every way forward through the walker,
and neither moves again — the 1995 model has no fluctuation term to break the symmetry, and a standing
robot has no reason to. Nav2 answers a stuck controller with a recovery tree (back up, spin, wait); here
the robot gives way, as a person would:

1. *standoff*: the robot has stayed within ``give_way_move`` of one spot for ``give_way_time`` seconds with a
   disc (walker or robot) within ``give_way_distance`` of its edge (`standoff_watch`);
2. *where to*: the nearest disc is the one in the way; the robot picks, among points on rings around it, the
   reachable one with room to stand that lies farthest to the side of the line from that disc through the
   robot — the way the disc wants to go — preferring near points and, where there is no side room (a
   one-lane dead end), points farther from the disc (backing away) (`yield_point`);
3. *yielding*: the robot's local planner steers for that point (and, with MPPI, treats it as the goal, so
   it stops there) until the disc has moved ``GONE_MOVE`` metres from where it stood and is farther than
   ``give_way_distance + GONE_MARGIN`` from the robot's edge, or ``give_way_hold`` seconds have passed
   (`release`); then the robot tracks its path again.

Pure functions over the episode's ``[B, N]`` batch (one robot per function where the docstring says so).
Distances in metres, times in seconds.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax.numpy as jnp

__all__ = ["GiveWay", "initial_give_way", "standoff_watch", "yield_point", "release", "RINGS", "DIRECTIONS",
           "GONE_MOVE", "GONE_MARGIN"]

RINGS = (0.5, 0.8, 1.2, 1.6, 2.0)
"""m: distances from the robot of the candidate points."""

DIRECTIONS = 16
"""Candidate directions per ring (every 22.5°)."""

_SEGMENT_POINTS = 5
"""The straight way to a candidate is checked for clearance at this many points."""

STAND_ROOM = 0.05
"""m: a candidate needs this much clearance beyond d_safe to the map (room to stand while the disc passes)."""

DISC_ROOM = 0.5
"""m: a candidate this close to any disc's edge is not taken (it would step into another walker)."""

GONE_MOVE = 1.0
"""m: the disc given way to has moved this far from where it stood when the robot began to yield..."""

GONE_MARGIN = 1.0
"""m: ...and is this much farther than ``give_way_distance`` from the robot's edge: the yield ends."""


class GiveWay(NamedTuple):
    """The give-way watch and manoeuvre of each robot (``[B, N]`` unless noted; part of the episode's carry).

    Attributes:
      anchor: ``f32[B, N, 2]`` where the robot has stood since ``anchor_t`` (m).
      anchor_t: ``i32[B, N]`` step since which the robot stayed near ``anchor`` with a disc near.
      active: ``bool[B, N]`` the robot is giving way.
      point: ``f32[B, N, 2]`` the point it steers for while giving way (m).
      since: ``i32[B, N]`` step at which it began to give way.
      disc: ``i32[B, N]`` index of the disc it gives way to (into the discs the robot sees).
      disc_at: ``f32[B, N, 2]`` where that disc stood then (m).
      count: ``i32[B, N]`` how many times the robot has given way.
    """

    anchor: jnp.ndarray
    anchor_t: jnp.ndarray
    active: jnp.ndarray
    point: jnp.ndarray
    since: jnp.ndarray
    disc: jnp.ndarray
    disc_at: jnp.ndarray
    count: jnp.ndarray


def initial_give_way(pos: jnp.ndarray) -> GiveWay:
    """The watch at step 0 for robots at ``pos [B, N, 2]``: anchored where they start, not giving way."""
    zeros = jnp.zeros(pos.shape[:2], jnp.int32)
    return GiveWay(anchor=pos, anchor_t=zeros, active=jnp.zeros(pos.shape[:2], bool), point=pos, since=zeros,
                   disc=zeros, disc_at=pos, count=zeros)


def standoff_watch(gw: GiveWay, pos: jnp.ndarray, near: jnp.ndarray, t: jnp.ndarray, move: float) -> GiveWay:
    """Restarts the standoff clock of robots (``pos [B, N, 2]``) that moved ``move`` m from their anchor or have no
    disc ``near bool[B, N]``; ``t`` the step."""
    moved = jnp.sum((pos - gw.anchor) ** 2, axis=-1) > move * move
    anchor = jnp.where(moved[..., None], pos, gw.anchor)
    anchor_t = jnp.where(moved | ~near, t, gw.anchor_t)
    return gw._replace(anchor=anchor, anchor_t=anchor_t)


def yield_point(pos: jnp.ndarray, disc: jnp.ndarray, disc_pos: jnp.ndarray, disc_rad: jnp.ndarray,
                clearance: Callable[[jnp.ndarray, jnp.ndarray], jnp.ndarray],
                d_safe) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Where one robot at ``pos [2]`` steps to, out of the way of the disc at ``disc [2]``.

    Args:
      pos: ``f32[2]`` the robot (m).
      disc: ``f32[2]`` the disc in the way (m).
      disc_pos, disc_rad: ``f32[D, 2]``, ``f32[D]`` every disc the robot sees (a candidate keeps ``DISC_ROOM``
        from each).
      clearance: ``(x, y) -> m`` the static map's clearance lookup.
      d_safe: the local planner's minimal clearance to the map (m).

    Returns:
      ``(point f32[2], found bool)``: the candidate of `RINGS` × `DIRECTIONS` with room to stand (clearance
      ``d_safe + STAND_ROOM``), a straight way to it kept ``d_safe`` from the map, ``DISC_ROOM`` from every disc
      and not towards the disc in the way, that maximises ``min(lateral, 2) + 0.3·min(away, 2) − 0.2·distance``:
      ``lateral`` its distance from the line from the disc through the robot, ``away`` how much farther from
      the disc along that line it is than the robot. ``found`` is False if no candidate qualifies.
    """
    rings = jnp.asarray(RINGS, pos.dtype)
    ang = jnp.arange(DIRECTIONS, dtype=pos.dtype) * (2.0 * jnp.pi / DIRECTIONS)
    step = jnp.stack([jnp.cos(ang), jnp.sin(ang)], axis=-1)  # [A, 2]
    cand = (pos + rings[:, None, None] * step[None]).reshape(-1, 2)  # [Q, 2]
    frac = jnp.arange(1, _SEGMENT_POINTS + 1, dtype=pos.dtype) / _SEGMENT_POINTS
    way = pos + frac[:, None, None] * (cand - pos)  # [P, Q, 2]
    way_clear = jnp.min(clearance(way[..., 0], way[..., 1]), axis=0)  # [Q]
    room = clearance(cand[:, 0], cand[:, 1]) >= d_safe + STAND_ROOM
    gap = jnp.sqrt(jnp.sum((cand[:, None] - disc_pos[None]) ** 2, axis=-1)) - disc_rad  # [Q, D]
    line = pos - disc
    u = line / jnp.maximum(jnp.sqrt(jnp.sum(line * line)), 1e-6)
    rel = cand - disc
    lateral = jnp.abs(u[0] * rel[:, 1] - u[1] * rel[:, 0])
    away = (cand - pos) @ u
    ok = room & (way_clear >= d_safe) & jnp.all(gap >= DISC_ROOM, axis=-1) & (away >= -0.2)
    dist = jnp.sqrt(jnp.sum((cand - pos) ** 2, axis=-1))
    score = jnp.minimum(lateral, 2.0) + 0.3 * jnp.clip(away, 0.0, 2.0) - 0.2 * dist
    best = jnp.argmax(jnp.where(ok, score, -jnp.inf))
    return cand[best], jnp.any(ok)


def release(gw: GiveWay, disc_pos: jnp.ndarray, disc_gap: jnp.ndarray, t: jnp.ndarray, period: float,
            hold: float, distance: float) -> jnp.ndarray:
    """``bool[B, N]``: giving way ends now — the disc given way to moved `GONE_MOVE` from where it stood and is
    ``distance + GONE_MARGIN`` from the robot's edge, or ``hold`` seconds passed. ``disc_pos [B, N, D, 2]``,
    ``disc_gap [B, N, D]`` (m, from the robot's edge) of every disc the robot sees, ``t`` the step."""
    at = jnp.take_along_axis(disc_pos, gw.disc[..., None, None], axis=2)[:, :, 0]  # [B, N, 2]
    gap = jnp.take_along_axis(disc_gap, gw.disc[..., None], axis=2)[..., 0]
    gone = (jnp.sum((at - gw.disc_at) ** 2, axis=-1) >= GONE_MOVE ** 2) & (gap > distance + GONE_MARGIN)
    expired = (t - gw.since).astype(jnp.float32) * period >= hold - 1e-6
    return gw.active & (gone | expired)
