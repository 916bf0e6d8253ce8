"""Walkers that see: the social force model (Helbing & Molnár 1995) for reactive moving obstacles.

A reactive walker (``MovingObstacles.reactive``) keeps the route a blind walker would follow, but
instead of being placed on it by time it is simulated inside the episode: it steers towards the
route's next vertex at its route speed and is pushed away from the other walkers, the robots and the
walls. Its acceleration (Helbing & Molnár 1995, Phys. Rev. E 51, 4282, Eqs. (1)–(8))::

    dv/dt = (v0·e − v) / τ  +  Σ_b w(e, −f_ab) f_ab  +  Σ_B w(e, −f_aB) f_aB

* driving term: relaxation towards the desired velocity ``v0·e`` (``e`` the unit vector to the next
  route vertex, ``v0`` the route speed) with relaxation time ``τ = 0.5 s``;
* repulsion from another walker or a robot ``b``: ``f_ab = −∇ V0·exp(−b/σ)`` with ``V0 = 2.1 m²/s²``,
  ``σ = 0.3 m`` and ``b`` the semi-minor axis of the ellipse around ``b``'s position that extends
  ``v_b·Δt`` (``Δt = 2 s``) along ``b``'s motion, ``2b = sqrt((|r| + |r − v_b Δt e_b|)² − (v_b Δt)²)``
  with ``r`` the vector from ``b`` to the walker — others are avoided where they are going;
* repulsion from walls: ``f_aB = −∇ U0·exp(−d/R)`` with ``U0 = 10 m²/s²``, ``R = 0.2 m`` and ``d`` the
  distance from the walker's centre to the nearest blocked square (the map's clearance lookup);
* body contact (Helbing, Farkas & Vicsek 2000, Nature 407, 487: ``k = 1.2·10⁵ kg/s²`` for an 80 kg
  pedestrian): a walker overlapping another disc or a wall by ``δ`` is pushed out with ``(k/m)·δ``. The
  1995 potentials alone let the walls of a 2 m corridor squeeze two walkers meeting head-on onto one line;
* field of view: a force from behind the walker (outside ``2φ = 200°`` around ``e``) counts with weight
  ``c = 0.5``;
* the speed is capped at ``1.3·v0`` (the paper's maximal acceleration of the desired speed).

The paper's ellipse uses the other pedestrian's step ``v_b·Δt``; its forces are per unit mass. The
parameters are the paper's (its Section III); ours are that ``b`` is measured between the discs' edges
(walkers and robots are discs of their radius), the wall distance from the map lookup, and the body
contact force above. The walker follows its route's
vertices in the blind model's order (bounce or loop), moving on to the next vertex once within
`VERTEX_RADIUS` of the current one or once past it.

Losing sight of the route (ours): the driving term steers straight at the next vertex, so a walker pushed off
its route (shoved back through a junction into a side corridor, say) can end up with a wall between it and that
vertex, where the wall's push balances the drive and it stands against the wall for good: a local minimum of the
model, in up to 11 % of 180 s episodes on the MovingAI maps with 5 walkers at 1.0 m/s. A person who has taken a
wrong turn goes back the way they came. So each walker keeps a trail of `TRAIL` breadcrumbs, points
`TRAIL_SPACING` m apart from which it could see its current vertex (the straight line to it keeps
`SIGHT_CLEARANCE` from the map, checked once per control period over the whole line by
`jaxplan.nav._tracking.way_clear`), restarted at the vertex just reached when it moves on to the next. A walker
that cannot see its vertex heads for its latest breadcrumb instead, dropping each as it comes within
`VERTEX_RADIUS`, back to the first: the vertex it last reached, in sight of this one (route segments are clear at
the walker's radius). Where the walker stood when it moved on (up to `VERTEX_RADIUS` short of the vertex, or past
it) may be out of sight of the next vertex; walkers that went back there hovered. A walker that never loses sight
of its route moves exactly as without the trail; most lose it for a moment at some corner (the line to the next
vertex grazing the corner's square once they have moved on).

Integration: semi-implicit Euler in `SUBSTEPS` steps per control period (0.025 s at the default
0.2 s): stable for the contact stiffness (``h·sqrt(k/m) ≈ 1 < 2``) and fine against ``τ`` and the
potentials' length scales at walking speeds.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.nav._tracking import SIGHT_CLEARANCE, way_clear

__all__ = ["SocialForce", "WalkerState", "initial_walkers", "advance_walkers", "SUBSTEPS", "VERTEX_RADIUS", "TRAIL",
           "TRAIL_SPACING"]

SUBSTEPS = 8
"""Integration steps per control period."""

VERTEX_RADIUS = 0.3
"""m: a reactive walker heads for its route's next vertex once this close to the current one."""

