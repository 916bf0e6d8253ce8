"""One MPPI control step as a pure, jittable function of arrays (Williams et al.'s information-theoretic MPC).

`mppi_control` is what a navigation episode calls inside its `lax.scan` over control steps:

1. K raw sequences = the warm-started mean sequence ``[T, 2]`` + Gaussian noise (σ_v, σ_ω per
   control; `jaxplan.mppi._noise`). Fixed candidates: row 0 is the mean itself, row 1 brakes to rest and
   straightens (so a stop is always on the table — the passive-safety fallback), and for a robot that can turn
   in place row 2 stands and turns towards the sub-goal over the first half of the horizon (`TURN_ROW`);
2. every sequence is clamped to the robot's dynamic window period by period and rolled out
   (`jaxplan.mppi._rollout`), its critics summed (`jaxplan.mppi._critics`);
3. cost = Σ weight·critic + ``collision`` if its clearance drops below d_safe (+ the control cost
   γ·Σ u·ε/σ² when γ > 0); with ``safety="predicted"``, a sequence whose end state cannot brake to rest
   before a predicted contact is excluded, and with ``safety="passive"`` one whose first control is not passively
   safe (`jaxplan.dwa.passive_slack`: the robot can still brake out of every walker's reach);
4. the new mean is the softmax average of the clamped sequences with weights
   ``exp(−(cost − min cost)/λ)``; its first control is applied. With no feasible sequence the
   robot takes the one that keeps the most clearance (among those that keep d_safe from the map,
   if any: the DWA's "flee"), and with none admissible the braking candidate. With ``safety="passive"`` the
   applied control itself is checked too: a blend that is not safe gives way to the best-weighted safe sequence;
5. the caller shifts the new mean by one period (`shift`) to warm-start the next step.

Everything is differentiable through the softmax in the critic weights and λ (the noise is drawn
from an explicit key), like the softmax-relaxed DWA.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxplan.dwa import (
    ClearanceTable,
    DiscObstacles,
    braking_periods,
    curvature_limit,
    disc_clearance,
    passive_slack,
    speed_cap,
    static_clearance,
    walker_speed_bound,
)
from jaxplan.mppi import _critics as C
from jaxplan.mppi._config import MPPIConfig, MPPIParams
from jaxplan.mppi._noise import gaussian
from jaxplan.mppi._rollout import Sequences, rollout

__all__ = ["MPPIInfo", "mppi_control", "shift", "initial_sequence", "ESCAPE_SLACK", "MEAN_ROW", "BRAKE_ROW",
           "TURN_ROW", "fixed_rows"]

ESCAPE_SLACK = 1e-4
"""Metres an escaping sequence may lose against the current clearance (as the DWA's)."""

MEAN_ROW, BRAKE_ROW, TURN_ROW = 0, 1, 2
"""The fixed candidate rows: the mean sequence itself, braking to rest, and turning in place towards the sub-goal.

Why the turn: a unicycle that has come to rest facing a wall a few centimetres outside d_safe has no feasible
sequence that moves (every one that drives first brings it inside d_safe), and the noisy sequences that stand
turn by chance in either direction, so their softmax average barely turns: measured among walkers on
maze-32-32-2, robots stood like that for 80-120 s until the time limit. The candidate stands and turns by the
angle to the sub-goal (at most ``omega_max``), which keeps the clearance of a disc footprint and wins on the
heading critic; facing the sub-goal, sequences that drive become feasible. A robot that cannot turn in place
(`jaxplan.dwa.curvature_limit`, an Ackermann) has no such row.
"""


def fixed_rows(config: MPPIConfig) -> int:
    """How many of the K rows are fixed candidates (the rest are noisy): 3, or 2 for a robot that cannot turn in
    place."""
    return 2 if curvature_limit(config.robot) is not None else 3


class MPPIInfo(NamedTuple):
    """What a step saw and decided (a pytree; a batch adds leading axes).

    Attributes:
      sequence: ``f32[T, 2]`` the new mean sequence (its row 0 is the control); `shift` it for the next step.
      costs: ``f32[K]`` every sequence's cost (lower is better; +inf when excluded as not admissible).
      weights: ``f32[K]`` softmax weights (sum to 1).
      feasible: ``bool[K]`` clearance >= d_safe over the horizon.
      admissible: ``bool[K]`` the braking run from the end is contact-free (all True when not asked).
      clearance: ``f32[K]`` minimum clearance (m) of each sequence.
      controls: ``f32[K, T, 2]`` the clamped sequences.
      chosen: ``i32`` the sequence with the largest weight.
      recovery: ``bool`` no sequence was feasible (the flee fallback was applied).
      points: ``f32[K, T·substeps, 3]`` rollout points, or None.
    """

    sequence: jnp.ndarray
    costs: jnp.ndarray
    weights: jnp.ndarray
    feasible: jnp.ndarray
    admissible: jnp.ndarray
    clearance: jnp.ndarray
    controls: jnp.ndarray
    chosen: jnp.ndarray
    recovery: jnp.ndarray
    points: jnp.ndarray | None


def initial_sequence(config: MPPIConfig, state: jnp.ndarray) -> jnp.ndarray:
    """``f32[T, 2]``: hold the current velocity (the mean of a robot's first step)."""
    return jnp.broadcast_to(state[3:5], (config.steps, 2)).astype(jnp.float32)


def shift(sequence: jnp.ndarray) -> jnp.ndarray:
    """The warm start of the next step: drop the applied control, repeat the last (``[..., T, 2]``)."""
    return jnp.concatenate([sequence[..., 1:, :], sequence[..., -1:, :]], axis=-2)


def _turn(config: MPPIConfig, state: jnp.ndarray, subgoal: jnp.ndarray) -> jnp.ndarray:
    """``f32[T, 2]``: stand, and turn by the angle to ``subgoal`` over the first half of the horizon (then hold)."""
    T = config.steps
    d = subgoal - state[:2]
    err = jnp.arctan2(d[1], d[0]) - state[2]
    err = jnp.arctan2(jnp.sin(err), jnp.cos(err))
    half = max(T // 2, 1)
    w = jnp.clip(err / (half * config.period), -config.robot.omega_max, config.robot.omega_max)
    omega = jnp.where(jnp.arange(T) < half, w, 0.0)
    return jnp.stack([jnp.zeros_like(omega), omega], axis=-1).astype(state.dtype)


def _raw(config: MPPIConfig, params: MPPIParams, mean: jnp.ndarray, key, state: jnp.ndarray,
         subgoal: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(raw [K, T, 2], noise [K, T, 2])``: the mean plus scaled noise, the first `fixed_rows` the fixed
    candidates (their noise as the control cost sees it: the candidate minus the mean)."""
    K, T = config.samples, config.steps
    sigma = jnp.stack([params.noise_v, params.noise_omega]).astype(mean.dtype)
    noise = gaussian(key, (K, T, 2)) * sigma
    noise = noise.at[MEAN_ROW].set(0.0)
    raw = mean[None] + noise
    raw = raw.at[BRAKE_ROW].set(0.0)  # v -> 0 and ω -> 0 as fast as the window allows
    if fixed_rows(config) > TURN_ROW:
        raw = raw.at[TURN_ROW].set(_turn(config, state, subgoal))
        noise = noise.at[TURN_ROW].set(raw[TURN_ROW] - mean)
    return raw, noise


def _current_clearance(clearance, state: jnp.ndarray, margin) -> jnp.ndarray:
    """Clearance (m) of the robot's reference point now, the discs inflated by ``margin`` (the escape threshold)."""
    c_map, c_disc = clearance(state[0:1], state[1:2], jnp.asarray(0.0, state.dtype))
    return jnp.minimum(c_map, c_disc - margin)[0]


def _iteration(table, config: MPPIConfig, params: MPPIParams, state, mean, key, ctx, obstacles, finish):
    raw, noise = _raw(config, params, mean, key, state, ctx.subgoal)
    moving = obstacles is not None and obstacles.radii.shape[-1] > 0
    dt = config.period / config.substeps

    def clearance(x, y, t):
        c_map = static_clearance(table, x, y, config.clearance)
        return c_map, disc_clearance(obstacles, x, y, t, dt) if moving else jnp.full_like(c_map, jnp.inf)

    def inflate(t):
        return params.disc_margin + params.disc_growth * t

    closing = jnp.max(jnp.sqrt(jnp.sum(obstacles.velocities ** 2, axis=-1)), initial=0.0) if moving else 0.0
    seq: Sequences = rollout(config, state, raw, clearance, ctx, finish, inflate if moving else None, closing)
    threshold = config.d_safe
    if config.escape:
        threshold = jnp.minimum(threshold, _current_clearance(clearance, state, inflate(0.0)) - ESCAPE_SLACK)
    feasible = seq.clearance >= threshold
    admissible = seq.admissible
    if config.safety == "passive":
        discs = obstacles if moving else None

        def passive(u):  # u [n, 2]: the first controls to check
            return passive_slack(table, config.clearance, config.robot, state, u[:, 0], u[:, 1], config.period,
                                 discs, walker_speed_bound(config.walker_speed_max, discs),
                                 braking_periods(config.robot, config.period, config.brake_periods)) >= 0.0

        admissible = passive(seq.controls[:, 0])
    costs = C.cost(seq.terms, params) + params.collision * (~feasible)
    sigma2 = jnp.stack([params.noise_v, params.noise_omega]) ** 2
    costs = costs + params.gamma * jnp.sum(mean[None] * noise / sigma2, axis=(1, 2))
    costs = jnp.where(admissible, costs, jnp.inf)
    any_admissible = jnp.any(admissible)
    finite = jnp.where(jnp.isfinite(costs), costs, jnp.max(jnp.where(jnp.isfinite(costs), costs, -jnp.inf)))
    logits = -(finite - jnp.min(finite)) / params.temperature
    weights = jax.nn.softmax(jnp.where(admissible | ~any_admissible, logits, -jnp.inf))
    blended = jnp.einsum("k,ktc->tc", weights, seq.controls)

    any_feasible = jnp.any(feasible & admissible)
    safe = seq.static >= config.d_safe
    flee = jnp.argmax(jnp.where((safe | ~jnp.any(safe)) & admissible, seq.clearance, -jnp.inf))
    new = jnp.where(any_feasible, blended, seq.controls[flee])
    new = jnp.where(any_admissible, new, seq.controls[BRAKE_ROW])
    kappa = curvature_limit(config.robot)
    if kappa is not None:  # |ω| <= κ|v| is a bow-tie with reversing, not convex: clip the blend
        new = new.at[:, 1].set(jnp.clip(new[:, 1], -kappa * jnp.abs(new[:, 0]), kappa * jnp.abs(new[:, 0])))
    chosen = jnp.argmax(weights).astype(jnp.int32)
    if config.safety == "passive":
        # The admissible set is not convex: a blend of safe first controls need not be safe. Then the
        # best-weighted safe sequence, or braking (the braking row) when none is safe.
        ok = passive(new[None, 0])[0]
        new = jnp.where(ok, new, jnp.where(any_admissible, seq.controls[chosen], seq.controls[BRAKE_ROW]))
    info = MPPIInfo(new, costs, weights, feasible, admissible, seq.clearance, seq.controls, chosen,
                    ~any_feasible, seq.points)
    return new, info


def mppi_control(table: ClearanceTable, config: MPPIConfig, params: MPPIParams, state: jnp.ndarray,
                 mean: jnp.ndarray, key: jax.Array, subgoal: jnp.ndarray, goal: jnp.ndarray | None = None,
                 obstacles: DiscObstacles | None = None, path: jnp.ndarray | None = None,
                 n_path: jnp.ndarray | None = None, finish: jnp.ndarray | None = None) -> tuple[jnp.ndarray, MPPIInfo]:
    """One MPPI step for one robot (pure; jit it, vmap it, scan it, differentiate it).

    Args:
      table: the map's `jaxplan.dwa.ClearanceTable`.
      config: `MPPIConfig`.
      params: `MPPIParams`.
      state: ``f32[5]`` (x, y, θ, v, ω) in m, rad, m/s, rad/s.
      mean: ``f32[T, 2]`` the warm-started mean sequence (`shift` of the last step's, or
        `initial_sequence`).
      key: PRNG key of this step's noise.
      subgoal: ``f32[2]`` (m) the point to head for now.
      goal: ``f32[2]`` (m) the goal, or None (the sub-goal).
      obstacles: `jaxplan.dwa.DiscObstacles` (M discs) or None.
      path: ``f32[L, 2]`` (m) the local stretch of the global path, or None; ``n_path`` its valid points.
      finish: ``f32[3]`` (x, y, radius) the goal region where the run ends, or None.

    Returns:
      ``(control f32[2] = (v, ω), MPPIInfo)``; ``info.sequence`` is the new mean (its row 0 the control).

    With a speed limit layer in ``table`` (a map's Nav2 speed mask), the top speed of every sampled sequence
    is capped at the value of the robot's cell (`jaxplan.dwa.speed_cap`).
    """
    state = jnp.asarray(state, jnp.float32)
    if table.speed_limit is not None:
        config = config.replace(robot=dataclasses.replace(
            config.robot, v_max=speed_cap(table, state[:2], config.robot.v_max)))
    goal = subgoal if goal is None else goal
    if path is None:
        path, n_path = jnp.zeros((2, 2), jnp.float32), jnp.asarray(0, jnp.int32)
    elif n_path is None:
        n_path = jnp.asarray(path.shape[0], jnp.int32)
    robot = config.robot
    reach = jnp.maximum(jnp.abs(robot.v_min), robot.v_max) * config.horizon
    near = jnp.sum((state[:2] - goal) ** 2) <= config.goal_radius ** 2
    ctx = C.Context(jnp.asarray(subgoal, jnp.float32), jnp.asarray(goal, jnp.float32), path, n_path, state[:2],
                    reach, near)
    info = None
    for i in range(config.iterations):
        mean, info = _iteration(table, config, params, state, mean, jax.random.fold_in(key, i), ctx, obstacles,
                                finish)
    return mean[0], info
