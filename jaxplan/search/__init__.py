"""Global planners on the grid: exact (A*, Dijkstra), key-node-guided A* and sampling (RRT*, MRBS-RRT*).

Importing this package registers ``astar``, ``dijkstra``, ``astar_kng``, ``rrt_star`` and
``mrbs_rrt`` with `jaxplan.registry`. The exact searches underneath (`search_graph`,
`shortest_lengths`, `distance_from`) belong to `jaxplan.grid` and are re-exported here.
`exact_objective` computes each colony's own optimum: the exact minimum of a planner's path cost
(not only the length) under its move and turn rules.
"""

from jaxplan.grid import SearchGraph, distance_from, search_graph, shortest_lengths
from jaxplan.search._exact import astar, dijkstra, path_cost
from jaxplan.search._kng import astar_kng
from jaxplan.search._objective import (
    OBJECTIVE_PLANNERS,
    NonAdditiveCost,
    ObjectiveTerms,
    exact_objective,
    exact_objectives,
    objective_cost_to_go,
    objective_terms,
    path_objective,
    path_objectives,
)
from jaxplan.search._sampling import mrbs_rrt, rrt_star

__all__ = [
    "SearchGraph", "astar", "astar_kng", "dijkstra", "distance_from", "mrbs_rrt", "path_cost", "rrt_star",
    "search_graph", "shortest_lengths",
    "NonAdditiveCost", "OBJECTIVE_PLANNERS", "ObjectiveTerms", "exact_objective", "exact_objectives",
    "objective_cost_to_go", "objective_terms",
    "path_objective", "path_objectives",
]
