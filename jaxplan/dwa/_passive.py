"""Passive motion safety against walkers of bounded speed: can the robot be touched only at rest?

The check of ``safety="passive"`` (`jaxplan.dwa.DWAConfig.safety`, `jaxplan.mppi.MPPIConfig.safety`;
Fraichard & Asama 2004's inevitable collision states, Bouraine, Fraichard & Salhi 2012's passive motion safety).

**Assumptions.** Every walker (a disc of radius ``r_j``) moves no faster than ``V`` = ``walker_speed_max`` (m/s),
whatever else it does, and its position ``w_j`` is known at the start of each control period. So ``t`` seconds
after now, walker j is inside the disc of radius ``r_j + V·t`` around ``w_j``: its *reachable set*, grown from
where it is now, not from where it was predicted to go. Other robots count as walkers (with their own speed
bound). The robot follows its commands exactly: a command ``(v, ω)`` takes effect at the start of its period
and is held (the episode's motion model, `jaxplan.dwa.advance`).

**The check.** A candidate control ``(v, ω)`` — a DWA sample, or the first control of an MPPI sequence — is
*admissible* when the manoeuvre "one period at ``(v, ω)``, then brake" keeps the robot, as long as it moves,
out of every reachable set and at least its footprint radius ``R`` from the map. Braking is the command
`clamp_controls` gives for ``(0, 0)``, period after period: the speed falls by ``decel·P`` per period (rises by
``accel·P`` when reversing) and the yaw rate by ``alpha·P`` (within an `Ackermann` robot's cone): the hardest
stop the robot can make, and heading kept as soon as its turn has run out. That manoeuvre is also what a robot
with no admissible control does (`brake`).

**Why it is safe.** Say the control chosen at step k was admissible. At step k + 1 the robot is where the
manoeuvre's first period left it, and braking is the manoeuvre's remainder; the walkers are within ``V·P`` of
where they were, so every reachable set measured from their new positions lies inside one measured from the
old. The remainder is therefore still clear — admissible, or, if this discretised check now refuses it, still
safe to take: `brake` takes it. By induction from a robot that starts at rest, the robot is never inside a
reachable set while it moves, so a walker can touch it only at rest.

**Discretisation margin.** The manoeuvre is checked at ``POINTS_PER_PERIOD`` evenly spaced times per control
period, the period's start and end included (``δ = P / POINTS_PER_PERIOD`` apart). Between two checks the
robot's covering disc centre moves at most ``L = |v_k| + |ω_k|·o`` metres per second (``v_k, ω_k`` that
period's command, ``o`` the farthest covering disc's offset from the reference point: 0 for a `Disc`), and a
reachable set's edge at most ``V``. A clearance that is ``L``-Lipschitz in time and at least ``c`` at both ends
of an interval of length ``δ`` is at least ``c − L·δ/2`` inside it. So an interval passes when both its ends are

    map:     clearance  ≥ R + L·δ/2 + ε
    walkers: |p − w_j| − r_j − V·t  ≥ R + (L + V)·δ/2 + ε

with ``ε = FLOAT_SLACK`` (1 mm) for the float32 difference between this check's rotor arcs and the episode's
`jaxplan.dwa.advance`; at 1.2 m/s, 1.0 m/s walkers, 0.2 s periods and two checks per period the walkers'
margin is 0.11 m. The map clearance is the map's lookup (``DWAConfig.clearance``): exact near the walls with
``"hybrid"`` (the default) and ``"exact"``, not with ``"bilinear"``. A manoeuvre still moving after
``brake_periods`` periods is not admissible (it was not checked to its end).
"""

from __future__ import annotations

import math
from typing import Any, Protocol, TypeVar, cast

import jax
import jax.numpy as jnp
from jax import lax

from jaxplan.dwa._clearance import ClearanceTable, DiscObstacles, static_clearance
from jaxplan.dwa._fastmath import rotor
from jaxplan.dwa._robot import Disc, Robot, footprint_offsets, footprint_radius
from jaxplan.dwa._window import Num, clamp_controls

__all__ = ["passive_slack", "brake", "braking_periods", "with_brake_periods", "walker_speed_bound",
           "DEFAULT_WALKER_SPEED", "POINTS_PER_PERIOD", "FLOAT_SLACK", "FALLBACK_PERIODS"]

DEFAULT_WALKER_SPEED = 1.5
"""m/s: the walkers' speed bound when none is given and the scenario is not known (a brisk walk; li2026's fastest
moving obstacles). Discs seen moving faster raise it to their speed."""

