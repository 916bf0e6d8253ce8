"""The front door of the global planners: `plan`, `plan_batch`, `plan_memory` and `planners`
(docs/guide/planners.md), as ``jaxplan.plan``, ``jaxplan.plan_batch`` and ``jaxplan.planners``.

Planners register themselves with `jaxplan.registry` when their module is imported: the exact and
sampling planners of `jaxplan.search` (``astar``, ``dijkstra``, ``astar_kng``, ``rrt_star``,
``mrbs_rrt``) and the colonies of `jaxplan.aco` (``aco``, ``iaco``, ``risk_aco``, ``opt_ant``,
``praco``, each with its one-compiled-call batch). This module sits above both and imports them, so
`plan`, `plan_batch` and `planners` see every planner jaxplan ships whatever the caller imported before
(``import jaxplan`` itself imports nothing until a name is used); a planner added with
`jaxplan.register_planner` joins them.

`plan` and `plan_batch` take the same arguments in the same order — ``(grid, start(s), goal(s), *,
planner="astar", seed(s)=..., **planner parameters)`` — and `plan_batch` adds the batch's ``mesh`` and
``progress``, as `jaxplan.navigate_batch` does beside `jaxplan.navigate`.
"""

from __future__ import annotations

from typing import Any

from jax.sharding import Mesh
from numpy.typing import ArrayLike

import jaxplan.aco  # noqa: F401  (registers the colonies)
import jaxplan.search  # noqa: F401  (registers the exact and sampling planners)
from jaxplan.core.deprecation import keyword_only, warn_deprecated
from jaxplan.grid import GridMap
from jaxplan.registry import PlannerSpec, Seeds, plan_memory, registered, run_planner, run_planner_batch
from jaxplan.result import BatchResult, PlanResult

__all__ = ["DEFAULT_PLANNER", "plan", "plan_batch", "plan_memory", "planners"]

DEFAULT_PLANNER = "astar"
"""The planner `plan` and `plan_batch` run when none is named: exact, deterministic and cheap."""


class _Default(str):
    """`DEFAULT_PLANNER` as `plan_batch`'s default: equal to it (and shown as it by `inspect.signature`), but a
    distinct object, so that a call that names no planner can be told apart for one release (its default was
    ``"aco"``)."""

    __slots__ = ()


_BATCH_DEFAULT = _Default(DEFAULT_PLANNER)


def planners() -> dict[str, PlannerSpec]:
    """Every planner by name (`PlannerSpec`: its function, every parameter with its default, a description)."""
    return registered()


@keyword_only("planner", "seed")
def plan(grid: GridMap, start: ArrayLike, goal: ArrayLike, *, planner: str = DEFAULT_PLANNER, seed: int = 0,
         **overrides: Any) -> PlanResult:
    """Plans one path with a registered planner.

    Args:
      grid: the map.
      start, goal: ``(x, y)`` cells.
      planner: a name from `planners()` (default ``"astar"``).
      seed: PRNG seed (exact planners ignore it).
      **overrides: planner parameters; an unknown name raises ``ValueError``.

    Returns:
      `PlanResult`; an unreachable goal gives ``success=False``, ``length=inf``.

    ``planner`` and ``seed`` by position (``plan(grid, s, g, "iaco", 3)``, the previous release's form) still work
    for one release, with a `DeprecationWarning`.

    Example::

        import jaxplan as jp
        scene = jp.demo_warehouse()
        res = jp.plan(scene.grid, scene.start, scene.goal, planner="iaco", seed=0, ants=20, iterations=10)
    """
    return run_planner(grid, start, goal, planner, seed, **overrides)


@keyword_only("planner", "seeds")
def plan_batch(grid: GridMap, starts: ArrayLike, goals: ArrayLike, *, planner: str = _BATCH_DEFAULT,
               seeds: Seeds = range(1), mesh: Mesh | str | None = "auto", progress: bool = False,
               **overrides: Any) -> BatchResult:
    """Runs ``planner`` on every scenario with every seed: one compiled call for an ACO planner.

    Args:
      grid: the map.
      starts, goals: ``int[N, 2]`` cells.
      planner: a registered planner (default ``"astar"``, as `plan`). The ACO planners run batched; exact
        planners solve each scenario once and repeat it across seeds, since they ignore the seed; sampling
        planners run once per scenario and seed.
      seeds: iterable of non-negative integer seeds (R of them), or one integer.
      mesh: a 1-D device mesh (`jaxplan.scale.batch_mesh`), ``"auto"`` (default: every local
        device when there are several and each gets at least 8 scenarios — the library's CPU
        default, `jaxplan.scale.auto_mesh`) or None (one device). An ACO planner's scenarios
        are split over the mesh's devices (padded to a multiple of the device count with
        copies of the last scenario, which are dropped again); the results equal the
        single-device call's. Other planners ignore it.
      progress: show progress on stderr (`jaxplan.core.progress`; only on a terminal): an ACO batch is one
        compiled call, so its bar names the stage (compiling, then the call) with the elapsed time and no estimate
        of time left; the other planners run scenario by scenario, with a bar and time left. The results are the
        same either way.
      **overrides: planner parameters, as for `plan`.

    Returns:
      `BatchResult` with leading axes ``[N, R]``.

    Before it allocates, the batch's working memory (`plan_memory`) is checked against the limit
    (`jaxplan.scale.memory_limit`). For one release, the previous release's forms still work with a
    `DeprecationWarning`: ``planner`` and ``seeds`` by position, and a call that names no planner — it now runs
    ``"astar"``, where the previous release ran ``"aco"``.
    """
    if planner is _BATCH_DEFAULT:
        warn_deprecated("plan_batch() called without planner=: its default planner is now 'astar', as plan()'s "
                        "(it was 'aco'); pass planner= explicitly to silence this warning", stacklevel=4)
    return run_planner_batch(grid, starts, goals, str(planner), seeds, mesh=mesh, progress=progress, **overrides)
