"""The navigation episode as one compiled program: sub-goals → local planner → motion → checks.

`run_episodes` advances ``B`` independent episodes of ``N`` robots each (``N = 1`` for
single-robot navigation; in multi-robot mode every robot treats the others as moving
discs) by one control period per step (`_step`), in these stages:

1. `_seen_discs`: moving obstacles are placed on their routes at time ``t`` (`obstacle_state`) —
   walkers that see (`jaxplan.nav._social`) are where the episode's simulation put them — and the
   robots become covering discs for each other;
2. `_next_waypoints`: each robot's current waypoint (switching to the next within the switch
   radius, `jaxplan.nav._tracking.subgoal_index`);
3. `_watch_progress`: the stall and orbit watches (`NavConfig.stall_time`, `NavConfig.orbit_angle`);
4. `_replanning` (with re-planning on): a robot whose next metres of path are blocked by a disc,
   which has drifted more than `NavConfig.replan_deviation` off its path, or which stalled,
   re-plans from where it is on the planning map with the cells around the discs closed
   (`jaxplan.nav._replan`); detours round discs are re-checked;
5. `_subgoal`: the point to steer for, the current waypoint or a look-ahead point on the
   waypoint polyline;
6. `_local_control`: the local planner picks the control: the DWA step (`dwa_control`, obstacles =
   moving discs predicted at constant velocity + the other robots), the MPPI step (`mppi_control`,
   the same discs, warm-started from the robot's last sequence, noise keyed by episode, robot and
   step) or pure path following, its top speed capped near corners;
7. `_move_and_contacts`: the walkers that see move for the period (the social force model, reacting to
   where the robots are at its start), the robot moves along the exact arc (`advance`), and is checked for contact
   with the map (clearance below its radius), a moving disc or another robot at
   `NavConfig.contact_checks` evenly spaced times of the period;
8. `_bookkeeping`: a robot is done at the goal (within the tolerance), at its time limit, or — when
   the config says so — at its first collision; a done robot stays where it is.

Everything is explicitly batched over ``[B, N]`` (no ``vmap`` around the step), so the
re-planning branch is a real `lax.cond` taken only on steps where some robot needs it.
Steps run in chunks of `NavConfig.chunk` inside a `lax.while_loop` that stops once every
robot of every episode is done; trajectories go to fixed-size buffers.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from jaxplan.dwa import (
    ClearanceTable,
    Disc,
    DiscObstacles,
    DWAParams,
    advance,
    dwa_control,
    footprint_offsets,
    footprint_radius,
    speed_cap,
    static_clearance,
)
from jaxplan.metrics import point_polyline_distance
from jaxplan.mppi import MPPIParams, initial_sequence, mppi_control, shift
from jaxplan.nav._config import NavConfig
from jaxplan.nav._give_way import GiveWay, initial_give_way, release, standoff_watch, yield_point
from jaxplan.nav._moving import MovingObstacles, obstacle_state, route_target
from jaxplan.nav._replan import path_blocked, replan_slots
from jaxplan.nav._social import SocialForce, WalkerState, advance_walkers, initial_walkers
from jaxplan.nav._state import (
    ACTIVE_SPEED,
    COLLISION,
    GOAL,
    RUNNING,
    TIMEOUT,
    Carry,
    EpisodeInputs,
    EpisodeOutput,
)
from jaxplan.nav._tracking import (
    SIGHT_CLEARANCE,
    corner_cap,
    follow,
    lookahead_point,
    rewatch,
    subgoal_index,
    threatened,
    way_clear,
)

__all__ = ["run_episodes", "initial_carry", "run_chunk"]

SOCIAL_FORCE = SocialForce()
"""The walkers' social force parameters (Helbing & Molnár 1995; see `jaxplan.nav._social`)."""

_FAR = 1e6  # metres: where a disc that must not matter is put (finite: keeps gradients finite)


def _robot_discs(state: jnp.ndarray, robot) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Covering discs of the footprints: centres ``[..., C, 2]`` (m) and their radius (m)."""
    fp = robot.footprint
    r = footprint_radius(fp)
    if isinstance(fp, Disc):
        return state[..., None, :2], r
    off = jnp.asarray(footprint_offsets(fp))  # [C]
    c, s = jnp.cos(state[..., 2:3]), jnp.sin(state[..., 2:3])
    return jnp.stack([state[..., 0:1] + off * c, state[..., 1:2] + off * s], axis=-1), r



def _map_clearance(table: ClearanceTable):
    """``f(x, y) -> m``: the clearance to the map at points ``[P]`` (the exact ``"hybrid"`` lookup), as the
    straight-way checks, the yield point and the walkers' wall force take it."""
    return lambda x, y: static_clearance(table, x, y, "hybrid")


def _current_waypoint(c: Carry) -> jnp.ndarray:
    """``[B, N, 2]`` the waypoint each robot is tracking (m)."""
    return jnp.take_along_axis(c.waypoints, c.index[..., None, None], axis=2)[:, :, 0]


