"""One-path host versions of the geometry metrics (numpy, float64), for planners.

They evaluate the very definitions of `jaxplan.metrics._path` (written once over an
array module) with numpy instead of JAX: a planner fills `PlanResult.turns` once per path,
and there a compiled JAX call (its dispatch, and a compilation per padded length) would
cost more than the metric. Batches belong to the JAX functions and `path_metrics`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from jaxplan.metrics import _path as P

__all__ = ["path_length", "heading_changes", "count_turns", "count_sharp_turns", "smoothness", "max_curvature"]


def _points(points: ArrayLike) -> tuple[np.ndarray, int]:
    p = np.asarray(points)
    if p.ndim != 2 or p.shape[-1] != 2:
        if p.size == 0:  # an empty list or array: no point
            return np.zeros((0, 2)), 0
        raise ValueError(f"points must have shape [L, 2], got {p.shape}")
    return p, len(p)


def path_length(points: ArrayLike, resolution: float = 1.0) -> float:
    """Summed segment lengths of ``[L, 2]`` points (cells or metres), times ``resolution``."""
    p, n = _points(points)
    return float(np.sum(P._segments(p, n, np)[2]) * resolution) if n >= 2 else 0.0


def heading_changes(points: ArrayLike) -> np.ndarray:
    """``f64[V]`` absolute heading change (rad, in [0, π]) at each interior vertex, repeated points skipped."""
    p, n = _points(points)
    if n < 3:
        return np.zeros(0)
    heading, *_, vertex = P._vertex_turns(p, n, np)
    return heading[vertex]


def count_turns(points: ArrayLike) -> int:
    """Vertices whose heading change exceeds 1e-6 rad."""
    p, n = _points(points)
    return int(P._turn_counts(p, n, np, ("turns",))["turns"]) if n >= 3 else 0


def count_sharp_turns(points: ArrayLike) -> int:
    """Vertices whose heading change is at least 45° (less a 1e-9 rad tolerance)."""
    p, n = _points(points)
    return int(P._turn_counts(p, n, np, ("sharp_turns",))["sharp_turns"]) if n >= 3 else 0


def smoothness(points: ArrayLike) -> float:
    """``1 − mean|Δheading|/π`` over interior vertices (1 for a straight path or fewer than 3 points)."""
    p, n = _points(points)
    return float(P._turn_counts(p, n, np, ("smoothness",))["smoothness"]) if n >= 3 else 1.0


def max_curvature(points: ArrayLike, resolution: float = 1.0) -> float:
    """Largest Menger curvature (1/m) over interior vertices of cell-coordinate points (0 if none)."""
    p, n = _points(points)
    return float(P._geometry(p, n, resolution, np)["max_curvature"]) if n >= 3 else 0.0
