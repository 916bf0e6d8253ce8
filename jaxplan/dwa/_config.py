"""Configuration (what shapes and switches the compiled step) and parameters (what tuning changes).

`DWAConfig` is a frozen dataclass registered as a pytree: its counts and switches
(``n_v``, ``n_omega``, ``horizon``, ``dt``, ``evaluator``, ``clearance``, ``selection``,
``keep_rollouts``, ``unroll``, and the robot's class and footprint kind) are static —
one compilation per combination — while its distances and the robot's limits are
traced leaves: changing a limit does not recompile, and robots with different limits
can be ``vmap``-ped. `DWAParams` holds the critic
weights and the softmax temperature as arrays: the quantities tuning ``vmap``-s over
and differentiates (docs/guide/experiments.md), never a reason to recompile.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.dwa._robot import Robot, Unicycle

__all__ = ["DWAConfig", "DWAParams", "EVALUATORS", "CLEARANCE_MODES", "SELECTIONS", "RECOVERIES", "default_params"]

EVALUATORS = ("weighted", "fuzzy", "classic")
"""Rollout evaluators: cui2025's Eq. (7) weighted sum, cui2025's fuzzy evaluation, PythonRobotics' costs."""

CLEARANCE_MODES = ("hybrid", "bilinear", "exact")
"""Static-obstacle clearance lookups (see `jaxplan.dwa._clearance`)."""

RECOVERIES = ("rotate", "flee")
"""What a step does when no sample is feasible."""

SELECTIONS = ("argmax", "softmax")
"""How the control is chosen from the scored samples."""


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DWAConfig:
    """Everything about a DWA step except the critic weights.

    Attributes:
      robot: `Unicycle` (default, cui2025) or `Ackermann` (li2026).
      period: control period Δt of the dynamic window (s; cui2025 replans every 0.2 s).
      d_safe: a rollout whose clearance (m, from a footprint disc centre to the nearest
        blocked square or moving disc edge) drops below this anywhere on the horizon is
        infeasible (cui2025 Eq. (8), 0.3 m). At least the footprint radius.
      d_clip: clearance at which the clearance critic saturates (m): O = min(c, d_clip)/d_clip;
        also the "far" breakpoint of the fuzzy clearance input.
      path_clip: distance (m) from the global path at which the path critic reaches 0.
      n_v, n_omega: samples per axis of the window grid (static; S = n_v·n_omega).
      horizon, dt: rollout length and step (s; static, T = horizon/dt points per rollout).
      evaluator: ``"weighted"``, ``"fuzzy"`` or ``"classic"`` (static).
      clearance: ``"hybrid"`` (default), ``"bilinear"`` or ``"exact"`` (static).
      selection: ``"argmax"`` or ``"softmax"`` (temperature-relaxed, differentiable; static).
      keep_rollouts: return every sample's trajectory ``[S, T, 3]`` in `DWAInfo` (static;
        episodes switch it off to avoid carrying ``S·T`` poses per step).
      unroll: rollout steps per iteration of the rollout loop (static): fewer iterations
        launch fewer kernels (a single robot's step is mostly launch overhead on a CPU)
        at the price of a longer compilation.
      escape: when the robot is already closer than d_safe to an obstacle (a moving disc
        came close, or it started there), a rollout is also feasible if it never gets
        closer than the current clearance (less `ESCAPE_SLACK`), so the robot can move
        away instead of rotating in place for ever (static; the navigation guide's recovery still
        applies when even that is impossible).
      recovery: what to do when no sample is feasible (static): ``"rotate"`` — the navigation guide's
        stop and rotate in place towards the sub-goal — or ``"flee"``: take the sample whose
        rollout keeps the largest minimum clearance (against a moving disc heading for the
        robot, standing still is often the worst choice; navigation episodes use this).
      straighten: fractions f of the horizon (static; default none). For each, an extra
        ``n_v × n_omega_straight`` grid of samples over the same window whose rollouts turn
        at ω for the first round(f·T) points and then drive straight on at v: a lane change
        or a side-step round a disc in a corridor, where every constant-curvature arc long
        enough to pass reaches a wall within the horizon. The control of such a sample is its
        (v, ω) for the next period, as for the others: the straight part is only a promise
        the next steps may keep. Each fraction must leave at least one point on either part.
      n_omega_straight: yaw-rate samples per speed in each ``straighten`` grid (static).
      admissible: passive motion safety (static): a sample is feasible only if, from its rollout's end, the
        robot can still brake to rest along its path before any predicted contact (`braking_clearance`).
      brake_points: points of that braking check (static).
    """

    robot: Robot = Unicycle()
    period: float = 0.2
    d_safe: float = 0.3
    d_clip: float = 1.0
    path_clip: float = 1.0
    n_v: int = dataclasses.field(default=20, metadata=dict(static=True))
    n_omega: int = dataclasses.field(default=40, metadata=dict(static=True))
    horizon: float = dataclasses.field(default=2.0, metadata=dict(static=True))
    dt: float = dataclasses.field(default=0.1, metadata=dict(static=True))
    evaluator: str = dataclasses.field(default="weighted", metadata=dict(static=True))
    clearance: str = dataclasses.field(default="hybrid", metadata=dict(static=True))
    selection: str = dataclasses.field(default="argmax", metadata=dict(static=True))
    keep_rollouts: bool = dataclasses.field(default=True, metadata=dict(static=True))
    unroll: int = dataclasses.field(default=4, metadata=dict(static=True))
    escape: bool = dataclasses.field(default=True, metadata=dict(static=True))
    recovery: str = dataclasses.field(default="rotate", metadata=dict(static=True))
    straighten: tuple[float, ...] = dataclasses.field(default=(), metadata=dict(static=True))
    n_omega_straight: int = dataclasses.field(default=20, metadata=dict(static=True))
    admissible: bool = dataclasses.field(default=False, metadata=dict(static=True))
    brake_points: int = dataclasses.field(default=8, metadata=dict(static=True))

    @property
    def steps(self) -> int:
        """Trajectory points per rollout, T = round(horizon / dt)."""
        return int(round(self.horizon / self.dt))

    @property
    def samples(self) -> int:
        """Samples per step, S = n_v · n_omega (+ n_v · n_omega_straight per ``straighten`` fraction)."""
        return self.n_v * (self.n_omega + len(self.straighten) * self.n_omega_straight)

    def turn_steps(self) -> tuple[int, ...]:
        """Points each ``straighten`` grid turns for, round(f·T)."""
        return tuple(int(round(f * self.steps)) for f in self.straighten)

    def replace(self, **changes) -> "DWAConfig":
        return dataclasses.replace(self, **changes)


