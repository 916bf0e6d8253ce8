"""jaxplan: grid path planning for warehouse robots and logistics vehicles, in JAX.

The public names are re-exported here::

    import jaxplan as jp
    grid = jp.load_map("den520d.map")
    scen = jp.load_scenarios("den520d.map.scen")
    opt = jp.shortest_lengths(grid, scen.starts, scen.goals)
    res = jp.plan(grid, scen.starts[0], scen.goals[0], planner="astar")

Importing jaxplan has no side effect: it changes no JAX setting and loads no subpackage. Each
public name is imported from its subpackage when first used (PEP 562 ``__getattr__``), so
``import jaxplan`` and the command line's ``--help`` start without JAX or numba. To shard batches
over one CPU host device per core, opt in with `use_host_devices` before the first JAX
computation (the command line does). The on-disk compilation caches turn on when compiled code is
first loaded (`enable_compilation_cache` chooses their folder; ``JAXPLAN_CACHE=off`` turns them off).
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS: dict[str, tuple[str, ...]] = {
    "grid": (
        "GridMap", "Neighbours", "Scenarios", "clearance_field", "goal_distance_field", "grid_from_array", "load_map",
        "load_scenarios", "neighbour_table", "passable", "resample", "save_map", "MountainGenerator",
        "RandomMapGenerator",
        "Scene", "UrbanGenerator", "WarehouseGenerator", "demo_warehouse", "poisson_risk", "warehouse_chen2023",
        "warehouse_yu2020",
    ),
    "aco": ("TourResult", "TSPProblem", "load_tour", "load_tsplib", "solve_tsp", "tour_length"),
    "planning": ("plan", "plan_batch", "planners"),
    "registry": ("PlannerSpec", "register_planner"),
    "result": ("BatchResult", "PlanResult"),
    "dwa": ("Ackermann", "Disc", "DiscObstacles", "DWAConfig", "DWAInfo", "DWAParams", "Rectangle", "Unicycle",
            "DWAStepper", "dwa_control", "dwa_control_batch", "dwa_step", "make_stepper"),
    "mppi": ("MPPIConfig", "MPPIParams", "mppi_control", "mppi_step"),
    "metrics": ("EnergyModel", "EpisodeTiming", "PathMetrics", "path_metrics"),
    "smoothing": ("Smoothed", "smooth"),
    "nav": ("Episode", "EpisodeBatch", "MovingObstacles", "NavConfig", "crossing_traffic", "head_on",
            "moving_obstacles", "navigate", "navigate_batch", "navigate_multi", "pipelines", "random_obstacles"),
    "search": ("SearchGraph", "astar", "dijkstra", "distance_from", "search_graph", "shortest_lengths"),
    "scale": ("use_host_devices",),
    "core.compile_cache": ("enable_compilation_cache",),
}
"""Subpackage (or module) of jaxplan -> the public names re-exported from it."""

_SOURCE = {name: module for module, names in _EXPORTS.items() for name in names}

_DEPRECATED = {"warehouse_seed003": "warehouse_chen2023", "warehouse_seed004": "warehouse_yu2020"}
"""Names of the previous release (papers by internal number) -> their author-year names; kept for one release."""

_SUBMODULES = ("aco", "cli", "core", "dwa", "experiments", "grid", "metrics", "mppi", "nav", "papers", "planning",
               "registry", "result", "scale", "search", "smoothing", "tune")
"""Subpackages and modules reachable as attributes (``jp.search.path_cost``), imported on first use (``jp.smooth``
is the function; its subpackage is ``jp.smoothing``)."""

__all__ = sorted([*_SOURCE, "metrics"])


def _load(name: str) -> Any:
    value = getattr(importlib.import_module(f"jaxplan.{_SOURCE[name]}"), name)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __getattr__(name: str) -> Any:
    if name in _SOURCE:
        return _load(name)
    if name in _SUBMODULES:
        return importlib.import_module(f"jaxplan.{name}")
    if name == "__version__":
        from jaxplan.core.version import VERSION

        return VERSION
    if name in _DEPRECATED:
        import warnings

        new = _DEPRECATED[name]
        warnings.warn(f"jaxplan.{name} is deprecated; use jaxplan.{new} (papers are named by first author and year)",
                      DeprecationWarning, stacklevel=2)
        return _load(new)
    raise AttributeError(f"module 'jaxplan' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | set(_SUBMODULES) | {"__version__"})