def _watch_progress(config: NavConfig, c: Carry, pos: jnp.ndarray, crowded: jnp.ndarray,
                    goal: jnp.ndarray) -> Carry:
    """Updates the stall and orbit watches (see `NavConfig.stall_time`, `NavConfig.orbit_angle`):
    ``pos, goal [B, N, 2]``; ``crowded [B, N]``: a disc is near.

    The stall watch restarts whenever the current waypoint changes (passed, or another after
    a re-plan), and while a disc is near (then slow progress is an evasion or a wait, not an
    orbit). The orbit watch sums the heading change until the robot comes ``switch_radius``
    closer to its goal than ever before; re-plans do not restart it, so a robot that circles
    while drifting off its path and re-planning (each re-plan a new waypoint) is caught too.
    """
    target = _current_waypoint(c)  # [B, N, 2]
    # No gradient through the watches: a robot standing on its only waypoint has d = 0, where sqrt's is NaN.
    d = jnp.sqrt(jnp.sum(lax.stop_gradient(target - pos) ** 2, axis=-1))
    restart = jnp.any(target != c.watch, axis=-1) | crowded  # the initial NaN restarts
    closer = d < c.closest - config.stall_progress
    reset = restart | closer
    progress_t = jnp.where(reset, c.t, c.progress_t)
    closest = jnp.where(reset, d, c.closest)
    stalled = (c.t - progress_t).astype(jnp.float32) * config.dwa.period >= config.stall_time
    # Creeping and stalled again: re-plan again from here. The clock restarts at every stall, so once per stall_time.
    again = c.creep & stalled
    progress_t = jnp.where(stalled, c.t, progress_t)
    d_goal = jnp.sqrt(jnp.sum(lax.stop_gradient(goal - pos) ** 2, axis=-1))
    nearer = d_goal < c.goal_best - config.switch_radius
    spin = c.spin + lax.stop_gradient(c.state[..., 4]) * config.dwa.period  # the yaw rate just applied
    orbit = jnp.abs(spin) >= config.orbit_angle
    fresh = nearer | crowded | orbit
    spin = jnp.where(fresh, 0.0, spin)
    goal_best = jnp.where(nearer, d_goal, c.goal_best)
    creep = (~restart & (c.creep | stalled)) | (orbit & ~crowded)
    creep_goal = jnp.where(creep & ~c.creep, d_goal, c.creep_goal)
    if math.isfinite(config.creep_reach):  # loose once that much closer to its goal (a circling robot does not come)
        creep = creep & ~(c.creep & (d_goal < creep_goal - config.creep_reach))
    stall_replan = creep & (c.stall_replan | ~c.creep | again)
    return c._replace(watch=target, closest=closest, progress_t=progress_t, creep=creep, stall_replan=stall_replan,
                      spin=spin, goal_best=goal_best, creep_goal=creep_goal)


def _centres_at(obs: MovingObstacles, times: jnp.ndarray) -> jnp.ndarray:
    """``[K, B, M, 2]`` centres of every episode's obstacles along their routes at ``times [K]`` (s)."""
    return jax.vmap(lambda tk: jax.vmap(obstacle_state, in_axes=(0, None))(obs, tk)[0])(times)


def _oracle_track(obs: MovingObstacles, t: jnp.ndarray, steps: int, dt: float, pos_all: jnp.ndarray,
                  vel_all: jnp.ndarray) -> jnp.ndarray:
    """``[B, N, D, steps + 1, 2]`` centres at ``t, t + dt, …, t + steps·dt``: the obstacles (the first
    M of the D discs) along their true routes, the other robots (and walkers that see) at constant velocity."""
    B, N, D = pos_all.shape[:3]
    M = obs.radii.shape[-1]
    taus = jnp.arange(steps + 1, dtype=jnp.float32) * dt
    fut = _centres_at(obs, t + taus)  # [K, B, M, 2]
    fut = jnp.broadcast_to(jnp.moveaxis(fut, 0, 2)[:, None], (B, N, M, steps + 1, 2))
    linear = pos_all[..., None, :] + vel_all[..., None, :] * taus[:, None]  # [B, N, D, K, 2]
    if obs.reactive is not None:  # a walker that sees has no route to know in advance: constant velocity
        fut = jnp.where(obs.reactive[:, None, :, None, None], linear[:, :, :M], fut)
    return jnp.concatenate([fut, linear[:, :, M:]], axis=2) if D > M else fut

class _Discs(NamedTuple):
    """The discs each robot sees at time ``t``: ``D = M`` moving obstacles, then (with ``N > 1``) every
    robot's ``C`` covering discs, its own parked far away.

    Attributes:
      pos, vel: ``f32[B, N, D, 2]`` centres (m) and velocities (m/s); rad: ``f32[B, N, D]`` radii (m).
      robots: ``f32[B, N, C, 2]`` the robots' covering discs; radius: their radius (m).
    """

    pos: jnp.ndarray
    vel: jnp.ndarray
    rad: jnp.ndarray
    robots: jnp.ndarray
    radius: jnp.ndarray


def _obstacles_now(obs: MovingObstacles, walkers: WalkerState | None, t: jnp.ndarray):
    """``(positions, velocities) f32[B, M, 2]`` of the moving obstacles at time ``t``: on their routes, or where the
    simulation put the walkers that see."""
    opos, ovel = jax.vmap(obstacle_state, in_axes=(0, None))(obs, t)  # [B, M, 2]
    if walkers is None:
        return opos, ovel
    react = obs.reactive[..., None]
    return jnp.where(react, walkers.pos, opos), jnp.where(react, walkers.vel, ovel)


def _seen_discs(robot, obs: MovingObstacles, state: jnp.ndarray, t: jnp.ndarray,
                walkers: WalkerState | None = None) -> _Discs:
    """Stage 1: the moving obstacles at time ``t`` (s), and the robots (``state [B, N, 5]``) as discs for each
    other."""
    B, N = state.shape[:2]
    M = obs.radii.shape[-1]
    opos, ovel = _obstacles_now(obs, walkers, t)
    rc, rr = _robot_discs(state, robot)  # [B, N, C, 2]
    C = rc.shape[2]
    rvel = state[..., 3:4] * jnp.stack([jnp.cos(state[..., 2]), jnp.sin(state[..., 2])], axis=-1)  # [B, N, 2]
    # Discs seen by robot i: the M obstacles, then (with N > 1) every robot's C covering discs, its own
    # moved far away. A lone robot sees only the obstacles (no disc at all on a static map).
    pos_all = jnp.broadcast_to(opos[:, None], (B, N, M, 2))  # [B, N, D, 2]
    vel_all = jnp.broadcast_to(ovel[:, None], (B, N, M, 2))
    rad_all = jnp.broadcast_to(obs.radii[:, None], (B, N, M))
    if N > 1:
        others = jnp.broadcast_to(rc.reshape(B, 1, N * C, 2), (B, N, N * C, 2))
        own = jnp.repeat(jnp.eye(N, dtype=bool), C, axis=1)[None, :, :, None]  # [1, N, N*C, 1]
        others = jnp.where(own, _FAR + jnp.arange(N * C, dtype=jnp.float32)[None, None, :, None] * 10.0, others)
        ovel_r = jnp.broadcast_to(jnp.repeat(rvel, C, axis=1).reshape(B, 1, N * C, 2), (B, N, N * C, 2))
        ovel_r = jnp.where(own, 0.0, ovel_r)
        pos_all = jnp.concatenate([pos_all, others], axis=2)
        vel_all = jnp.concatenate([vel_all, ovel_r], axis=2)
        rad_all = jnp.concatenate([rad_all, jnp.where(own[..., 0], 0.0, rr) * jnp.ones((B, N, N * C))], axis=2)
    return _Discs(pos_all, vel_all, rad_all, rc, rr)


