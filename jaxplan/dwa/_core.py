"""One DWA control step as a pure, jittable function of arrays, for one robot or a batch.

`dwa_control` is what a navigation episode calls inside its `lax.scan` over control
steps (and ``vmap``-s over episodes): window → samples → rollouts with clearance →
feasibility → critics → evaluator → selection (or recovery). It cannot raise; the
host front `jaxplan.dwa.dwa_step` validates inputs first.

Selection:
  * ``"argmax"`` — the best feasible sample (DWA as published).
  * ``"softmax"`` — the temperature-relaxed choice for differentiable tuning: the
    control is the average of the feasible samples' controls weighted by
    ``softmax(score / temperature)``; it lies in the window (a convex combination of
    points of a convex set) and tends to the argmax as the temperature goes to 0. An
    `Ackermann` robot that may reverse has its blended yaw rate clipped to its curvature
    limit (|ω| <= κ|v| is not convex across v = 0).

Recovery (docs/guide/navigation.md): when no sample is feasible the robot brakes as hard as the
window allows towards v = 0 and turns as fast as it allows towards the sub-goal's
side (left when the sub-goal is dead ahead) — "stop and rotate in place"; an
`Ackermann` robot cannot turn on the spot, so its yaw rate also follows the curvature
limit and it simply stops. ``DWAInfo.recovery`` flags it. With ``recovery="flee"`` the
robot instead takes the sample whose rollout keeps the most clearance: a moving disc
heading for a stopped robot hits it, which among random walkers was most of the collisions.
Among the samples that keep d_safe from the map, if any do: the most clearance from anything
can lead into a wall (see `_flee`).

Safety (`DWAConfig.safety`): with ``"predicted"`` a sample is feasible only if the robot can brake to rest from its
rollout's end before any predicted contact (`braking_clearance`); with ``"passive"`` only if one period at its
(v, ω) and then the hardest braking keep the robot off the map and out of every walker's reachable set
(`jaxplan.dwa._passive`). In passive mode the recovery is restricted to such samples, and with none the robot
brakes; a softmax blend, a stuck-escape turn or a turn in place is checked too and replaced when it fails.

The ``"classic"`` evaluator adds PythonRobotics' stuck-escape rule: when the chosen
speed and the current speed are both below 0.001 m/s, turn (PythonRobotics commands
``-max_delta_yaw_rate``; here the most negative yaw rate inside the window, so the
control stays admissible). ``DWAInfo.stuck`` flags it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from jaxplan.dwa import _critics as C
from jaxplan.dwa._brake import braking_clearance
from jaxplan.dwa._clearance import ClearanceTable, DiscObstacles, disc_clearance, speed_cap, static_clearance
from jaxplan.dwa._config import DWAConfig, DWAParams
from jaxplan.dwa._fuzzy import fuzzy_evaluate
from jaxplan.dwa._passive import brake, braking_periods, passive_slack, walker_speed_bound
from jaxplan.dwa._robot import Disc, curvature_limit, footprint_offsets, footprint_radius
from jaxplan.dwa._rollout import rollout
from jaxplan.dwa._window import dynamic_window, sample_controls

__all__ = ["DWAInfo", "dwa_control", "dwa_control_batch", "evaluate", "trajectory", "STUCK_SPEED"]

STUCK_SPEED = 0.001
"""PythonRobotics' ``robot_stuck_flag_cons`` (m/s)."""

ESCAPE_SLACK = 1e-4
"""Metres an escaping rollout may lose against the current clearance (float noise of a rollout parallel to a wall)."""


