"""Dynamic Window Approach local planner: robot models, dynamic window, batched rollouts, critics, fuzzy evaluation.

Host front::

    import jaxplan as jp
    u, info = jp.dwa_step(state, subgoal, grid)             # state [5] or [B, 5]
    u, _ = jp.dwa_step(state, subgoal, grid, full_info=False)  # the control alone
    step = jp.make_stepper(grid, config)                    # one robot on a fixed map, in a loop
    u = step(state, subgoal)

Pure core, for episodes (`lax.scan` over control steps, `vmap` over episodes)::

    from jaxplan.dwa import DWAConfig, clearance_table, default_params, dwa_control
    from jaxplan.grid import collision_map
    table = clearance_table(collision_map(grid))
    u, info = dwa_control(table, DWAConfig(keep_rollouts=False), default_params(), state, subgoal)
"""

from jaxplan.dwa._brake import braking_clearance
from jaxplan.dwa._clearance import (
    HYBRID_EXACT_CELLS,
    ClearanceTable,
    DiscObstacles,
    clearance_table,
    disc_clearance,
    no_obstacles,
    speed_cap,
    static_clearance,
)
from jaxplan.dwa._config import (
    CLEARANCE_MODES,
    EVALUATORS,
    SAFETY_MODES,
    SELECTIONS,
    DWAConfig,
    DWAParams,
    default_params,
    safety_from_admissible,
)
from jaxplan.dwa._core import DWAInfo, dwa_control, dwa_control_batch, evaluate, trajectory
from jaxplan.dwa._critics import Critics, critics
from jaxplan.dwa._fastmath import abs_angle, rotor
from jaxplan.dwa._fuzzy import fuzzy_evaluate, input_memberships, rule_table
from jaxplan.dwa._passive import (
    DEFAULT_WALKER_SPEED,
    FLOAT_SLACK,
    POINTS_PER_PERIOD,
    brake,
    braking_periods,
    passive_slack,
    walker_speed_bound,
    with_brake_periods,
)
from jaxplan.dwa._robot import (
    Ackermann,
    Disc,
    Rectangle,
    Robot,
    Unicycle,
    advance,
    curvature_limit,
    footprint_offsets,
    footprint_radius,
)
from jaxplan.dwa._rollout import Rollouts, rollout
from jaxplan.dwa._step import (
    as_obstacles,
    check_safety,
    dwa_step,
    obstacles_to_local,
    table_of,
    validate_config,
    validate_params,
)
from jaxplan.dwa._stepper import DWAStepper, make_stepper
from jaxplan.dwa._window import (
    Window,
    clamp_controls,
    curvature_window,
    dynamic_window,
    sample_controls,
    window_of,
)

__all__ = [
    "Robot", "abs_angle", "as_obstacles", "braking_clearance", "curvature_limit", "rotor",
    "Ackermann", "CLEARANCE_MODES", "ClearanceTable", "Critics", "DWAConfig", "DWAInfo", "DWAParams", "Disc",
    "DiscObstacles", "DWAStepper", "EVALUATORS", "HYBRID_EXACT_CELLS", "Rectangle", "Rollouts", "SELECTIONS",
    "Unicycle", "Window",
    "advance", "clearance_table", "critics", "default_params", "disc_clearance", "dwa_control", "dwa_control_batch",
    "dwa_step", "dynamic_window", "evaluate", "footprint_offsets", "footprint_radius", "fuzzy_evaluate",
    "input_memberships", "make_stepper", "no_obstacles", "rollout", "rule_table", "sample_controls",
    "obstacles_to_local", "speed_cap", "static_clearance", "table_of",
    "trajectory", "validate_config", "validate_params",
    "DEFAULT_WALKER_SPEED", "FLOAT_SLACK", "POINTS_PER_PERIOD", "SAFETY_MODES", "brake", "braking_periods",
    "check_safety", "clamp_controls", "curvature_window", "passive_slack", "safety_from_admissible",
    "walker_speed_bound", "window_of", "with_brake_periods",
]
