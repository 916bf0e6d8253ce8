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
import warnings
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.dwa._robot import Robot, Unicycle

__all__ = ["DWAConfig", "DWAParams", "EVALUATORS", "CLEARANCE_MODES", "SELECTIONS", "RECOVERIES", "SAFETY_MODES",
           "default_params", "safety_from_admissible"]

EVALUATORS = ("weighted", "fuzzy", "classic")
"""Rollout evaluators: cui2025's Eq. (7) weighted sum, cui2025's fuzzy evaluation, PythonRobotics' costs."""

CLEARANCE_MODES = ("hybrid", "bilinear", "exact")
"""Static-obstacle clearance lookups (see `jaxplan.dwa._clearance`)."""

RECOVERIES = ("rotate", "flee")
"""What a step does when no sample is feasible."""

SELECTIONS = ("argmax", "softmax")
"""How the control is chosen from the scored samples."""

SAFETY_MODES = ("none", "predicted", "passive")
"""What a local planner checks before it commits to a control (docs/guide/navigation.md, "Safety"):

* ``"none"`` (default): nothing beyond its own clearance to the predicted obstacles;
* ``"predicted"``: a rollout counts only if the robot can brake to rest after its horizon before any *predicted*
  contact (`jaxplan.dwa.braking_clearance`; the option once called ``admissible=True``);
* ``"passive"``: a control counts only if, after its first control period, the robot can brake to rest before
  reaching any point a walker *can* reach at ``walker_speed_max`` from where it is now, and before the map
  (`jaxplan.dwa.passive_slack`): whatever the walkers do, the robot is at rest whenever one touches it.
"""


def safety_from_admissible(owner: object, admissible: bool | None) -> None:
    """The deprecated ``admissible`` field of a local planner's config mapped onto ``safety`` (in place, from
    ``__post_init__``): True becomes ``"predicted"`` with a `DeprecationWarning`; the field is then cleared, so
    that configs equal in meaning compare and hash equal."""
    if admissible is None:
        return
    warnings.warn(f"{type(owner).__name__}(admissible=...) is deprecated; use safety='predicted' (admissible=True) "
                  "or safety='none' (admissible=False)", DeprecationWarning, stacklevel=4)
    if admissible:
        object.__setattr__(owner, "safety", "predicted")
    object.__setattr__(owner, "admissible", None)


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
      safety: ``"none"`` (default), ``"predicted"`` or ``"passive"`` (static; `SAFETY_MODES`). ``"predicted"``: a
        sample is feasible only if, from its rollout's end, the robot can still brake to rest along its path before
        any predicted contact (`braking_clearance`). ``"passive"``: only if, after one control period at the
        sample's (v, ω), braking as hard as the robot can keeps it off the map and out of every walker's reach
        (`passive_slack`); when no sample passes, the robot brakes (`brake`).
      walker_speed_max: the walkers' speed bound (m/s) of ``safety="passive"``, or None: the scenario's in a
        navigation episode, else the larger of `DEFAULT_WALKER_SPEED` and the fastest disc's current speed.
      brake_points: points of the ``"predicted"`` braking check (static).
      brake_periods: control periods the ``"passive"`` braking run may take to stop (static), or None: enough
        for the robot's limits (`braking_periods`); a run not at rest by then does not pass.
      admissible: deprecated: ``True`` is ``safety="predicted"`` (a `DeprecationWarning`; read back as None).
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
    safety: str = dataclasses.field(default="none", metadata=dict(static=True))
    walker_speed_max: float | None = None
    brake_points: int = dataclasses.field(default=8, metadata=dict(static=True))
    brake_periods: int | None = dataclasses.field(default=None, metadata=dict(static=True))
    admissible: bool | None = dataclasses.field(default=None, metadata=dict(static=True))

    def __post_init__(self) -> None:
        safety_from_admissible(self, self.admissible)

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

    def replace(self, **changes: Any) -> "DWAConfig":
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