def _next_waypoints(config: NavConfig, table: ClearanceTable, c: Carry, pos: jnp.ndarray) -> Carry:
    """Stage 2: each robot's current waypoint (`subgoal_index`); ``pos [B, N, 2]`` (m)."""
    B, N = pos.shape[:2]
    # Only a creeping robot holds a waypoint whose way on is not clear: applied to every robot, the
    # rule sharpened turns at corners and cost evasions among walkers.
    near = jnp.where(c.creep, config.switch_min, config.switch_radius).reshape(-1)
    index = jax.vmap(subgoal_index, in_axes=(0, 0, 0, 0, None, 0, None, None))(
        pos.reshape(B * N, 2), c.waypoints.reshape((B * N,) + c.waypoints.shape[2:]), c.n_wp.reshape(-1),
        c.index.reshape(-1), config.switch_radius, near, config.dwa.d_safe, _map_clearance(table)).reshape(B, N)
    return c._replace(index=index)


def _crowded(config: NavConfig, discs: _Discs, pos: jnp.ndarray) -> jnp.ndarray:
    """``bool[B, N]``: a disc within half the look-ahead (slow progress or drift is then an evasion)."""
    gap = jnp.sqrt(jnp.sum((discs.pos - pos[:, :, None, :]) ** 2, axis=-1)) - discs.rad  # [B, N, D]
    return jnp.any(gap < 0.5 * config.block_distance, axis=-1)


def _replanning(config: NavConfig, table: ClearanceTable, free: jnp.ndarray, inputs: EpisodeInputs, c: Carry,
                pos: jnp.ndarray, discs: _Discs, crowded: jnp.ndarray) -> Carry:
    """Stage 4: the robots that must re-plan (path blocked, drifted off, stalled) or may re-check a detour,
    and their re-plans (`replan_slots`, in a `lax.cond` taken only on steps where some robot needs one)."""
    B, N = pos.shape[:2]
    M = inputs.obstacles.radii.shape[-1]
    C = discs.robots.shape[2]
    period = config.dwa.period
    pos_all, vel_all = discs.pos, discs.vel
    reach = discs.rad + discs.radius + config.block_margin
    if N > 1:
        # Another robot blocks a path only while it stands (parked at its goal, or waiting): a moving
        # one is left to the DWA — measured: two robots re-planning around each other's predicted
        # tracks kept swerving into each other.
        moving = (jnp.abs(c.state[..., 3]) >= 0.1) & ~c.done  # [B, N]
        robot_reach = jnp.where(jnp.repeat(moving, C, axis=1)[:, None, :], 0.0, reach[:, :, M:])
        reach = jnp.concatenate([reach[:, :, :M], robot_reach], axis=2)
    sight = _map_clearance(table)
    # Drifted off the path (e.g. overshot an aisle) — unless a disc is within half the look-ahead:
    # then the drift is an evasion, and a fresh path through the disc undoes it (measured: two
    # robots crossing re-planned back into each other). Not once a wall stands between the robot and
    # its current waypoint: then the evasion has taken it into another corridor, which leads elsewhere
    # (maze-32-32-2 among walkers that see: a robot tracked a path 2 m away through a wall into a dead end
    # and stood there).
    ahead = _current_waypoint(c)
    in_sight = jax.vmap(jax.vmap(lambda p, w: way_clear(p, w, SIGHT_CLEARANCE, sight, whole=True)))(pos, ahead)
    lost = (c.error > config.replan_deviation) & (~crowded | ~in_sight)
    if M > 0 or N > 1:
        # Each disc at its predicted positions over the next block_horizon seconds.
        ts = jnp.arange(int(config.block_horizon / 0.5) + 1, dtype=jnp.float32) * 0.5  # [P]
        future = pos_all[:, :, :, None, :] + vel_all[:, :, :, None, :] * ts[:, None]  # [B, N, D, P, 2]
        P = ts.shape[0]
        # A walker going the robot's way along its path is followed, not gone round (room-64-64-8:
        # robots went round walkers walking ahead of them through other rooms, 1.5-2x the way).
        going = jnp.broadcast_to(vel_all[:, :, :, None, :], future.shape).reshape(B, N, -1, 2)
        recede = jnp.where(jnp.arange(pos_all.shape[2]) < M, config.recede_speed, jnp.inf)  # walkers only
        blocked = jax.vmap(jax.vmap(path_blocked, in_axes=(0, 0, 0, 0, 0, 0, None, 0, None)),
                           in_axes=(0, 0, 0, 0, 0, 0, None, 0, None))(
            pos, c.waypoints, c.n_wp, c.index, future.reshape(B, N, -1, 2), jnp.repeat(reach, P, axis=-1),
            config.block_distance, going, jnp.repeat(recede, P))
    else:
        blocked = jnp.zeros((B, N), bool)
        future, P = pos_all[:, :, :, None, :], 1
    due = (c.t - c.last_replan).astype(jnp.float32) * period >= config.replan_period - 1e-6
    # A robot that starts creeping also re-plans from where it stalled (once, when a slot is
    # free): momentum may have carried it into a pocket the old path's next waypoint cannot be
    # reached from in a line.
    must = (blocked | lost | c.stall_replan) & due & ~c.done
    # A path planned around discs may have been a long way round a walker that has since moved
    # on: it is re-checked, and replaced by a clearly shorter one (room-64-64-8 among walkers:
    # robots went on through other rooms, 1.5-2x the way, until the time limit).
    since = (c.t - c.last_replan).astype(jnp.float32) * period
    check = c.detour & (since >= config.recheck_period - 1e-6) & due & ~c.done & ~must
    need = jnp.where(must, 2, jnp.where(check, 1, 0))
    # Nor is the way closed around a walker moving away from the robot: a re-plan would go round
    # it, and the next re-check (or block) back (a robot following a walker up a warehouse aisle
    # re-planned over and over).
    rel = pos_all - pos[:, :, None, :]
    away = jnp.sum(vel_all * rel, axis=-1) / jnp.maximum(jnp.sqrt(jnp.sum(rel * rel, axis=-1)), 1e-6)
    away = (away >= recede) if (M > 0 or N > 1) else jnp.zeros_like(reach, bool)
    closing = future.reshape(B, N, -1, 2), jnp.repeat(jnp.where(away, 0.0, reach), P, axis=-1)
    # A robot re-planning after a stall starts its new path from its cell's centre when it cannot go straight on.
    anchor = c.stall_replan
    # Stalled or lost behind a wall: its path cannot be kept, even if every way round the discs is closed.
    stranded = c.stall_replan | (lost & ~in_sight)
    c, tried, replaced = lax.cond(jnp.any(need > 0),
                                  lambda cc: replan_slots(config, free, table.resolution, cc, inputs, need, *closing,
                                                          anchor=anchor, clearance=sight, stranded=stranded),
                                  lambda cc: (cc, jnp.zeros_like(must), jnp.zeros_like(must)), c)
    c = c._replace(last_replan=jnp.where(tried, c.t, c.last_replan))
    if M > 0 or N > 1:  # with no disc at all nothing is closed, and no path goes round anything
        c = c._replace(detour=c.detour | (replaced & must))
    # A creeping robot keeps creeping along its new path, to that path's first waypoint: released
    # by the re-plan, the robot that orbited went back to full speed and orbited again (measured).
    watch, closest, progress_t = rewatch(c.creep & tried, _current_waypoint(c), pos, c.watch, c.closest,
                                         c.progress_t, c.t)
    return c._replace(watch=watch, closest=closest, progress_t=progress_t, stall_replan=c.stall_replan & ~tried)