class DWAInfo(NamedTuple):
    """What a step saw and decided (a pytree; a batch adds a leading axis to every field).

    Attributes:
      scores: ``f32[S]`` evaluator scores of every sample (higher is better; computed
        for infeasible samples too, but they are never chosen).
      rollouts: ``f32[S, T, 3]`` every sample's trajectory points (x, y, theta) at
        ``dt, 2·dt, …, T·dt`` (cui2025's Figure 4 fan), or None when the config does not
        keep them (``keep_rollouts=False``, what episodes use).
      feasible: ``bool[S]`` minimum clearance >= d_safe over the horizon.
      chosen: ``i32`` index of the best feasible sample (−1 in recovery). With softmax
        selection it is the argmax, the sample the blend leans on most.
      samples: ``f32[S, 2]`` the (v, ω) samples.
      clearance: ``f32[S]`` minimum clearance of each rollout (m).
      window: ``f32[4]`` (v_lo, v_hi, ω_lo, ω_hi) of the dynamic window.
      recovery: ``bool`` no sample was feasible; the control is the recovery manoeuvre.
      stuck: ``bool`` the classic stuck-escape rule fired (it turns the robot, within an
        `Ackermann` robot's curvature limit: at rest, not at all).
    """

    scores: jnp.ndarray
    rollouts: jnp.ndarray
    feasible: jnp.ndarray
    chosen: jnp.ndarray
    samples: jnp.ndarray
    clearance: jnp.ndarray
    window: jnp.ndarray
    recovery: jnp.ndarray
    stuck: jnp.ndarray


def trajectory(state: jnp.ndarray, control: jnp.ndarray, steps: int, dt: float) -> jnp.ndarray:
    """``[T, 3]`` poses at ``dt … T·dt`` under a constant control, in closed form (exact arcs).

    For plotting the trajectory of a returned control (with argmax selection it equals
    ``info.rollouts[info.chosen]``; a softmax blend is generally none of the samples).
    """
    t = jnp.arange(1, steps + 1, dtype=state.dtype) * dt
    v, w = control[0], control[1]
    chord = v * t * jnp.sinc(w * t / (2 * math.pi))
    mid = state[2] + w * t / 2
    return jnp.stack([state[0] + chord * jnp.cos(mid), state[1] + chord * jnp.sin(mid), state[2] + w * t], axis=-1)


def evaluate(cr: C.Critics, v: jnp.ndarray, feasible: jnp.ndarray, config: DWAConfig, params: DWAParams,
             with_path: bool = True) -> jnp.ndarray:
    """Scores ``[S]`` of the rollouts under the configured evaluator (static choice; ``with_path``
    static: whether a global path was given)."""
    if config.evaluator == "weighted":
        return C.weighted(cr, params, feasible, with_path)
    if config.evaluator == "fuzzy":
        f = fuzzy_evaluate(cr.heading_error / math.pi, window_speed(cr.velocity, feasible), cr.min_clearance, params,
                           config.d_safe, config.d_clip)
        # Path and goal critics, if weighted, join the fuzzy rating as a weighted average.
        main = params.heading + params.velocity + params.clearance
        total = main + params.path + params.goal
        return (main * f + params.path * cr.path + params.goal * cr.goal) / jnp.maximum(total, 1e-12)
    if config.evaluator == "classic":
        return C.classic(cr, params, v, config.robot)
    raise ValueError(f"unknown evaluator {config.evaluator!r}")


def window_speed(velocity: jnp.ndarray, feasible: jnp.ndarray) -> jnp.ndarray:
    """The fuzzy speed input ``[S]``: V rescaled to [0, 1] over the feasible samples (V itself if they all agree).

    cui2025 feeds a "normalised speed"; normalised over the window — as the weighted
    evaluator normalises its critics over the samples — rather than by v_max. With
    V = v/v_max a robot at rest sees only "slow" samples (its window reaches 0.1 m/s),
    and the clearance it keeps by staying put outweighs the speed it would gain: a fuzzy-DWA
    robot starting in an aisle would never move.
    """
    lo = jnp.min(jnp.where(feasible, velocity, jnp.inf))
    hi = jnp.max(jnp.where(feasible, velocity, -jnp.inf))
    span = hi - lo
    wide = span > 1e-6
    return jnp.where(wide, jnp.clip((velocity - lo) / jnp.where(wide, span, 1.0), 0.0, 1.0), velocity)


