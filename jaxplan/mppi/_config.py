"""Configuration (what shapes and switches the compiled step) and parameters (what tuning changes) of MPPI.

`MPPIConfig` is a frozen dataclass registered as a pytree, like `jaxplan.dwa.DWAConfig`: its counts
and switches (``samples``, ``steps``, ``substeps``, ``iterations``, ``clearance``, ``safety``,
``keep_rollouts``, the robot's class and footprint kind) are static — one compilation per combination
— while distances and the robot's limits are traced leaves. `MPPIParams` holds the critic weights,
the softmax temperature λ and the sampling noise as arrays: what tuning ``vmap``-s over and
differentiates, never a reason to recompile.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxplan.dwa import Robot, Unicycle, safety_from_admissible

__all__ = ["MPPIConfig", "MPPIParams", "default_params", "CRITICS"]

CRITICS = ("obstacle", "dynamic", "path_align", "path_follow", "goal", "goal_heading", "prefer_forward", "constraint")
"""The critics, in the order `MPPIParams` holds their weights (see `jaxplan.mppi._critics`)."""


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class MPPIConfig:
    """Everything about an MPPI step except the critic weights, temperature and noise.

    Attributes:
      robot: `jaxplan.dwa.Unicycle` (default) or `Ackermann`; its limits bound every sampled control.
      period: control period (s). A control sequence holds one (v, ω) per period, as the episode
        applies it: the velocity steps to the command at the start of the period and is held.
      d_safe: a rollout whose clearance (m, footprint disc centre to the nearest blocked square or
        predicted disc edge) drops below this is infeasible (as the DWA's ``d_safe``).
      d_clip: clearance (m) to the map at which the obstacle critic stops charging.
      disc_clip: clearance (m) to the moving discs' inflated edges at which the dynamic critic stops charging.
      path_clip: distance (m) from the global path at which the path-align critic saturates.
      goal_radius: the goal critic charges only while the robot is within this distance (m) of the
        goal (Nav2's ``threshold_to_consider``), so far from the goal the path critics lead.
      samples: K, noisy control sequences per iteration (static), including the candidates below.
      steps: T, controls per sequence (static): the horizon is ``steps · period`` seconds.
      substeps: clearance and critics are evaluated this many times per control (static): at 1.2 m/s
        and 0.2 s a single point per control would step 0.24 m past a corner.
      iterations: MPPI iterations per control step (static; Nav2 recommends 1 with more samples).
      clearance: static-map lookup of `jaxplan.dwa.static_clearance` (static).
      safety: ``"none"`` (default), ``"predicted"`` or ``"passive"`` (static; `jaxplan.dwa.SAFETY_MODES`).
        ``"predicted"``: a sequence counts only if, after its horizon, the robot can still brake to rest along its
        path before any predicted contact (see `jaxplan.mppi._rollout`). ``"passive"``: only if, after its first
        control's period, braking as hard as the robot can keeps it off the map and out of every walker's reach
        (`jaxplan.dwa.passive_slack`); the applied control (the softmax blend's first) is checked too, and gives
        way to the best-weighted safe sequence, or to braking when no sequence is safe. Sequences that do not
        count are never chosen.
      walker_speed_max: the walkers' speed bound (m/s) of ``safety="passive"``, or None: the scenario's in a
        navigation episode, else as `jaxplan.dwa.walker_speed_bound`.
      brake_points: points of the ``"predicted"`` braking check after the horizon (static).
      brake_periods: control periods the ``"passive"`` braking run may take to stop (static), or None: enough
        for the robot's limits (`jaxplan.dwa.braking_periods`).
      admissible: deprecated: ``True`` is ``safety="predicted"`` (a `DeprecationWarning`; read back as None).
      escape: when the robot is already closer than d_safe (a disc came close), a sequence is also
        feasible if it never gets closer than the current clearance (static; as the DWA's).
      keep_rollouts: return every sample's points ``[K, T·substeps, 3]`` in `MPPIInfo` (static).
    """

    robot: Robot = Unicycle()
    period: float = 0.2
    d_safe: float = 0.3
    d_clip: float = 0.5
    disc_clip: float = 1.0
    path_clip: float = 1.0
    goal_radius: float = 2.0
    samples: int = dataclasses.field(default=256, metadata=dict(static=True))
    steps: int = dataclasses.field(default=10, metadata=dict(static=True))
    substeps: int = dataclasses.field(default=2, metadata=dict(static=True))
    iterations: int = dataclasses.field(default=1, metadata=dict(static=True))
    clearance: str = dataclasses.field(default="hybrid", metadata=dict(static=True))
    safety: str = dataclasses.field(default="none", metadata=dict(static=True))
    walker_speed_max: float | None = None
    brake_points: int = dataclasses.field(default=8, metadata=dict(static=True))
    brake_periods: int | None = dataclasses.field(default=None, metadata=dict(static=True))
    escape: bool = dataclasses.field(default=True, metadata=dict(static=True))
    keep_rollouts: bool = dataclasses.field(default=False, metadata=dict(static=True))
    admissible: bool | None = dataclasses.field(default=None, metadata=dict(static=True))

    def __post_init__(self) -> None:
        safety_from_admissible(self, self.admissible)

    @property
    def horizon(self) -> float:
        """Seconds covered by a sequence, ``steps · period``."""
        return self.steps * self.period

    @property
    def points(self) -> int:
        """Rollout points per sequence, ``steps · substeps``."""
        return self.steps * self.substeps

    def replace(self, **changes: Any) -> "MPPIConfig":
        return dataclasses.replace(self, **changes)


class MPPIParams(NamedTuple):
    """Temperature, noise and critic weights: scalars (or arrays with batch axes). A pytree.

    Attributes:
      temperature: λ of the softmax over sequence costs (cost units; Williams et al.'s
        information-theoretic MPC): small follows the cheapest sequences, large averages them all.
      noise_v, noise_omega: standard deviations (m/s, rad/s) of the Gaussian noise added to every
        control of the warm-started mean sequence.
      gamma: weight of the information-theoretic control cost γ·Σ u·ε/σ² (Williams et al. 2017,
        Nav2's ``gamma``); 0 switches it off.
      collision: cost of an infeasible sequence (clearance below d_safe): large, so that the
        softmax keeps to feasible sequences whenever there are any.
      disc_margin, disc_growth: the moving discs are kept ``disc_margin + disc_growth · t`` metres farther
        than their constant-velocity prediction at ``t`` s ahead (feasibility and the dynamic critic): a
        walker may turn, and the longer ahead, the farther it may be from where it was predicted. The default
        margin, 0.2 m, is the measured best of 0, 0.2 and 0.3 among walkers that see (docs/decisions.md).
      obstacle, dynamic, path_align, path_follow, goal, goal_heading, prefer_forward, constraint: critic
        weights (`CRITICS`; each critic is normalised to about [0, 1], see `jaxplan.mppi._critics`).
    """

    temperature: jnp.ndarray
    noise_v: jnp.ndarray
    noise_omega: jnp.ndarray
    gamma: jnp.ndarray
    collision: jnp.ndarray
    disc_margin: jnp.ndarray
    disc_growth: jnp.ndarray
    obstacle: jnp.ndarray
    dynamic: jnp.ndarray
    path_align: jnp.ndarray
    path_follow: jnp.ndarray
    goal: jnp.ndarray
    goal_heading: jnp.ndarray
    prefer_forward: jnp.ndarray
    constraint: jnp.ndarray


_DEFAULTS = dict(temperature=0.02, noise_v=0.25, noise_omega=0.6, gamma=0.0, collision=100.0, disc_margin=0.2,
                 disc_growth=0.0, obstacle=1.0, dynamic=3.0, path_align=0.5, path_follow=2.0, goal=1.0,
                 goal_heading=0.5, prefer_forward=1.0, constraint=0.2)


def default_params(**overrides: float) -> MPPIParams:
    """The default `MPPIParams` (numpy float32 scalars), with optional overrides.

    Raises:
      ValueError: an unknown name, or a value that is not a finite number >= 0 (temperature and
        noise > 0).
    """
    unknown = sorted(set(overrides) - set(_DEFAULTS))
    if unknown:
        raise ValueError(f"unknown MPPI parameter(s) {unknown}; the parameters are {sorted(_DEFAULTS)}")
    d = {**_DEFAULTS, **overrides}
    for k, v in d.items():
        v = float(v)
        positive = k in ("temperature", "noise_v", "noise_omega")
        if not math.isfinite(v) or v < 0 or (positive and v == 0):
            raise ValueError(f"MPPI parameter {k!r} must be a finite number {'> 0' if positive else '>= 0'}, "
                             f"got {overrides.get(k, v)!r}")
    return MPPIParams(**{k: np.float32(v) for k, v in d.items()})