def _subgoal(config: NavConfig, c: Carry, pos: jnp.ndarray) -> tuple[jnp.ndarray, Carry]:
    """Stage 5: ``[B, N, 2]`` the point each robot steers for: its current waypoint, or the look-ahead point
    (whose segment becomes the current waypoint)."""
    if config.subgoal == "key_nodes":
        return _current_waypoint(c), c
    sub, seg = jax.vmap(jax.vmap(lookahead_point, in_axes=(0, 0, 0, 0, None, 0)), in_axes=(0, 0, 0, 0, None, 0))(
        pos, c.waypoints, c.n_wp, c.index, config.lookahead, c.origin)
    return sub, c._replace(index=seg)


def _give_way(config: NavConfig, table: ClearanceTable, c: Carry, pos: jnp.ndarray, discs: _Discs,
              sub: jnp.ndarray) -> tuple[jnp.ndarray, Carry]:
    """Stage 5b (`NavConfig.gives_way`): the standoff watch, the end of a robot's giving way, and its start (in a
    `lax.cond` taken only on steps where some robot's standoff is due); a robot giving way steers for its yield
    point instead of ``sub [B, N, 2]``."""
    gw: GiveWay = c.give_way
    period = config.dwa.period
    gap = jnp.sqrt(jnp.sum((discs.pos - pos[:, :, None, :]) ** 2, axis=-1)) - discs.rad - discs.radius  # [B, N, D]
    near = jnp.any(gap < config.give_way_distance, axis=-1)
    gw = standoff_watch(gw, pos, near, c.t, config.give_way_move)
    ended = release(gw, discs.pos, gap, c.t, period, config.give_way_hold, config.give_way_distance)
    gw = gw._replace(active=gw.active & ~ended, anchor=jnp.where(ended[..., None], pos, gw.anchor),
                     anchor_t=jnp.where(ended, c.t, gw.anchor_t))
    due = ~gw.active & ~c.done & near & ((c.t - gw.anchor_t).astype(jnp.float32) * period
                                         >= config.give_way_time - 1e-6)

    def start(g: GiveWay) -> GiveWay:
        j = jnp.argmin(gap, axis=-1).astype(jnp.int32)  # [B, N] the disc in the way: the nearest
        at = jnp.take_along_axis(discs.pos, j[..., None, None], axis=2)[:, :, 0]
        point, found = jax.vmap(jax.vmap(yield_point, in_axes=(0, 0, 0, 0, None, None)),
                                in_axes=(0, 0, 0, 0, None, None))(
            pos, at, discs.pos, discs.rad, _map_clearance(table), config.dwa.d_safe)
        begin = due & found
        b2 = begin[..., None]
        # No point to go to: the clock restarts, and the robot looks again after another give_way_time.
        return g._replace(active=g.active | begin, point=jnp.where(b2, point, g.point),
                          since=jnp.where(begin, c.t, g.since), disc=jnp.where(begin, j, g.disc),
                          disc_at=jnp.where(b2, at, g.disc_at), count=g.count + begin.astype(jnp.int32),
                          anchor_t=jnp.where(due, c.t, g.anchor_t))

    gw = lax.cond(jnp.any(due), start, lambda g: g, gw)
    return jnp.where(gw.active[..., None], gw.point, sub), c._replace(give_way=gw)


LOCAL_PATH_POINTS = 4
"""Waypoints ahead (after the one before the current) that the MPPI path-align critic sees."""


