"""The episode program's state and its inputs and outputs (pytrees, leading axes ``[B episodes, N robots]``),
shared by its stages (`jaxplan.nav._episode`) and the in-episode re-planner (`jaxplan.nav._replan`)."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax.numpy as jnp

from jaxplan.nav._moving import MovingObstacles

__all__ = ["RUNNING", "GOAL", "COLLISION", "TIMEOUT", "REASONS", "ACTIVE_SPEED", "EpisodeInputs", "EpisodeOutput",
           "Carry"]

RUNNING, GOAL, COLLISION, TIMEOUT = 0, 1, 2, 3
REASONS = ("running", "goal", "collision", "time limit")
"""Why a robot stopped, indexed by the codes above."""

ACTIVE_SPEED = 0.05
"""m/s: a contact is active when the robot moves faster than this as it begins (docs/guide/navigation.md), else
passive —
the robot was at rest and was hit (passive motion safety asks only that no contact be active)."""


class EpisodeInputs(NamedTuple):
    """One call's episodes (a pytree; leading axes ``[B, N]`` = episodes, robots).

    Attributes:
      start: ``f32[B, N, 5]`` initial states (x, y, theta, v, omega).
      goal: ``f32[B, N, 2]`` goal positions (m).
      goal_cell: ``i32[B, N, 2]`` goal cells (for re-planning).
      waypoints: ``f32[B, N, K, 2]`` waypoint polylines (m), ending at the goal; slots after
        ``n_waypoints`` repeat the last.
      n_waypoints: ``i32[B, N]`` (>= 1).
      time_limit: ``f32[B, N]`` seconds (<= `NavConfig.max_time`).
      obstacles: `MovingObstacles` with leaves ``[B, M, …]`` (``M`` may be 0).
      active: ``bool[B, N]`` robots that run; the others stand still at their start from step 0
        (an infeasible scenario), still present as discs for the rest.
      key: ``u32[B, 2]`` each episode's PRNG key data (`jax.random.key_data`): the MPPI step's noise
        (its robot and step folded in); unused by the other local planners.
    """

    start: jnp.ndarray
    goal: jnp.ndarray
    goal_cell: jnp.ndarray
    waypoints: jnp.ndarray
    n_waypoints: jnp.ndarray
    time_limit: jnp.ndarray
    obstacles: MovingObstacles
    active: jnp.ndarray
    key: jnp.ndarray


class EpisodeOutput(NamedTuple):
    """What `run_episodes` returns (numpy after transfer). ``S`` = `NavConfig.steps`.

    Attributes:
      states: ``f32[B, S + 1, N, 5]`` state after each step (row 0 = start); rows after a
        robot is done repeat its final state.
      controls: ``f32[B, S, N, 2]`` the (v, omega) applied at each step (zero once done).
      recovery: ``bool[B, S, N]`` the DWA found no feasible sample (recovery manoeuvre).
      steps: ``i32[B, N]`` control steps the robot took (its episode time = steps · period).
      reason: ``i32[B, N]`` `REASONS` code.
      collisions: ``i32[B, N]`` contacts (runs of colliding steps) with map, discs or robots.
      active_contacts: ``i32[B, N]`` those that began while the robot moved faster than `ACTIVE_SPEED`
        (its command during the period in which the contact began); the rest are passive (at rest).
      pair_collisions: ``i32[B, N, N]`` contacts between robots i and j (symmetric).
      replans: ``i32[B, N]`` successful re-plans.
      rmse: ``f32[B, N]`` RMS distance (m) of the positions after each step to the polyline
        the robot was tracking at that step (from where it adopted it — the start or the
        position of a re-plan — through its waypoints); NaN for a robot that did not move.
      waypoints: ``f32[B, N, K, 2]`` and ``n_waypoints [B, N]``: the final waypoint lists.
      executed: ``i32[B]`` control steps the loop ran (a multiple of the chunk; the loop stops
        once every robot of the batch — on a mesh, of the device's share — is done).
      walkers: ``f32[B, S + 1, M, 2]`` where the moving obstacles were after each step when some walkers see
        (their own simulation; the blind ones on their routes as well), or None when every disc is blind
        (their positions follow from the routes).
      give_ways: ``i32[B, N]`` times the robot gave way (`jaxplan.nav._give_way`), or None when the episode's
        robots do not give way (`NavConfig.gives_way`).
    """

    states: jnp.ndarray
    controls: jnp.ndarray
    recovery: jnp.ndarray
    steps: jnp.ndarray
    reason: jnp.ndarray
    collisions: jnp.ndarray
    active_contacts: jnp.ndarray
    pair_collisions: jnp.ndarray
    replans: jnp.ndarray
    rmse: jnp.ndarray
    waypoints: jnp.ndarray
    n_waypoints: jnp.ndarray
    executed: jnp.ndarray
    walkers: jnp.ndarray | None = None
    give_ways: jnp.ndarray | None = None


class Carry(NamedTuple):
    """What a step of the episode loop carries to the next (``[B, N]`` per robot unless noted)."""

    state: jnp.ndarray  # [B, N, 5]
    waypoints: jnp.ndarray  # [B, N, K, 2]
    n_wp: jnp.ndarray  # [B, N]
    index: jnp.ndarray  # [B, N] current waypoint
    done: jnp.ndarray  # [B, N]
    reason: jnp.ndarray  # [B, N]
    steps: jnp.ndarray  # [B, N]
    hit: jnp.ndarray  # [B, N] in contact after the last step
    pair_hit: jnp.ndarray  # [B, N, N]
    collisions: jnp.ndarray  # [B, N]
    active_contacts: jnp.ndarray  # [B, N] contacts begun while moving faster than ACTIVE_SPEED
    pair_collisions: jnp.ndarray  # [B, N, N]
    replans: jnp.ndarray  # [B, N]
    last_replan: jnp.ndarray  # [B, N] step of the last re-plan attempt
    origin: jnp.ndarray  # [B, N, 2] where the tracked polyline begins (start, or the position at a re-plan)
    sq_error: jnp.ndarray  # [B, N] sum of squared distances to the tracked polyline
    error: jnp.ndarray  # [B, N] distance to the tracked polyline after the last step
    watch: jnp.ndarray  # [B, N, 2] the waypoint whose approach is being watched (m)
    closest: jnp.ndarray  # [B, N] closest approach to that waypoint so far (m)
    progress_t: jnp.ndarray  # [B, N] step of the last approach by NavConfig.stall_progress
    creep: jnp.ndarray  # [B, N] stalled: top speed stall_speed until the waypoint is passed (or creep_distance)
    creep_goal: jnp.ndarray  # [B, N] distance to the goal where the robot last began to creep (m)
    spin: jnp.ndarray  # [B, N] net heading change (rad) since the last approach to the goal, a crowd or an orbit
    goal_best: jnp.ndarray  # [B, N] that approach: closest distance to the goal so far (m)
    stall_replan: jnp.ndarray  # [B, N] started creeping, its re-plan not attempted yet (no free slot)
    detour: jnp.ndarray  # [B, N] tracking a path planned around discs: re-checked every NavConfig.recheck_period
    plan: jnp.ndarray  # [B, N, T, 2] the MPPI step's warm start (T = 0 for the other local planners)
    walkers: Any  # WalkerState [B, M] of the walkers that see, or None when every disc is blind
    give_way: Any  # GiveWay [B, N] (jaxplan.nav._give_way), or None when the robots do not give way
    t: jnp.ndarray  # scalar step counter