class DWAParams(NamedTuple):
    """Critic weights and the selection temperature: scalars (or arrays with batch axes). A pytree.

    Attributes:
      heading: α, weight of the heading critic G (cui2025 Eq. (7): 0.4).
      velocity: β, weight of the velocity critic V (0.3).
      clearance: γ, weight of the clearance critic O (0.3).
      path: weight of the global-path critic (0: off unless a path is given).
      goal: weight of the goal-distance critic (0: off).
      temperature: softmax temperature of ``selection="softmax"`` (score units).

    The ``"classic"`` evaluator reads heading/velocity/clearance as PythonRobotics'
    ``to_goal_cost_gain``, ``speed_cost_gain`` and ``obstacle_cost_gain`` (0.15, 1, 1).
    """

    heading: jnp.ndarray
    velocity: jnp.ndarray
    clearance: jnp.ndarray
    path: jnp.ndarray
    goal: jnp.ndarray
    temperature: jnp.ndarray


_DEFAULTS = {
    "weighted": dict(heading=0.4, velocity=0.3, clearance=0.3, path=0.0, goal=0.0, temperature=0.05),
    "fuzzy": dict(heading=0.4, velocity=0.3, clearance=0.3, path=0.0, goal=0.0, temperature=0.02),
    "classic": dict(heading=0.15, velocity=1.0, clearance=1.0, path=0.0, goal=0.0, temperature=0.05),
}


def default_params(evaluator: str = "weighted", **overrides: float) -> DWAParams:
    """The default `DWAParams` of an evaluator (numpy float32 scalars), with optional overrides.

    >>> float(default_params("weighted", path=0.2).path)
    0.2
    """
    if evaluator not in _DEFAULTS:
        raise ValueError(f"unknown evaluator {evaluator!r}; choose from {EVALUATORS}")
    d = dict(_DEFAULTS[evaluator])
    unknown = set(overrides) - set(d)
    if unknown:
        raise ValueError(f"unknown DWA parameter(s) {sorted(unknown)}; the parameters are {sorted(d)}")
    d.update(overrides)
    # numpy scalars, not jax arrays: building eight device arrays costs more than a step.
    return DWAParams(**{k: np.float32(v) for k, v in d.items()})