def _local_path(wp: jnp.ndarray, n: jnp.ndarray, index: jnp.ndarray, origin: jnp.ndarray):
    """The stretch of one robot's waypoint polyline ``wp [K, 2]`` around its current waypoint: ``[W + 1, 2]`` points
    (the waypoint before the current one — or the polyline's origin — then up to ``W`` from the current on, the
    last repeated) and their valid count."""
    ahead = wp[jnp.minimum(index + jnp.arange(LOCAL_PATH_POINTS), n - 1)]
    prev = jnp.where(index > 0, wp[jnp.maximum(index - 1, 0)], origin)
    return jnp.concatenate([prev[None], ahead]), 1 + jnp.minimum(n - index, LOCAL_PATH_POINTS)


def _local_control(config: NavConfig, table: ClearanceTable, params: DWAParams | MPPIParams, inputs: EpisodeInputs,
                   c: Carry, pos: jnp.ndarray, sub: jnp.ndarray, discs: _Discs, t: jnp.ndarray,
                   per_episode: bool = False) -> tuple:
    """Stage 6: the local planner's control ``u [B, N, 2]`` (zero once done), ``recovery bool[B, N]`` and the
    MPPI warm starts ``[B, N, T, 2]``; the top speed is capped near corners (not for MPPI) and while creeping,
    unless a walker closes in. ``per_episode``: every leaf of ``params`` has a leading episode axis ``[B]``."""
    dwa = config.dwa
    robot = dwa.robot
    obs = inputs.obstacles
    B, N = pos.shape[:2]
    M = obs.radii.shape[-1]
    pos_all, vel_all, rad_all = discs.pos, discs.vel, discs.rad
    flat = lambda x: x.reshape((B * N,) + x.shape[2:])  # noqa: E731
    if config.local == "mppi":
        # MPPI brakes for corners within its own horizon: the caps that keep the DWA's constant-velocity
        # rollouts from overshooting corners only slowed it (docs/decisions.md, "MPPI in episodes").
        v_top = jnp.broadcast_to(jnp.asarray(robot.v_max, pos.dtype), (B * N,))
    else:
        cap = jax.vmap(lambda p_, w_, n_, i_: corner_cap(config, p_, w_, n_, i_, robot.decel))(
            flat(pos), flat(c.waypoints), flat(c.n_wp), flat(c.index))
        v_top = jnp.minimum(robot.v_max, jnp.maximum(cap, config.corner_speed))
    v_top = jnp.where(flat(c.creep), jnp.minimum(v_top, config.stall_speed), v_top)
    plan = c.plan
    if config.local in ("dwa", "mppi"):  # `follow` does not avoid anything: lifting its caps sends it into walls
        # Walkers only: robots avoid each other, and two robots meeting at a corner should slow down.
        threat = threatened(config, pos, pos_all[:, :, :M], vel_all[:, :, :M], rad_all[:, :, :M])
        v_top = jnp.where(flat(threat), robot.v_max, v_top)
        track = None
        if config.prediction == "oracle" and M > 0:
            if config.local == "dwa":
                track = _oracle_track(obs, t, dwa.steps, dwa.dt, pos_all, vel_all)
            else:
                mc = config.local_mppi()
                track = _oracle_track(obs, t, mc.points, mc.period / mc.substeps, pos_all, vel_all)
        obstacles = DiscObstacles(flat(pos_all), flat(vel_all), flat(rad_all), None if track is None else flat(track))
        # The run ends in the goal disc: rollouts are checked only until they enter it (a goal at
        # the end of a dead end is otherwise reached only by rollouts that run on into its end wall).
        finish = jnp.concatenate([flat(inputs.goal), jnp.full((B * N, 1), config.goal_tolerance, inputs.goal.dtype)],
                                 axis=-1)
    if table.speed_limit is not None:  # the map's speed limit at each robot's cell, of the robot's top speed
        v_top = jnp.minimum(v_top, speed_cap(table, flat(pos), robot.v_max))
        table = table._replace(speed_limit=None)  # applied: the local planners must not scale v_top again
    goal = inputs.goal
    if c.give_way is not None:
        # Giving way: towards the yield point, arriving slowly (the DWA has no goal to stop at), and for MPPI the
        # point is the goal and the path a line to it (its goal critic stops the robot there).
        gw = c.give_way
        to_point = jnp.sqrt(jnp.sum((gw.point - pos) ** 2, axis=-1)).reshape(-1)
        v_top = jnp.where(gw.active.reshape(-1), jnp.minimum(v_top, jnp.maximum(to_point, 0.1)), v_top)
        goal = jnp.where(gw.active[..., None], gw.point, goal)
    # Passive safety without a given bound: each episode's fastest walker (`NavConfig.walker_speed_max`).
    own = config.local_mppi() if config.local == "mppi" else dwa
    scenario_speed = config.local in ("dwa", "mppi") and own.safety == "passive" and own.walker_speed_max is None
    walker_speed = jnp.repeat(_walker_speed(obs, robot, N), N) if scenario_speed else None  # [B·N]
    if config.local == "mppi":
        mcfg = config.local_mppi()
        path, n_path = jax.vmap(_local_path)(flat(c.waypoints), flat(c.n_wp), flat(c.index), flat(c.origin))
        if c.give_way is not None:
            line = jnp.broadcast_to(flat(c.give_way.point)[:, None], path.shape).at[:, 0].set(flat(pos))
            giving = flat(c.give_way.active)
            path = jnp.where(giving[:, None, None], line, path)
            n_path = jnp.where(giving, 2, n_path)
        robot_index = jnp.tile(jnp.arange(N, dtype=jnp.uint32), B)
        keys = jax.vmap(lambda kd, r: jax.random.fold_in(jax.random.wrap_key_data(kd), c.t.astype(jnp.uint32) * N + r))(
            jnp.repeat(inputs.key, N, axis=0), robot_index)

        def mppi(state, mean, key, subgoal, goal, d, path_, n_path_, vmax, finish_, vw, p=params):
            cfg = mcfg.replace(robot=dataclasses.replace(mcfg.robot, v_max=vmax))
            if vw is not None:
                cfg = cfg.replace(walker_speed_max=vw)
            return mppi_control(table, cfg, p, state, mean, key, subgoal, goal, d, path_, n_path_, finish_)

        args = (flat(c.state), flat(c.plan), keys, flat(sub), flat(goal), obstacles, path, n_path, v_top, finish,
                walker_speed)
        u, info = jax.vmap(mppi)(*args, _per_robot(params, N)) if per_episode else jax.vmap(mppi)(*args)
        recovery = info.recovery.reshape(B, N)
        plan = jnp.where(c.done[..., None, None], c.plan, shift(info.sequence).reshape(c.plan.shape))
    elif config.local == "dwa":

        def control(state, subgoal, d, wp, vmax, finish, vw, p=params):
            cfg = dataclasses.replace(dwa, robot=dataclasses.replace(robot, v_max=vmax))
            if vw is not None:
                cfg = cfg.replace(walker_speed_max=vw)
            return dwa_control(table, cfg, p, state, subgoal, d, wp if config.path_critic else None, finish)

        args = (flat(c.state), flat(sub), obstacles, flat(c.waypoints), v_top, finish, walker_speed)
        u, info = jax.vmap(control)(*args, _per_robot(params, N)) if per_episode else jax.vmap(control)(*args)
        recovery = info.recovery.reshape(B, N)
    else:
        u = jax.vmap(lambda s, g, vmax: follow(config, dataclasses.replace(robot, v_max=vmax), s, g))(
            flat(c.state), flat(sub), v_top)
        recovery = jnp.zeros((B, N), bool)
    u = u.reshape(B, N, 2)
    u = jnp.where(c.done[..., None], 0.0, u)
    return u, recovery & ~c.done, plan


