"""The front door of the global planners: `plan` and `planners` (docs/guide/planners.md), as ``jaxplan.plan`` and
``jaxplan.planners``.

Planners register themselves with `jaxplan.registry` when their module is imported: the exact and
sampling planners of `jaxplan.search` (``astar``, ``dijkstra``, ``astar_kng``, ``rrt_star``,
``mrbs_rrt``) and the colonies of `jaxplan.aco` (``aco``, ``iaco``, ``risk_aco``, ``opt_ant``,
``praco``). This module sits above both and imports them, so `plan` and `planners` see every
planner jaxplan ships whatever the caller imported before (``import jaxplan`` itself imports
nothing until a name is used); a planner added with `jaxplan.register_planner` joins them.
"""

from __future__ import annotations

from typing import Any

from numpy.typing import ArrayLike

import jaxplan.aco  # noqa: F401  (registers the colonies)
import jaxplan.search  # noqa: F401  (registers the exact and sampling planners)
from jaxplan.grid import GridMap
from jaxplan.registry import PlannerSpec, registered, run_planner
from jaxplan.result import PlanResult

__all__ = ["plan", "planners"]


def planners() -> dict[str, PlannerSpec]:
    """Every planner by name (`PlannerSpec`: its function, every parameter with its default, a description)."""
    return registered()


def plan(grid: GridMap, start: ArrayLike, goal: ArrayLike, planner: str = "astar", seed: int = 0,
         **overrides: Any) -> PlanResult:
    """Plans one path with a registered planner.

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells.
      planner: a name from `planners()`.
      seed: PRNG seed (exact planners ignore it).
      **overrides: planner parameters; an unknown name raises ``ValueError``.

    Returns:
      `PlanResult`; an unreachable goal gives ``success=False``, ``length=inf``.

    Example::

        import jaxplan as jp
        scene = jp.demo_warehouse()
        res = jp.plan(scene.grid, scene.start, scene.goal, planner="iaco", seed=0, ants=20, iterations=10)
    """
    return run_planner(grid, start, goal, planner, seed, **overrides)
