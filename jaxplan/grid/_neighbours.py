"""Neighbourhoods for 4-, 8- and 16-connected moves, as flat tables ready for gathers.

Move rule (docs/guide/maps-and-scenarios.md#conventions): a move from cell c to c + (dx, dy) is allowed when every
cell whose closed square meets the closed segment between the two centres is
passable. For straight moves that is just the target; for diagonal moves the
segment passes through the shared corner, so both orthogonal neighbours must be
free (MovingAI's "no corner cutting", chen2023's "de-pointing"); for the
knight moves of chu2024 (±1, ±2)/(±2, ±1) the two cells the segment crosses
must be free. Step lengths are 1, √2 and √5 times the resolution.
"""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from jaxplan.grid._gridmap import GridMap, passable

__all__ = ["Neighbours", "neighbour_table", "offsets", "segment_cells", "CONNECTIVITIES", "check_connectivity"]

CONNECTIVITIES = (4, 8, 16)


def check_connectivity(connectivity: int) -> int:
    """``connectivity`` as an int if it is 4, 8 or 16; else ``ValueError``."""
    if connectivity not in CONNECTIVITIES:
        raise ValueError(f"connectivity must be one of {CONNECTIVITIES}, got {connectivity!r}")
    return int(connectivity)


@lru_cache(maxsize=None)
def offsets(connectivity: int) -> np.ndarray:
    """``int32[K, 2]`` moves (dx, dy), sorted counter-clockwise by angle from +x (east).

    With y pointing down (rows), "counter-clockwise" is on screen clockwise; what
    matters is that consecutive indices are adjacent headings.
    """
    k = check_connectivity(connectivity)
    moves = [(1, 0), (0, 1), (-1, 0), (0, -1)]
    if k >= 8:
        moves += [(1, 1), (-1, 1), (-1, -1), (1, -1)]
    if k == 16:
        moves += [(2, 1), (1, 2), (-1, 2), (-2, 1), (-2, -1), (-1, -2), (1, -2), (2, -1)]
    moves.sort(key=lambda m: np.arctan2(m[1], m[0]) % (2 * np.pi))
    out = np.array(moves, dtype=np.int32)
    out.setflags(write=False)
    return out


def _segment_meets_square(p0: tuple[Fraction, Fraction], p1: tuple[Fraction, Fraction], cx: int, cy: int) -> bool:
    """Exact (rational) closed-segment / closed-unit-square test (Liang–Barsky)."""
    t0, t1 = Fraction(0), Fraction(1)
    for p, d, lo, hi in ((p0[0], p1[0] - p0[0], cx, cx + 1), (p0[1], p1[1] - p0[1], cy, cy + 1)):
        if d == 0:
            if p < lo or p > hi:
                return False
            continue
        a, b = (lo - p) / d, (hi - p) / d
        if a > b:
            a, b = b, a
        t0, t1 = max(t0, a), min(t1, b)
        if t0 > t1:
            return False
    return True


@lru_cache(maxsize=None)
def segment_cells(dx: int, dy: int) -> tuple[tuple[int, int], ...]:
    """Offsets of the cells, other than the two end cells, whose closed square the
    segment between the centres of (0, 0) and (dx, dy) touches."""
    half = Fraction(1, 2)
    p0, p1 = (half, half), (dx + half, dy + half)
    cells = []
    for cy in range(min(0, dy), max(0, dy) + 1):
        for cx in range(min(0, dx), max(0, dx) + 1):
            if (cx, cy) in ((0, 0), (dx, dy)):
                continue
            if _segment_meets_square(p0, p1, cx, cy):
                cells.append((cx, cy))
    return tuple(cells)


class Neighbours(NamedTuple):
    """Flat move tables of one map (numpy arrays; pass them to jnp as they are).

    Attributes:
      index: ``int32[C, K]`` flat index of the cell reached by move k from cell c;
        where the move is not allowed it holds c itself, so gathers never go out of range.
      valid: ``bool[C, K]`` whether move k from cell c is allowed (source and target
        passable, no blocked cell crossed, target inside the map).
      offsets: ``int32[K, 2]`` the moves (dx, dy).
      step: ``f32[K]`` the length of each move in metres.
      connectivity: 4, 8 or 16.
    """

    index: np.ndarray  # type: ignore[assignment]  # a field named as tuple.index
    valid: np.ndarray
    offsets: np.ndarray
    step: np.ndarray
    connectivity: int


def neighbour_table(grid: GridMap, connectivity: int = 8, vehicle_height: float | None = None) -> Neighbours:
    """Builds the move table of ``grid`` for the given connectivity.

    Args:
      grid: the map.
      connectivity: 4, 8 or 16.
      vehicle_height: if given, cells whose ``clearance_height`` is not above it are blocked.

    Returns:
      `Neighbours` with ``C = H * W`` rows (blocked cells have no valid moves).
    """
    k = check_connectivity(connectivity)
    ok = passable(grid, vehicle_height)
    H, W = ok.shape
    # Pad by two blocked cells so every move of up to 2 cells can be read without bounds checks.
    pad = np.zeros((H + 4, W + 4), dtype=bool)
    pad[2:-2, 2:-2] = ok
    offs = offsets(k)
    ys, xs = np.mgrid[0:H, 0:W]
    flat = (ys * W + xs).astype(np.int32)
    index = np.empty((H * W, len(offs)), dtype=np.int32)
    valid = np.empty((H * W, len(offs)), dtype=bool)

    def shifted(dx: int, dy: int) -> np.ndarray:
        return pad[2 + dy : 2 + dy + H, 2 + dx : 2 + dx + W]

    for j, (dx, dy) in enumerate(offs):
        v = ok & shifted(dx, dy)
        for cx, cy in segment_cells(int(dx), int(dy)):
            v = v & shifted(cx, cy)
        valid[:, j] = v.ravel()
        index[:, j] = np.where(v, flat + dy * W + dx, flat).ravel()
    step = (np.hypot(offs[:, 0], offs[:, 1]) * float(grid.resolution)).astype(np.float32)
    return Neighbours(index=index, valid=valid, offsets=np.array(offs), step=step, connectivity=k)