def _walker_speed(obs: MovingObstacles, robot, N: int) -> jnp.ndarray:
    """``f32[B]``: each episode's walker speed bound — its fastest walker (one that sees, `SOCIAL_FORCE.max_speed`
    times its route speed), and with ``N > 1`` robots at least the robots' top speed (they are discs for each
    other)."""
    speeds = jnp.asarray(obs.speeds, jnp.float32)
    if obs.reactive is not None:
        speeds = speeds * jnp.where(obs.reactive, SOCIAL_FORCE.max_speed, 1.0)
    top = jnp.max(speeds, axis=-1, initial=0.0)
    if N > 1:
        top = jnp.maximum(top, jnp.maximum(robot.v_max, -robot.v_min))
    return top


def _per_robot(params, N: int):
    """Per-episode params (leaves ``[B, ...]``) repeated for each of the ``N`` robots: leaves ``[B·N, ...]``."""
    return jax.tree_util.tree_map(lambda x: jnp.repeat(jnp.asarray(x), N, axis=0), params)


def _move_walkers(config: NavConfig, table: ClearanceTable, obs: MovingObstacles, c: Carry, discs: _Discs):
    """Stage 7a: the walkers that see, moved for one period (`advance_walkers`, each episode's robots as they are
    at its start): their new `WalkerState` ``[B, M]`` and positions ``f32[SUBSTEPS, B, M, 2]`` at the end of each
    integration step."""
    B, N = c.state.shape[:2]
    C = discs.robots.shape[2]
    rvel = c.state[..., 3:4] * jnp.stack([jnp.cos(c.state[..., 2]), jnp.sin(c.state[..., 2])], axis=-1)
    robots = discs.robots.reshape(B, N * C, 2)
    robots_vel = jnp.repeat(rvel, C, axis=1).reshape(B, N * C, 2)
    # Robots that are done stay where they are, standing: walkers still go round them.
    robots_vel = jnp.where(jnp.repeat(c.done, C, axis=1)[..., None], 0.0, robots_vel)

    def one(w, wp, n, sp, rad, lp, react, rb, rv):
        return advance_walkers(SOCIAL_FORCE, w, wp, n, sp, rad, lp, react, rb, rv, discs.radius, _map_clearance(table),
                               config.dwa.period)

    new, path = jax.vmap(one)(c.walkers, obs.waypoints, obs.n_waypoints, obs.speeds, obs.radii, obs.loop,
                              obs.reactive, robots, robots_vel)
    return new, jnp.swapaxes(path, 0, 1)


def _move_and_contacts(config: NavConfig, table: ClearanceTable, obs: MovingObstacles, c: Carry, u: jnp.ndarray,
                       t: jnp.ndarray, radius: jnp.ndarray, walked: jnp.ndarray | None = None
                       ) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """Stage 7b: the new states ``[B, N, 5]`` (a done robot stays, at rest), and the contacts during the move:
    ``hit bool[B, N]`` (map, moving disc or robot) and ``pair bool[B, N, N]`` (robot i with robot j)."""
    B, N = c.state.shape[:2]
    M = obs.radii.shape[-1]
    period = config.dwa.period
    robot = config.dwa.robot
    new = advance(c.state, u, period)
    new = jnp.where(c.done[..., None], c.state.at[..., 3:].set(0.0), new)

    # Contacts during the move: at K evenly spaced times of (t, t + period], the robots on their
    # exact arcs and the discs on their routes. Checked at t + period alone, a robot and a walker
    # closing at up to 2.2 m/s (0.44 m per period) can overlap in between and part unseen.
    K = config.contact_checks
    frac = jnp.arange(1, K + 1, dtype=new.dtype) / K  # [K]
    each = lambda a: jnp.broadcast_to(a, (K,) + a.shape)  # noqa: E731
    pose = advance(each(c.state), each(u), frac[:, None, None] * period)  # [K, B, N, 5]; a done robot (u = 0) stays
    ocs = _centres_at(obs, t + frac * period)  # [K, B, M, 2]
    if walked is not None:  # walkers that see: where the simulation moved them, between its integration steps
        J = walked.shape[0]
        steps = jnp.concatenate([c.walkers.pos[None], walked])  # [J + 1, B, M, 2] from the period's start
        at = frac * J
        lo = jnp.clip(jnp.floor(at).astype(jnp.int32), 0, J - 1)
        w = (at - lo)[:, None, None, None]
        sim = steps[lo] * (1.0 - w) + steps[lo + 1] * w  # [K, B, M, 2]
        ocs = jnp.where(obs.reactive[None, :, :, None], sim, ocs)
    nc, _ = _robot_discs(pose, robot)  # [K, B, N, C, 2]
    clear = static_clearance(table, nc[..., 0], nc[..., 1], "hybrid")  # [K, B, N, C]
    hit_map = jnp.any(clear < radius, axis=(0, 3))
    if M > 0:
        gap = jnp.sqrt(jnp.sum((nc[..., None, :] - ocs[:, :, None, None, :, :]) ** 2, axis=-1))  # [K, B, N, C, M]
        hit_obs = jnp.any(gap < radius + obs.radii[None, :, None, None, :], axis=(0, 3, 4))
    else:
        hit_obs = jnp.zeros((B, N), bool)
    if N > 1:
        d = jnp.sqrt(jnp.sum((nc[:, :, :, None, :, None, :] - nc[:, :, None, :, None, :, :]) ** 2, axis=-1))
        pair = jnp.any(d < 2 * radius, axis=(0, 4, 5)) & ~jnp.eye(N, dtype=bool)  # [B, N, N]
    else:
        pair = jnp.zeros((B, N, N), bool)
    hit = hit_map | hit_obs | jnp.any(pair, axis=-1)
    return new, hit, pair