def _recovery(config: DWAConfig, state: jnp.ndarray, subgoal: jnp.ndarray, window) -> jnp.ndarray:
    """Brake towards v = 0 and turn towards the sub-goal's side, as hard as the window allows."""
    v = jnp.clip(0.0, window.v_lo, window.v_hi)
    dx, dy = subgoal[0] - state[0], subgoal[1] - state[1]
    c, s = jnp.cos(state[2]), jnp.sin(state[2])
    side = jnp.where(c * dy - s * dx < 0, -1.0, 1.0)  # sub-goal to the right: turn right
    w = side * config.robot.omega_max
    kappa = curvature_limit(config.robot)
    if kappa is not None:
        w = jnp.clip(w, -kappa * jnp.abs(v), kappa * jnp.abs(v))
    return jnp.stack([v, jnp.clip(w, window.w_lo, window.w_hi)])


def _current_clearance(clearance, state: jnp.ndarray, footprint) -> jnp.ndarray:
    """Clearance (m) of the footprint at the current pose (time 0)."""
    x, y, th = state[0:1], state[1:2], state[2]
    offsets = (0.0,) if isinstance(footprint, Disc) else footprint_offsets(footprint)
    c = [clearance(x + o * jnp.cos(th), y + o * jnp.sin(th), 0.0) for o in offsets]
    return jnp.min(jnp.concatenate(c)) if len(c) > 1 else c[0][0]


def _flee(ro, d_safe, allowed: jnp.ndarray | None = None) -> jnp.ndarray:
    """Index of the sample that keeps the most clearance, among those that keep d_safe from the map if any do
    (and among the ``allowed`` ones, ``bool[S]``, if given: the passively safe ones).

    The most clearance from anything can be a flight from a walker into a wall: among walkers,
    robots fleeing by clearance alone ended on walls.
    """
    if allowed is None:
        if ro.static is None:
            return jnp.argmax(ro.clearance)
        safe = ro.static >= d_safe
        return jnp.argmax(jnp.where(safe | ~jnp.any(safe), ro.clearance, -jnp.inf))
    pick = allowed
    if ro.static is not None:
        safe = (ro.static >= d_safe) & allowed
        pick = jnp.where(jnp.any(safe), safe, allowed)
    return jnp.argmax(jnp.where(pick, ro.clearance, -jnp.inf))


