"""Path, run and episode metrics (definitions: docs/guide/smoothing-and-metrics.md).

Batched JAX functions over padded arrays (``jit``/``vmap``-able, shapes in the docstrings):

* paths (`_path`, `_clearance`, `_polyline`): `path_length_padded`, `count_turns_padded`,
  `count_sharp_turns_padded`, `smoothness_padded`, `max_curvature_padded`,
  `geometry_metrics`, `vertex_turns`, `clearance_metrics`, `vertex_clearance`,
  `point_polyline_distance`, `hausdorff`, `hausdorff_bounds`;
* runs (`_run`): `converged_iteration`, `optimum_iteration`, `turning_point`, `diversity`;
* episodes (`_episode`): `collision_steps`, `collisions`, `arrival_time`, `success`,
  `rmse`, `energy`, `EnergyModel`, `EpisodeTiming`.

The front `path_metrics(path, grid, reference=None, optimal=None, n=None)` returns the
path metrics (`PathMetrics`, a field per metric) for one path or a batch in one compiled call. One-path
host versions (numpy, same definitions): `path_length`, `heading_changes`,
`count_turns`, `count_sharp_turns`, `smoothness`, `max_curvature`.
"""

from jaxplan.metrics._clearance import clearance_metrics, vertex_clearance
from jaxplan.metrics._episode import (
    EnergyModel,
    EpisodeTiming,
    arrival_time,
    collision_steps,
    collisions,
    energy,
    rmse,
    success,
)
from jaxplan.metrics._front import path_metrics
from jaxplan.metrics._host import (
    count_sharp_turns,
    count_turns,
    heading_changes,
    max_curvature,
    path_length,
    smoothness,
)
from jaxplan.metrics._path import (
    SHARP_TURN,
    TURN_EPS,
    count_sharp_turns_padded,
    count_turns_padded,
    geometry_metrics,
    max_curvature_padded,
    path_length_padded,
    smoothness_padded,
    vertex_turns,
)
from jaxplan.metrics._polyline import HAUSDORFF_SAMPLES, hausdorff, hausdorff_bounds, point_polyline_distance
from jaxplan.metrics._result import PATH_METRICS, PathMetrics
from jaxplan.metrics._run import (
    CONVERGED_RTOL,
    CONVERGED_RTOL_STRICT,
    converged_iteration,
    diversity,
    optimum_iteration,
    turning_point,
)

__all__ = [
    "CONVERGED_RTOL", "CONVERGED_RTOL_STRICT", "EnergyModel", "EpisodeTiming", "HAUSDORFF_SAMPLES", "PATH_METRICS",
    "PathMetrics", "SHARP_TURN", "TURN_EPS",
    "arrival_time", "clearance_metrics", "collision_steps", "collisions", "converged_iteration",
    "count_sharp_turns", "count_sharp_turns_padded", "count_turns", "count_turns_padded", "diversity", "energy",
    "geometry_metrics", "hausdorff", "hausdorff_bounds", "heading_changes", "max_curvature",
    "max_curvature_padded", "optimum_iteration", "path_length", "path_length_padded", "path_metrics",
    "point_polyline_distance", "rmse", "smoothness", "smoothness_padded", "success", "turning_point",
    "vertex_clearance", "vertex_turns",
]