def _bookkeeping(config: NavConfig, inputs: EpisodeInputs, c: Carry, new: jnp.ndarray, hit: jnp.ndarray,
                 pair: jnp.ndarray, u: jnp.ndarray) -> Carry:
    """Stage 8: contact counts (onsets of contact), steps, tracking error, and why a robot is done (goal,
    collision when the config stops on one, time limit); a done robot stays done."""
    period = config.dwa.period
    active = ~c.done
    onset = hit & ~c.hit & active
    pair_onset = pair & ~c.pair_hit & (active[:, :, None] | active[:, None, :])

    steps = c.steps + active.astype(jnp.int32)
    # Tracking error: distance to the polyline being tracked (origin, then the waypoints).
    poly = jnp.concatenate([c.origin[:, :, None, :], c.waypoints], axis=2)
    err = point_polyline_distance(new[:, :, None, :2], poly, c.n_wp + 1)[..., 0]
    sq_error = c.sq_error + jnp.where(active, err * err, 0.0)
    at_goal = jnp.sqrt(jnp.sum((new[..., :2] - inputs.goal) ** 2, axis=-1)) <= config.goal_tolerance
    timeout = steps.astype(jnp.float32) * period >= inputs.time_limit - 1e-6
    crash = hit & config.stop_on_collision
    reason = jnp.where(at_goal, GOAL, jnp.where(crash, COLLISION, jnp.where(timeout, TIMEOUT, RUNNING)))
    reason = jnp.where(c.done, c.reason, reason)
    done = c.done | (reason != RUNNING)
    return c._replace(
        state=new, done=done, reason=reason, steps=steps, hit=hit, pair_hit=pair,
        collisions=c.collisions + onset.astype(jnp.int32),
        active_contacts=c.active_contacts + (onset & (jnp.abs(u[..., 0]) > ACTIVE_SPEED)).astype(jnp.int32),
        pair_collisions=c.pair_collisions + pair_onset.astype(jnp.int32), sq_error=sq_error, error=err,
        t=c.t + 1,
    )


def _step(config: NavConfig, table: ClearanceTable, free: jnp.ndarray, params: DWAParams | MPPIParams,
          inputs: EpisodeInputs, c: Carry, per_episode: bool = False):
    """One control period of every robot: the stages in the order of the module docstring."""
    t = c.t.astype(jnp.float32) * config.dwa.period
    discs = _seen_discs(config.dwa.robot, inputs.obstacles, c.state, t, c.walkers)
    pos = c.state[..., :2]
    c = _next_waypoints(config, table, c, pos)
    crowded = _crowded(config, discs, pos)
    c = _watch_progress(config, c, pos, crowded, inputs.goal)  # stage 3
    if config.replan:
        c = _replanning(config, table, free, inputs, c, pos, discs, crowded)
    sub, c = _subgoal(config, c, pos)
    if c.give_way is not None and discs.pos.shape[2] > 0:  # with no disc at all there is nothing to give way to
        sub, c = _give_way(config, table, c, pos, discs, sub)
    u, recovery, plan = _local_control(config, table, params, inputs, c, pos, sub, discs, t, per_episode)
    c = c._replace(plan=plan)
    walked = None
    if c.walkers is not None:
        walkers, walked = _move_walkers(config, table, inputs.obstacles, c, discs)
    new, hit, pair = _move_and_contacts(config, table, inputs.obstacles, c, u, t, discs.radius, walked)
    if c.walkers is not None:
        c = c._replace(walkers=walkers)
    c = _bookkeeping(config, inputs, c, new, hit, pair, u)
    seen = None if c.walkers is None else _obstacles_now(inputs.obstacles, c.walkers, t + config.dwa.period)[0]
    return c, (new, u, recovery, seen)


def _initial_walkers(obs: MovingObstacles) -> WalkerState | None:
    """The walkers that see at ``t = 0`` (``[B, M]``), placed as the blind model places them; None if none sees."""
    if obs.reactive is None:
        return None
    pos, vel = jax.vmap(obstacle_state, in_axes=(0, None))(obs, 0.0)
    target, forward = jax.vmap(route_target, in_axes=(0, None))(obs, 0.0)
    return initial_walkers(pos, vel, target, forward)


def _initial_plans(config: NavConfig, start: jnp.ndarray) -> jnp.ndarray:
    """``f32[B, N, T, 2]``: each robot's first MPPI warm start (its start velocity held); ``T = 0`` unless MPPI."""
    if config.local != "mppi":
        return jnp.zeros(start.shape[:2] + (0, 2), start.dtype)
    mc = config.local_mppi()
    return jax.vmap(jax.vmap(lambda s: initial_sequence(mc, s)))(start).astype(start.dtype)


