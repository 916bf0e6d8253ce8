"""Maps: the `GridMap` pytree, MovingAI and ROS map_server I/O, resampling, neighbourhoods, the move graph and
exact distances on it, distance fields, the exact collision geometry of cells (`CollisionMap`) and generators."""

from jaxplan.grid._collision import (
    PAD,
    POINT_WINDOW,
    TOUCH,
    CollisionMap,
    cached_collision_map,
    collision_map,
    point_clearance,
    polyline_free,
    segment_clearance,
    segment_free,
    segment_window,
)
from jaxplan.grid._cost_to_go import state_cost_to_go
from jaxplan.grid._fields import clearance_field, goal_distance_field
from jaxplan.grid._files import is_ros_map, load_map, save_map
from jaxplan.grid._generators import (
    MountainGenerator,
    RandomMapGenerator,
    Scene,
    UrbanGenerator,
    WarehouseGenerator,
    as_rng,
    demo_warehouse,
    poisson_risk,
    warehouse_chen2023,
    warehouse_yu2020,
)
from jaxplan.grid._graph import SearchGraph, distance_from, search_graph, shortest_lengths, shortest_path
from jaxplan.grid._gridmap import GridMap, check_cell, check_cells, check_pair, check_pairs, grid_from_array, passable
from jaxplan.grid._movingai import (
    Scenarios,
    load_movingai_map,
    load_scenarios,
    parse_map,
    parse_scenarios,
    save_movingai_map,
)
from jaxplan.grid._neighbours import (
    CONNECTIVITIES,
    Neighbours,
    check_connectivity,
    neighbour_table,
    offsets,
    segment_cells,
)
from jaxplan.grid._resample import resample, resampled_shape
from jaxplan.grid._ros import load_ros_map, occupancy_values, read_pgm, read_ros_yaml, save_ros_map
from jaxplan.grid._search_parts import (
    H_EUCLID,
    H_MANHATTAN,
    H_NONE,
    H_OCTILE,
    cell_heuristic,
    heap_pop,
    heap_push,
    heap_room,
)

__all__ = [
    "CONNECTIVITIES", "GridMap", "Neighbours", "Scenarios", "check_cell", "check_cells", "check_pair", "check_pairs",
    "check_connectivity", "clearance_field", "goal_distance_field", "grid_from_array", "load_map", "load_scenarios",
    "neighbour_table", "offsets", "parse_map", "parse_scenarios", "passable", "save_map", "segment_cells",
    "SearchGraph", "distance_from", "search_graph", "shortest_lengths", "shortest_path",
    "PAD", "POINT_WINDOW", "TOUCH", "CollisionMap", "cached_collision_map", "collision_map", "point_clearance",
    "polyline_free", "segment_clearance", "segment_free", "segment_window",
    "MountainGenerator", "RandomMapGenerator", "Scene", "UrbanGenerator", "WarehouseGenerator", "as_rng",
    "demo_warehouse", "poisson_risk", "warehouse_chen2023", "warehouse_yu2020",
    "is_ros_map", "load_movingai_map", "save_movingai_map", "load_ros_map", "save_ros_map", "read_ros_yaml",
    "read_pgm", "occupancy_values", "resample", "resampled_shape", "state_cost_to_go",
    "heap_pop", "heap_push", "heap_room", "cell_heuristic", "H_NONE", "H_MANHATTAN", "H_OCTILE",
    "H_EUCLID",
]