TRAIL = 32
"""Breadcrumbs a walker keeps (the oldest dropped first): 15.5 m of the way back at `TRAIL_SPACING`."""

TRAIL_SPACING = 0.5
"""m between a walker's breadcrumbs."""


class SocialForce(NamedTuple):
    """The social force model's parameters (Helbing & Molnár 1995, Section III), per unit mass."""

    tau: float = 0.5  # s, relaxation time of the driving term
    v0: float = 2.1  # m²/s², strength of the repulsive potential between walkers
    sigma: float = 0.3  # m, its range
    dt_step: float = 2.0  # s, the step Δt of the other's motion in the ellipse
    u0: float = 10.0  # m²/s², strength of the wall potential
    r_wall: float = 0.2  # m, its range
    view: float = math.radians(100.0)  # φ: half the field of view
    behind: float = 0.5  # c: weight of a force from outside the field of view
    max_speed: float = 1.3  # the speed cap, in units of the desired speed
    contact: float = 1.2e5 / 80.0  # 1/s², body contact stiffness per unit mass (Helbing, Farkas & Vicsek 2000)


class WalkerState(NamedTuple):
    """Reactive walkers' state (leading axes ``[..., M]``).

    Attributes:
      pos, vel: ``f32[..., M, 2]`` position (m) and velocity (m/s).
      target: ``i32[..., M]`` index of the route vertex the walker heads for.
      step: ``i32[..., M]`` +1 or −1, the direction it travels its route (a bounce reverses it).
      trail: ``f32[..., M, TRAIL, 2]`` breadcrumbs (m), the first ``depth`` valid, the latest last.
      depth: ``i32[..., M]`` valid breadcrumbs (>= 1).
    """

    pos: jnp.ndarray
    vel: jnp.ndarray
    target: jnp.ndarray
    step: jnp.ndarray
    trail: jnp.ndarray
    depth: jnp.ndarray


def initial_walkers(pos: jnp.ndarray, vel: jnp.ndarray, target: jnp.ndarray, forward: jnp.ndarray) -> WalkerState:
    """The state at ``t = 0`` from the blind model's placement (`jaxplan.nav._moving.route_target`): position,
    velocity, the route vertex headed for, and whether the route is travelled forwards. The trail starts at the
    position (on the route, in sight of the vertex)."""
    trail = jnp.broadcast_to(pos[..., None, :], pos.shape[:-1] + (TRAIL, 2))
    depth = jnp.ones(pos.shape[:-1], jnp.int32)
    return WalkerState(pos, vel, target.astype(jnp.int32), jnp.where(forward, 1, -1).astype(jnp.int32), trail, depth)


def _follow_trail(state: WalkerState, goal_pt: jnp.ndarray, wall) -> tuple[WalkerState, jnp.ndarray, jnp.ndarray]:
    """The trail at a control period's start: ``(state with the trail updated, lost bool[M], crumb f32[M, 2])``.

    A walker in sight of its vertex (``goal_pt [M, 2]``) lays a breadcrumb where it stands once `TRAIL_SPACING`
    from its latest; one that has lost sight drops the latest breadcrumb once within `VERTEX_RADIUS` of it (never
    the first) and heads for the one then latest, ``crumb``.
    """
    idx = jnp.arange(TRAIL)
    seen = jax.vmap(lambda x, g: way_clear(x, g, SIGHT_CLEARANCE, wall, whole=True))(state.pos, goal_pt)
    last = jnp.take_along_axis(state.trail, (state.depth - 1)[:, None, None], axis=1)[:, 0]  # [M, 2]
    gap = jnp.sqrt(jnp.sum((state.pos - last) ** 2, axis=-1))
    lay = seen & (gap >= TRAIL_SPACING)
    full = state.depth >= TRAIL
    # A full trail drops its oldest breadcrumb to make room.
    shifted = jnp.where(full[:, None, None], jnp.roll(state.trail, -1, axis=1), state.trail)
    slot = jnp.minimum(state.depth, TRAIL - 1)
    laid = jnp.where((idx[None] == slot[:, None])[..., None], state.pos[:, None], shifted)
    trail = jnp.where(lay[:, None, None], laid, state.trail)
    depth = jnp.where(lay, jnp.minimum(state.depth + 1, TRAIL), state.depth)
    depth = jnp.where(~seen & (gap < VERTEX_RADIUS) & (depth > 1), depth - 1, depth)
    crumb = jnp.take_along_axis(trail, (depth - 1)[:, None, None], axis=1)[:, 0]
    return state._replace(trail=trail, depth=depth), ~seen, crumb