def initial_carry(config: NavConfig, inputs: EpisodeInputs) -> Carry:
    """The episode loop's carry before step 0 (pure): every robot at its start, nothing counted yet."""
    B, N = inputs.start.shape[:2]
    zeros = jnp.zeros((B, N), jnp.int32)
    return Carry(
        state=inputs.start, waypoints=inputs.waypoints, n_wp=inputs.n_waypoints, index=zeros, done=~inputs.active,
        reason=zeros, steps=zeros, hit=jnp.zeros((B, N), bool), pair_hit=jnp.zeros((B, N, N), bool),
        collisions=zeros, active_contacts=zeros, pair_collisions=jnp.zeros((B, N, N), jnp.int32), replans=zeros,
        last_replan=zeros - 10**6, origin=inputs.start[..., :2], sq_error=jnp.zeros((B, N), inputs.start.dtype),
        error=jnp.zeros((B, N), inputs.start.dtype), watch=jnp.full((B, N, 2), jnp.nan, inputs.start.dtype),
        closest=jnp.zeros((B, N), inputs.start.dtype), progress_t=zeros, creep=jnp.zeros((B, N), bool),
        creep_goal=jnp.zeros((B, N), inputs.start.dtype),
        spin=jnp.zeros((B, N), inputs.start.dtype),
        goal_best=jnp.sqrt(jnp.sum(lax.stop_gradient(inputs.goal - inputs.start[..., :2]) ** 2, axis=-1)),
        stall_replan=jnp.zeros((B, N), bool), detour=jnp.zeros((B, N), bool),
        plan=_initial_plans(config, inputs.start), walkers=_initial_walkers(inputs.obstacles),
        give_way=initial_give_way(inputs.start[..., :2]) if config.gives_way else None,
        t=jnp.asarray(0, jnp.int32),
    )


def run_chunk(config: NavConfig, table: ClearanceTable, free: jnp.ndarray, params: DWAParams | MPPIParams,
              inputs: EpisodeInputs, carry: Carry, per_episode: bool = False) -> Carry:
    """`NavConfig.chunk` steps of every episode from ``carry`` (pure; ``config`` and ``per_episode`` static),
    the trajectories dropped: what `jaxplan.nav.run_outcomes` steps between its compactions."""
    return lax.scan(lambda cc, _: (_step(config, table, free, params, inputs, cc, per_episode)[0], None), carry,
                    None, length=config.chunk)[0]


def run_episodes(config: NavConfig, steps: int, table: ClearanceTable, free: jnp.ndarray,
                 params: DWAParams | MPPIParams, inputs: EpisodeInputs, per_episode: bool = False) -> EpisodeOutput:
    """Runs ``B`` episodes of ``N`` robots (pure; jit with ``config`` and ``steps`` static).

    Args:
      config: `NavConfig`.
      steps: ``S``, the buffer length in control steps (static, a multiple of ``config.chunk``).
      table: the map's `ClearanceTable` (collision and DWA clearance).
      free: ``bool[H, W]`` the planning map (inflated) used when re-planning.
      params: `DWAParams` (`MPPIParams` when ``config.local == "mppi"``).
      inputs: `EpisodeInputs`.
      per_episode: every leaf of ``params`` has a leading axis ``[B]``: episode b runs with its own weights
        (static). Tuning evaluates a population of weight vectors as episodes of one batch this way
        (`jaxplan.tune.nav_objective`); each episode's steps are those it would run with its weights alone.
    """
    B, N = inputs.start.shape[:2]
    chunk = config.chunk
    carry = initial_carry(config, inputs)
    states = jnp.broadcast_to(inputs.start[None], (steps + 1, B, N, 5))
    controls = jnp.zeros((steps, B, N, 2), inputs.start.dtype)
    recov = jnp.zeros((steps, B, N), bool)
    walked = None if carry.walkers is None else jnp.broadcast_to(carry.walkers.pos[None],
                                                                  (steps + 1,) + carry.walkers.pos.shape)

    def body(loop):
        c, st, ct, rc, wk, k = loop
        c, (s, u, r, w) = lax.scan(lambda cc, _: _step(config, table, free, params, inputs, cc, per_episode), c,
                                   None, length=chunk)
        st = lax.dynamic_update_slice(st, s, (k * chunk + 1, 0, 0, 0))
        ct = lax.dynamic_update_slice(ct, u, (k * chunk, 0, 0, 0))
        rc = lax.dynamic_update_slice(rc, r, (k * chunk, 0, 0))
        if wk is not None:
            wk = lax.dynamic_update_slice(wk, w, (k * chunk + 1, 0, 0, 0))
        return c, st, ct, rc, wk, k + 1

    def cond(loop):
        c, _, _, _, _, k = loop
        return (k * chunk < steps) & ~jnp.all(c.done)

    c, states, controls, recov, walked, k = lax.while_loop(
        cond, body, (carry, states, controls, recov, walked, jnp.asarray(0)))
    # Rows after a robot's last step hold its final pose at rest, whether the loop reached them
    # (a done robot is set to v = omega = 0) or stopped first (on a mesh, once its device was done).
    rows = jnp.arange(steps + 1)[:, None, None]
    states = jnp.where((rows <= c.steps[None])[..., None], states, c.state.at[..., 3:].set(0.0)[None])
    sw = lambda x: jnp.swapaxes(x, 0, 1)  # noqa: E731  [S, B, ...] -> [B, S, ...]
    return EpisodeOutput(
        states=sw(states), controls=sw(controls), recovery=sw(recov), steps=c.steps, reason=c.reason,
        collisions=c.collisions, active_contacts=c.active_contacts, pair_collisions=c.pair_collisions,
        replans=c.replans,
        rmse=jnp.sqrt(c.sq_error / jnp.where(c.steps > 0, c.steps, jnp.nan)), waypoints=c.waypoints,
        n_waypoints=c.n_wp, executed=jnp.broadcast_to(k * chunk, (B,)),
        walkers=None if walked is None else jnp.where(  # rows after the loop stopped: where they were then
            (jnp.arange(steps + 1) <= k * chunk)[:, None, None, None], walked,
            walked[jnp.minimum(k * chunk, steps)][None]).swapaxes(0, 1),
        give_ways=None if c.give_way is None else c.give_way.count,
    )
