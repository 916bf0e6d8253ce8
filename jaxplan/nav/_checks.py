"""Checks of a navigation call's arguments: cells on the map, the `NavConfig`, seeds, teams, obstacle sets.

Every problem is a ``ValueError`` naming it, raised before any planning or compilation.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np
from jax.sharding import Mesh
from numpy.typing import ArrayLike

from jaxplan.core.names import did_you_mean
from jaxplan.dwa import (
    SAFETY_MODES,
    DWAParams,
    braking_periods,
    footprint_radius,
    validate_config,
    validate_params,
    with_brake_periods,
)
from jaxplan.grid import GridMap
from jaxplan.mppi import MPPIParams
from jaxplan.mppi import validate_config as validate_mppi_config
from jaxplan.mppi import validate_params as validate_mppi_params
from jaxplan.nav._config import LOCAL_PLANNERS, PREDICTIONS, SUBGOAL_MODES, NavConfig
from jaxplan.nav._moving import MovingObstacles, no_obstacles
from jaxplan.nav._pipelines import Pipeline, get_pipeline
from jaxplan.scale import auto_mesh

__all__ = ["RunArgs", "checked_run", "resolve_config", "obstacle_sets", "check_obstacle_starts"]


def _cells(name: str, a: ArrayLike, grid: GridMap, shape: tuple) -> np.ndarray:
    arr = np.asarray(a)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr.astype(float))) or not np.all(arr.astype(float) == np.round(arr.astype(float))):
        raise ValueError(f"{name} must be integer cells (x, y), got {arr.tolist()!r}")
    arr = arr.astype(np.int64)
    H, W = grid.shape
    out = (arr[..., 0] < 0) | (arr[..., 0] >= W) | (arr[..., 1] < 0) | (arr[..., 1] >= H)
    if np.any(out):
        bad = arr[out][0]
        raise ValueError(f"{name} cell {tuple(bad.tolist())} is outside the {W}x{H} map")
    free = np.asarray(grid.free)
    blocked = ~free[arr[..., 1], arr[..., 0]]
    if np.any(blocked):
        bad = arr[blocked][0]
        raise ValueError(f"{name} cell {tuple(bad.tolist())} is on a blocked cell")
    return arr


def resolve_config(config: NavConfig | None, pipeline: Pipeline, local_planner: str | None) -> NavConfig:
    """The `NavConfig` an episode runs with: ``config`` (default `NavConfig()`) with the local planner and DWA
    evaluator of ``local_planner`` / the config / ``pipeline`` (in that order), every field checked (``ValueError``)."""
    cfg = NavConfig() if config is None else config
    if not isinstance(cfg, NavConfig):
        raise ValueError(f"config must be a NavConfig, got {type(cfg).__name__}")
    local = local_planner or cfg.local or pipeline.local
    if local not in LOCAL_PLANNERS:
        raise ValueError(f"unknown local planner {local!r}{did_you_mean(str(local), LOCAL_PLANNERS)} "
                         f"(choose from {', '.join(LOCAL_PLANNERS)})")
    if cfg.subgoal not in SUBGOAL_MODES:
        raise ValueError(f"unknown sub-goal mode {cfg.subgoal!r}; choose from {SUBGOAL_MODES}")
    if cfg.prediction not in PREDICTIONS:
        raise ValueError(f"unknown prediction {cfg.prediction!r}; choose from {PREDICTIONS}")
    evaluator = cfg.evaluator or pipeline.evaluator
    dwa, mppi = _with_safety(cfg, local)
    dwa = with_brake_periods(validate_config(dwa.replace(evaluator=evaluator, keep_rollouts=False)))
    if mppi.safety == "passive" and mppi.brake_periods is None:  # the episode's robot is dwa's
        mppi = mppi.replace(brake_periods=braking_periods(dwa.robot, dwa.period))
    validate_mppi_config(cfg.replace(dwa=dwa, mppi=mppi).local_mppi())
    for f in ("switch_radius", "switch_min", "lookahead", "goal_tolerance", "max_time", "replan_period",
              "replan_deviation", "block_distance", "block_margin", "follow_gain", "threat_distance", "threat_speed",
              "corner_exponent", "recheck_gain"):
        v = getattr(cfg, f)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise ValueError(f"NavConfig.{f} must be a finite number >= 0, got {v!r}")
    if cfg.goal_tolerance <= 0 or cfg.max_time <= 0:
        raise ValueError("NavConfig.goal_tolerance and max_time must be > 0")
    for f, what in (("stall_time", "creeping"), ("orbit_angle", "the orbit watch"),
                    ("recheck_period", "detour re-checks"), ("recede_speed", "the rule")):
        v = getattr(cfg, f)
        if not (isinstance(v, (int, float)) and not math.isnan(v) and v > 0):
            raise ValueError(f"NavConfig.{f} must be a number > 0 (inf disables {what}), got {v!r}")
    v = cfg.creep_distance
    if v is not None and not (isinstance(v, (int, float)) and not math.isnan(v) and v > 0):
        raise ValueError(f"NavConfig.creep_distance must be None or a number > 0 (inf: creep until the waypoint), "
                         f"got {v!r}")
    for f in ("stall_progress", "stall_speed", "give_way_time", "give_way_distance", "give_way_move",
              "give_way_hold"):
        v = getattr(cfg, f)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"NavConfig.{f} must be a finite number > 0, got {v!r}")
    for f in ("chunk", "replan_sweeps", "replan_cells", "replan_slots", "contact_checks"):
        if not isinstance(getattr(cfg, f), int) or getattr(cfg, f) < 1:
            raise ValueError(f"NavConfig.{f} must be a positive integer, got {getattr(cfg, f)!r}")
    if cfg.give_way not in (None, True, False):
        raise ValueError(f"NavConfig.give_way must be True, False or None (on with MPPI), got {cfg.give_way!r}")
    if not isinstance(cfg.replan_group, int) or cfg.replan_group < 0:
        raise ValueError(f"NavConfig.replan_group must be an integer >= 0 (0: the whole batch), "
                         f"got {cfg.replan_group!r}")
    return cfg.replace(dwa=dwa, mppi=mppi.replace(keep_rollouts=False), local=local, evaluator=evaluator)


def _with_safety(cfg: NavConfig, local: str) -> tuple[Any, Any]:
    """``(dwa, mppi)`` configs with `NavConfig.safety` and `NavConfig.walker_speed_max` set on both (when given),
    checked."""
    dwa, mppi = cfg.dwa, cfg.mppi
    if cfg.safety is not None:
        if cfg.safety not in SAFETY_MODES:
            raise ValueError(f"unknown safety {cfg.safety!r}{did_you_mean(str(cfg.safety), SAFETY_MODES)} "
                             f"(choose from {', '.join(SAFETY_MODES)})")
        dwa, mppi = dwa.replace(safety=cfg.safety), mppi.replace(safety=cfg.safety)
    v = cfg.walker_speed_max
    if v is not None:
        if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise ValueError(f"NavConfig.walker_speed_max must be None or a finite number >= 0 (m/s), got {v!r}")
        dwa, mppi = dwa.replace(walker_speed_max=float(v)), mppi.replace(walker_speed_max=float(v))
    if local == "follow" and cfg.safety not in (None, "none"):
        raise ValueError(f"safety={cfg.safety!r} needs a local planner that checks its controls ('dwa' or "
                         "'mppi'); 'follow' avoids nothing")
    return dwa, mppi


def obstacle_sets(obstacles: Any, E: int, R: int, seeds: list[int]) -> list[list[MovingObstacles]]:
    """``[E][R]`` obstacle sets from None, one set, an ``[E][R]`` nested list, or ``f(e, seed)``."""
    if obstacles is None:
        return [[no_obstacles(0) for _ in range(R)] for _ in range(E)]
    if isinstance(obstacles, MovingObstacles):
        return [[obstacles for _ in range(R)] for _ in range(E)]
    if callable(obstacles):
        return [[obstacles(e, s) for s in seeds] for e in range(E)]
    sets = list(obstacles)
    if len(sets) != E or any(len(list(row)) != R for row in sets):
        raise ValueError(f"obstacles must be one MovingObstacles, a callable f(scenario, seed), or an [{E}][{R}] "
                         "nested list")
    return [list(row) for row in sets]



def check_obstacle_starts(pos: np.ndarray, rad: np.ndarray, start_xy: np.ndarray, radius: float, where: str) -> None:
    """Raises if a disc (``pos [M, 2]`` at t = 0, ``rad [M]``) overlaps a robot at ``start_xy [N, 2]``."""
    for i, p in enumerate(start_xy):
        gap = np.hypot(*(pos - p).T) - rad - radius
        if np.any(gap < 0):
            j = int(np.argmin(gap))
            raise ValueError(f"{where}: moving obstacle {j} starts inside robot {i} (centres "
                             f"{np.round(pos[j], 3).tolist()} and {np.round(p, 3).tolist()} m, radii "
                             f"{float(rad[j]):g} + {radius:g} m)")


class RunArgs(NamedTuple):
    """A run's checked arguments: the pipeline, the resolved config, seeds, ``[E, N, 2]`` start and goal cells,
    the local planner's params (`DWAParams`, or `MPPIParams` for ``"mppi"``) and the robot's footprint radius (m)."""

    pipe: Pipeline
    cfg: NavConfig
    seeds: list[int]
    starts: np.ndarray
    goals: np.ndarray
    params: DWAParams | MPPIParams
    radius: float


def checked_run(grid: GridMap, starts: np.ndarray, goals: np.ndarray, pipeline: str | None,
                global_planner: str | None, local_planner: str | None, seeds: Sequence[int],
                config: NavConfig | None, params: DWAParams | MPPIParams | Mapping[str, float] | None,
                time_limit: float | None,
                mesh: Mesh | str | None) -> RunArgs:
    """A navigation call's arguments (``starts, goals [E, N, 2]`` cells), every one checked (``ValueError`` naming
    the problem) before any work, with the pipeline and `NavConfig` resolved."""
    if not isinstance(grid, GridMap):
        raise ValueError(f"grid must be a GridMap, got {type(grid).__name__}")
    auto_mesh(mesh, 1)  # a bad mesh argument fails before any work
    if pipeline is not None and global_planner is not None:
        raise ValueError("give either a pipeline or a global_planner, not both")
    if pipeline is not None:
        pipe = get_pipeline(pipeline)
    else:
        gp = "iaco" if global_planner is None else global_planner
        pipe = Pipeline(f"{gp}+{local_planner or 'dwa'}", gp, {}, ("key_nodes",), local_planner or "dwa",
                        "weighted", "custom")
    cfg = resolve_config(config, pipe, local_planner)
    robot = cfg.dwa.robot
    seeds = [int(s) for s in seeds]
    if not seeds or any(s < 0 for s in seeds):
        raise ValueError(f"seeds must be a non-empty list of integers >= 0, got {seeds!r}")
    E, N = starts.shape[:2]
    starts = _cells("start", starts, grid, (E, N, 2))
    goals = _cells("goal", goals, grid, (E, N, 2))
    if np.any(np.all(starts == goals, axis=-1)):
        raise ValueError("a start equals its goal: there is nothing to navigate")
    if time_limit is not None and not (math.isfinite(time_limit) and 0 < time_limit <= cfg.max_time):
        raise ValueError(f"time_limit must be in (0, max_time = {cfg.max_time}] s, got {time_limit!r}")
    if cfg.local == "mppi":
        if isinstance(params, DWAParams):
            raise ValueError("params are DWAParams but the local planner is 'mppi': give MPPIParams or a dict")
        p = validate_mppi_params(params)
    else:
        if isinstance(params, MPPIParams):
            raise ValueError(f"params are MPPIParams but the local planner is {cfg.local!r}: give DWAParams or a dict")
        p = validate_params(params, cfg.dwa.evaluator)
    radius = float(footprint_radius(robot.footprint))
    if N > 1:
        _check_team(starts, goals, float(grid.resolution), radius)
    return RunArgs(pipe, cfg, seeds, starts, goals, p, radius)


def _check_team(starts: np.ndarray, goals: np.ndarray, res: float, radius: float) -> None:
    """Teammates (``[E, N, 2]`` cells) may not overlap at the start, nor share a goal (one would park on it)."""
    N = starts.shape[1]
    for what, cells in (("start", starts), ("goal", goals)):
        xy = (cells + 0.5) * res  # [E, N, 2]
        d = xy[:, :, None] - xy[:, None, :]  # [E, N, N, 2]
        gap = np.where(np.eye(N, dtype=bool), np.inf, np.hypot(d[..., 0], d[..., 1]))
        if np.any(gap < 2 * radius):
            e, i, j = np.unravel_index(int(np.argmin(gap)), gap.shape)
            raise ValueError(f"team {e}: robots {i} and {j} have {what} cells {cells[e, i].tolist()} and "
                             f"{cells[e, j].tolist()}, {gap[e, i, j]:.3g} m apart: closer than two footprint "
                             f"radii ({2 * radius:g} m)")

