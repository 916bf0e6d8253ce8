"""The planner registry (docs/guide/planners.md), at the bottom of the planners' import graph.

Every planner has the signature ``fn(grid, start, goal, seed, **params) -> PlanResult``
and registers its defaults with `register_planner` when its module is imported; `resolve`
merges a call's overrides into them and rejects unknown names, so a typo never silently
falls back to a default. The registry sees the planners whose modules have been imported:
the front door `jaxplan.plan` / `jaxplan.planners` (`jaxplan.planning`) imports every
planner jaxplan ships first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping

from numpy.typing import ArrayLike

from jaxplan.core.names import did_you_mean
from jaxplan.grid import GridMap
from jaxplan.result import PlanResult

__all__ = ["PlannerSpec", "register_planner", "registered", "resolve", "run_planner"]


@dataclass(frozen=True)
class PlannerSpec:
    """A registered planner.

    Attributes:
      name: registry name (``jp.plan(..., planner=name)``).
      fn: ``fn(grid, start, goal, seed, **params) -> PlanResult``.
      defaults: every parameter the planner accepts, with its default.
      description: one line, citing the seed paper where there is one.
      validate: optional ``validate(params) -> None`` raising ``ValueError`` on a bad value.
    """

    name: str
    fn: Callable[..., PlanResult]
    defaults: Mapping[str, Any]
    description: str
    validate: Callable[[Mapping[str, Any]], None] | None = field(default=None, compare=False)


_REGISTRY: dict[str, PlannerSpec] = {}


def register_planner(
    name: str,
    fn: Callable[..., PlanResult],
    defaults: Mapping[str, Any],
    description: str,
    validate: Callable[[Mapping[str, Any]], None] | None = None,
) -> PlannerSpec:
    """Adds a planner to the registry (at import time of the module that defines it)."""
    if name in _REGISTRY:
        raise ValueError(f"planner {name!r} is already registered")
    spec = PlannerSpec(name, fn, MappingProxyType(dict(defaults)), description, validate)
    _REGISTRY[name] = spec
    return spec


def registered() -> dict[str, PlannerSpec]:
    """The planners registered so far by name, with their defaults and descriptions (`jaxplan.planners` lists
    every planner jaxplan ships)."""
    return dict(_REGISTRY)


def _check_numbers(name: str, params: Mapping[str, Any]) -> None:
    for k, v in params.items():
        if isinstance(v, float) and math.isnan(v):
            raise ValueError(f"planner {name!r}: parameter {k!r} is NaN")


def resolve(planner: str, overrides: Mapping[str, Any]) -> tuple[PlannerSpec, dict[str, Any]]:
    """The spec of ``planner`` and its parameters with ``overrides`` applied and checked."""
    spec = _REGISTRY.get(planner)
    if spec is None:
        raise ValueError(f"unknown planner {planner!r}{did_you_mean(str(planner), _REGISTRY)} "
                         f"(registered: {', '.join(sorted(_REGISTRY))})")
    unknown = sorted(set(overrides) - set(spec.defaults))
    if unknown:
        # Each unknown name with its own suggestion: ``iteration=10`` reads "did you mean 'iterations'?".
        named = "; ".join(f"{k!r}{did_you_mean(str(k), spec.defaults)}" for k in unknown)
        raise ValueError(
            f"planner {planner!r} has no parameter(s) {named} "
            f"(it accepts: {', '.join(sorted(spec.defaults)) or 'none'})"
        )
    params = {**spec.defaults, **overrides}
    _check_numbers(planner, params)
    if spec.validate is not None:
        spec.validate(params)
    return spec, params


def run_planner(grid: GridMap, start: ArrayLike, goal: ArrayLike, planner: str = "astar", seed: int = 0,
                **overrides: Any) -> PlanResult:
    """Plans one path with an already registered planner (the dispatch behind `jaxplan.plan`).

    Args and returns as `jaxplan.plan`; for modules inside jaxplan that import their planners' modules.
    """
    if not isinstance(grid, GridMap):
        raise TypeError(f"grid must be a GridMap (see jp.load_map / jp.grid_from_array), got {type(grid).__name__}")
    spec, params = resolve(planner, overrides)
    return spec.fn(grid, start, goal, seed, **params)
