"""`NavConfig`: how a two-level navigation episode runs (static switches and traced distances)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax

from jaxplan.dwa import DWAConfig
from jaxplan.mppi import MPPIConfig

__all__ = ["NavConfig", "LOCAL_PLANNERS", "SUBGOAL_MODES", "PREDICTIONS"]

LOCAL_PLANNERS = ("dwa", "mppi", "follow")
"""``"dwa"``: the DWA step; ``"mppi"``: the MPPI step (`jaxplan.mppi`); ``"follow"``: pure path following
without obstacle avoidance (cui2025's "without DWA" ablation): turn towards the sub-goal, slow down with the
heading error, within the robot's dynamic window."""

SUBGOAL_MODES = ("key_nodes", "lookahead")
"""``"key_nodes"``: aim at the current waypoint and switch to the next within ``switch_radius``
(cui2025/li2026); ``"lookahead"``: aim at the point ``lookahead`` metres further along the
waypoint polyline than the robot's projection on it."""

PREDICTIONS = ("constant_velocity", "oracle")
"""How the DWA predicts moving obstacles over its horizon. ``"constant_velocity"``: from their
position and velocity now (what a robot can know). ``"oracle"``: along their true routes (an
ablation: perfect prediction of every walker's turns and bounces, an upper bound for any
walker predictor; other robots stay at constant velocity, as their futures depend on their
own choices)."""


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class NavConfig:
    """A navigation episode's settings. Distances in metres, times in seconds.

    The measurements behind the defaults below are in docs/decisions.md.

    Attributes:
      dwa: the local planner's `DWAConfig` (robot, control period, d_safe, samples). Its
        rollouts are never kept in an episode, and its evaluator is set from ``evaluator``.
        Its recovery defaults to ``"flee"`` here (see `DWAConfig.recovery`), and its clearance
        critic saturates at ``d_clip = 0.5`` m: a robot centred in a 1 m aisle (the MovingAI
        maps at 1 m per cell) has 0.5 m, and with the DWA's own 1.0 m the fuzzy evaluator rates
        every aisle "close" and cuts it, so robots circled in front of aisle entrances. Opt-in:
        ``dwa=NavConfig().dwa.replace(straighten=(0.25, 0.5))`` also samples rollouts that turn
        for the first 0.5 s or 1 s and then drive straight on (2 × 20 × 20 more samples):
        side-steps round a walker in a corridor, where a constant arc long enough to pass ends
        at a wall. It helps among walkers on most maps, but a lone robot's control step costs
        several times as long, so it is not the default.
      mppi: the MPPI local planner's `jaxplan.mppi.MPPIConfig` (samples, horizon, critics' distances,
        passive-safety option), used when ``local = "mppi"``. The episode's robot, control period
        and d_safe are ``dwa``'s for every local planner (one robot model per episode): the MPPI
        step runs with ``mppi.replace(robot=dwa.robot, period=dwa.period, d_safe=dwa.d_safe)``.
      local: ``"dwa"``, ``"mppi"``, ``"follow"`` (static; see `LOCAL_PLANNERS`), or None: the
        pipeline's.
      evaluator: the DWA evaluator (``"weighted"``, ``"fuzzy"``, ``"classic"``; static), or
        None: the pipeline's (fuzzy for ``iaco_dwa``, weighted for the others).
      subgoal: ``"key_nodes"`` or ``"lookahead"`` (static; see `SUBGOAL_MODES`).
      switch_radius: a waypoint counts as passed within this distance (li2026: 1 m). While
        the robot creeps (see ``stall_time``), only if the straight way to the next keeps
        ``dwa.d_safe`` from the map for its first 3.2 m, and otherwise within ``switch_min``.
      switch_min: see ``switch_radius``.
      lookahead: look-ahead distance along the path in ``"lookahead"`` mode.
      goal_tolerance: the goal is reached within this distance of the goal cell's centre.
      max_time: the longest episode (static: it sizes the trajectory buffers); a per-episode
        time limit up to it is an input of the run.
      chunk: control steps per iteration of the outer loop (static): the loop stops at the
        first chunk boundary after every robot is done.
      stop_on_collision: a colliding robot stops there (``reason = collision``); when False
        it drives on and contacts are counted (li2026's Table 3 counts collisions) (static).
      contact_checks: contacts (robot disc within a blocked square, a moving disc or another
        robot) are checked at this many evenly spaced times of each control period, the last
        at its end (static). A robot and a walker close by up to 0.44 m per period (1.2 + 1.0
        m/s), so a check at the period's end alone misses grazing contacts; with 4 checks
        (0.11 m apart) an unseen overlap is under 3 mm deep. 1 checks at the end only, as
        episodes did before this field existed.
      replan: re-plan in the episode when the path ahead is blocked or the robot has drifted
        off it (static; see `jaxplan.nav._replan`).
      replan_deviation: drifting farther than this from the tracked path triggers a re-plan
        from where the robot is. A DWA robot that misses an aisle entrance is carried past
        the cross aisles it would need (it cannot turn into a 1 m aisle at speed) and, without
        a re-plan, may drive to the map's far end. Not while a disc is within half of
        ``block_distance``: then the drift is an evasion.
      replan_period: at most one re-plan per robot per this many seconds (cui2025: 0.2 s).
      block_distance: how far along the remaining path a disc is looked for (6 m: a walker
        closing head-on in a 1 m aisle must be seen while the robot can still turn round).
      block_horizon: a disc blocks the path if it comes near it within this many seconds,
        predicted at constant velocity (sampled every 0.5 s); re-planning closes the cells
        around those predicted positions too.
      block_margin: extra distance beyond the two radii within which a disc blocks the path
        and within which cells around it are closed when re-planning.
      replan_sweeps: bound on the distance field's relaxation sweeps (static).
      replan_slots: robots of a group of episodes (``replan_group``) that can re-plan in the
        same step (static); others wait a step. The cost of a re-planning step is that of
        this many fields per group, whatever the group's size.
      replan_group: consecutive episodes of a batch sharing the ``replan_slots`` budget
        (static); 0 = the whole batch (on a mesh: each device's share, so results would
        depend on the device count). With a group size, results are independent of the device
        count: `navigate_batch` then splits episodes over a mesh (``mesh="auto"``: all local
        devices, given at least one group and 8 episodes per device), padding the batch to
        whole groups per device with episodes that do not run; without a mesh, a partial
        last group is simply a smaller group. The default, 25, also keeps results from
        depending on the batch's size: with one budget for the whole batch, robots waited
        for a slot when many needed one, and a large batch succeeded less often than small
        ones — for a few per cent more time per episode.
      replan_cells: longest re-planned path in moves (static).
      path_critic: pass the waypoint polyline to the DWA path critic (static; its weight is
        `DWAParams.path`).
      follow_gain: yaw-rate gain (1/s) of the ``"follow"`` controller.
      corner_speed: top speed (m/s) at a corner — a waypoint where the path turns by at
        least ``corner_angle`` (rad). Approaching one, the local planner's top speed is
        capped to sqrt(corner_speed² + 2·decel·d), d the distance left before the switch
        radius, and stays at corner_speed until the robot is ``switch_radius`` past it.
        The DWA looks 2 s ahead; at 1.2 m/s and 0.5 m/s² a robot needs 1.4 m to brake, so
        without the cap it overshoots every turn into a 1 m aisle. The goal counts as a
        corner (the cap reaches corner_speed at the goal tolerance), so the robot does not
        orbit it. ``inf`` disables it.
        A corner's speed grows as the turn φ gets gentler: corner_speed / (1 − cos φ) **
        ``corner_exponent``, never below corner_speed — so corner_speed at 90° and sharper,
        0.55 m/s at 45° and 0.85 m/s at 29° with the defaults (0 gives corner_speed at every
        corner). Faster gentle corners shorten episodes on maps with many of them (not on the
        warehouse, whose corners are right angles) and leave fewer robots out of time among
        walkers. The exponent is half that of a constant-radius turn's bound (lateral
        overshoot ∝ v · (1 − cos φ)), which would let a 29° turn be taken at full speed — and
        that overshot.
      corner_exponent: see ``corner_speed``.
      corner_angle: the smallest turn (rad) that makes a waypoint a corner (15°: entering a 1 m
        aisle at 29° and 1.2 m/s overshot it).
      stall_time: a robot that has not come ``stall_progress`` closer to its current waypoint
        for this many seconds, with no disc within half of ``block_distance``, creeps: its top
        speed is ``stall_speed`` until it passes its current waypoint (it keeps creeping along
        a re-planned path) or a disc comes that near, and it re-plans from where it stalled
        (with ``replan``). DWA's scores can make a robot circle at full speed: its 2 s
        rollouts through a near waypoint overshoot it and end facing away, and between close
        obstacles only hard turns stay feasible at speed; such a robot circles until the time
        limit, and creeping, it arrives. Creeping costs time when a robot stalls far from its
        waypoint, but arrives. A creeping robot that stalls again re-plans again, once per
        ``stall_time`` (a robot can creep off the cell its path began at into one from which
        the straight way to its waypoint crosses a blocked cell). ``inf`` disables it.
      stall_progress: metres of approach that count as progress (see ``stall_time``).
      stall_speed: top speed (m/s) while creeping.
      creep_distance: a creeping robot stops creeping once it is this much (m) closer to its
        goal than where it began (static; a robot circling in place does not come closer):
        None (default) = 2 m with the MPPI local planner, unlimited with DWA and path following
        (their results stay those measured before the option existed). MPPI brakes for its own
        corners, so it needs the creep only to get loose; held to ``stall_speed`` along a
        re-planned path's long first leg it lost minutes (docs/decisions.md, "MPPI in episodes").
      threat_distance: a moving obstacle whose edge is within this distance of the robot's
        centre, and whose own speed component towards that centre exceeds ``threat_speed``
        (m/s), lifts the corner speed cap of a DWA robot: it may then drive at full speed, to
        get out of the way. The walkers do not avoid the robot, and a robot held at corner
        speed cannot outrun one: with the cap kept, walkers hit slow robots from behind. The
        DWA still keeps d_safe from the map. The disc's own speed, not the closing speed,
        decides: the latter would fall as the robot speeds away and put the cap back. Other
        robots do not count (they avoid each other, and two meeting at a corner should slow
        down), nor does the ``follow`` planner, which avoids nothing. A creeping robot stops
        creeping anyway when a disc comes within half of ``block_distance``. Without moving
        obstacles nothing changes; 0 disables it.
      threat_speed: see ``threat_distance``.
      orbit_angle: a DWA robot can circle at full speed where its 2 s rollouts overshoot its
        next waypoint; if it also drifts off its path, each re-plan gives it a new waypoint and
        restarts the stall watch (``stall_time``). So the heading change is summed too, until
        the robot comes ``switch_radius`` closer to its goal than ever before (or a disc comes
        within half of ``block_distance``): a net turn of this many radians creeps the robot as
        a stall does (a robot circling through re-plans otherwise runs out of time). ``inf``
        disables it.
      recheck_period: a robot whose path was re-planned around discs (a walker in a door, say)
        re-plans again every this many seconds while it follows that path, and takes the new
        path only if it is ``recheck_gain`` metres shorter than what is left of the current one:
        the walker may have moved on, and the way round may be through other rooms. Re-checks
        take re-planning slots only when no robot must re-plan. Without moving obstacles or
        other robots nothing changes; ``inf`` disables it.
      recheck_gain: see ``recheck_period``.
      recede_speed: a walker moving along the robot's path, the robot's way, at least this fast
        (m/s) does not block that path, and a walker moving away from the robot that fast is not
        closed off when re-planning: the robot follows it (the DWA keeps its distance) instead of
        going round it — and, going round, turning back at the next re-check and round again,
        re-planning over and over until the time limit. ``inf`` disables it.
      prediction: how the DWA predicts the moving obstacles (static; see `PREDICTIONS`):
        ``"constant_velocity"`` (default) or ``"oracle"``, their true routes — an ablation that
        separates prediction error from what the local planner can do at all. Re-planning and
        the threat rule keep the constant-velocity view.
      give_way: a robot in a standoff steps out of the way of the disc it faces and waits
        (`jaxplan.nav._give_way`; static): True, False, or None (default) — on with the MPPI local
        planner, off with DWA and path following (their results stay those measured before the
        option existed; turn it on to compare). Walkers that see stop in front of a robot standing in
        their way, and without it the two stand until the time limit.
      give_way_time: seconds a robot must have stayed within ``give_way_move`` of one spot, with a
        disc within ``give_way_distance`` of its edge, before it gives way.
      give_way_distance: see ``give_way_time`` (m, edge to edge).
      give_way_move: see ``give_way_time`` (m).
      give_way_hold: the longest a robot gives way (s) before it tracks its path again (it gives way
        again after another ``give_way_time`` if still stuck).
      safety: what the local planner checks before it commits to a control (static; `jaxplan.dwa.SAFETY_MODES`):
        ``"none"``, ``"predicted"`` (brake to rest before any *predicted* contact) or ``"passive"`` (brake to rest
        before any point a walker *can* reach: the robot is touched only at rest, whatever the walkers do;
        docs/guide/navigation.md), set on both ``dwa`` and ``mppi``; or None (default): their own ``safety``
        (``"none"`` unless set there). Needs the ``"dwa"`` or ``"mppi"`` local planner.
      walker_speed_max: the walkers' speed bound (m/s) of ``"passive"``, set on both ``dwa`` and ``mppi``; or
        None (default): theirs, and if they have none the scenario's — each episode's fastest walker (a walker
        that sees can go 1.3 times its route speed, `jaxplan.nav._social`), and with several robots at least the
        robots' top speed (they are discs for each other).
    """

    dwa: DWAConfig = DWAConfig(keep_rollouts=False, recovery="flee", d_clip=0.5)
    mppi: MPPIConfig = MPPIConfig()
    local: str | None = dataclasses.field(default=None, metadata=dict(static=True))
    evaluator: str | None = dataclasses.field(default=None, metadata=dict(static=True))
    subgoal: str = dataclasses.field(default="key_nodes", metadata=dict(static=True))
    switch_radius: float = 1.0
    switch_min: float = 0.25
    lookahead: float = 1.5
    goal_tolerance: float = 0.5
    max_time: float = dataclasses.field(default=180.0, metadata=dict(static=True))
    chunk: int = dataclasses.field(default=25, metadata=dict(static=True))
    stop_on_collision: bool = dataclasses.field(default=True, metadata=dict(static=True))
    contact_checks: int = dataclasses.field(default=4, metadata=dict(static=True))
    replan: bool = dataclasses.field(default=True, metadata=dict(static=True))
    replan_deviation: float = 1.0
    replan_period: float = 0.2
    block_distance: float = 6.0
    block_horizon: float = dataclasses.field(default=3.0, metadata=dict(static=True))
    block_margin: float = 0.1
    replan_sweeps: int = dataclasses.field(default=512, metadata=dict(static=True))
    replan_cells: int = dataclasses.field(default=256, metadata=dict(static=True))
    replan_slots: int = dataclasses.field(default=2, metadata=dict(static=True))
    replan_group: int = dataclasses.field(default=25, metadata=dict(static=True))
    path_critic: bool = dataclasses.field(default=False, metadata=dict(static=True))
    follow_gain: float = 2.0
    corner_speed: float = 0.3
    corner_exponent: float = 0.5
    corner_angle: float = math.radians(15.0)
    stall_time: float = 4.0
    stall_progress: float = 0.25
    stall_speed: float = 0.3
    threat_distance: float = 3.0
    threat_speed: float = 0.2
    orbit_angle: float = 2.0 * math.pi
    recheck_period: float = 3.0
    recheck_gain: float = 5.0
    recede_speed: float = 0.5
    creep_distance: float | None = dataclasses.field(default=None, metadata=dict(static=True))
    prediction: str = dataclasses.field(default="constant_velocity", metadata=dict(static=True))
    give_way: bool | None = dataclasses.field(default=None, metadata=dict(static=True))
    give_way_time: float = 3.0
    give_way_distance: float = 1.0
    give_way_move: float = 0.3
    give_way_hold: float = 10.0
    safety: str | None = dataclasses.field(default=None, metadata=dict(static=True))
    walker_speed_max: float | None = None

    @property
    def steps(self) -> int:
        """Control steps of the longest episode, a multiple of ``chunk``."""
        n = math.ceil(self.max_time / self.dwa.period - 1e-9)
        return math.ceil(n / self.chunk) * self.chunk

    @property
    def creep_reach(self) -> float:
        """How much closer (m) to its goal a creeping robot comes before it is released (``creep_distance``;
        by default 2 m with MPPI, ``inf`` otherwise)."""
        if self.creep_distance is not None:
            return float(self.creep_distance)
        return 2.0 if self.local == "mppi" else math.inf

    @property
    def gives_way(self) -> bool:
        """Whether the robots give way (``give_way``, or by default with the MPPI local planner)."""
        return self.local == "mppi" if self.give_way is None else bool(self.give_way)

    def local_mppi(self) -> MPPIConfig:
        """The MPPI step's config: ``mppi`` with the episode's robot, period and d_safe (``dwa``'s)."""
        return self.mppi.replace(robot=self.dwa.robot, period=self.dwa.period, d_safe=self.dwa.d_safe)

    def replace(self, **changes: Any) -> "NavConfig":
        return dataclasses.replace(self, **changes)
