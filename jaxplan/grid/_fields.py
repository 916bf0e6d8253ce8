"""Distance fields over a map: obstacle clearance (Euclidean) and exact goal distance."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from jaxplan.grid._graph import distance_from
from jaxplan.grid._gridmap import GridMap, check_cell, passable

__all__ = ["clearance_field", "goal_distance_field"]


def clearance_field(grid: GridMap, border_is_obstacle: bool = True) -> np.ndarray:
    """Exact distance in metres from each cell centre to the nearest blocked cell's boundary.

    The nearest point of a blocked unit square to a cell centre always lies on the
    half-cell lattice (a corner or an edge midpoint of that square), so a Euclidean
    distance transform (scipy.ndimage) over that lattice, with every lattice point
    of every blocked square marked, gives the exact point-to-square distance rather
    than the centre-to-centre approximation. A free cell next to a wall gets
    ``0.5 * res``; a free cell diagonal to a blocked one ``√2/2 * res``; blocked cells 0.

    Args:
      grid: the map.
      border_is_obstacle: treat the outside of the map as blocked (a robot leaving
        the map collides), the default. If False and the map has no blocked cell,
        the field is ``inf``.

    Returns:
      ``f32[H, W]`` clearance in metres.
    """
    blocked = ~np.asarray(grid.free, dtype=bool)
    if border_is_obstacle:
        blocked = np.pad(blocked, 1, constant_values=True)
    if not blocked.any():
        return np.full(grid.shape, np.inf, dtype=np.float32)
    h, w = blocked.shape
    # Lattice point (2y + j, 2x + i), i, j in {0, 1, 2}, lies on the closed square of cell (x, y).
    lattice = np.zeros((2 * h + 1, 2 * w + 1), dtype=bool)
    for j in range(3):
        for i in range(3):
            lattice[j : j + 2 * h : 2, i : i + 2 * w : 2] |= blocked
    dist = ndimage.distance_transform_edt(~lattice, sampling=0.5)
    centres = dist[1::2, 1::2]
    if border_is_obstacle:
        centres = centres[1:-1, 1:-1]
    return (centres * float(grid.resolution)).astype(np.float32)


def goal_distance_field(
    grid: GridMap, goal: ArrayLike, connectivity: int = 8, vehicle_height: float | None = None
) -> np.ndarray:
    """Exact shortest-path distance (m) from every cell to ``goal`` under the move rules.

    Args:
      grid: the map.
      goal: ``(x, y)`` cell.
      connectivity: 4, 8 or 16 (moves are symmetric, so distance to and from the goal agree).
      vehicle_height: cells too low for the vehicle are blocked.

    Returns:
      ``f32[H, W]``: metres; ``inf`` for blocked cells and cells that cannot reach the goal.
    """
    g = check_cell(grid, goal, "goal", passable(grid, vehicle_height))
    d = distance_from(grid, g, connectivity=connectivity, vehicle_height=vehicle_height)
    return d.astype(np.float32)
