"""The papers' two-level systems as named pipelines, and the ablations of cui2025's Table 1.

A pipeline is a global planner (a registry name and overrides), the reduction of its path
to waypoints (smoothers of `jaxplan.smoothing`, run with the robot's d_safe as clearance),
and a local planner (DWA with an evaluator, MPPI, or pure path following).
"""

from __future__ import annotations

import dataclasses
from types import MappingProxyType
from typing import Any, Mapping

from jaxplan.core.names import did_you_mean

__all__ = ["Pipeline", "PIPELINES", "pipelines", "get_pipeline"]


@dataclasses.dataclass(frozen=True)
class Pipeline:
    """A two-level navigation system.

    Attributes:
      name: registry name.
      global_planner: a `jaxplan.planners()` name.
      planner_overrides: overrides of the global planner's defaults.
      waypoints: smoothers applied to the global path, in order (`jaxplan.smoothing.SMOOTHERS` names).
      local: ``"dwa"``, ``"mppi"`` or ``"follow"``.
      evaluator: the DWA evaluator (``"weighted"``, ``"fuzzy"``, ``"classic"``; unused by MPPI).
      description: one line, citing the seed.
    """

    name: str
    global_planner: str
    planner_overrides: Mapping[str, Any]
    waypoints: tuple[str, ...]
    local: str
    evaluator: str
    description: str


_KEY = ("los", "key_nodes")
"""Key nodes of an ACO path: its line-of-sight vertices (the ants' zig-zag removed), then the turns >= 20°."""


def _p(name, planner, waypoints, evaluator, description, local="dwa", **overrides) -> Pipeline:
    return Pipeline(name, planner, MappingProxyType(overrides), tuple(waypoints), local, evaluator, description)


PIPELINES: Mapping[str, Pipeline] = MappingProxyType({p.name: p for p in (
    _p("iaco_dwa", "iaco", _KEY, "fuzzy",
       "cui2025 IACO-DWA: elite multi-objective ACO, key nodes, fuzzy-evaluated DWA (IDWA)"),
    _p("aco_dwa", "aco", _KEY, "weighted", "cui2025's ACO-DWA baseline: Ant System, key nodes, weighted DWA"),
    _p("astar_kng_dwa", "astar", ["key_nodes"], "weighted",
       "li2026 A*-KNG-DWA: exact A*, key-node guidance (turns >= 20 deg), weighted DWA"),
    _p("opt_ant_dwa", "opt_ant", ["los", "bezier"], "weighted",
       "chu2024 Opt Ant-DWA: 16-direction Opt Ant, line-of-sight pruning and Bezier corners, weighted DWA"),
    _p("rrt_star_dwa", "rrt_star", ["key_nodes"], "weighted", "li2026's RRT* baseline tracked by weighted DWA"),
    _p("mrbs_rrt_dwa", "mrbs_rrt", ["key_nodes"], "weighted",
       "li2026 MRBS: multi-region biased RRT*, key nodes, weighted DWA"),
    # Beyond DWA: the same global plans tracked by MPPI (Williams et al. 2017; Nav2's default controller).
    _p("iaco_mppi", "iaco", _KEY, "weighted", "IACO (cui2025) and key nodes, tracked by the MPPI local planner",
       local="mppi"),
    _p("astar_kng_mppi", "astar", ["key_nodes"], "weighted",
       "A*-KNG (li2026), tracked by the MPPI local planner", local="mppi"),
    # cui2025 Table 1 ablations of IACO-DWA.
    _p("iaco_dwa_no_elite", "iaco", _KEY, "fuzzy",
       "cui2025 Table 1 B: IACO-DWA without elite reinforcement (delta = 0)", delta=0.0),
    _p("iaco_dwa_no_fitness", "iaco", _KEY, "fuzzy",
       "cui2025 Table 1 C: IACO-DWA without the multi-objective fitness (length only: lambdas = (1, 0, 0))",
       lambdas=(1.0, 0.0, 0.0)),
    _p("iaco_follow", "iaco", _KEY, "fuzzy",
       "cui2025 Table 1 D: IACO without DWA: pure path following of the key nodes", local="follow"),
    _p("iaco_dwa_weighted", "iaco", _KEY, "weighted",
       "cui2025 Table 1 E: IACO-DWA without fuzzy evaluation (weighted sum)"),
)})
"""The named pipelines (`pipelines()` lists them)."""


def pipelines() -> dict[str, Pipeline]:
    """All named pipelines."""
    return dict(PIPELINES)


def get_pipeline(name: str) -> Pipeline:
    """The pipeline ``name``; a clear error listing the names otherwise."""
    p = PIPELINES.get(name)
    if p is None:
        raise ValueError(f"unknown pipeline {name!r}{did_you_mean(str(name), PIPELINES)} "
                         f"(choose from {', '.join(PIPELINES)})")
    return p
