"""`make_stepper`: one robot on a fixed map, stepped from Python in a loop (a research script, a ROS node).

`dwa_step` does, on every call, what any call might need: it checks the configuration and weights,
looks the map's tables up, and returns the info record. A script that steps the same robot on the
same map does that work once: `make_stepper` validates the configuration and weights, builds the
map's `ClearanceTable` and puts it, the configuration and the weights on the device, and returns a
`DWAStepper`. Each call then checks the state and sub-goal with scalar arithmetic (finite, window
not empty, robot on a free cell of the map: the errors of `dwa_step`) and runs one compiled step
that returns the control alone — the same control as `dwa_step`, bit for bit. Like `dwa_step`'s
one-robot programs, the step is compiled without XLA:CPU's loop split across threads
(`jaxplan.core.xla`): called from Python, one robot's loops are too small to pay for waking a thread.

The stepper keeps the map as it was when it was built (its free cells and tables); for another map,
make another stepper.
"""

from __future__ import annotations

import dataclasses
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.dwa._clearance import ClearanceTable
from jaxplan.dwa._config import DWAConfig, DWAParams
from jaxplan.dwa._core import DWAInfo
from jaxplan.dwa._passive import with_brake_periods
from jaxplan.dwa._step import (
    _numpy_info,
    _single,
    _single_control,
    device_config,
    dwa_step,
    one_robot,
    params_on_device,
    table_of,
    validate_config,
    validate_params,
)
from jaxplan.grid import GridMap

__all__ = ["DWAStepper", "make_stepper"]


@dataclasses.dataclass(frozen=True, eq=False)
class DWAStepper:
    """A compiled DWA step for one robot on one map (built by `make_stepper`).

    ``stepper(state, subgoal)`` -> ``control f32[2]`` = (v, omega) for the next control period;
    `info` gives the full `DWAInfo` of a state when a script wants it (as `dwa_step`).

    Attributes:
      grid: the map, as given (the stepper's tables are those of its layers when the stepper was built).
      config: the validated `DWAConfig`.
      params: the validated `DWAParams` (float32 scalars).
      table: the map's `ClearanceTable` (device arrays).
    """

    grid: GridMap
    config: DWAConfig
    params: DWAParams
    table: ClearanceTable
    _map: GridMap = dataclasses.field(repr=False)
    _lean: DWAConfig = dataclasses.field(repr=False)
    _full: DWAConfig = dataclasses.field(repr=False)
    _params: DWAParams = dataclasses.field(repr=False)

    def __repr__(self) -> str:
        H, W = self.grid.shape
        return f"DWAStepper(map {H}x{W} cells of {float(self.grid.resolution):g} m, config={self.config!r})"

    def _robot(self, state: ArrayLike, subgoal: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        robot = one_robot(state, subgoal, self._map, self.config)
        if robot is None:  # not one robot, or a check failed: dwa_step's checks name the problem
            dwa_step(state, subgoal, self._map, params=self.params, config=self.config, full_info=False)
            raise ValueError(f"the stepper takes one robot's state [5] and sub-goal [2], got shapes "
                             f"{np.shape(state)} and {np.shape(subgoal)}")
        return robot

    def __call__(self, state: ArrayLike, subgoal: ArrayLike) -> np.ndarray:
        """The control ``f32[2]`` = (v, omega) for one robot.

        Args:
          state: ``[5]`` = (x, y, theta, v, omega) in m, rad, m/s, rad/s (world frame, as `dwa_step`).
          subgoal: ``[2]`` (m) the point the robot heads for.

        Raises:
          ValueError: as `dwa_step`: a mis-shaped or non-finite state or sub-goal, an empty dynamic
            window, a robot centred off the map or on a blocked cell.
        """
        st, sg = self._robot(state, subgoal)
        return np.asarray(_single_control(self.table, self._lean, self._params, st, sg))

    def info(self, state: ArrayLike, subgoal: ArrayLike) -> tuple[np.ndarray, DWAInfo]:
        """``(control, DWAInfo)`` of one step, as `dwa_step` returns them (rollouts in the world frame)."""
        st, sg = self._robot(state, subgoal)
        return _numpy_info(_single(self.table, self._full, self._params, st, sg, None, None), self._map)


def make_stepper(grid: GridMap, config: DWAConfig | None = None,
                 params: DWAParams | Mapping[str, float] | None = None) -> DWAStepper:
    """A compiled single-robot DWA step for a fixed map and robot (see the module docstring).

    Args:
      grid: the map (`GridMap`); its clearance table is built here.
      config: `DWAConfig` (default `DWAConfig()`: cui2025's robot, weighted evaluator); checked here.
      params: `DWAParams`, a dict of overrides of the evaluator's defaults, or None; checked here.

    Returns:
      A `DWAStepper`: ``stepper(state, subgoal)`` is ``dwa_step(state, subgoal, grid, params,
      config=config)[0]`` for one robot without moving discs or a path, with per call only the
      state's checks and one compiled step (the first call compiles).

    Raises:
      ValueError: a grid that is not a `GridMap`, an invalid config or invalid weights (as `dwa_step`).

    Example:
      >>> import numpy as np, jaxplan as jp
      >>> grid = jp.grid_from_array(np.ones((20, 20), bool), resolution=0.5)
      >>> step = jp.make_stepper(grid)
      >>> u = step([2.0, 5.0, 0.0, 0.5, 0.0], [8.0, 5.0])
      >>> bool((u == jp.dwa_step([2.0, 5.0, 0.0, 0.5, 0.0], [8.0, 5.0], grid)[0]).all())
      True
    """
    if not isinstance(grid, GridMap):
        raise ValueError(f"grid must be a GridMap, got {type(grid).__name__}")
    config = with_brake_periods(validate_config(DWAConfig() if config is None else config))
    prm = validate_params(params, config.evaluator)
    # The stepper's own copy of the layers it reads: later writes into grid's arrays do not reach it.
    free = np.array(grid.free, dtype=bool)
    limit = None if grid.speed_limit is None else np.array(grid.speed_limit, dtype=np.float32)
    for a in (free, limit):
        if a is not None:
            a.setflags(write=False)
    snapshot = grid._replace(free=free, speed_limit=limit)
    return DWAStepper(grid=grid, config=config, params=prm, table=table_of(snapshot), _map=snapshot,
                      _lean=device_config(config, True), _full=device_config(config), _params=params_on_device(prm))
