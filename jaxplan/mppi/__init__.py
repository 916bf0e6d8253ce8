"""MPPI local planner: Model Predictive Path Integral control (Williams et al. 2017), after Nav2's MPPI controller.

K noisy control sequences over a horizon of T periods, warm-started by shifting the last solution,
clamped to the robot's dynamic window and rolled out through the robot models of `jaxplan.dwa`,
scored by small critics (`jaxplan.mppi._critics`) and averaged with a softmax of temperature λ —
one array program per step, batched over robots and episodes inside a navigation episode's
`lax.scan` (``local_planner="mppi"``), and differentiable through its softmax.

One robot from Python (the previous call's ``info.sequence`` warm-starts the next)::

    import jaxplan as jp
    u, info = jp.mppi_step(state, subgoal, grid, sequence=None, key=0)
    u, info = jp.mppi_step(new_state, subgoal, grid, sequence=info.sequence, key=1)

Pure core, for episodes::

    from jaxplan.dwa import clearance_table
    from jaxplan.grid import collision_map
    from jaxplan.mppi import MPPIConfig, default_params, initial_sequence, mppi_control, shift
    table = clearance_table(collision_map(grid))
    mean = initial_sequence(config, state)
    u, info = mppi_control(table, config, default_params(), state, mean, key, subgoal)
    mean = shift(info.sequence)
"""

from jaxplan.dwa import clamp_controls
from jaxplan.mppi._config import CRITICS, MPPIConfig, MPPIParams, default_params
from jaxplan.mppi._core import (
    BRAKE_ROW,
    MEAN_ROW,
    TURN_ROW,
    MPPIInfo,
    fixed_rows,
    initial_sequence,
    mppi_control,
    shift,
)
from jaxplan.mppi._critics import Context, Terms
from jaxplan.mppi._rollout import Sequences, rollout
from jaxplan.mppi._step import mppi_step, validate_config, validate_params

__all__ = [
    "BRAKE_ROW", "CRITICS", "Context", "MEAN_ROW", "MPPIConfig", "MPPIInfo", "MPPIParams", "Sequences", "TURN_ROW",
    "Terms", "clamp_controls", "default_params", "fixed_rows", "initial_sequence", "mppi_control", "mppi_step",
    "rollout", "shift", "validate_config", "validate_params",
]
