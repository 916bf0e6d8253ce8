"""jaxplan: grid path planning for warehouse robots and logistics vehicles, in JAX.

The public names of DESIGN §3 are re-exported here::

    import jaxplan as jp
    grid = jp.load_map("den520d.map")
    scen = jp.load_scenarios("den520d.map.scen")
    opt = jp.shortest_lengths(grid, scen.starts, scen.goals)
    res = jp.plan(grid, scen.starts[0], scen.goals[0], planner="astar")
"""

# First, before anything can start JAX's backend: one CPU host device per core (see
# jaxplan.scale.configure_host_devices for the measurement and $JAXPLAN_HOST_DEVICES to change it).
from jaxplan.scale import configure_host_devices as _configure_host_devices

_configure_host_devices()

from jaxplan.grid import (
    GridMap,
    Neighbours,
    Scenarios,
    clearance_field,
    goal_distance_field,
    grid_from_array,
    load_map,
    load_scenarios,
    neighbour_table,
    passable,
    save_map,
    MountainGenerator,
    RandomMapGenerator,
    Scene,
    UrbanGenerator,
    WarehouseGenerator,
    demo_warehouse,
    poisson_risk,
    warehouse_chen2023,
    warehouse_yu2020,
)
from jaxplan.aco import BatchResult, TourResult, TSPProblem, load_tour, load_tsplib, plan_batch, solve_tsp, tour_length
from jaxplan.registry import PlannerSpec, plan, planners, register_planner
from jaxplan.result import PlanResult
from jaxplan import metrics
from jaxplan.dwa import (
    Ackermann, Disc, DiscObstacles, DWAConfig, DWAInfo, DWAParams, Rectangle, Unicycle, dwa_control,
    dwa_control_batch, dwa_step,
)
from jaxplan.metrics import EnergyModel, EpisodeTiming, path_metrics
from jaxplan.smooth import Smoothed, smooth
from jaxplan.nav import (
    Episode, EpisodeBatch, MovingObstacles, NavConfig, crossing_traffic, head_on, moving_obstacles, navigate,
    navigate_batch, navigate_multi, pipelines, random_obstacles,
)
from jaxplan.search import SearchGraph, astar, dijkstra, distance_from, search_graph, shortest_lengths
from jaxplan.core.version import VERSION as __version__

_DEPRECATED = {"warehouse_seed003": "warehouse_chen2023", "warehouse_seed004": "warehouse_yu2020"}
"""Names of the previous release (papers by internal number) -> their author-year names; kept for one release."""


def __getattr__(name: str):
    if name in _DEPRECATED:
        import warnings

        new = _DEPRECATED[name]
        warnings.warn(f"jaxplan.{name} is deprecated; use jaxplan.{new} (papers are named by first author and year)",
                      DeprecationWarning, stacklevel=2)
        return globals()[new]
    raise AttributeError(f"module 'jaxplan' has no attribute {name!r}")



__all__ = [
    "BatchResult", "plan_batch", "TourResult", "TSPProblem", "load_tour", "load_tsplib", "solve_tsp", "tour_length", "GridMap", "MountainGenerator", "Neighbours", "PlanResult", "PlannerSpec", "RandomMapGenerator", "Scenarios",
    "Scene", "SearchGraph", "UrbanGenerator", "WarehouseGenerator", "astar", "clearance_field", "demo_warehouse",
    "dijkstra", "distance_from", "goal_distance_field", "grid_from_array", "load_map", "load_scenarios",
    "neighbour_table", "passable", "plan", "planners", "poisson_risk", "register_planner", "save_map",
    "search_graph", "shortest_lengths", "smooth", "Smoothed", "metrics", "path_metrics", "Ackermann", "Disc", "DiscObstacles", "DWAConfig", "DWAInfo", "DWAParams", "Rectangle", "Unicycle", "dwa_control", "dwa_control_batch", "dwa_step", "EnergyModel", "EpisodeTiming", "warehouse_chen2023", "warehouse_yu2020",
    "Episode", "EpisodeBatch", "MovingObstacles", "NavConfig", "crossing_traffic", "head_on", "moving_obstacles",
    "navigate", "navigate_batch", "navigate_multi", "pipelines", "random_obstacles",
]