def _ellipse_b(r: jnp.ndarray, v_other: jnp.ndarray, dt_step: float) -> jnp.ndarray:
    """The semi-minor axis ``b`` (m) of Helbing & Molnár's Eq. (4); ``r [..., 2]`` from the other to the walker."""
    step = v_other * dt_step
    s = jnp.sqrt(jnp.sum(step * step, axis=-1) + 1e-12)
    a = jnp.sqrt(jnp.sum(r * r, axis=-1) + 1e-12)
    c = jnp.sqrt(jnp.sum((r - step) ** 2, axis=-1) + 1e-12)
    return 0.5 * jnp.sqrt(jnp.maximum((a + c) ** 2 - s * s, 1e-12))


def _weight(e: jnp.ndarray, f: jnp.ndarray, p: SocialForce) -> jnp.ndarray:
    """Field-of-view weight: 1 if the force's source (direction −f) is within ±φ of ``e``, else ``c``."""
    fn = jnp.sqrt(jnp.sum(f * f, axis=-1) + 1e-12)
    cos = jnp.sum(e * -f, axis=-1) / fn
    return jnp.where(cos >= jnp.cos(p.view), 1.0, p.behind)


def _pair_force(p: SocialForce, x: jnp.ndarray, other: jnp.ndarray, other_vel: jnp.ndarray, reach) -> jnp.ndarray:
    """The repulsion ``[2]`` on a walker at ``x`` from one walker or robot: ``−∇_x V0·exp(−(b − reach)/σ)`` and the body
    contact force if the discs overlap; ``reach`` the sum of the two radii (edges, not centres, meet)."""

    def potential(xx):
        b = _ellipse_b(xx - other, other_vel, p.dt_step)
        return p.v0 * jnp.exp(-jnp.maximum(b - reach, 0.0) / p.sigma)

    r = x - other
    dist = jnp.sqrt(jnp.sum(r * r) + 1e-12)
    body = p.contact * jnp.maximum(reach - dist, 0.0) * r / dist  # overlapping discs pushed apart
    return -jax.grad(potential)(x) + body


def _forces(p: SocialForce, pos: jnp.ndarray, e: jnp.ndarray, radii: jnp.ndarray, others: jnp.ndarray,
            others_vel: jnp.ndarray, others_rad: jnp.ndarray, active: jnp.ndarray, wall) -> jnp.ndarray:
    """Repulsion ``[M, 2]`` (per unit mass) on M walkers from ``others [D, 2]`` (walkers, then robots) and the walls,
    each weighted by the field of view; ``active [M, D]`` masks the pairs that act (not a walker on itself)."""
    per = jax.vmap(lambda x, r: jax.vmap(lambda o, ov, orad: _pair_force(p, x, o, ov, r + orad))(
        others, others_vel, others_rad))(pos, radii)  # [M, D, 2]
    per = jnp.where(active[..., None], per, 0.0)
    f_others = jnp.sum(_weight(e[:, None, :], per, p)[..., None] * per, axis=1)
    f_wall, f_touch = _wall_force(p, pos, radii, wall)
    return f_others + _weight(e, f_wall, p)[:, None] * f_wall + f_touch


def _wall_force(p: SocialForce, pos: jnp.ndarray, radii: jnp.ndarray, wall) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(−∇ U0·exp(−d/R), body contact)`` ``[M, 2]`` each: the wall potential's force on each walker (``d`` its
    centre's distance to the nearest blocked square) and the push out of a wall it overlaps."""

    def u(x):
        return p.u0 * jnp.exp(-jnp.maximum(wall(x[None, 0], x[None, 1])[0], 0.0) / p.r_wall)

    def d(x):
        return wall(x[None, 0], x[None, 1])[0]

    grad_d = jax.vmap(jax.grad(d))(pos)  # points away from the wall
    dist = jax.vmap(d)(pos)
    touch = p.contact * jnp.maximum(radii - dist, 0.0)[:, None] * grad_d
    return -jax.vmap(jax.grad(u))(pos), touch


