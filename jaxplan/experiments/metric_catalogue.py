"""The metrics an experiment records: the catalogue of every metric a config may name (`METRICS`).

Each `Metric` says which planner kinds it applies to, its unit and one line of description, and how the outputs
treat it (a wall-clock time goes to timings.csv, a rate is averaged as a share, an opt-in metric costs extra work
per chunk). The values themselves are computed by `jaxplan.experiments.trial_metrics` (paths and episodes, on the
host), `jaxplan.experiments.team` (a team's episode) and `jaxplan.metrics` (the library's path and episode
metrics); docs/guide/smoothing-and-metrics.md defines them. The config reference lists this catalogue
(``docs/guide/config.md``, "Metrics").
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

__all__ = ["Metric", "METRICS", "ACCURACY_GAP"]


@dataclass(frozen=True)
class Metric:
    """A metric a config may name.

    Attributes:
      name: column name in trials.csv / summary.csv.
      kinds: planner kinds it applies to (``"plan"``, ``"navigate"``).
      unit: for tables ("" for counts and ratios).
      description: one line (docs/guide/smoothing-and-metrics.md).
      timing: a wall-clock time: written to timings.csv per chunk, not to trials.csv
        (it differs from run to run; trials.csv must not).
      given_success: averaged over successful trials only (e.g. the arrival time).
      rate: a 0/1 outcome whose per-seed mean is a rate.
      default: in the default metric set of a config that lists none (the opt-in metrics cost
        extra work per chunk: exact reference paths, smoothing).
    """

    name: str
    kinds: frozenset
    unit: str
    description: str
    timing: bool = False
    given_success: bool = False
    rate: bool = False
    default: bool = True


ACCURACY_GAP = 0.10
"""cui2025's "accuracy" (docs/guide/smoothing-and-metrics.md): the share of trials that succeed with an optimality gap
<= this."""

_P, _N, _B = frozenset({"plan"}), frozenset({"navigate"}), frozenset({"plan", "navigate"})
_T, _PT = frozenset({"tsp"}), frozenset({"plan", "tsp"})
METRICS: Mapping[str, Metric] = MappingProxyType({m.name: m for m in (
    Metric("success", _B | _T, "", "plan: goal reached; navigate: goal reached without collision in time; "
                                   "tsp: 1 (every run returns a tour)", rate=True),
    Metric("accuracy", _B, "", "cui2025: success with optimality gap <= 10 % (plan: the raw grid path against the "
                               "octile optimum; navigate: the executed path against the line-of-sight smoothed "
                               "exact path on the planning map)", rate=True, default=False),
    Metric("length", _P, "m", "path length"),
    Metric("tour_length", _T, "", "closed-tour length in the instance's metric (TSPLIB rounding)"),
    Metric("optimality_gap", _PT, "", "plan: length / exact 8-connected octile optimum - 1; tsp: tour length / "
                                      "optimal tour length - 1"),
    Metric("objective_gap", _P, "", "the planner's own cost of its path / the exact minimum of that cost - 1 "
                                    "(jaxplan.search.exact_objective; nan for planners whose cost is no sum over "
                                    "moves and turns)", default=False),
    Metric("turns", _P, "", "path vertices with a heading change"),
    Metric("sharp_turns", _P, "", "heading changes >= 45 deg"),
    Metric("los_length", _P, "m", "path length after line-of-sight smoothing (yu2020 sec. 3.3, smoother 'los')",
           default=False),
    Metric("los_turns", _P, "", "turns after line-of-sight smoothing", default=False),
    Metric("los_length_reduction", _P, "", "1 - los_length / length (yu2020 Table 4)", default=False),
    Metric("los_turns_reduction", _P, "", "1 - los_turns / turns (nan for a straight path)", default=False),
    Metric("smoothness", _B, "", "1 - mean |heading change| / pi over the path's vertices (navigate: the executed "
           "path resampled every cell length)"),
    Metric("min_clearance", _P, "m", "smallest vertex clearance"),
    Metric("mean_clearance", _B, "m", "mean vertex clearance (navigate: of the executed path resampled every cell "
           "length; cui2025 Table 1's average obstacle distance)"),
    Metric("max_curvature", _B, "1/m", "plan: Menger curvature at path vertices; navigate: executed |omega|/v"),
    Metric("hausdorff", _B, "m", "Hausdorff distance of the global path to the exact A* path (cui2025 Fig. 9)"),
    Metric("cost", _P, "", "the planner's own objective"),
    Metric("converged_iteration", _PT, "", "first iteration (0-based) whose best cost (tsp: tour length) is within "
                                           "1 % of the run's final best: the general definition"),
    Metric("converged_iteration_strict", _PT, "", "as converged_iteration within 0.1 % of the final best: the "
                                                  "sensitivity row of the convergence iteration", default=False),
    Metric("turning_point", _PT, "", "chu2024's iterative stabilization: the iteration (counted from 1) from which "
                                     "the best cost stays at its final value", default=False),
    Metric("optimum_iteration", _PT, "", "yu2020's number of iterations: the generation (counted from 1) in which "
                                         "the run's final best is first found", default=False),
    Metric("collisions", _N, "", "contacts with the map or moving discs (a team: with other robots too, summed "
                                 "over its robots)"),
    Metric("arrived", _N, "", "share of the robots at their goals without collision in time (one robot: success; "
                              "a team: its robots that succeeded / robots)", default=False),
    Metric("robot_contacts", _N, "", "robot-robot contacts of a team, each pair's contact once (0 for one robot)",
           default=False),
    Metric("active_contacts", _N, "", "contacts begun while the robot moved faster than 0.05 m/s", default=False),
    Metric("passive_contacts", _N, "", "contacts begun with the robot at rest", default=False),
    Metric("time_s", _N, "s", "simulated time to the goal", given_success=True),
    Metric("rmse", _N, "m", "RMS distance of executed positions to the tracked path"),
    Metric("energy", _N, "J", "energy proxy (docs/guide/smoothing-and-metrics.md)"),
    Metric("path_length", _N, "m", "executed path length"),
    Metric("recoveries", _N, "", "control steps with no feasible DWA sample"),
    Metric("replans", _N, "", "in-episode re-plans"),
    Metric("plan_time_s", _B | _T, "s", "global planning (tsp: solving) wall time per trial (chunk time / trials)",
           timing=True),
    Metric("step_time_s", _N, "s", "wall time per control step of one robot", timing=True),
)})
"""Every metric a config may name, in the column order of the outputs."""