def dwa_control(table: ClearanceTable, config: DWAConfig, params: DWAParams, state: jnp.ndarray,
                subgoal: jnp.ndarray, obstacles: DiscObstacles | None = None,
                path: jnp.ndarray | None = None, finish: jnp.ndarray | None = None) -> tuple[jnp.ndarray, DWAInfo]:
    """One DWA step for one robot (pure; jit it, vmap it, scan it, differentiate it).

    Args:
      table: the map's `ClearanceTable` (`jaxplan.dwa.clearance_table`).
      config: `DWAConfig` (static counts and switches, traced limits and distances).
      params: `DWAParams` critic weights and temperature.
      state: ``f32[5]`` (x, y, theta, v, omega) in m, rad, m/s, rad/s.
      subgoal: ``f32[2]`` (m) the point the heading and goal critics aim at.
      obstacles: `DiscObstacles` with ``M`` discs (``[M, 2]`` positions and velocities,
        ``[M]`` radii; a ``[M, K, 2]`` track sampled every ``config.dt`` replaces the
        constant-velocity prediction) or None.
      path: ``f32[L, 2]`` the global path (m) for the path critic, or None.
      finish: ``f32[3]`` (x, y, radius) the goal region where the robot's run ends, or None:
        rollout points after a rollout enters it are not checked (see `rollout`).

    Returns:
      ``(control f32[2] = (v, omega), DWAInfo)``.

    With a speed limit layer in ``table`` (a map's Nav2 speed mask), the window's top speed is capped at the
    value of the robot's cell (`speed_cap`).
    """
    if table.speed_limit is not None:
        config = config.replace(robot=dataclasses.replace(
            config.robot, v_max=speed_cap(table, state[:2], config.robot.v_max)))
    robot = config.robot
    steps, dt = config.steps, config.dt
    window = dynamic_window(robot, state, config.period)
    v, w = sample_controls(robot, window, config.n_v, config.n_omega)

    moving = obstacles is not None and obstacles.radii.shape[-1] > 0
    # Fleeing from discs needs the map's part of the clearance on its own (see `_flee`).
    split = moving and config.recovery == "flee"

    def clearance(x, y, t):
        c = static_clearance(table, x, y, config.clearance)
        if split:
            return c, disc_clearance(obstacles, x, y, t, dt)
        if moving:
            c = jnp.minimum(c, disc_clearance(obstacles, x, y, t, dt))
        return c

    def combined(x, y, t):
        c = clearance(x, y, t)
        return jnp.minimum(*c) if split else c

    ro = rollout(state, v, w, clearance, robot.footprint, steps, dt, keep=config.keep_rollouts,
                 unroll=config.unroll, finish=finish, split=split)
    if config.straighten:
        # The turn-then-straight grids roll out in a loop of their own, so that the default
        # configuration's constant-curvature loop stays as it is.
        v2, w2 = sample_controls(robot, window, config.n_v, config.n_omega_straight)
        k = np.repeat(np.asarray(config.turn_steps(), np.float32), v2.shape[0])
        v2, w2 = jnp.tile(v2, len(config.straighten)), jnp.tile(w2, len(config.straighten))
        ro2 = rollout(state, v2, w2, clearance, robot.footprint, steps, dt, keep=config.keep_rollouts,
                      unroll=config.unroll, finish=finish, split=split, turn_steps=jnp.asarray(k))
        ro = jax.tree.map(lambda a, b: jnp.concatenate([a, b]), ro, ro2)
        v, w = jnp.concatenate([v, v2]), jnp.concatenate([w, w2])
    threshold = config.d_safe
    if config.escape:
        threshold = jnp.minimum(threshold, _current_clearance(combined, state, robot.footprint) - ESCAPE_SLACK)
    feasible = ro.clearance >= threshold
    passive = None
    if config.safety == "passive":
        discs = obstacles if moving else None

        def admissible(v_, w_):
            return passive_slack(table, config.clearance, robot, state, v_, w_, config.period, discs,
                                 walker_speed_bound(config.walker_speed_max, discs),
                                 braking_periods(robot, config.period, config.brake_periods)) >= 0.0

        passive = admissible(v, w)
        feasible = feasible & passive
    elif config.safety == "predicted":
        # The turn-then-straight samples end driving straight: they brake along a straight line.
        w_end = w if not config.straighten else jnp.concatenate([w[:config.n_v * config.n_omega],
                                                                 jnp.zeros_like(w[config.n_v * config.n_omega:])])
        closing = jnp.max(jnp.sqrt(jnp.sum(obstacles.velocities ** 2, axis=-1)), initial=0.0) if moving else 0.0
        stopping = braking_clearance(combined, robot, ro.end[:, 0], ro.end[:, 1],
                                     lax.complex(ro.end_dir[:, 0], ro.end_dir[:, 1]), v, w_end, steps * dt,
                                     config.brake_points, closing)
        feasible = feasible & (stopping >= footprint_radius(robot.footprint))
    reach = jnp.maximum(jnp.abs(robot.v_min), robot.v_max) * (steps * dt)
    cr = C.critics(ro.end, ro.clearance, v, state, subgoal, robot, config.d_clip, config.path_clip, reach, path,
                   ro.end_dir)
    scores = evaluate(cr, v, feasible, config, params, path is not None)

    masked = jnp.where(feasible, scores, -jnp.inf)
    chosen = jnp.argmax(masked).astype(jnp.int32)
    any_feasible = feasible[chosen]  # the argmax of the masked scores is feasible if any sample is
    u_samples = jnp.stack([v, w], axis=-1)  # [S, 2]
    kappa = curvature_limit(robot)
    if config.selection == "softmax":
        logits = jnp.where(feasible, scores / params.temperature, -jnp.inf)
        weights = jax.nn.softmax(jnp.where(any_feasible, logits, 0.0))
        u = weights @ u_samples
        if kappa is not None:
            # With reversing (v_min < 0), |ω| <= κ|v| is a bow-tie, not a convex set: a blend of
            # forward and backward samples can turn tighter than the car can (without, a no-op).
            u = jnp.stack([u[0], jnp.clip(jnp.clip(u[1], -kappa * jnp.abs(u[0]), kappa * jnp.abs(u[0])),
                                          window.w_lo, window.w_hi)])
    elif config.selection == "argmax":
        u = u_samples[chosen]
    else:
        raise ValueError(f"unknown selection {config.selection!r}")

    stuck = any_feasible & False  # derived from the inputs, not a constant: shard_map needs it varying
    if config.evaluator == "classic":
        stuck = (jnp.abs(u[0]) < STUCK_SPEED) & (jnp.abs(state[3]) < STUCK_SPEED) & any_feasible
        w_escape = window.w_lo
        if kappa is not None:  # a car cannot turn on the spot: the escape turn obeys its curvature limit
            w_escape = jnp.clip(jnp.clip(w_escape, -kappa * jnp.abs(u[0]), kappa * jnp.abs(u[0])), window.w_lo,
                                window.w_hi)
        u = jnp.where(stuck, jnp.stack([u[0], w_escape]), u)

    if config.recovery == "flee":
        u_rec = u_samples[_flee(ro, config.d_safe, passive)]
    elif config.recovery == "rotate":
        u_rec = _recovery(config, state, subgoal, window)
    else:
        raise ValueError(f"unknown recovery {config.recovery!r}")
    if passive is not None:
        # Nothing passively safe: brake (the remainder of the last safe manoeuvre; see `jaxplan.dwa._passive`).
        stop = brake(robot, state, config.period)
        safe_rec = jnp.where(jnp.any(passive), u_samples[_flee(ro, config.d_safe, passive)], stop)
        if config.recovery == "flee":
            u_rec = safe_rec
    u = jnp.where(any_feasible, u, u_rec)
    if passive is not None and (config.selection == "softmax" or config.evaluator == "classic"
                                or config.recovery == "rotate"):
        # A blend, a stuck-escape turn or a turn in place is none of the checked samples: check it too.
        ok = admissible(u[None, 0], u[None, 1])[0]
        u = jnp.where(ok, u, jnp.where(any_feasible, u_samples[chosen], safe_rec))
    info = DWAInfo(
        scores=scores, rollouts=ro.poses, feasible=feasible, chosen=jnp.where(any_feasible, chosen, -1),
        samples=u_samples, clearance=ro.clearance, window=jnp.stack(list(window)),
        recovery=~any_feasible, stuck=stuck,
    )
    return u, info