POINTS_PER_PERIOD = 2
"""Checks per control period of the manoeuvre (the start and end of each period included)."""

FLOAT_SLACK = 1e-3
"""m added to every margin: float32 rounding between this check's arcs and the episode's motion model."""

FALLBACK_PERIODS = 32
"""Braking periods checked when ``brake_periods`` is None and the robot's limits are traced (not known when the
program is built); the host fronts and navigation episodes set it from the limits instead."""

_SMALL_ANGLE = 1e-4
_EPS2 = 1e-12  # floor under squared distances: keeps sqrt's gradient finite at 0



class SafetyConfig(Protocol):
    """What `with_brake_periods` reads of a local planner's config (`DWAConfig`, `jaxplan.mppi.MPPIConfig`)."""

    @property
    def safety(self) -> str: ...

    @property
    def brake_periods(self) -> int | None: ...

    @property
    def robot(self) -> Robot: ...

    @property
    def period(self) -> float: ...

    def replace(self, **changes: Any) -> Any: ...


C = TypeVar("C", bound=SafetyConfig)


def braking_periods(robot: Robot, period: Num, brake_periods: int | None = None) -> int:
    """Control periods after the first that braking from the robot's top speed takes, plus one for rounding
    (``brake_periods`` if given); `FALLBACK_PERIODS` when the limits are traced. Static: it sizes the check."""
    if brake_periods is not None:
        return int(brake_periods)
    try:
        forward = float(robot.v_max) / float(robot.decel)
        backward = max(-float(robot.v_min), 0.0) / float(robot.accel)
        return int(math.ceil(max(forward, backward) / float(period) - 1e-9)) + 1  # type: ignore[arg-type]
    except (TypeError, jax.errors.ConcretizationTypeError):
        return FALLBACK_PERIODS


def with_brake_periods(config: C) -> C:
    """A `DWAConfig` or `jaxplan.mppi.MPPIConfig` with ``safety="passive"`` and no ``brake_periods``, given the
    count its robot's limits need (`braking_periods`, while they are plain numbers); any other config as it is."""
    if config.safety != "passive" or config.brake_periods is not None:
        return config
    return cast(C, config.replace(brake_periods=braking_periods(config.robot, config.period)))


def walker_speed_bound(speed_max: Num | None, obstacles: DiscObstacles | None) -> jnp.ndarray:
    """The walkers' speed bound (m/s): ``speed_max`` if given, else the larger of `DEFAULT_WALKER_SPEED` and the
    fastest disc's current speed."""
    if speed_max is not None:
        return jnp.asarray(speed_max, jnp.float32)
    if obstacles is None or obstacles.radii.shape[-1] == 0:
        return jnp.asarray(DEFAULT_WALKER_SPEED, jnp.float32)
    fastest = jnp.max(jnp.sqrt(jnp.sum(obstacles.velocities ** 2, axis=-1)))
    return jnp.maximum(DEFAULT_WALKER_SPEED, fastest).astype(jnp.float32)


def brake(robot: Robot, state: jnp.ndarray, period: Num) -> jnp.ndarray:
    """``f32[2]``: the hardest braking command from ``state [5]`` — speed and yaw rate as near 0 as one period
    allows (`clamp_controls` of ``(0, 0)``). What a robot with no admissible control does."""
    v, w = clamp_controls(robot, state[3], state[4], jnp.zeros_like(state[3]), jnp.zeros_like(state[4]), period)
    return jnp.stack([v, w])


