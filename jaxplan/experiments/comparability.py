"""Which of a paper's numbers can stand beside ours: one rule, applied by code (figures, verdicts).

The rule: an absolute number — a length, a count of turns, iterations, collisions or re-plans, a time, an
energy, a clearance, a distance — depends on the map or instance it was measured on. On a stand-in (a
generated map, a public instance in place of the paper's unpublished one) it measures the stand-in, not
the paper's setting, so it is *not comparable* with the paper's number; what the paper claims about it is
judged as a within-paper contrast instead (proposed against baseline on the same map, seeds and pairs).
Rates and normalised ratios (success, accuracy, optimality gaps, reduction rates, smoothness, curvature)
are comparable on any map. On the paper's own map or instance (``MapSpec.paper_map``) every number is.

Example:
  >>> from jaxplan.experiments.comparability import comparable
  >>> comparable("success", paper_map=False), comparable("turns", paper_map=False), comparable("turns", True)
  (True, False, True)
"""

from __future__ import annotations

__all__ = ["ABSOLUTE_METRICS", "comparable"]

ABSOLUTE_METRICS: frozenset[str] = frozenset({
    # lengths and distances (m, or the instance's metric)
    "length", "path_length", "los_length", "tour_length", "hausdorff", "rmse", "min_clearance", "mean_clearance",
    # counts
    "turns", "sharp_turns", "los_turns", "collisions", "active_contacts", "passive_contacts", "robot_contacts",
    "replans", "recoveries",
    # iterations
    "converged_iteration", "converged_iteration_strict", "turning_point", "optimum_iteration",
    # times, energy and the planners' own costs
    "time_s", "plan_time_s", "step_time_s", "energy", "cost",
})
"""Metrics whose values are absolute numbers of the map or instance they were measured on (see the module)."""


def comparable(metric: str, paper_map: bool) -> bool:
    """Whether the paper's value of ``metric`` may be set beside ours.

    Args:
      metric: a `jaxplan.experiments.config.METRICS` name.
      paper_map: the map (or instance) is the paper's own, as published (``MapSpec.paper_map``).

    Returns:
      True for a rate or normalised ratio on any map, and for every metric on the paper's own map; False
      for an absolute number (`ABSOLUTE_METRICS`: lengths, turns, iterations, collisions, times, energy)
      on a stand-in map or instance.
    """
    return bool(paper_map) or metric not in ABSOLUTE_METRICS