def dwa_control_batch(table: ClearanceTable, config: DWAConfig, params: DWAParams, states: jnp.ndarray,
                      subgoals: jnp.ndarray, obstacles: DiscObstacles | None = None, path: jnp.ndarray | None = None,
                      chunk: int | None = 128, finish: jnp.ndarray | None = None) -> tuple[jnp.ndarray, DWAInfo]:
    """`dwa_control` for ``B`` robots: ``states [B, 5]``, ``subgoals [B, 2]``, ``finish [B, 3]`` or None.

    ``obstacles`` may be shared (``[M, 2]``/``[M]`` fields) or per robot (``[B, M, 2]``/``[B, M]``);
    ``path`` shared ``[L, 2]`` or per robot ``[B, L, 2]``. Robots are processed ``chunk``
    (static) at a time, each chunk vectorised (`lax.map` with ``batch_size``): the
    working set of a rollout step then stays in cache (on a CPU, chunks of 128 robots beat
    one vmap over a large batch, and smaller chunks were slower: every kernel launch is
    amortised over fewer points). ``chunk=None``, or a chunk of at least B, vmaps the whole
    batch (what a GPU wants). Returns controls ``[B, 2]`` and a `DWAInfo` with a leading
    ``B`` axis.

    The per-sample fields of `DWAInfo` (scores, feasible, samples, clearance) are
    about 14 MB per step for 1,024 robots. A jitted caller that returns only what it
    reads (say the controls and ``info.recovery``, as a navigation episode does) lets
    XLA skip writing them, which saves time per step and compilation.
    """
    ob_batched = obstacles is not None and obstacles.radii.ndim == 2
    path_batched = path is not None and path.ndim == 3
    xs = (states, subgoals, obstacles if ob_batched else None, path if path_batched else None, finish)

    def one(x):
        st, sg, ob, pa, fi = x
        return dwa_control(table, config, params, st, sg, ob if ob_batched else obstacles,
                           pa if path_batched else path, fi)

    if chunk is None or chunk >= states.shape[0]:
        return jax.vmap(one)(xs)
    return lax.map(one, xs, batch_size=chunk)