def passive_slack(table: ClearanceTable, mode: str, robot: Robot, state: jnp.ndarray, v: jnp.ndarray,
                  w: jnp.ndarray, period: Num, obstacles: DiscObstacles | None, speed: Num,
                  periods: int) -> jnp.ndarray:
    """``f32[S]``: how much room (m) the manoeuvre of each candidate control keeps; admissible where ``>= 0``.

    Args:
      table: the map's clearance table; ``mode`` its lookup (static, `jaxplan.dwa.static_clearance`).
      robot: the robot (limits, footprint).
      state: ``f32[5]`` the robot now (x, y, θ, v, ω).
      v, w: ``f32[S]`` the candidate commands for the next period (inside the robot's window).
      period: the control period P (s).
      obstacles: the walkers and other robots as discs (their ``positions`` now and ``radii``; velocities and
        tracks are not used), or None.
      speed: their speed bound V (m/s).
      periods: braking periods checked after the first (static; `braking_periods`).

    Returns:
      The smallest slack over the moving part of each manoeuvre — clearance less ``R``, less the module's margins
      — ``+inf`` for one that never moves, ``-inf`` for one still moving after ``periods`` braking periods.
    """
    fp = robot.footprint
    radius = footprint_radius(fp)
    disc = isinstance(fp, Disc)
    offsets = jnp.zeros(1) if disc else jnp.asarray(footprint_offsets(fp))
    reach_o = 0.0 if disc else jnp.max(jnp.abs(offsets))
    J = POINTS_PER_PERIOD
    delta = period / J
    walkers = None
    if obstacles is not None and obstacles.radii.shape[-1] > 0:
        # Where the discs are now: the reachable sets grow from here (V·t below). [M] each.
        walkers = (obstacles.positions[:, 0], obstacles.positions[:, 1], obstacles.radii)
    speed = jnp.asarray(speed, v.dtype)

    def clearances(x: jnp.ndarray, y: jnp.ndarray, h: jnp.ndarray, t: Num) -> tuple[jnp.ndarray, jnp.ndarray]:
        """``(map, walkers)`` clearance (m) of the footprint at ``x, y [S]``, heading ``h``, ``t`` s from now."""
        c_map = c_walk = None
        for j in range(offsets.shape[0]):
            cx, cy = (x, y) if disc else (x + offsets[j] * h.real, y + offsets[j] * h.imag)
            m = static_clearance(table, cx, cy, mode)
            c_map = m if c_map is None else jnp.minimum(c_map, m)
            if walkers is not None:  # [S, M] distances to the discs' edges, the nearest kept
                wx, wy, wr = walkers
                d2 = (cx[:, None] - wx) ** 2 + (cy[:, None] - wy) ** 2
                d = jnp.min(jnp.sqrt(jnp.maximum(d2, _EPS2)) - wr, axis=-1)
                c_walk = d if c_walk is None else jnp.minimum(c_walk, d)
        assert c_map is not None  # at least one covering disc
        if c_walk is None:
            c_walk = jnp.full_like(c_map, jnp.inf)
        return c_map, c_walk - speed * t

    zero = v * 0.0  # derived from the inputs, so that the carry varies like its updates
    h0 = lax.complex(jnp.cos(state[2]) + zero, jnp.sin(state[2]) + zero)
    x0, y0 = state[0] + zero, state[1] + zero
    m0, w0 = clearances(x0, y0, h0, 0.0)
    init = (x0, y0, h0, state[3] + zero, state[4] + zero, m0, w0, zero + jnp.inf)

    def body(carry: tuple, k: jnp.ndarray) -> tuple[tuple, None]:
        x, y, h, v_prev, w_prev, prev_map, prev_walk, best = carry
        vb, wb = clamp_controls(robot, v_prev, w_prev, zero, zero, period)
        first = k == 0
        vk, wk = jnp.where(first, v, vb), jnp.where(first, w, wb)
        speed_k = jnp.abs(vk) + reach_o * jnp.abs(wk)  # the covering discs' top speed this period (L)
        moving = speed_k > 0.0
        margin_map = speed_k * (delta / 2) + FLOAT_SLACK
        margin_walk = (speed_k + speed) * (delta / 2) + FLOAT_SLACK
        phi = wk * (delta / 2)
        small = jnp.abs(phi) < _SMALL_ANGLE
        q = rotor(phi)
        arc_scale = vk * delta / jnp.where(small, 1.0, phi)
        t0 = k.astype(v.dtype) * period
        qj = None
        for j in range(1, J + 1):
            qj = q if qj is None else qj * q
            arc = jnp.where(small, vk * (j * delta), arc_scale * qj.imag)
            p = h * qj * arc
            hj = h * qj * qj
            c_map, c_walk = clearances(x + p.real, y + p.imag, hj, t0 + j * delta)
            slack = jnp.minimum(jnp.minimum(prev_map, c_map) - margin_map,
                                jnp.minimum(prev_walk, c_walk) - margin_walk) - radius
            best = jnp.minimum(best, jnp.where(moving, slack, jnp.inf))
            prev_map, prev_walk = c_map, c_walk
        h = hj * lax.rsqrt(jnp.real(hj * jnp.conj(hj))).astype(hj.dtype)  # keep it a unit rotor
        return (x + p.real, y + p.imag, h, vk, wk, prev_map, prev_walk, best), None

    carry, _ = lax.scan(body, init, jnp.arange(periods + 1, dtype=jnp.int32))
    v_end, w_end, best = carry[3], carry[4], carry[7]
    at_rest = (v_end == 0.0) & ((reach_o * w_end) == 0.0)
    return jnp.where(at_rest, best, -jnp.inf)