def advance_walkers(p: SocialForce, state: WalkerState, waypoints: jnp.ndarray, n: jnp.ndarray,
                    speeds: jnp.ndarray, radii: jnp.ndarray, loop: jnp.ndarray, reactive: jnp.ndarray,
                    robots: jnp.ndarray, robots_vel: jnp.ndarray, robot_radius, wall, period: float,
                    substeps: int = SUBSTEPS) -> tuple[WalkerState, jnp.ndarray]:
    """One control period of the reactive walkers of one episode.

    Args:
      p: `SocialForce` parameters.
      state: `WalkerState` ``[M]``.
      waypoints, n, speeds, radii, loop: the routes (``[M, K, 2]``, ``[M]``…) of `MovingObstacles`.
      reactive: ``bool[M]`` which walkers this model moves (the others keep their state).
      robots, robots_vel: ``f32[C, 2]`` the robots' covering discs and their velocities; ``robot_radius`` (m).
      wall: ``wall(x, y) -> m`` clearance to the map at points ``[P]``.
      period: seconds.

    Returns:
      ``(state after the period, positions f32[substeps, M, 2] at the end of each substep)``.
    """
    M = radii.shape[0]
    h = period / substeps
    others_rad = jnp.concatenate([radii, jnp.broadcast_to(jnp.asarray(robot_radius, radii.dtype), robots.shape[:1])])
    eye = jnp.eye(M, dtype=bool)
    act = jnp.concatenate([~eye & reactive[:, None] & (radii[None] > 0),
                           jnp.broadcast_to(reactive[:, None], (M, robots.shape[0]))], axis=1)

    state, lost, crumb = _follow_trail(state, waypoints[jnp.arange(M), state.target], wall)

    def sub(s: WalkerState, _):
        goal_pt = waypoints[jnp.arange(M), s.target]
        to = jnp.where(lost[:, None], crumb, goal_pt) - s.pos
        dist = jnp.sqrt(jnp.sum(to * to, axis=-1) + 1e-12)
        e = to / dist[:, None]
        drive = (speeds[:, None] * e - s.vel) / p.tau
        others = jnp.concatenate([s.pos, robots])
        others_vel = jnp.concatenate([s.vel, robots_vel])
        f = _forces(p, s.pos, e, radii, others, others_vel, others_rad, act, wall)
        vel = s.vel + h * (drive + f)
        speed = jnp.sqrt(jnp.sum(vel * vel, axis=-1) + 1e-12)
        cap = p.max_speed * speeds
        vel = vel * jnp.minimum(1.0, cap / speed)[:, None]
        pos = s.pos + h * vel
        # Next vertex: within VERTEX_RADIUS, or past it (the route turned behind the walker); not while going
        # back along the trail.
        reached = ~lost & ((jnp.sqrt(jnp.sum((goal_pt - pos) ** 2, axis=-1)) < VERTEX_RADIUS) | (jnp.sum(
            (goal_pt - pos) * e, axis=-1) < 0))
        nxt = s.target + s.step
        last = jnp.maximum(n - 1, 0)
        wrap = loop & (nxt > last)
        bounce = ~loop & ((nxt > last) | (nxt < 0))
        target = jnp.where(wrap, 0, jnp.where(bounce, s.target - s.step, nxt))
        step = jnp.where(bounce, -s.step, s.step)
        moved_on = reached & (n > 1)
        target = jnp.where(moved_on, jnp.clip(target, 0, last), s.target).astype(jnp.int32)
        step = jnp.where(moved_on, step, s.step)
        # A new vertex, a new trail: it starts at the vertex just reached (on the route, in sight of the new one;
        # where the walker stands may not be).
        trail = jnp.where(moved_on[:, None, None], goal_pt[:, None], s.trail)
        depth = jnp.where(moved_on, 1, s.depth)
        r1, r2 = reactive[:, None], reactive[:, None, None]
        new = WalkerState(jnp.where(r1, pos, s.pos), jnp.where(r1, vel, s.vel), jnp.where(reactive, target, s.target),
                          jnp.where(reactive, step, s.step), jnp.where(r2, trail, s.trail),
                          jnp.where(reactive, depth, s.depth))
        return new, new.pos

    return jax.lax.scan(sub, state, None, length=substeps)
